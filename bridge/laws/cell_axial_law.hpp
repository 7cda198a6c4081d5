#pragma once
/// \file
/// The macro cell law in one direction: force against shortening of a cell
/// (confined compression, Bertrand et al. 2006 Fig. 12 and Sec. 4), with
/// plastic memory. Used between x-neighbours, for the boulder-face impact law,
/// and by the fitting to evaluate model curves. A pure function of value types.
///
/// Convention: u is the shortening (compression positive, m); F >= 0 is the
/// compressive force (N). The cell carries no tension: a cell is a contact
/// between granular boxes, whose netting is slack in tension at this scale, so
/// when u < u_p (the elastic part would be negative) the force is zero and the
/// two cells separate without force.
///
/// - elastic_perfectly_plastic: F = k (u - u_p), capped at F_y; while capped
///   the whole increment is plastic (u_p = u - F_y / k).
/// - bilinear: linear isotropic hardening; after yield the loading tangent is
///   k_h (< k): the yield force grows as F_y + H u_p with H = k k_h / (k - k_h).
///   Unloading and reloading are elastic with k.
namespace gabion::bridge {

enum class AxialModel { ElasticPerfectlyPlastic, Bilinear };

/// Parameters of the axial (or impact) law.
struct AxialLawParams {
  AxialModel model = AxialModel::ElasticPerfectlyPlastic;
  double stiffness_N_m = 0.0;             ///< elastic stiffness k (N/m)
  double yield_force_N = 0.0;             ///< first yield force F_y (N)
  double hardening_stiffness_N_m = 0.0;   ///< post-yield tangent k_h, bilinear only (N/m), 0 <= k_h < k
};

/// Result of one evaluation: the force and the updated plastic shortening.
struct AxialResponse {
  double force_N = 0.0;
  double plastic_m = 0.0;
};

/// Force for shortening `u_m` given the plastic shortening `plastic_m` carried
/// from the previous evaluation (return mapping; exact for any step size).
inline AxialResponse axialResponse(const AxialLawParams& p, double u_m, double plastic_m) {
  const double k = p.stiffness_N_m;
  const double H = p.model == AxialModel::Bilinear ? k * p.hardening_stiffness_N_m / (k - p.hardening_stiffness_N_m) : 0.0;
  const double trial = k * (u_m - plastic_m);
  if (trial <= 0.0) return {0.0, plastic_m};  // separated: no tension
  const double yield = p.yield_force_N + H * plastic_m;
  if (trial <= yield) return {trial, plastic_m};
  // Plastic: F = yield(u_p') = k (u - u_p'), solved for u_p'.
  const double up = (k * u_m - p.yield_force_N) / (k + H);
  return {k * (u_m - up), up};
}

/// Elastic energy stored at force F (J).
inline double axialElasticEnergy(const AxialLawParams& p, double force_N) {
  return 0.5 * force_N * force_N / p.stiffness_N_m;
}

}  // namespace gabion::bridge
