#include "micro/linked_nodes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "micro/integrator.hpp"

namespace gabion::micro {

LinkedNodes::LinkedNodes(const Scene& scene, const Links& links, Particles& p) {
  const std::vector<std::uint32_t>& ids = links.nodeIds();
  const std::size_t n = ids.size();
  n_.resize(n);
  for (auto* v : {&hfx_, &hfy_, &hfz_, &htx_, &hty_, &htz_, &sx_, &sy_, &sz_, &lfx_, &lfy_, &lfz_, &rx_, &ry_, &rz_})
    v->assign(n, 0.0);
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint32_t id = ids[k], i = p.slot[id];
    n_.id[k] = id;
    n_.x[k] = p.x[i], n_.y[k] = p.y[i], n_.z[k] = p.z[i];
    n_.vx[k] = p.vx[i], n_.vy[k] = p.vy[i], n_.vz[k] = p.vz[i];
    n_.wx[k] = p.wx[i], n_.wy[k] = p.wy[i], n_.wz[k] = p.wz[i];
    n_.r[k] = p.r[i];
    n_.mass[k] = p.mass[i], n_.inv_mass[k] = p.inv_mass[i], n_.inv_inertia[k] = p.inv_inertia[i];
    n_.alpha[k] = p.alpha[i];
    const SphereSpec& spec = scene.spheres[id];
    if (spec.rides_wall >= 0) {
      riders_.push_back(static_cast<std::uint32_t>(k));
      rider_wall_.push_back(static_cast<std::uint32_t>(spec.rides_wall));
    }
    // (a rider moves with its wall: its work on the rest is a driven node's)
    if (spec.fixed && (spec.velocity_m_s != Vec3::Zero() || spec.rides_wall >= 0))
      driven_.push_back(static_cast<std::uint32_t>(k));
    // The store's free-sphere pass must not move them on its own.
    p.mass[i] = p.inv_mass[i] = p.inv_inertia[i] = p.alpha[i] = 0.0;
  }
  rider_force_.assign(riders_.size(), Vec3::Zero());
}

void LinkedNodes::ride(const std::vector<Wall>& walls, double dt) {
  for (std::size_t r = 0; r < riders_.size(); ++r) {
    const std::uint32_t k = riders_[r];
    const Vec3 v = walls[rider_wall_[r]].step_displacement / dt;
    n_.vx[k] = v.x(), n_.vy[k] = v.y(), n_.vz[k] = v.z();
    rider_force_[r].setZero();
  }
}

void LinkedNodes::addRiderForces(int substeps) {
  const double share = 1.0 / substeps;
  for (std::size_t r = 0; r < riders_.size(); ++r) {
    const std::uint32_t k = riders_[r];
    rider_force_[r] += share * Vec3(lfx_[k], lfy_[k], lfz_[k]);
  }
}

void LinkedNodes::addWallForces(std::vector<Vec3>& forces_N) const {
  for (std::size_t r = 0; r < riders_.size(); ++r) forces_N[rider_wall_[r]] += rider_force_[r];
}

void LinkedNodes::hold(const Particles& p, bool rebuilt, std::size_t k0, std::size_t k1) {
  const std::uint32_t* id = n_.id.data();
  for (std::size_t k = k0; k < k1; ++k) {
    const std::uint32_t i = p.slot[id[k]];
    hfx_[k] = p.fx[i], hfy_[k] = p.fy[i], hfz_[k] = p.fz[i];
    htx_[k] = p.tx[i], hty_[k] = p.ty[i], htz_[k] = p.tz[i];
    sx_[k] = n_.x[k], sy_[k] = n_.y[k], sz_[k] = n_.z[k];
    rx_[k] = ry_[k] = rz_[k] = 0.0;
  }
  if (rebuilt)
    for (std::size_t k = k0; k < k1; ++k) {
      const std::uint32_t i = p.slot[id[k]];
      n_.x0[k] = p.x0[i], n_.y0[k] = p.y0[i], n_.z0[k] = p.z0[i];
    }
}

void LinkedNodes::addBeams(const Links& links, std::size_t k0, std::size_t k1) {
  links.addNodeBeams(hfx_.data(), hfy_.data(), hfz_.data(), htx_.data(), hty_.data(), htz_.data(), k0, k1);
}

SphereSums LinkedNodes::advance(const Links& links, int k, int substeps, double h, const Vec3& g, bool measure,
                                std::size_t k0, std::size_t k1) {
  // The held forces' impulse over the whole step comes in the first kick;
  // local damping, a force against the unbalanced force, sees in every
  // sub-step the physical force (held + links): a node in equilibrium is not
  // damped by the impulse's swing inside the step.
  const double held = k == 0 ? static_cast<double>(substeps) : 0.0;
  links.nodeForces(lfx_.data(), lfy_.data(), lfz_.data(), k0, k1);
  const HeldForces f{hfx_.data(), hfy_.data(), hfz_.data(), htx_.data(), hty_.data(), htz_.data(), lfx_.data(),
                     lfy_.data(), lfz_.data(), held,        rx_.data(),  ry_.data(),  rz_.data()};
  return integrateHeld(n_, f, k0, k1, h, g, measure);
}

