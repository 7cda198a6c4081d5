#pragma once
/// \file
/// The particle store of the fine DEM: every sphere that takes part in
/// contact detection (free spheres and the member spheres of rigid blocks),
/// as structure-of-arrays. The fields are declared once, in
/// forEachStateField() and forEachScratchField(); that list drives growth
/// (resize), the re-sort into cell order (Engine::reorderParticles) and checkpoints (archive). Every particle has a
/// stable id (its input order: free spheres, then block members) that
/// survives the re-sort: `slot[id]` is its current index.
#include <cstddef>
#include <cstdint>
#include <new>
#include <vector>

#include "bridge/state_archive.hpp"

namespace gabion::micro {

/// Contact groups: a particle belongs to one group 0 .. kGroupCount-1; two
/// particles touch only if each one's group is in the other's mask
/// (Particles::group_mask). Block members never touch their own block, and
/// particles joined by a link never touch each other (micro/links.hpp).
constexpr int kGroupCount = 32;

/// Allocates on cache-line (64-byte) boundaries: the workers' ranges of a
/// field, cut at multiples of eight particles, then share no cache line (two
/// cores writing one line take it from each other at every step).
template <class T>
struct CacheLineAllocator {
  using value_type = T;
  static constexpr std::align_val_t kAlign{64};
  CacheLineAllocator() = default;
  template <class U>
  CacheLineAllocator(const CacheLineAllocator<U>&) {}
  T* allocate(std::size_t n) { return static_cast<T*>(::operator new(n * sizeof(T), kAlign)); }
  void deallocate(T* p, std::size_t) { ::operator delete(p, kAlign); }
  template <class U>
  bool operator==(const CacheLineAllocator<U>&) const {
    return true;
  }
  template <class U>
  bool operator!=(const CacheLineAllocator<U>&) const {
    return false;
  }
};
/// A field of the particle store.
template <class T>
using Field = std::vector<T, CacheLineAllocator<T>>;
/// Particles per cache line of a double field: the grain at which workers'
/// ranges are cut and force buffers are marked.
constexpr std::size_t kParticlesPerLine = static_cast<std::size_t>(CacheLineAllocator<double>::kAlign) / sizeof(double);

struct Particles {
  // --- state: moves with the particle when the store is re-sorted
  Field<double> x, y, z;        ///< centre (m)
  Field<double> vx, vy, vz;     ///< velocity (m/s)
  Field<double> wx, wy, wz;     ///< angular velocity (rad/s)
  Field<double> r;              ///< radius (m)
  Field<double> inv_body_mass;  ///< 1/m of the owning body (1/kg); 0: fixed (contact damping, pairs)
  /// free spheres only (else 0), for the integrator: mass gives the weight,
  /// inv_mass and inv_inertia the motion (SphereSpec::mass_scale)
  Field<double> mass, inv_mass, inv_inertia;
  Field<double> alpha;                   ///< Cundall local damping of free spheres (-)
  std::vector<std::int32_t> body;        ///< owning block, -1 for a free sphere
  std::vector<std::uint32_t> mat;        ///< material (32-bit: the vector kernels gather it)
  std::vector<std::uint32_t> id;         ///< stable id
  std::vector<std::uint8_t> group;       ///< contact group (0 .. kGroupCount-1)
  std::vector<std::uint8_t> size_class;  ///< size class of the neighbour grid (micro/neighbour_grid.hpp)

  // --- scratch: recomputed, not carried through a re-sort
  Field<double> fx, fy, fz;  ///< force of this step (N)
  Field<double> tx, ty, tz;  ///< torque about the centre (N m)
  Field<double> x0, y0, z0;  ///< centre at the last neighbour-list build (m)

  /// id -> current index (not re-sorted: rewritten after each re-sort).
  std::vector<std::uint32_t> slot;
  /// Group g touches group h iff bit h of group_mask[g] is set (symmetric).
  std::uint32_t group_mask[kGroupCount];

  Particles() {
    for (auto& m : group_mask) m = ~0u;
  }

  std::size_t size() const { return x.size(); }

  /// Calls f(name, vector) for every state field (the one list of them).
  template <class F>
  void forEachStateField(F&& f) {
    f("x", x), f("y", y), f("z", z), f("vx", vx), f("vy", vy), f("vz", vz), f("wx", wx), f("wy", wy), f("wz", wz);
    f("r", r), f("inv_body_mass", inv_body_mass), f("mass", mass), f("inv_mass", inv_mass);
    f("inv_inertia", inv_inertia), f("alpha", alpha);
    f("body", body), f("mat", mat), f("id", id), f("group", group), f("size_class", size_class);
  }
  /// Calls f(name, vector) for every scratch field.
  template <class F>
  void forEachScratchField(F&& f) {
    f("fx", fx), f("fy", fy), f("fz", fz), f("tx", tx), f("ty", ty), f("tz", tz), f("x0", x0), f("y0", y0), f("z0", z0);
  }
  /// Every field, state and scratch, with the id -> index map, into or out
  /// of a checkpoint (bridge/state_archive.hpp): what the store holds
  /// between two steps.
  void archive(bridge::StateArchive& a) {
    const auto field = [&a](const char* name, auto& v) { a(name, v); };
    forEachStateField(field);
    forEachScratchField(field);
    a("slot", slot);
  }

  /// n particles, all fields zero, stable ids 0 .. n-1 in place.
  void resize(std::size_t n) {
    const auto zero = [n](const char*, auto& v) { v.assign(n, {}); };
    forEachStateField(zero);
    forEachScratchField(zero);
    body.assign(n, -1);
    slot.resize(n);
    for (std::size_t k = 0; k < n; ++k) id[k] = slot[k] = static_cast<std::uint32_t>(k);
  }

  /// Whether particles i and j may touch (groups; not the same block; at
  /// least one of them moves).
  bool mayTouch(std::size_t i, std::size_t j) const {
    if (body[i] >= 0 && body[i] == body[j]) return false;
    if (((group_mask[group[i]] >> group[j]) & 1u) == 0) return false;
    return inv_body_mass[i] > 0.0 || inv_body_mass[j] > 0.0;
  }
};

}  // namespace gabion::micro
