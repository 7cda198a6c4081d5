#include "micro/linked_nodes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "bridge/laws/contact_damping.hpp"

namespace gabion::micro {
namespace {
// One component's kick: v1 = v0 + h inv (kick + local damping of the
// physical force `phys`), the damping's work added to `local` (branch-free,
// so that the node loop vectorises).
[[gnu::always_inline]] inline double kickOne(double h, double& local, double phys, double kick, double v0, double inv,
                                             double alpha) {
  const double fd = bridge::localDampingForce({alpha}, phys, v0);
  const double v1 = v0 + h * inv * (kick + fd);
  local -= fd * (v0 + v1) * 0.5 * h;
  return v1;
}
}  // namespace

LinkedNodes::LinkedNodes(const Scene& scene, const Links& links, Particles& p) {
  const std::vector<std::uint32_t>& ids = links.nodeIds();
  const std::size_t n = ids.size();
  n_.resize(n);
  for (auto* v : {&hfx_, &hfy_, &hfz_, &htx_, &hty_, &htz_, &sx_, &sy_, &sz_, &lfx_, &lfy_, &lfz_}) v->assign(n, 0.0);
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
    if (spec.fixed && spec.velocity_m_s != Vec3::Zero()) driven_.push_back(static_cast<std::uint32_t>(k));
    // The store's free-sphere pass must not move them on its own.
    p.mass[i] = p.inv_mass[i] = p.inv_inertia[i] = p.alpha[i] = 0.0;
  }
}

void LinkedNodes::hold(const Particles& p, bool rebuilt) {
  const std::uint32_t* id = n_.id.data();
  for (std::size_t k = 0; k < size(); ++k) {
    const std::uint32_t i = p.slot[id[k]];
    hfx_[k] = p.fx[i], hfy_[k] = p.fy[i], hfz_[k] = p.fz[i];
    htx_[k] = p.tx[i], hty_[k] = p.ty[i], htz_[k] = p.tz[i];
  }
  if (rebuilt)
    for (std::size_t k = 0; k < size(); ++k) {
      const std::uint32_t i = p.slot[id[k]];
      n_.x0[k] = p.x0[i], n_.y0[k] = p.y0[i], n_.z0[k] = p.z0[i];
    }
  sx_ = n_.x, sy_ = n_.y, sz_ = n_.z;
}

// One vectorised pass over the nodes' arrays (as the free spheres';
// micro/integrator.cpp): the links' force of this sub-step is in lf*, the
// held forces' share of this kick is held x hf*.
template <bool kMeasure>
SphereSums LinkedNodes::kickAndDrift(double held, double h, const Vec3& g) {
  const std::size_t n = size();
  double* __restrict X = n_.x.data(), * __restrict Y = n_.y.data(), * __restrict Z = n_.z.data();
  double* __restrict VX = n_.vx.data(), * __restrict VY = n_.vy.data(), * __restrict VZ = n_.vz.data();
  double* __restrict WX = n_.wx.data(), * __restrict WY = n_.wy.data(), * __restrict WZ = n_.wz.data();
  const double* __restrict HX = hfx_.data(), * __restrict HY = hfy_.data(), * __restrict HZ = hfz_.data();
  const double* __restrict TX = htx_.data(), * __restrict TY = hty_.data(), * __restrict TZ = htz_.data();
  const double* __restrict LX = lfx_.data(), * __restrict LY = lfy_.data(), * __restrict LZ = lfz_.data();
  const double *__restrict M = n_.mass.data(), *__restrict IM = n_.inv_mass.data(),
               *__restrict II = n_.inv_inertia.data(), *__restrict AL = n_.alpha.data();
  const double* __restrict X0 = n_.x0.data(), * __restrict Y0 = n_.y0.data(), * __restrict Z0 = n_.z0.data();
  const double gx = g.x(), gy = g.y(), gz = g.z(), extra = held - 1.0;
  double local = 0.0, ke_t = 0.0, ke_r = 0.0, pe = 0.0, finite = 0.0, max_d2 = 0.0;
#pragma omp simd reduction(+ : local, ke_t, ke_r, pe, finite) reduction(max : max_d2)
  for (std::size_t j = 0; j < n; ++j) {
    const double m = M[j], im = IM[j], ii = II[j], al = AL[j];
    const double fx = HX[j] + LX[j] + m * gx, fy = HY[j] + LY[j] + m * gy, fz = HZ[j] + LZ[j] + m * gz;
    const double vx = kickOne(h, local, fx, fx + extra * HX[j], VX[j], im, al);
    const double vy = kickOne(h, local, fy, fy + extra * HY[j], VY[j], im, al);
    const double vz = kickOne(h, local, fz, fz + extra * HZ[j], VZ[j], im, al);
    const double wx = kickOne(h, local, TX[j], held * TX[j], WX[j], ii, al);
    const double wy = kickOne(h, local, TY[j], held * TY[j], WY[j], ii, al);
    const double wz = kickOne(h, local, TZ[j], held * TZ[j], WZ[j], ii, al);
    const double x0 = X[j], y0 = Y[j], z0 = Z[j];
    const double x1 = x0 + h * vx, y1 = y0 + h * vy, z1 = z0 + h * vz;
    if (kMeasure) {
      ke_t += 0.5 * m * (vx * vx + vy * vy + vz * vz);
      ke_r += ii > 0.0 ? 0.5 * (wx * wx + wy * wy + wz * wz) / ii : 0.0;
      pe -= m * (gx * 0.5 * (x0 + x1) + gy * 0.5 * (y0 + y1) + gz * 0.5 * (z0 + z1));
    }
    VX[j] = vx, VY[j] = vy, VZ[j] = vz, WX[j] = wx, WY[j] = wy, WZ[j] = wz;
    X[j] = x1, Y[j] = y1, Z[j] = z1;
    finite += x1 + y1 + z1 + vx + vy + vz + wx + wy + wz;
    const double ex = x1 - X0[j], ey = y1 - Y0[j], ez = z1 - Z0[j];
    max_d2 = std::max(max_d2, ex * ex + ey * ey + ez * ez);
  }
  return {local, ke_t, ke_r, pe, finite, max_d2};
}

