#include "micro/integrator.hpp"

#include <algorithm>
#include <cmath>

#include "bridge/laws/contact_damping.hpp"
#include "micro/rigid_body.hpp"

namespace gabion::micro {

namespace {
// The free spheres of one worker's range in one pass over their arrays
// (translation and rotation of the three components, branch-free so that the
// loop vectorises; SoA arrays, no aliasing between them): each array is read
// once per step. Also the largest squared displacement since the last list
// build; block members are placed afterwards and checked there.
// One component's kick with Cundall local damping
// (bridge::localDampingForce, branch-free): v1 = v0 + dt inv_m (kick + Fd),
// Fd the damping of the physical force F; the damping work is added to
// `local`. A free sphere's kick is its force; a link node's first sub-step
// kick also carries the step's held impulse (micro/linked_nodes.hpp).
// kDamped false: no local damping (alpha 0), the kick alone (`local` untouched).
template <bool kDamped>
[[gnu::always_inline]] inline double dampedKick(double F, double kick, double v0, double inv_m, double alpha, double dt,
                                                double& local) {
  if constexpr (!kDamped) return v0 + dt * inv_m * kick;
  const double Fd = bridge::localDampingForce({alpha}, F, v0);
  const double v1 = v0 + dt * inv_m * (kick + Fd);
  local -= Fd * (v0 + v1) * 0.5 * dt;
  return v1;
}

// (1/2) (a . b) / inv_m: a kinetic energy of inertial mass 1 / inv_m (J),
// 0 for an immovable body (inv_m 0).
[[gnu::always_inline]] inline double halfDotOverInv(double ax, double ay, double az, double bx, double by, double bz,
                                                    double inv_m) {
  return inv_m > 0.0 ? 0.5 * (ax * bx + ay * by + az * bz) / inv_m : 0.0;
}

// kHeld: the link nodes' arrays (HeldForces), else the store's forces.
template <bool kMeasure, bool kHeld>
SphereSums sphereLoop(Particles& p, std::size_t b, std::size_t e, double dt, const Vec3& g, const HeldForces* held) {
  double* __restrict X = p.x.data(), * __restrict Y = p.y.data(), * __restrict Z = p.z.data();
  double* __restrict VX = p.vx.data(), * __restrict VY = p.vy.data(), * __restrict VZ = p.vz.data();
  double* __restrict WX = p.wx.data(), * __restrict WY = p.wy.data(), * __restrict WZ = p.wz.data();
  const double* __restrict FX = kHeld ? held->hx : p.fx.data(), * __restrict FY = kHeld ? held->hy : p.fy.data(), * __restrict FZ = kHeld ? held->hz : p.fz.data();
  const double* __restrict TX = kHeld ? held->tx : p.tx.data(), * __restrict TY = kHeld ? held->ty : p.ty.data(), * __restrict TZ = kHeld ? held->tz : p.tz.data();
  const double* __restrict LX = kHeld ? held->lx : nullptr, * __restrict LY = kHeld ? held->ly : nullptr, * __restrict LZ = kHeld ? held->lz : nullptr;
  const double extra = kHeld ? held->held - 1.0 : 0.0, spin = kHeld ? held->held : 1.0;
  double* __restrict RX = kHeld ? held->rx : nullptr, * __restrict RY = kHeld ? held->ry : nullptr, * __restrict RZ = kHeld ? held->rz : nullptr;
  const double *__restrict M = p.mass.data(), *__restrict IM = p.inv_mass.data(), *__restrict II = p.inv_inertia.data(),
               *__restrict AL = p.alpha.data();
  const double* __restrict X0 = p.x0.data(), * __restrict Y0 = p.y0.data(), * __restrict Z0 = p.z0.data();
  const double gx = g.x(), gy = g.y(), gz = g.z();
  double local = 0.0, ke_t = 0.0, ke_r = 0.0, pe = 0.0, finite = 0.0, max_d2 = 0.0, ke_now = 0.0;
#pragma omp simd reduction(+ : local, ke_t, ke_r, pe, finite, ke_now) reduction(max : max_d2)
  for (std::size_t i = b; i < e; ++i) {
    const double m = M[i], im = IM[i], ii = II[i], al = AL[i];
    // (a node's physical force: held + links + weight)
    const double fx = kHeld ? FX[i] + LX[i] + m * gx : FX[i] + m * gx;
    const double fy = kHeld ? FY[i] + LY[i] + m * gy : FY[i] + m * gy;
    const double fz = kHeld ? FZ[i] + LZ[i] + m * gz : FZ[i] + m * gz;
    const double vx = dampedKick<true>(fx, kHeld ? fx + extra * FX[i] : fx, VX[i], im, al, dt, local);
    const double vy = dampedKick<true>(fy, kHeld ? fy + extra * FY[i] : fy, VY[i], im, al, dt, local);
    const double vz = dampedKick<true>(fz, kHeld ? fz + extra * FZ[i] : fz, VZ[i], im, al, dt, local);
    const double wx = dampedKick<true>(TX[i], kHeld ? spin * TX[i] : TX[i], WX[i], ii, al, dt, local);
    const double wy = dampedKick<true>(TY[i], kHeld ? spin * TY[i] : TY[i], WY[i], ii, al, dt, local);
    const double wz = dampedKick<true>(TZ[i], kHeld ? spin * TZ[i] : TZ[i], WZ[i], ii, al, dt, local);
    const double x0 = X[i], y0 = Y[i], z0 = Z[i];
    const double x1 = x0 + dt * vx, y1 = y0 + dt * vy, z1 = z0 + dt * vz;
    if (kMeasure) {
      // The ledger's kinetic energy: at the positions x0 where the forces
      // (and the elastic energy) were taken, between the velocities of the
      // half steps before and after, (1/2) m v- . v+, the energy the leapfrog
      // conserves exactly for a linear spring; (1/2) m v+^2 would be half a
      // step off the elastic energy and swing by omega dt / 2 through every
      // contact; with the potential at x0 too, it is exact for gravity.
      // ke_now is (1/2) m v+^2: how fast the bodies move now, what the
      // stages' stop criteria read. (m g is the weight; the kinetic energy is
      // that of the inertial mass 1 / im: mass scaling.)
      ke_t += halfDotOverInv(VX[i], VY[i], VZ[i], vx, vy, vz, im);
      pe -= m * (gx * x0 + gy * y0 + gz * z0);
      ke_r += halfDotOverInv(WX[i], WY[i], WZ[i], wx, wy, wz, ii);
      ke_now += halfDotOverInv(vx, vy, vz, vx, vy, vz, im) + halfDotOverInv(wx, wy, wz, wx, wy, wz, ii);
    }
    VX[i] = vx, VY[i] = vy, VZ[i] = vz, WX[i] = wx, WY[i] = wy, WZ[i] = wz;
    if constexpr (kHeld) RX[i] += dt * wx, RY[i] += dt * wy, RZ[i] += dt * wz;
    X[i] = x1, Y[i] = y1, Z[i] = z1;
    finite += x1 + y1 + z1 + vx + vy + vz + wx + wy + wz;
    const double ex = x1 - X0[i], ey = y1 - Y0[i], ez = z1 - Z0[i];
    max_d2 = std::max(max_d2, ex * ex + ey * ey + ez * ez);
  }
  return {local, ke_t, ke_r, pe, finite, max_d2, ke_now};
}

// a b + c, rounded once where the machine has FMA (as GCC contracts it in
// the loops), so that the rounding does not depend on whether the compiler
// hoists a * b out of a loop where a is invariant (the one-body form) and
// rounds it apart.
[[gnu::always_inline]] inline double mulAdd(double a, double b, double c) {
#ifdef __FMA__
  return std::fma(a, b, c);
#else
  return a * b + c;
#endif
}

// The free spheres without local damping (sphereLoop's arithmetic, the kick
// alone) in two passes, translation then rotation: each pass streams 15 or 9
// arrays where one pass would stream 24 (the settling benchmark's
// integration 10 to 20 % faster, the same arrays bit for bit). The damping
// work is zero; the finiteness probe and the kinetic energy "now" add the
// two passes' sums. kOne: every sphere of the range has the first one's
// mass, inertial mass and moment, read once instead of from three arrays
// (the same arrays bit for bit).
template <bool kMeasure, bool kOne>
SphereSums sphereLoopUndamped(Particles& p, std::size_t b, std::size_t e, double dt, const Vec3& g) {
  double* __restrict X = p.x.data(), * __restrict Y = p.y.data(), * __restrict Z = p.z.data();
  double* __restrict VX = p.vx.data(), * __restrict VY = p.vy.data(), * __restrict VZ = p.vz.data();
  const double* __restrict FX = p.fx.data(), * __restrict FY = p.fy.data(), * __restrict FZ = p.fz.data();
  const double* __restrict M = p.mass.data(), * __restrict IM = p.inv_mass.data();
  const double* __restrict X0 = p.x0.data(), * __restrict Y0 = p.y0.data(), * __restrict Z0 = p.z0.data();
  const double gx = g.x(), gy = g.y(), gz = g.z();
  const double m0 = b < e ? M[b] : 0.0, im0 = b < e ? IM[b] : 0.0;
  double ke_t = 0.0, pe = 0.0, finite = 0.0, max_d2 = 0.0, ke_now_t = 0.0;
#pragma omp simd reduction(+ : ke_t, pe, finite, ke_now_t) reduction(max : max_d2)
  for (std::size_t i = b; i < e; ++i) {
    const double m = kOne ? m0 : M[i], im = kOne ? im0 : IM[i];
    double none = 0.0;
    const double vx = dampedKick<false>(0.0, mulAdd(m, gx, FX[i]), VX[i], im, 0.0, dt, none);
    const double vy = dampedKick<false>(0.0, mulAdd(m, gy, FY[i]), VY[i], im, 0.0, dt, none);
    const double vz = dampedKick<false>(0.0, mulAdd(m, gz, FZ[i]), VZ[i], im, 0.0, dt, none);
    const double x0 = X[i], y0 = Y[i], z0 = Z[i];
    const double x1 = x0 + dt * vx, y1 = y0 + dt * vy, z1 = z0 + dt * vz;
    if (kMeasure) {  // (as in sphereLoop)
      ke_t += halfDotOverInv(VX[i], VY[i], VZ[i], vx, vy, vz, im);
      pe -= m * (gx * x0 + gy * y0 + gz * z0);
      ke_now_t += halfDotOverInv(vx, vy, vz, vx, vy, vz, im);
    }
    VX[i] = vx, VY[i] = vy, VZ[i] = vz;
    X[i] = x1, Y[i] = y1, Z[i] = z1;
    finite += x1 + y1 + z1 + vx + vy + vz;
    const double ex = x1 - X0[i], ey = y1 - Y0[i], ez = z1 - Z0[i];
    max_d2 = std::max(max_d2, ex * ex + ey * ey + ez * ez);
  }
  double* __restrict WX = p.wx.data(), * __restrict WY = p.wy.data(), * __restrict WZ = p.wz.data();
  const double* __restrict TX = p.tx.data(), * __restrict TY = p.ty.data(), * __restrict TZ = p.tz.data();
  const double* __restrict II = p.inv_inertia.data();
  const double ii0 = b < e ? II[b] : 0.0;
  double ke_r = 0.0, finite_r = 0.0, ke_now_r = 0.0;
#pragma omp simd reduction(+ : ke_r, finite_r, ke_now_r)
  for (std::size_t i = b; i < e; ++i) {
    const double ii = kOne ? ii0 : II[i];
    double none = 0.0;
    const double wx = dampedKick<false>(0.0, TX[i], WX[i], ii, 0.0, dt, none);
    const double wy = dampedKick<false>(0.0, TY[i], WY[i], ii, 0.0, dt, none);
    const double wz = dampedKick<false>(0.0, TZ[i], WZ[i], ii, 0.0, dt, none);
    if (kMeasure) {
      ke_r += halfDotOverInv(WX[i], WY[i], WZ[i], wx, wy, wz, ii);
      ke_now_r += halfDotOverInv(wx, wy, wz, wx, wy, wz, ii);
    }
    WX[i] = wx, WY[i] = wy, WZ[i] = wz;
    finite_r += wx + wy + wz;
  }
  return {0.0, ke_t, ke_r, pe, finite + finite_r, max_d2, ke_now_t + ke_now_r};
}
}  // namespace

SphereSums integrateSpheres(Particles& p, std::size_t b, std::size_t e, double dt, const Vec3& g, bool measure,
                            bool maybe_damped, bool one_body) {
  // Without local damping on the range (every alpha 0, as in dynamic runs)
  // the kick is the force alone: the selects and the damping work of
  // dampedKick drop out, a fifth of the loop's time on the settling benchmark.
  const auto* alpha = p.alpha.data();
  const bool damped = maybe_damped && std::any_of(alpha + b, alpha + e, [](double a) { return a != 0.0; });
  if (!damped && one_body)
    return measure ? sphereLoopUndamped<true, true>(p, b, e, dt, g) : sphereLoopUndamped<false, true>(p, b, e, dt, g);
  if (!damped)
    return measure ? sphereLoopUndamped<true, false>(p, b, e, dt, g) : sphereLoopUndamped<false, false>(p, b, e, dt, g);
  return measure ? sphereLoop<true, false>(p, b, e, dt, g, nullptr) : sphereLoop<false, false>(p, b, e, dt, g, nullptr);
}

SphereSums integrateHeld(Particles& n, const HeldForces& f, std::size_t b, std::size_t e, double h, const Vec3& g,
                         bool measure) {
  return measure ? sphereLoop<true, true>(n, b, e, h, g, &f) : sphereLoop<false, true>(n, b, e, h, g, &f);
}

SphereSums integrateBlock(RigidBlock& b, Particles& p, double dt, const Vec3& g, bool measure) {
  SphereSums s;
  if (b.fixed) return s;
  Vec3 F = b.mass * g, T = Vec3::Zero();
  for (const std::uint32_t id : b.ids) {
    const std::uint32_t i = p.slot[id];
    const Vec3 f(p.fx[i], p.fy[i], p.fz[i]);
    F += f;
    T += Vec3(p.x[i] - b.x.x(), p.y[i] - b.x.y(), p.z[i] - b.x.z()).cross(f) + Vec3(p.tx[i], p.ty[i], p.tz[i]);
  }
  const bridge::LocalDampingParams ld{b.alpha};
  Vec3 Fd, Td;
  for (int c = 0; c < 3; ++c) {
    Fd[c] = bridge::locallyDampedForce(ld, F[c], b.v[c]) - F[c];
    Td[c] = bridge::locallyDampedForce(ld, T[c], b.omega[c]) - T[c];
  }
  const Vec3 v0 = b.v, w0 = b.omega, x0 = b.x, L0 = b.L;
  b.v += dt * b.inv_mass * (F + Fd);
  b.L += dt * (T + Td);
  b.x += dt * b.v;
  freeRotate(b.q, b.L, b.inertia, dt);
  b.omega = angularVelocityWorld(b.q, b.L, b.inertia);
  s.local = -(Fd.dot(v0 + b.v) + Td.dot(w0 + b.omega)) * 0.5 * dt;
  if (measure) {
    // (between the half steps, and now: as for spheres)
    s.ke_t = 0.5 * b.mass * v0.dot(b.v);
    s.ke_r = 0.5 * L0.dot(b.omega);
    s.pe = -b.mass * g.dot(x0);
    s.ke_now = 0.5 * b.mass * b.v.squaredNorm() + 0.5 * b.L.dot(b.omega);
  }
  s.finite = b.x.sum() + b.v.sum() + b.L.sum();
  const Eigen::Matrix3d R = b.q.toRotationMatrix();  // (once for all the members)
  // A member's move since the list build, from the block's: no reading of
  // the members' x0, scattered over the store.
  const Eigen::Matrix3d turn = R - b.R0;
  const Vec3 moved = b.x - b.x0;
  for (std::size_t k = 0; k < b.ids.size(); ++k) {
    const std::uint32_t i = p.slot[b.ids[k]];
    const Vec3& o = b.offsets[k];
    const Vec3 arm = R * o;
    const Vec3 vm = b.v + b.omega.cross(arm);
    p.x[i] = b.x.x() + arm.x(), p.y[i] = b.x.y() + arm.y(), p.z[i] = b.x.z() + arm.z();
    p.vx[i] = vm.x(), p.vy[i] = vm.y(), p.vz[i] = vm.z();
    p.wx[i] = b.omega.x(), p.wy[i] = b.omega.y(), p.wz[i] = b.omega.z();
    s.max_d2 = std::max(s.max_d2, (moved + turn * o).squaredNorm());
  }
  return s;
}

}  // namespace gabion::micro
