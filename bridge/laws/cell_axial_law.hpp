#pragma once
/// \file
/// The macro cell law in one direction: force against shortening of a cell
/// (confined compression, Bertrand et al. 2006 Fig. 12 and Sec. 4), with
/// plastic memory. The macro model uses it for its axial, lateral and ground
/// links and for the boulder-face impact law; the fitting evaluates model
/// curves with it. The return mapping itself is the elastic-plastic spring of
/// elastic_plastic.hpp, shared with the fine DEM's F_lim cap; this header maps
/// the law's parameters onto it.
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
#include "bridge/laws/elastic_plastic.hpp"

namespace gabion::bridge {

enum class AxialModel { ElasticPerfectlyPlastic, Bilinear };

/// Parameters of the axial (or impact) law.
struct AxialLawParams {
  AxialModel model = AxialModel::ElasticPerfectlyPlastic;
  double stiffness_N_m = 0.0;            ///< elastic stiffness k (N/m)
  double yield_force_N = 0.0;            ///< first yield force F_y (N)
  double hardening_stiffness_N_m = 0.0;  ///< post-yield tangent k_h, bilinear only (N/m), 0 <= k_h < k
};

/// The law as the elastic-plastic spring of elastic_plastic.hpp (the same
/// return mapping as the fine DEM's F_lim cap): no hardening for
/// elastic_perfectly_plastic, H = k k_h / (k - k_h) for bilinear.
inline ElasticPlasticParams axialSpring(const AxialLawParams& p) {
  if (p.model == AxialModel::Bilinear)
    return hardeningSpring(p.stiffness_N_m, p.yield_force_N, p.hardening_stiffness_N_m);
  return {p.stiffness_N_m, p.yield_force_N, 0.0, 0.0};
}

/// Result of one evaluation: the force (N), the updated plastic shortening
/// (m) and the plastic work of the update (J).
using AxialResponse = ElasticPlasticResponse;

/// Force for shortening `u_m` given the plastic shortening `plastic_m` carried
/// from the previous evaluation (return mapping; exact for any step size).
inline AxialResponse axialResponse(const AxialLawParams& p, double u_m, double plastic_m) {
  return elasticPlasticResponse(axialSpring(p), u_m, plastic_m);
}

/// Elastic energy stored at force F (J).
inline double axialElasticEnergy(const AxialLawParams& p, double force_N) {
  return elasticPlasticEnergy(axialSpring(p), force_N);
}

}  // namespace gabion::bridge
