#include "bridge/json_reader.hpp"

#include <algorithm>
#ifdef __GLIBC__
#include <malloc.h>
#endif

#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include "bridge/errors.hpp"

namespace gabion::bridge {

using Json = nlohmann::json;

std::string escapePointerToken(const std::string& key) {
  std::string out;
  out.reserve(key.size());
  for (char c : key) {
    if (c == '~') {
      out += "~0";
    } else if (c == '/') {
      out += "~1";
    } else {
      out += c;
    }
  }
  return out;
}

namespace {

// Nesting deeper than this is refused on reading: no case or law file needs
// it, and writing a deeper document back (summary.json copies the laws)
// recurses once per level.
constexpr int kMaxDepth = 64;
// A string (a description, a law's provenance note) is at most 1 MB, and a
// JSON file at most 1 GB: free text is bounded, and a file past these was
// not written by hand nor by Gabion.
constexpr std::size_t kMaxStringBytes = std::size_t{1} << 20;
constexpr std::uintmax_t kMaxFileBytes = std::uintmax_t{1000} * 1000 * 1000;

// A first, DOM-less pass over a document (nlohmann's SAX interface):
// refuses a key repeated within one object (JSON leaves it undefined; the
// last one would silently win) and nesting deeper than kMaxDepth, naming
// the JSON pointer. Syntax errors are left to the parse that follows.
class ParseGuard : public nlohmann::json_sax<Json> {
 public:
  explicit ParseGuard(std::string file) : file_(std::move(file)) {}
  bool null() override { return element(); }
  bool boolean(bool) override { return element(); }
  bool number_integer(number_integer_t) override { return element(); }
  bool number_unsigned(number_unsigned_t) override { return element(); }
  bool number_float(number_float_t, const string_t&) override { return element(); }
  bool string(string_t& v) override {
    element();
    if (v.size() > kMaxStringBytes)
      throw InputError(file_, pointer(),
                       "a string of " + std::to_string(v.size()) + " bytes, more than " +
                           std::to_string(kMaxStringBytes) + " (free text such as a description is bounded)");
    return true;
  }
  bool binary(binary_t&) override { return element(); }
  bool start_object(std::size_t) override { return open(false); }
  bool start_array(std::size_t) override { return open(true); }
  bool end_object() override { return close(); }
  bool end_array() override { return close(); }
  bool key(string_t& k) override {
    Frame& f = frames_.back();
    f.key = k;
    if (!f.keys.insert(k).second)
      throw InputError(file_, pointer(), "duplicate key '" + k + "' (each key once per object)");
    return true;
  }
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) override { return false; }

