#pragma once
/// \file
/// The elastic-plastic spring with plastic memory, written once for the two
/// laws that are this spring: the fine DEM's normal contact with its force cap
/// F_lim (contact_normal.hpp; Bertrand et al. 2006 Sec. 3.2) and the macro
/// cell law (cell_axial_law.hpp; Fig. 12), which the macro model uses for its
/// axial, lateral, ground and boulder-face links. A pure, branch-free
/// function of value types (selects, no branches on data), so that it
/// vectorises inside `#pragma omp simd` loops and every scalar caller runs
/// the same arithmetic.
///
/// Convention: u is the spring's compression (an overlap, a shortening; m)
/// and u_p its permanent (plastic) part, which only grows. The force
/// F = k (u - u_p) >= 0 pushes apart; it is zero for u <= u_p (no tension: the
/// bodies separate without force and the plastic part stays as a gap), and
/// it is limited by the yield force Y(u_p): F_y + H u_p, linear isotropic
/// hardening with modulus H >= 0 (H = 0: perfectly plastic, F <= F_y); or,
/// for a spring that softens (-k < H < 0), F_y up to the plastic part u_s,
/// then F_y + H (u_p - u_s) down to a residual force F_r, then F_r.
///
/// Return mapping (Simo & Hughes 1998, Sec. 1.4), exact for any increment:
/// when the trial force T = k (u - u_p) exceeds Y(u_p), the new state is the
/// one on the yield line, F' = Y(u_p') with u_p' = u - F'/k. Hardening:
///   F' = Y + (k_h / k) (T - Y),   k_h / k = H / (k + H),
/// k_h being the post-yield tangent. Softening: on the falling line
/// F' = (F_y + H (u - u_s)) k / (k + H) (the line is a function of u_p'
/// alone), clamped to [F_r, F_y]: F_y on the flat part before u_s, F_r past
/// the knee u_k = u_s + (F_r - F_y) / H (k + H > 0 makes the root unique).
/// The work dissipated by the update is the yield force integrated over the
/// plastic increment: (Y + F')/2 (u_p' - u_p) while hardening; piece by piece
/// over the flat part, the falling line and the residual while softening
/// (exact: the yield force is piecewise linear in u_p).
#include <limits>