SphereSums LinkedNodes::advance(const Links& links, int k, int substeps, double h, const Vec3& g, bool measure,
                                double& driven_work) {
  // The held forces' impulse over the whole step comes in the first kick;
  // local damping, a force against the unbalanced force, sees in every
  // sub-step the physical force (held + links): a node in equilibrium is not
  // damped by the impulse's swing inside the step.
  const double held = k == 0 ? static_cast<double>(substeps) : 0.0;
  const std::size_t n = size();
  for (std::size_t j = 0; j < n; ++j) {
    const Vec3 f = links.nodeForce(j);
    lfx_[j] = f.x(), lfy_[j] = f.y(), lfz_[j] = f.z();
  }
  const SphereSums s = measure ? kickAndDrift<true>(held, h, g) : kickAndDrift<false>(held, h, g);
  // A driven node keeps its velocity: the work it did on the rest over h.
  for (const std::uint32_t j : driven_)
    driven_work -= h * ((held * hfx_[j] + lfx_[j]) * n_.vx[j] + (held * hfy_[j] + lfy_[j]) * n_.vy[j] +
                        (held * hfz_[j] + lfz_[j]) * n_.vz[j]);
  return s;
}

void LinkedNodes::store(Particles& p, double dt) const {
  const double inv = 1.0 / dt;
  const std::uint32_t *id = n_.id.data(), *slot = p.slot.data();
  // Positions, mean velocities over the step, spins; then forces.
  {
    double* __restrict X = p.x.data(), * __restrict Y = p.y.data(), * __restrict Z = p.z.data();
    double* __restrict VX = p.vx.data(), * __restrict VY = p.vy.data(), * __restrict VZ = p.vz.data();
    const double *x = n_.x.data(), *y = n_.y.data(), *z = n_.z.data();
    const double *sx = sx_.data(), *sy = sy_.data(), *sz = sz_.data();
    for (std::size_t k = 0; k < size(); ++k) {
      const std::uint32_t i = slot[id[k]];
      X[i] = x[k], Y[i] = y[k], Z[i] = z[k];
      VX[i] = (x[k] - sx[k]) * inv, VY[i] = (y[k] - sy[k]) * inv, VZ[i] = (z[k] - sz[k]) * inv;
    }
  }
  {
    double* __restrict WX = p.wx.data(), * __restrict WY = p.wy.data(), * __restrict WZ = p.wz.data();
    double* __restrict FX = p.fx.data(), * __restrict FY = p.fy.data(), * __restrict FZ = p.fz.data();
    const double *wx = n_.wx.data(), *wy = n_.wy.data(), *wz = n_.wz.data();
    for (std::size_t k = 0; k < size(); ++k) {
      const std::uint32_t i = slot[id[k]];
      WX[i] = wx[k], WY[i] = wy[k], WZ[i] = wz[k];
      FX[i] = hfx_[k] + lfx_[k], FY[i] = hfy_[k] + lfy_[k], FZ[i] = hfz_[k] + lfz_[k];
    }
  }
}

double criticalLinkStep(const Scene& scene) {
  std::vector<double> k_link(scene.spheres.size(), 0.0);
  for (const LinkSpec& l : scene.links) k_link[l.a] += l.stiffness(), k_link[l.b] += l.stiffness();
  double dt = std::numeric_limits<double>::infinity();
  for (std::size_t s = 0; s < scene.spheres.size(); ++s)
    if (!scene.spheres[s].fixed && k_link[s] > 0.0)
      dt = std::min(dt, std::sqrt(sphereMass(scene, scene.spheres[s]) / k_link[s]));
  return dt;
}

int linkSubsteps(double dt_s, double dt_safety, double link_critical_s) {
  const double h = dt_safety * link_critical_s;
  return std::isfinite(h) && h > 0.0 ? std::max(1, static_cast<int>(std::ceil(dt_s / h - 1e-9))) : 1;
}

}  // namespace gabion::micro
