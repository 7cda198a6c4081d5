#pragma once
/// \file
/// Normal contact law of the fine DEM: linear spring k_n with an optional
/// normal force cap F_lim (elastic - perfectly plastic with plastic overlap
/// memory, Bertrand et al. 2006 Sec. 3.2 "CC" test: while F_n = F_lim and the
/// overlap grows the whole increment is plastic; otherwise dF_n = k_n dU_n),
/// with its plastic work and stored energy. It is the spring of
/// elastic_plastic.hpp with no hardening; this header only names it for the
/// contact. The viscous normal dashpot is in contact_damping.hpp. Pure,
/// branch-free functions of value types; used for particle-particle and
/// particle-wall contacts alike, by the SIMD kernels and the scalar paths.
///
/// Convention: overlap delta > 0 in contact (m); the elastic force F_n >= 0
/// pushes the bodies apart (N). The plastic overlap delta_p >= 0 is the part
/// of the overlap that is permanent: F_n = k_n (delta - delta_p), capped at
/// F_lim, and zero (no adhesion) when delta < delta_p.
#include <limits>

#include "bridge/laws/elastic_plastic.hpp"

namespace gabion::bridge {

/// Parameters of the normal law.
struct NormalContactParams {
  double stiffness_N_m = 0.0;                                      ///< k_n (N/m), > 0
  double force_limit_N = std::numeric_limits<double>::infinity();  ///< F_lim (N); infinity: purely elastic
};

/// The normal spring as the elastic-plastic spring: yield force F_lim, no hardening.
inline ElasticPlasticParams normalSpring(const NormalContactParams& p) {
  return {p.stiffness_N_m, p.force_limit_N, 0.0, 0.0};
}

/// One evaluation: force_N is the elastic normal force F_n >= 0 (N),
/// plastic_m the updated plastic overlap delta_p (m), plastic_work_J the work
/// dissipated plastically in this update, F_lim d(delta_p) (J).
using NormalContactResponse = ElasticPlasticResponse;

/// Return mapping of the elastic - perfectly plastic normal spring: exact for
/// any overlap increment (the plastic overlap only grows, by the part of the
/// increment carried at F_lim; the capped force is exactly F_lim).
inline NormalContactResponse normalContactForce(const NormalContactParams& p, double overlap_m,
                                                double plastic_overlap_m) {
  return elasticPlasticResponse</*kHardening=*/false>(normalSpring(p), overlap_m, plastic_overlap_m);
}

/// Elastic energy stored in the normal spring at force F_n (J).
inline double normalElasticEnergy(const NormalContactParams& p, double force_N) {
  return elasticPlasticEnergy(normalSpring(p), force_N);
}

}  // namespace gabion::bridge