 private:
  struct Frame {
    bool array;
    long long index;
    std::string key;
    std::set<std::string> keys;
  };
  bool element() {
    if (!frames_.empty() && frames_.back().array) ++frames_.back().index;
    return true;
  }
  bool open(bool array) {
    element();
    frames_.push_back({array, -1, {}, {}});
    if (frames_.size() > static_cast<std::size_t>(kMaxDepth))
      throw InputError(file_, pointer(), "nested deeper than " + std::to_string(kMaxDepth) + " levels");
    return true;
  }
  bool close() {
    frames_.pop_back();
    return true;
  }
  // Where the parser is: every open container's current element; the
  // innermost one only once it has an element (a key, an index).
  std::string pointer() const {
    std::string p;
    for (const Frame& f : frames_) {
      if (f.array ? f.index < 0 : f.key.empty() && f.keys.empty()) break;
      p += "/" + (f.array ? std::to_string(f.index) : escapePointerToken(f.key));
    }
    return p;
  }
  std::string file_;
  std::vector<Frame> frames_;
};

std::string typeName(const Json& v) {
  if (v.is_number()) return "a number";
  if (v.is_string()) return "a string";
  if (v.is_boolean()) return "a boolean";
  if (v.is_array()) return "an array";
  if (v.is_object()) return "an object";
  return "null";
}

const char* checkText(Check check) {
  switch (check) {
    case Check::Finite:
      return "must be a finite number";
    case Check::Positive:
      return "must be > 0";
    case Check::NonNegative:
      return "must be >= 0";
    case Check::Fraction:
      return "must be in [0, 1]";
    case Check::UnitOpen:
      return "must be in [0, 1)";
  }
  return "invalid";
}

bool satisfies(double x, Check check) {
  if (!std::isfinite(x)) return false;
  switch (check) {
    case Check::Finite:
      return true;
    case Check::Positive:
      return x > 0.0;
    case Check::NonNegative:
      return x >= 0.0;
    case Check::Fraction:
      return x >= 0.0 && x <= 1.0;
    case Check::UnitOpen:
      return x >= 0.0 && x < 1.0;
  }
  return false;
}

// used and whole are sorted; the pointer string is built only for an error.
void findUnknown(const Json& v, const std::string& ptr, const std::vector<const Json*>& used,
                 const std::vector<const Json*>& whole, const std::string& file) {
  if (std::binary_search(whole.begin(), whole.end(), &v)) return;
  if (v.is_object()) {
    for (auto it = v.begin(); it != v.end(); ++it) {
      if (!std::binary_search(used.begin(), used.end(), &it.value()))
        throw InputError(file, ptr + "/" + escapePointerToken(it.key()), "unknown key '" + it.key() + "'");
      if (it.value().is_structured())
        findUnknown(it.value(), ptr + "/" + escapePointerToken(it.key()), used, whole, file);
    }
  } else if (v.is_array()) {
    for (std::size_t i = 0; i < v.size(); ++i)
      if (v[i].is_structured()) findUnknown(v[i], ptr + "/" + std::to_string(i), used, whole, file);
  }
}

}  // namespace

// ---------------------------------------------------------------- JsonDocument

JsonDocument JsonDocument::load(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(file, "", "file does not exist");
  if (std::filesystem::is_directory(path, ec)) throw InputError(file, "", "is a directory, not a JSON file");
  if (!std::filesystem::is_regular_file(path, ec))  // (a FIFO or a device would block or never end)
    throw InputError(file, "", "not a regular file");
  if (const auto bytes = std::filesystem::file_size(path, ec); !ec && bytes > kMaxFileBytes)
    throw InputError(file, "",
                     "a JSON file of " + std::to_string(bytes / 1000000) + " MB, more than " +
                         std::to_string(kMaxFileBytes / 1000000) +
                         " MB (scenes of many bodies are generated, not listed: block_fills, nettings, cells)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(file, "", "cannot open file for reading");
  {
    ParseGuard guard(file);
    Json::sax_parse(in, &guard);
    in.clear();
    in.seekg(0);
  }
  Json value;
  try {
    value = Json::parse(in);  // from the stream: no copy of a large file's text beside its DOM
    if (in.bad()) throw InputError(file, "", "read error");
  } catch (const Json::exception& e) {  // (a syntax error, or a number beyond double: 1e400)
    std::string what = e.what();
    const auto pos = what.find("] ");
    throw InputError(file, "", "invalid JSON: " + (pos == std::string::npos ? what : what.substr(pos + 2)));
  }
  if (!value.is_object()) throw InputError(file, "", "top level must be a JSON object");
  return JsonDocument(std::move(value), file);
}

JsonDocument::JsonDocument(Json value, std::string file) : state_(std::make_shared<State>()) {
  state_->value = std::move(value);
  state_->file = std::move(file);
}

JsonReader JsonDocument::root() const {
  return JsonReader(&state_->value, "", state_);
}

void JsonDocument::applySet(const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InputError(state_->file, "", "--set '" + assignment + "': expected path.to.key=value");
  const std::string path = assignment.substr(0, eq);
  const std::string text = assignment.substr(eq + 1);
  Json value;
  ParseGuard guard(state_->file + ": --set '" + assignment + "'");
  Json::sax_parse(text, &guard);
  try {
    value = Json::parse(text);
  } catch (const Json::out_of_range& e) {  // (a number beyond double: 1e400)
    const std::string what = e.what();
    throw InputError(state_->file, "", "--set '" + assignment + "': " + what.substr(what.find("] ") + 2));
  } catch (const Json::parse_error&) {
    value = text;  // a bare word is a string
  }
  std::vector<std::string> parts;
  std::stringstream ss(path);
  for (std::string part; std::getline(ss, part, '.');) {
    if (part.empty()) throw InputError(state_->file, "", "--set '" + assignment + "': empty path segment");
    parts.push_back(part);
  }
  Json* node = &state_->value;
  std::string ptr;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const std::string& part = parts[i];
    const bool last = i + 1 == parts.size();
    if (node->is_object()) {
      ptr += "/" + escapePointerToken(part);
      // (an object the case lacks is made: a key no kind reads is then
      // refused as unknown when the case is read, so a typo still shows)
      if (!last && !node->contains(part)) (*node)[part] = Json::object();
      node = &(*node)[part];
    } else if (node->is_array()) {
      std::size_t idx = 0;
      try {
        std::size_t used_chars = 0;
        idx = std::stoul(part, &used_chars);
        if (used_chars != part.size()) throw std::invalid_argument(part);
      } catch (const std::exception&) {
        throw InputError(state_->file, ptr, "--set: '" + part + "' is not an array index");
      }
      ptr += "/" + part;
      if (idx >= node->size()) throw InputError(state_->file, ptr, "--set: array index out of range");
      node = &(*node)[idx];
    } else {
      throw InputError(state_->file, ptr, "--set: not an object or array, cannot descend into it");
    }
  }
  *node = std::move(value);
}