namespace gabion::bridge {

/// Parameters of the spring. `hardening_N_m` and `tangent_ratio` describe
/// the same hardening and must agree (tangent_ratio = H / (k + H), built by
/// hardeningSpring); both are kept so that the hot loops do not recompute
/// the ratio. The perfectly plastic spring (both 0) is the default.
struct ElasticPlasticParams {
  double stiffness_N_m = 0.0;                                      ///< k (N/m), > 0
  double yield_force_N = std::numeric_limits<double>::infinity();  ///< first yield F_y (N), >= 0; infinity: elastic
  double hardening_N_m = 0.0;      ///< H (N/m): >= 0 hardening (the yield force F_y + H u_p), in (-k, 0) softening
  double tangent_ratio = 0.0;      ///< k_h / k = H / (k + H) (-), in (-inf, 1)
  double residual_force_N = 0.0;   ///< F_r (N), softening only: the yield force's floor
  double softening_onset_m = 0.0;  ///< u_s (m), softening only: the plastic part at which it starts to fall
};

/// One evaluation.
struct ElasticPlasticResponse {
  double force_N = 0.0;         ///< F >= 0 (N)
  double plastic_m = 0.0;       ///< updated plastic part u_p' (m)
  double plastic_work_J = 0.0;  ///< work dissipated plastically by this update (J), >= 0
};

/// The spring of post-yield tangent k_h (0 <= k_h < k): H = k k_h / (k - k_h).
inline ElasticPlasticParams hardeningSpring(double stiffness_N_m, double yield_force_N,
                                            double hardening_stiffness_N_m) {
  const double k = stiffness_N_m, kh = hardening_stiffness_N_m;
  return {k, yield_force_N, k * kh / (k - kh), kh / k, 0.0};
}

/// The spring that holds its peak F_y up to the plastic part u_s, then
/// softens with the falling tangent -k_s (k_s > 0: H = -k k_s / (k + k_s),
/// so k + H > 0 for any k_s) down to the residual force F_r
/// (0 <= F_r <= F_y), then flows at F_r.
inline ElasticPlasticParams softeningSpring(double stiffness_N_m, double peak_force_N, double onset_m,
                                            double softening_stiffness_N_m, double residual_force_N) {
  const double k = stiffness_N_m, ks = softening_stiffness_N_m;
  return {k, peak_force_N, -k * ks / (k + ks), -ks / k, residual_force_N, onset_m};
}

/// The softening yield force integrated over the plastic part from `a` to
/// `b` (J): the flat part [0, u_s] at F_y, the falling line [u_s, u_k] and
/// the residual [u_k, inf) at F_r, each over its share of [a, b].
inline double softeningYieldIntegral(const ElasticPlasticParams& p, double a, double b) {
  const double h = p.hardening_N_m, fy = p.yield_force_N, fr = p.residual_force_N, us = p.softening_onset_m;
  const double knee = us + (fr - fy) / h;
  const auto clamp = [](double x, double lo, double hi) { return x < lo ? lo : (x > hi ? hi : x); };
  const double c0 = clamp(a, us, knee), c1 = clamp(b, us, knee);
  const double fall = 0.5 * ((fy + h * (c0 - us)) + (fy + h * (c1 - us))) * (c1 - c0);
  return fy * (clamp(us, a, b) - a) + fall + fr * (b - clamp(knee, a, b));
}

/// Force for compression `u_m` given the plastic part `plastic_m` carried from
/// the previous evaluation (return mapping above). With H = 0 the capped force
/// is exactly F_y and the new plastic part u - F_y / k. `kHardening` = false
/// drops the hardening terms at compile time, for a spring that has none (the
/// contact's F_lim cap): F_y / k then stays loop-invariant in the SIMD kernels
/// instead of a division per contact; the result is the same as with
/// kHardening = true and H = 0.
template <bool kHardening = true>
inline ElasticPlasticResponse elasticPlasticResponse(const ElasticPlasticParams& p, double u_m, double plastic_m) {
  const double k = p.stiffness_N_m;
  const double trial = k * (u_m - plastic_m);
  double yield = p.yield_force_N, returned = p.yield_force_N;
  if constexpr (kHardening) {
    const double h = p.hardening_N_m, fy = p.yield_force_N, fr = p.residual_force_N, us = p.softening_onset_m;
    // hardening: the yield line at u_p, and F' on it
    const double line = fy + h * plastic_m;
    const double back = line + p.tangent_ratio * (trial - line);
    // softening: the yield force at u_p, and F' on the falling line, clamped
    const double at_up = fy + h * (plastic_m > us ? plastic_m - us : 0.0);
    const double falling = (fy + h * (u_m - us)) * (k / (k + h));
    const bool softens = h < 0.0;
    yield = softens ? (at_up > fr ? at_up : fr) : line;
    returned = softens ? (falling < fy ? (falling > fr ? falling : fr) : fy) : back;
  }
  const bool flows = trial > yield;  // implies trial > 0 (yield >= 0)
  // Every quantity is computed for every input and selected: lanes that do
  // not flow may hold inf or NaN here (F_y = infinity), never selected.
  // `trial > 0.0 &&` below repeats what `flows` implies: written so, gcc 12
  // keeps F_y / k of a uniform law out of the SIMD loops instead of a masked
  // division per lane.
  const double plastic = u_m - returned / k;
  double work = 0.5 * (yield + returned) * (plastic - plastic_m);
  // (only a softening spring integrates piece by piece: its knee divides by H < 0)
  if constexpr (kHardening) work = p.hardening_N_m < 0.0 ? softeningYieldIntegral(p, plastic_m, plastic) : work;
  ElasticPlasticResponse r;
  r.force_N = trial <= 0.0 ? 0.0 : (flows ? returned : trial);
  r.plastic_m = trial > 0.0 && flows ? plastic : plastic_m;
  r.plastic_work_J = trial > 0.0 && flows ? work : 0.0;
  return r;
}

/// Elastic energy stored in the spring at force F (J): F^2 / (2 k).
inline double elasticPlasticEnergy(const ElasticPlasticParams& p, double force_N) {
  return 0.5 * force_N * force_N / p.stiffness_N_m;
}

}  // namespace gabion::bridge
