#pragma once
/// \file
/// Validated reading of JSON input (cases, law files).
///
/// Every value is read through a JsonReader, which knows the file and the JSON
/// pointer of the node, so any error names both (`cases/x.json: /spheres/3/radius_m:
/// must be > 0`). The reader records which keys were read; JsonDocument::finish()
/// then rejects every key nobody read (an unknown key, usually a typo), the way
/// pbrt-v4 stops on an unused parameter. Validation stays on in Release builds.
#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace gabion::bridge {

using Vec3 = Eigen::Vector3d;

/// What a number must satisfy besides being finite.
enum class Check { Finite, Positive, NonNegative, Fraction /* in [0, 1] */, UnitOpen /* in [0, 1) */ };

class JsonReader;

/// A parsed JSON file with the bookkeeping of which keys were read.
class JsonDocument {
 public:
  /// Reads and parses a file; throws InputError naming the file (and the line
  /// for a syntax error) when it cannot.
  static JsonDocument load(const std::filesystem::path& path);
  JsonDocument(nlohmann::json value, std::string file);

  /// The reader of the root object.
  JsonReader root() const;
  /// Applies a command-line override `a.b.0.c=value` (value parsed as JSON, or
  /// taken as a string when it is not valid JSON). Throws InputError when the
  /// path does not lead to an existing object or array element.
  void applySet(const std::string& assignment);
  /// Throws InputError for the first key in the document that was never read.
  void finish() const;
  /// Frees the parsed value and the bookkeeping (json() is null afterwards):
  /// for a kind that has read all it needs from a large case, when the caller
  /// allows it (RunContext::may_release_case). Readers of this document must
  /// not be used afterwards.
  void releaseValue() const;
  /// Puts the parsed value under `key` of `record`, calls `use(record)` and
  /// takes the value back, also when `use` throws: a record that holds the
  /// whole case (run.json) without a copy of a large one. The value's nodes,
  /// which readers point at, do not move.
  void lendValue(nlohmann::json& record, const std::string& key,
                 const std::function<void(const nlohmann::json&)>& use) const;

  const nlohmann::json& json() const { return state_->value; }
  const std::string& file() const { return state_->file; }

 private:
  friend class JsonReader;
  struct State {
    nlohmann::json value;
    std::string file;
    // Values that were read, by address (stable: the value is not modified
    // after applySet); `whole`: read as a whole (raw), nothing inside is
    // checked. A pointer per key read, not a string. Once finish() has found
    // no unknown key, reading goes on unrecorded (what a kind reads was
    // checked by then) and both lists are freed.
    std::vector<const nlohmann::json*> used, whole;
    bool finished = false;
  };
  std::shared_ptr<State> state_;
};

/// A view of one JSON object inside a JsonDocument.
class JsonReader {
 public:
  bool has(const std::string& key) const;

  /// A required finite number satisfying `check`.
  double number(const std::string& key, Check check = Check::Finite) const;
  /// An optional number: `fallback` when absent.
  double number(const std::string& key, double fallback, Check check = Check::Finite) const;
  /// An optional number with no default: empty when absent (a change that
  /// replaces a value only where one is given).
  std::optional<double> optionalNumber(const std::string& key, Check check = Check::Finite) const;
  /// A required integer in [minimum, 2^31 - 1]: every count, index and
  /// step number fits an int, so what a caller narrows it to cannot wrap.
  long long integer(const std::string& key, long long minimum) const;
  long long integer(const std::string& key, long long fallback, long long minimum) const;
  /// A random seed: an integer in [0, 2^63 - 1].
  std::uint64_t seed(const std::string& key, std::uint64_t fallback) const;
  std::string string(const std::string& key) const;
  std::string string(const std::string& key, const std::string& fallback) const;
  /// A string that must be one of `options`.
  std::string choice(const std::string& key, const std::vector<std::string>& options) const;
  std::string choice(const std::string& key, const std::vector<std::string>& options,
                     const std::string& fallback) const;
  bool boolean(const std::string& key) const;
  bool boolean(const std::string& key, bool fallback) const;
  /// A required array of 3 finite numbers.
  Vec3 vec3(const std::string& key) const;
  Vec3 vec3(const std::string& key, const Vec3& fallback) const;
  /// A required array of finite numbers (each satisfying `check`), at least `min_size` long.
  std::vector<double> numbers(const std::string& key, Check check = Check::Finite, std::size_t min_size = 1) const;

  /// A required nested object.
  JsonReader object(const std::string& key) const;
  std::optional<JsonReader> optionalObject(const std::string& key) const;
  /// An array of objects; absent means empty unless `required`.
  std::vector<JsonReader> objects(const std::string& key, bool required = false) const;
  /// The same, one reader at a time, for an array too large to hold a reader
  /// per element beside it (a case's listed spheres); returns the count.
  std::size_t forEachObject(const std::string& key, const std::function<void(const JsonReader&)>& use,
                            bool required = false) const;
  /// The length of an array (0 when absent or not an array; nothing marked read).
  std::size_t arraySize(const std::string& key) const;
  /// The members of this object read as a name -> object map (all marked read).
  std::vector<std::pair<std::string, JsonReader>> members() const;
  /// The raw value of a key, its whole subtree marked as read (free-form data).
  const nlohmann::json& raw(const std::string& key) const;

  /// Throws InputError for `key` of this object with `message`.
  [[noreturn]] void fail(const std::string& key, const std::string& message) const;
  /// Throws InputError for element `index` of the array at `key` (e.g. /strain/3).
  [[noreturn]] void failElement(const std::string& key, std::size_t index, const std::string& message) const;
  /// Throws InputError for this object itself.
  [[noreturn]] void failHere(const std::string& message) const;
  /// JSON pointer of `key` in this object.
  std::string pointer(const std::string& key) const;
  const std::string& pointer() const { return pointer_; }
  const std::string& file() const { return state_->file; }
  const nlohmann::json& value() const { return *node_; }

 private:
  friend class JsonDocument;
  JsonReader(const nlohmann::json* node, std::string pointer, std::shared_ptr<JsonDocument::State> state);
  const nlohmann::json& required(const std::string& key) const;
  const nlohmann::json* find(const std::string& key) const;
  double checkedNumber(const std::string& key, const nlohmann::json& v, Check check) const;

  const nlohmann::json* node_;
  std::string pointer_;
  std::shared_ptr<JsonDocument::State> state_;
};

/// Escapes a key for use in a JSON pointer (RFC 6901).
std::string escapePointerToken(const std::string& key);

}  // namespace gabion::bridge
