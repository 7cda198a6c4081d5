// Fuzz target: a law file (gabion.law/2 or /1) through loadLawFile, which
// validates every law of every material.
#include <cstddef>
#include <cstdint>

#include "bridge/errors.hpp"
#include "bridge/law_file.hpp"
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    (void)gabion::bridge::loadLawFile(gabion::fuzz::inputFile(data, size, ".json"));
  } catch (const gabion::bridge::InputError&) {
  }
  return 0;
}