void JsonDocument::finish() const {
  if (state_->finished) return;
  for (auto* v : {&state_->used, &state_->whole}) {
    std::sort(v->begin(), v->end());
    v->erase(std::unique(v->begin(), v->end()), v->end());
  }
  findUnknown(state_->value, "", state_->used, state_->whole, state_->file);
  state_->finished = true;
  std::vector<const Json*>().swap(state_->used);
  std::vector<const Json*>().swap(state_->whole);
}

void JsonDocument::lendValue(nlohmann::json& record, const std::string& key,
                             const std::function<void(const nlohmann::json&)>& use) const {
  // (a move hands over the root's storage: the nodes below it stay put)
  record[key] = std::move(state_->value);
  const auto take_back = [&] { state_->value = std::move(record[key]); };
  try {
    use(record);
  } catch (...) {
    take_back();
    throw;
  }
  take_back();
}

void JsonDocument::releaseValue() const {
  state_->value = nullptr;
  std::vector<const Json*>().swap(state_->used);
  std::vector<const Json*>().swap(state_->whole);
#ifdef __GLIBC__
  malloc_trim(0);  // the many small nodes of a large case go back to the system
#endif
}

// ---------------------------------------------------------------- JsonReader

JsonReader::JsonReader(const Json* node, std::string pointer, std::shared_ptr<JsonDocument::State> state)
    : node_(node), pointer_(std::move(pointer)), state_(std::move(state)) {}

std::string JsonReader::pointer(const std::string& key) const {
  return pointer_ + "/" + escapePointerToken(key);
}

void JsonReader::fail(const std::string& key, const std::string& message) const {
  throw InputError(state_->file, pointer(key), message);
}

void JsonReader::failElement(const std::string& key, std::size_t index, const std::string& message) const {
  throw InputError(state_->file, pointer(key) + "/" + std::to_string(index), message);
}

void JsonReader::failHere(const std::string& message) const {
  throw InputError(state_->file, pointer_.empty() ? "/" : pointer_, message);
}

bool JsonReader::has(const std::string& key) const {
  return node_->is_object() && node_->contains(key);
}