void LinkedNodes::addDrivenWork(int k, int substeps, double h, double& driven_work) const {
  // A driven node keeps its velocity: the work it did on the rest over h.
  const double held = k == 0 ? static_cast<double>(substeps) : 0.0;
  for (const std::uint32_t j : driven_)
    driven_work -= h * ((held * hfx_[j] + lfx_[j]) * n_.vx[j] + (held * hfy_[j] + lfy_[j]) * n_.vy[j] +
                        (held * hfz_[j] + lfz_[j]) * n_.vz[j]);
}

void LinkedNodes::store(Particles& p, double dt, std::size_t k0, std::size_t k1) const {
  const double inv = 1.0 / dt;
  const std::uint32_t *id = n_.id.data(), *slot = p.slot.data();
  // Positions, mean velocities and mean spins over the step.
  double* __restrict X = p.x.data(), * __restrict Y = p.y.data(), * __restrict Z = p.z.data();
  double* __restrict VX = p.vx.data(), * __restrict VY = p.vy.data(), * __restrict VZ = p.vz.data();
  double* __restrict WX = p.wx.data(), * __restrict WY = p.wy.data(), * __restrict WZ = p.wz.data();
  const double *x = n_.x.data(), *y = n_.y.data(), *z = n_.z.data();
  const double *sx = sx_.data(), *sy = sy_.data(), *sz = sz_.data();
  const double *rx = rx_.data(), *ry = ry_.data(), *rz = rz_.data();
  for (std::size_t k = k0; k < k1; ++k) {
    const std::uint32_t i = slot[id[k]];
    X[i] = x[k], Y[i] = y[k], Z[i] = z[k];
    VX[i] = (x[k] - sx[k]) * inv, VY[i] = (y[k] - sy[k]) * inv, VZ[i] = (z[k] - sz[k]) * inv;
    WX[i] = rx[k] * inv, WY[i] = ry[k] * inv, WZ[i] = rz[k] * inv;
  }
}

std::optional<Vec3> LinkedNodes::force(std::uint32_t id) const {
  const auto it = std::lower_bound(n_.id.begin(), n_.id.end(), id);  // (ids increase with the node index)
  if (it == n_.id.end() || *it != id) return std::nullopt;
  const auto k = static_cast<std::size_t>(it - n_.id.begin());
  return Vec3(hfx_[k] + lfx_[k], hfy_[k] + lfy_[k], hfz_[k] + lfz_[k]);
}

double criticalLinkStep(const Scene& scene) {
  std::vector<double> k_link(scene.spheres.size(), 0.0);
  for (const LinkSpec& l : scene.links) k_link[l.a] += l.stiffness(), k_link[l.b] += l.stiffness();
  double dt = std::numeric_limits<double>::infinity();
  for (std::size_t s = 0; s < scene.spheres.size(); ++s)
    if (!scene.spheres[s].fixed && k_link[s] > 0.0)
      dt = std::min(dt, std::sqrt(sphereInertialMass(scene, scene.spheres[s]) / k_link[s]));
  return dt;
}

double criticalBeamStep(const Scene& scene) {
  // A node's sway against its beams' shear stiffness, and its turn against
  // their end stiffness (4 E I / L each) with its moment of inertia.
  std::vector<double> k_sway(scene.spheres.size(), 0.0), k_turn(scene.spheres.size(), 0.0);
  for (const LinkSpec& l : scene.links) {
    if (l.law != LinkSpec::Law::Wire || !l.beam.active()) continue;
    k_sway[l.a] += l.beam.shear_N_m, k_sway[l.b] += l.beam.shear_N_m;
    k_turn[l.a] += l.beam.endStiffness(), k_turn[l.b] += l.beam.endStiffness();
  }
  double dt = std::numeric_limits<double>::infinity();
  for (std::size_t s = 0; s < scene.spheres.size(); ++s) {
    const SphereSpec& sp = scene.spheres[s];
    if (sp.fixed || !(k_turn[s] > 0.0)) continue;
    const double m = sphereInertialMass(scene, sp);
    dt = std::min({dt, std::sqrt(m / k_sway[s]), std::sqrt(sphereInertialMoment(scene, sp) / k_turn[s])});
  }
  return dt;
}

int linkSubsteps(double dt_s, double dt_safety, double link_critical_s) {
  const double h = dt_safety * link_critical_s;
  return std::isfinite(h) && h > 0.0 ? std::max(1, static_cast<int>(std::ceil(dt_s / h - 1e-9))) : 1;
}

void LinkedNodes::archive(bridge::StateArchive& a) {
  bridge::StateArchive store = a.group("store");
  n_.archive(store);
  a("held_fx", hfx_), a("held_fy", hfy_), a("held_fz", hfz_), a("held_tx", htx_), a("held_ty", hty_);
  a("held_tz", htz_), a("start_x", sx_), a("start_y", sy_), a("start_z", sz_), a("turn_x", rx_), a("turn_y", ry_);
  a("turn_z", rz_), a("link_fx", lfx_), a("link_fy", lfy_), a("link_fz", lfz_);
  if (!riders_.empty()) a("rider_force", rider_force_);  // (a scene without riders keeps its checkpoint's keys)
}

}  // namespace gabion::micro
