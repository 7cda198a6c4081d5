#pragma once
/// \file
/// A run's state, field by field, to a checkpoint and back. Each part of an
/// engine lists its changing fields once, in a member archive(StateArchive&),
/// and that one list saves them (an HDF5 file, one dataset per field under
/// the part's group: readable with h5dump or h5py), loads them, or hashes
/// them (a digest of the whole state: a checkpoint is resumed only by the
/// run it came from, and tests compare two runs' states bit for bit).
///
/// Doubles are stored as float64, integers as int64, so that a state loaded
/// is the state saved, bit for bit. A field missing from the file, or of
/// another size than the loading part expects, is an InputError naming the
/// file and the field.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

namespace gabion::bridge {

class H5Writer;
class H5Reader;

/// FNV-1a 64 of `bytes`, continuing from `seed` (the archives' digest).
std::uint64_t fnv1a(const std::string& bytes, std::uint64_t seed = 1469598103934665603ull);
/// A digest as 16 hexadecimal digits.
std::string hexDigest(std::uint64_t digest);

class StateArchive {
 public:
  enum class Mode { Save, Load, Digest };
  /// Fields go into `writer` (committed by the caller).
  static StateArchive saving(H5Writer& writer);
  /// Fields come from `reader` (`file` names it in errors).
  static StateArchive loading(const H5Reader& reader, const std::string& file);
  /// Fields are hashed (FNV-1a over names and the bits of the values).
  static StateArchive digesting();

  Mode mode() const;
  bool loading() const { return mode() == Mode::Load; }
  /// The archive of the fields under `name` (a group: "walls/0").
  StateArchive group(const std::string& name) const;
  /// The digest of everything hashed so far (Digest mode).
  std::uint64_t digest() const;
  /// Whether field `name` is there to load (Load mode: a field that a
  /// checkpoint written by an older build lacks; saving and hashing: true).
  /// A field added to a part's list loads through it, with a fallback.
  bool has(const std::string& name) const;

  void operator()(const std::string& name, double& v);
  void operator()(const std::string& name, bool& v);
  template <class T, std::enable_if_t<std::is_integral_v<T> || std::is_enum_v<T>, int> = 0>
  void operator()(const std::string& name, T& v) {
    std::vector<long long> x{static_cast<long long>(v)};
    integers(name, x, 1);
    v = static_cast<T>(x[0]);
  }
  void operator()(const std::string& name, Eigen::Vector3d& v);
  void operator()(const std::string& name, Eigen::Quaterniond& q);
  void operator()(const std::string& name, std::string& s);
  void operator()(const std::string& name, std::vector<double>& v);
  void operator()(const std::string& name, std::vector<Eigen::Vector3d>& v);
  void operator()(const std::string& name, std::vector<std::string>& v);
  /// Doubles in a vector of another allocator (an aligned store's), through a copy.
  template <class A, std::enable_if_t<!std::is_same_v<A, std::allocator<double>>, int> = 0>
  void operator()(const std::string& name, std::vector<double, A>& v) {
    std::vector<double> x(v.begin(), v.end());
    (*this)(name, x);
    if (loading()) v.assign(x.begin(), x.end());
  }
  template <class T, std::enable_if_t<std::is_integral_v<T>, int> = 0>
  void operator()(const std::string& name, std::vector<T>& v) {
    std::vector<long long> x(v.begin(), v.end());
    integers(name, x, 0);
    if (loading()) v.assign(x.begin(), x.end());
  }

 private:
  struct Backend;
  StateArchive(std::shared_ptr<Backend> b, std::string prefix);
  /// The primitives every field goes through; `expect` > 0: the size a load
  /// must find (0: any); `width` > 1: saved as rows of that many values.
  void doubles(const std::string& name, std::vector<double>& v, std::size_t expect, std::size_t width = 1);
  void integers(const std::string& name, std::vector<long long>& v, std::size_t expect);
  std::string path(const std::string& name) const;
  std::shared_ptr<Backend> b_;
  std::string prefix_;
};

}  // namespace gabion::bridge
