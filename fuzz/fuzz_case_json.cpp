// Fuzz target: a case file through the JSON loader (the SAX pre-pass that
// refuses duplicate keys, deep nesting and huge numbers, then the DOM), a
// walk of its root as the kinds read it, and the --set parser on the same
// bytes. Bad input must end in InputError, never a crash or a hang.
#include <cstddef>
#include <cstdint>
#include <string>

#include "bridge/errors.hpp"
#include "bridge/json_reader.hpp"
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using gabion::bridge::InputError;
  using gabion::bridge::JsonDocument;
  try {
    JsonDocument doc = JsonDocument::load(gabion::fuzz::inputFile(data, size, ".json"));
    const auto root = doc.root();
    (void)root.string("format", "");
    (void)root.string("kind", "");
    for (const char* key : {"seed", "count", "threads"})
      if (root.has(key)) (void)root.integer(key, 0, 0);
    if (root.has("run")) {
      const auto run = root.object("run");
      (void)run.number("duration_s", 1.0, gabion::bridge::Check::Positive);
    }
    doc.applySet(std::string(reinterpret_cast<const char*>(data), size));
  } catch (const InputError&) {
  }
  return 0;
}