const Json* JsonReader::find(const std::string& key) const {
  if (!node_->is_object()) failHere("expected an object, got " + typeName(*node_));
  auto it = node_->find(key);
  if (it == node_->end()) return nullptr;
  if (!state_->finished) state_->used.push_back(&*it);
  return &*it;
}

const Json& JsonReader::required(const std::string& key) const {
  const Json* v = find(key);
  if (v == nullptr) fail(key, "missing required key");
  return *v;
}

double JsonReader::checkedNumber(const std::string& key, const Json& v, Check check) const {
  if (!v.is_number()) fail(key, "expected a number, got " + typeName(v));
  const double x = v.get<double>();
  if (!satisfies(x, check)) {
    std::ostringstream os;
    os << checkText(check) << " (got " << x << ")";
    fail(key, os.str());
  }
  return x;
}

double JsonReader::number(const std::string& key, Check check) const {
  return checkedNumber(key, required(key), check);
}

double JsonReader::number(const std::string& key, double fallback, Check check) const {
  const Json* v = find(key);
  return v == nullptr ? fallback : checkedNumber(key, *v, check);
}

std::optional<double> JsonReader::optionalNumber(const std::string& key, Check check) const {
  const Json* v = find(key);
  if (v == nullptr) return std::nullopt;
  return checkedNumber(key, *v, check);
}

namespace {

// An integer value as written (a positive one beyond 2^63 - 1 stays
// positive: "too large", not a wrapped negative), or fails.
long long integerValue(const JsonReader& r, const std::string& key, const Json& v, long long maximum) {
  if (!v.is_number_integer()) r.fail(key, "expected an integer, got " + typeName(v));
  if (v.is_number_unsigned() && v.get<unsigned long long>() > static_cast<unsigned long long>(maximum))
    r.fail(key, "must be <= " + std::to_string(maximum) + " (got " + std::to_string(v.get<unsigned long long>()) + ")");
  return v.get<long long>();
}

}  // namespace

long long JsonReader::integer(const std::string& key, long long minimum) const {
  constexpr long long kMax = std::numeric_limits<int>::max();
  const long long x = integerValue(*this, key, required(key), kMax);
  if (x < minimum) fail(key, "must be >= " + std::to_string(minimum) + " (got " + std::to_string(x) + ")");
  if (x > kMax) fail(key, "must be <= " + std::to_string(kMax) + " (got " + std::to_string(x) + ")");
  return x;
}

std::uint64_t JsonReader::seed(const std::string& key, std::uint64_t fallback) const {
  if (!has(key)) return fallback;
  const long long x = integerValue(*this, key, required(key), std::numeric_limits<long long>::max());
  if (x < 0) fail(key, "must be >= 0 (got " + std::to_string(x) + ")");
  return static_cast<std::uint64_t>(x);
}

long long JsonReader::integer(const std::string& key, long long fallback, long long minimum) const {
  return has(key) ? integer(key, minimum) : fallback;
}

std::string JsonReader::string(const std::string& key) const {
  const Json& v = required(key);
  if (!v.is_string()) fail(key, "expected a string, got " + typeName(v));
  return v.get<std::string>();
}

std::string JsonReader::string(const std::string& key, const std::string& fallback) const {
  return has(key) ? string(key) : fallback;
}

std::string JsonReader::choice(const std::string& key, const std::vector<std::string>& options) const {
  const std::string s = string(key);
  for (const auto& o : options)
    if (o == s) return s;
  std::string list;
  for (const auto& o : options) list += (list.empty() ? "" : ", ") + ("'" + o + "'");
  fail(key, "'" + s + "' is not one of " + list);
}

std::string JsonReader::choice(const std::string& key, const std::vector<std::string>& options,
                               const std::string& fallback) const {
  return has(key) ? choice(key, options) : fallback;
}

bool JsonReader::boolean(const std::string& key) const {
  const Json& v = required(key);
  if (!v.is_boolean()) fail(key, "expected true or false, got " + typeName(v));
  return v.get<bool>();
}

