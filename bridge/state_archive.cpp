#include "bridge/state_archive.hpp"

#include <cmath>
#include <cstring>
#include <sstream>

#include "bridge/errors.hpp"
#include "bridge/output.hpp"

namespace gabion::bridge {

std::uint64_t fnv1a(const std::string& bytes, std::uint64_t seed) {
  for (const char c : bytes) seed = (seed ^ static_cast<unsigned char>(c)) * 1099511628211ull;
  return seed;
}

std::string hexDigest(std::uint64_t digest) {
  std::ostringstream s;
  s << std::hex;
  s.width(16);
  s.fill('0');
  s << digest;
  return s.str();
}

struct StateArchive::Backend {
  Mode mode;
  H5Writer* writer = nullptr;
  const H5Reader* reader = nullptr;
  std::string file;
  std::uint64_t hash = 1469598103934665603ull;  // FNV-1a 64 offset basis

  void mix(const void* data, std::size_t bytes) {
    const auto* c = static_cast<const unsigned char*>(data);
    for (std::size_t k = 0; k < bytes; ++k) hash = (hash ^ c[k]) * 1099511628211ull;
  }
  void mixName(const std::string& name) {
    mix(name.data(), name.size());
    const std::uint64_t n = name.size();
    mix(&n, sizeof n);
  }
};

StateArchive::StateArchive(std::shared_ptr<Backend> b, std::string prefix)
    : b_(std::move(b)), prefix_(std::move(prefix)) {}

StateArchive StateArchive::saving(H5Writer& writer) {
  auto b = std::make_shared<Backend>();
  b->mode = Mode::Save;
  b->writer = &writer;
  return StateArchive(b, "");
}

StateArchive StateArchive::loading(const H5Reader& reader, const std::string& file) {
  auto b = std::make_shared<Backend>();
  b->mode = Mode::Load;
  b->reader = &reader;
  b->file = file;
  return StateArchive(b, "");
}

StateArchive StateArchive::digesting() {
  auto b = std::make_shared<Backend>();
  b->mode = Mode::Digest;
  return StateArchive(b, "");
}

StateArchive::Mode StateArchive::mode() const {
  return b_->mode;
}

StateArchive StateArchive::group(const std::string& name) const {
  return StateArchive(b_, prefix_ + "/" + name);
}

std::uint64_t StateArchive::digest() const {
  return b_->hash;
}

bool StateArchive::has(const std::string& name) const {
  return b_->mode != Mode::Load || b_->reader->has(path(name));
}

std::string StateArchive::path(const std::string& name) const {
  return prefix_ + "/" + name;
}

namespace {
[[noreturn]] void wrongSize(const std::string& file, const std::string& field, std::size_t found, std::size_t expect) {
  std::ostringstream m;
  m << "the checkpoint's field has " << found << " values where this run has " << expect
    << " (a checkpoint of another run?)";
  throw InputError(file, field, m.str());
}
}  // namespace

void StateArchive::doubles(const std::string& name, std::vector<double>& v, std::size_t expect, std::size_t width) {
  const std::string p = path(name);
  switch (b_->mode) {
    case Mode::Save:
      if (width > 1)
        b_->writer->write(p, v, std::vector<std::size_t>{v.size() / width, width});
      else
        b_->writer->write(p, v);
      return;
    case Mode::Digest:
      b_->mixName(p);
      if (!v.empty()) b_->mix(v.data(), v.size() * sizeof(double));
      return;
    case Mode::Load:
      v = b_->reader->read(p);
      if (expect > 0 && v.size() != expect) wrongSize(b_->file, p, v.size(), expect);
      return;
  }
}

void StateArchive::integers(const std::string& name, std::vector<long long>& v, std::size_t expect) {
  const std::string p = path(name);
  switch (b_->mode) {
    case Mode::Save:
      b_->writer->writeInts(p, v);
      return;
    case Mode::Digest:
      b_->mixName(p);
      if (!v.empty()) b_->mix(v.data(), v.size() * sizeof(long long));
      return;
    case Mode::Load:
      v = b_->reader->readInts(p);
      if (expect > 0 && v.size() != expect) wrongSize(b_->file, p, v.size(), expect);
      return;
  }
}

void StateArchive::operator()(const std::string& name, double& v) {
  std::vector<double> x{v};
  doubles(name, x, 1);
  v = x[0];
}

void StateArchive::operator()(const std::string& name, bool& v) {
  std::vector<long long> x{v ? 1 : 0};
  integers(name, x, 1);
  v = x[0] != 0;
}

void StateArchive::operator()(const std::string& name, Eigen::Vector3d& v) {
  std::vector<double> x{v.x(), v.y(), v.z()};
  doubles(name, x, 3);
  v = Eigen::Vector3d(x[0], x[1], x[2]);
}

void StateArchive::operator()(const std::string& name, Eigen::Quaterniond& q) {
  std::vector<double> x{q.w(), q.x(), q.y(), q.z()};
  doubles(name, x, 4);
  q = Eigen::Quaterniond(x[0], x[1], x[2], x[3]);
}

void StateArchive::operator()(const std::string& name, std::vector<double>& v) {
  doubles(name, v, 0);
}

void StateArchive::operator()(const std::string& name, std::vector<Eigen::Vector3d>& v) {
  std::vector<double> x;
  x.reserve(3 * v.size());
  for (const auto& e : v) x.insert(x.end(), {e.x(), e.y(), e.z()});
  doubles(name, x, 0, 3);
  if (!loading()) return;
  if (x.size() % 3 != 0) throw InputError(b_->file, path(name), "not a list of 3-vectors");
  v.resize(x.size() / 3);
  for (std::size_t k = 0; k < v.size(); ++k) v[k] = Eigen::Vector3d(x[3 * k], x[3 * k + 1], x[3 * k + 2]);
}

// A string is the attribute "text" of an empty dataset (h5dump shows it as text).
void StateArchive::operator()(const std::string& name, std::string& s) {
  const std::string p = path(name);
  switch (b_->mode) {
    case Mode::Save:
      b_->writer->write(p, std::vector<double>{});
      b_->writer->attribute(p, "text", s);
      return;
    case Mode::Digest:
      b_->mixName(p);
      b_->mixName(s);
      return;
    case Mode::Load:
      if (!b_->reader->has(p)) throw InputError(b_->file, p, "no such field in the checkpoint");
      s = b_->reader->attribute(p, "text");
      return;
  }
}

void StateArchive::operator()(const std::string& name, std::vector<std::string>& v) {
  std::string joined;
  for (const std::string& s : v) joined += s + '\n';
  (*this)(name, joined);
  if (!loading()) return;
  v.clear();
  std::size_t at = 0;
  for (std::size_t nl; (nl = joined.find('\n', at)) != std::string::npos; at = nl + 1)
    v.push_back(joined.substr(at, nl - at));
}

}  // namespace gabion::bridge