bool JsonReader::boolean(const std::string& key, bool fallback) const {
  return has(key) ? boolean(key) : fallback;
}

Vec3 JsonReader::vec3(const std::string& key) const {
  const Json& v = required(key);
  if (!v.is_array() || v.size() != 3) fail(key, "expected an array of 3 numbers");
  Vec3 out;
  for (int i = 0; i < 3; ++i) {
    if (!v[i].is_number()) fail(key, "element " + std::to_string(i) + ": expected a number, got " + typeName(v[i]));
    out[i] = v[i].get<double>();
    if (!std::isfinite(out[i])) fail(key, "element " + std::to_string(i) + ": must be finite");
  }
  return out;
}

Vec3 JsonReader::vec3(const std::string& key, const Vec3& fallback) const {
  return has(key) ? vec3(key) : fallback;
}

std::vector<double> JsonReader::numbers(const std::string& key, Check check, std::size_t min_size) const {
  const Json& v = required(key);
  if (!v.is_array()) fail(key, "expected an array of numbers, got " + typeName(v));
  if (v.size() < min_size)
    fail(key, "expected at least " + std::to_string(min_size) + (min_size == 1 ? " value" : " values"));
  std::vector<double> out;
  out.reserve(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!v[i].is_number()) fail(key, "element " + std::to_string(i) + ": expected a number, got " + typeName(v[i]));
    const double x = v[i].get<double>();
    if (!satisfies(x, check)) throw InputError(state_->file, pointer(key) + "/" + std::to_string(i), checkText(check));
    out.push_back(x);
  }
  return out;
}

JsonReader JsonReader::object(const std::string& key) const {
  const Json& v = required(key);
  if (!v.is_object()) fail(key, "expected an object, got " + typeName(v));
  return JsonReader(&v, pointer(key), state_);
}

std::optional<JsonReader> JsonReader::optionalObject(const std::string& key) const {
  if (!has(key)) return std::nullopt;
  return object(key);
}

std::vector<JsonReader> JsonReader::objects(const std::string& key, bool required_key) const {
  std::vector<JsonReader> out;
  out.reserve(arraySize(key));
  forEachObject(
      key, [&](const JsonReader& r) { out.push_back(r); }, required_key);
  return out;
}

std::size_t JsonReader::forEachObject(const std::string& key, const std::function<void(const JsonReader&)>& use,
                                      bool required_key) const {
  const Json* v = required_key ? &required(key) : find(key);
  if (v == nullptr) return 0;
  if (!v->is_array()) fail(key, "expected an array of objects, got " + typeName(*v));
  const std::string base = pointer(key);
  for (std::size_t i = 0; i < v->size(); ++i) {
    const std::string p = base + "/" + std::to_string(i);
    if (!(*v)[i].is_object()) throw InputError(state_->file, p, "expected an object, got " + typeName((*v)[i]));
    use(JsonReader(&(*v)[i], p, state_));
  }
  return v->size();
}

std::size_t JsonReader::arraySize(const std::string& key) const {
  if (!node_->is_object()) return 0;
  const auto it = node_->find(key);
  return it != node_->end() && it->is_array() ? it->size() : 0;
}

std::vector<std::pair<std::string, JsonReader>> JsonReader::members() const {
  if (!node_->is_object()) failHere("expected an object, got " + typeName(*node_));
  std::vector<std::pair<std::string, JsonReader>> out;
  for (auto it = node_->begin(); it != node_->end(); ++it) {
    const std::string p = pointer(it.key());
    if (!state_->finished) state_->used.push_back(&it.value());
    if (!it.value().is_object()) throw InputError(state_->file, p, "expected an object, got " + typeName(it.value()));
    out.emplace_back(it.key(), JsonReader(&it.value(), p, state_));
  }
  return out;
}

const Json& JsonReader::raw(const std::string& key) const {
  const Json& v = required(key);
  if (!state_->finished) state_->whole.push_back(&v);
  return v;
}

}  // namespace gabion::bridge
