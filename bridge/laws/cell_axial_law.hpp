#pragma once
/// \file
/// The macro cell law in one direction: force against shortening of a cell
/// (confined compression, Bertrand et al. 2006 Fig. 12 and Sec. 4), with
/// plastic memory and a lock-up. The macro model uses it for its axial,
/// lateral and ground links and for the boulder-face impact law; the fitting
/// evaluates model curves with it. The return mapping itself is the
/// elastic-plastic spring of elastic_plastic.hpp, shared with the fine DEM's
/// F_lim cap; this header maps the law's parameters onto it and adds the
/// lock-up.
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
/// - densifying: the bilinear spring stiffened from a fitted onset u_d as the
///   fill densifies (the CC curve's upturn at large strain): it adds
///   k_d max(0, u - u_d).
/// - softening (the boulder-face impact law of a cell in place: a peak the
///   cell's confinement and its blocks' inertia hold, then a cell that gives
///   way, docs/resolved.md): elastic up to the peak F_y, held over a plastic
///   shortening u_s, then a falling tangent -k_s down to the residual force
///   F_r, at which it flows. Only for the impact law; unloading and
///   reloading are elastic with k.
///
/// Rate (impact law only, any model): the fill a boulder sets moving resists
/// its indentation rate r = du/dt as a momentum flux does. The yield force
/// (and a softening law's residual) is raised by the overstress
/// c max(r, 0)^2 g(u) while the cell flows: F <= Y(u_p) + c r^2 g(u), with
/// g = min(1, u / u_a) (the boulder's section pressing on the fill grows
/// with its indentation; u_a = 0: g = 1). It can only hold the force
/// higher along the elastic line, never above k (u - u_p), so it adds no
/// stiffness to the critical time step; its work c r^2 du_p is dissipated
/// with the plastic work. c = 0 (the default) is the rate-independent law.
///
/// Lock-up (every model): a fill cannot be compressed beyond its densest
/// state, reached at the lock-up shortening u_L (from the fill's porosity).
/// Beyond it the dense fill adds k_L max(0, u - u_L). With k_L many times k
/// the cell stops shortening at u_L under any force the loose fill could
/// carry; the macro model reports a cell pushed well beyond u_L as crushed
/// (docs/macro.md). By default both added terms are functions of u alone
/// (no memory): they store k (u - u_0)^2 / 2 and give it back, so
///   F = F_ep(u, u_p) + G(u),  G(u) = k_d max(0, u - u_d) + k_L max(0, u - u_L),
/// and the stiffest tangent, unloading past both, is k + k_d + k_L: the one
/// that sets the critical time step.
///
/// Momentum flux (axial laws only; law files: "momentum_flux_kg_m",
/// "momentum_flux_growth_m"): a cell compacted fast by its neighbour sets its
/// fill moving ahead of the compaction front, and the neighbour pays the
/// momentum it gives: c_m max(r, 0)^2 g(u) added to the law's force while
/// the cell is in contact and shortens (r > 0), g = min(1, u / u_a) (u_a = 0:
/// g = 1) as the front forms. Confined compressions of a cell at several
/// plate speeds show it: the lid force rises with the plate speed squared,
/// the base force does not (docs/resolved.md); `fit` identifies c_m and u_a
/// on such curves (docs/fitting.md, "Momentum flux"). Its work is
/// dissipated (the fill's kinetic energy, lost in the compaction). Unlike
/// the impact law's rate term it does not raise a yield force: it adds to
/// the force whatever the law's state, so a soft cell law does not cap it.
///
/// Viscosity (axial laws only; law files: "viscosity_N_s_m"): the fill of a
/// cell pushed by its neighbour resists the rate of its shortening as a
/// dashpot in parallel with the law, F + eta r, while the cell is in
/// contact (F > 0), never pulling (the total stays >= 0): a cell behind the
/// struck one then creeps to its shortening instead of overshooting it and
/// coming back (docs/resolved.md). Its work eta r^2 is dissipated; the
/// macro model applies it along x between neighbours and against the back
/// support, and takes it into the critical time step (macro/model.cpp).
///
/// Plastic densification (densifying model with a lock-up, axial laws only;
/// law files: "densification": "plastic"): a fill compacted past u_d keeps
/// its compaction. The added force follows G on first loading and, below the
/// largest shortening m reached, the steep line of the dense skeleton,
/// k_u = k_d + k_L:  F_d = max(0, G(m) - k_u (m - u)), so that unloading and
/// reloading are stiffer than loading and the critical time step is
/// unchanged. It stores F_d^2 / (2 k_u) and dissipates
/// D(m) = A(m) - G(m)^2 / (2 k_u) (A the integral of G from 0 to m) as m
/// grows; past u_L, where G's tangent is k_u, D stops growing: the lock-up
/// is the dense skeleton's elastic response, compaction is not. The
/// compaction m is not a second state variable: the densifying spring is
/// hardening, so once it has yielded m is where its elastic line meets its
/// yield line, m = u_p + (F_y + H u_p) / k (every shortening reached since
/// lies on or below that line, and reloading yields again exactly there);
/// before it has yielded m <= F_y / k, below u_d (the law file checks
/// u_d >= F_y / k), where G is zero.
///
/// A fitted unloading stiffness of the dense part (law files:
/// "densification_unloading_stiffness_N_m" k_r >= k_d, with plastic
/// densification): the densification alone unloads along k_r,
/// F_d = max(0, k_d max(0, m - u_d) - k_r (m - u)), and the lock-up stays
/// elastic beside it, k_L max(0, u - u_L). A cell keeps part of its
/// compaction (a confined compression unloaded past the onset measures
/// k_r: docs/resolved.md). It stores F_d^2 / (2 k_r) and dissipates
/// D_r(m) = k_d a^2 / 2 - (k_d a)^2 / (2 k_r), a = max(0, m - u_d), which
/// grows with m as long as k_r >= k_d. Without it k_u = k_d + k_L above.
#include <cmath>
#include <limits>

#include "bridge/laws/elastic_plastic.hpp"

namespace gabion::bridge {

enum class AxialModel { ElasticPerfectlyPlastic, Bilinear, Densifying, Softening };

/// Parameters of the axial (or impact) law.
struct AxialLawParams {
  AxialModel model = AxialModel::ElasticPerfectlyPlastic;
  double stiffness_N_m = 0.0;            ///< elastic stiffness k (N/m)
  double yield_force_N = 0.0;            ///< first yield force F_y (N)
  double hardening_stiffness_N_m = 0.0;  ///< post-yield tangent k_h, bilinear and densifying (N/m), 0 <= k_h < k
  double densification_onset_m = std::numeric_limits<double>::infinity();  ///< u_d, densifying only (m)
  double densification_stiffness_N_m = 0.0;                                ///< k_d, densifying only (N/m)
  double lockup_shortening_m = std::numeric_limits<double>::infinity();    ///< u_L (m); infinity: no lock-up
  double lockup_stiffness_N_m = 0.0;                                       ///< k_L (N/m), >= 0
  double softening_stiffness_N_m = 0.0;   ///< k_s > 0, the falling tangent's magnitude, softening only (N/m)
  double residual_force_N = 0.0;          ///< F_r, 0 <= F_r <= F_y, softening only (N)
  double softening_onset_m = 0.0;         ///< u_s >= 0, plastic shortening held at the peak, softening only (m)
  double rate_coefficient_N_s2_m2 = 0.0;  ///< c >= 0, the overstress c r^2 at indentation rate r, impact only
  double rate_growth_m = 0.0;             ///< u_a >= 0: the overstress grows as min(1, u / u_a); 0: constant
  bool plastic_densification = false;     ///< densifying with a lock-up, axial only: compaction is kept (above)
  double viscosity_N_s_m = 0.0;           ///< eta >= 0: a dashpot in parallel while in contact, axial only (above)
  double densification_unloading_stiffness_N_m = 0.0;  ///< k_r >= k_d with plastic densification; 0: k_d + k_L
  double momentum_flux_kg_m = 0.0;                     ///< c_m >= 0: the momentum flux c_m r^2 g(u), axial only (above)
  double momentum_flux_growth_m = 0.0;                 ///< u_a >= 0: g = min(1, u / u_a); 0: g = 1
};

/// The growth g = min(1, u / u_a) of a rate term with the shortening or
/// indentation u (u_a = 0: g = 1), the impact overstress's and the momentum
/// flux's alike.
inline double rateGrowth(double u_m, double growth_m) {
  return growth_m > 0.0 && u_m < growth_m ? (u_m > 0.0 ? u_m : 0.0) / growth_m : 1.0;
}

/// What the fill's rate adds to an axial law's force `law_force_N` (N) at
/// shortening `u_m` and shortening rate `rate_m_s`: the dashpot eta r and the
/// momentum flux c_m max(r, 0)^2 min(1, u / u_a), while the cell is in
/// contact, no more negative than takes the total to zero.
inline double fillRateForce(double eta_N_s_m, double flux_kg_m, double flux_growth_m, double u_m, double rate_m_s,
                            double law_force_N) {
  if (!(law_force_N > 0.0)) return 0.0;
  const double r_pos = rate_m_s > 0.0 ? rate_m_s : 0.0;
  const double f = eta_N_s_m * rate_m_s + flux_kg_m * r_pos * r_pos * rateGrowth(u_m, flux_growth_m);
  return f > -law_force_N ? f : -law_force_N;
}

/// Whether two laws are the same law (every parameter equal).
inline bool sameLaw(const AxialLawParams& a, const AxialLawParams& b) {
  return a.model == b.model && a.stiffness_N_m == b.stiffness_N_m && a.yield_force_N == b.yield_force_N &&
         a.hardening_stiffness_N_m == b.hardening_stiffness_N_m && a.densification_onset_m == b.densification_onset_m &&
         a.densification_stiffness_N_m == b.densification_stiffness_N_m &&
         a.lockup_shortening_m == b.lockup_shortening_m && a.lockup_stiffness_N_m == b.lockup_stiffness_N_m &&
         a.softening_stiffness_N_m == b.softening_stiffness_N_m && a.residual_force_N == b.residual_force_N &&
         a.softening_onset_m == b.softening_onset_m && a.rate_coefficient_N_s2_m2 == b.rate_coefficient_N_s2_m2 &&
         a.rate_growth_m == b.rate_growth_m && a.plastic_densification == b.plastic_densification &&
         a.viscosity_N_s_m == b.viscosity_N_s_m &&
         a.densification_unloading_stiffness_N_m == b.densification_unloading_stiffness_N_m &&
         a.momentum_flux_kg_m == b.momentum_flux_kg_m && a.momentum_flux_growth_m == b.momentum_flux_growth_m;
}

/// True for the models with a hardening tangent (bilinear, densifying).
inline bool hardens(AxialModel m) {
  return m == AxialModel::Bilinear || m == AxialModel::Densifying;
}

/// The stiffest loading tangent of the law before lock-up (N/m): k, or
/// k_h + k_d past a densifying model's onset if that is stiffer. The default
/// lock-up stiffness is a multiple of it (bridge/law_file.hpp).
inline double looseStiffness(const AxialLawParams& p) {
  const double dense =
      p.model == AxialModel::Densifying ? p.hardening_stiffness_N_m + p.densification_stiffness_N_m : 0.0;
  return p.stiffness_N_m > dense ? p.stiffness_N_m : dense;
}

/// The law as the elastic-plastic spring of elastic_plastic.hpp (the same
/// return mapping as the fine DEM's F_lim cap): no hardening for
/// elastic_perfectly_plastic, H = k k_h / (k - k_h) for the hardening models,
/// H = -k k_s / (k + k_s) from u_s down to F_r for softening.
inline ElasticPlasticParams axialSpring(const AxialLawParams& p) {
  if (hardens(p.model)) return hardeningSpring(p.stiffness_N_m, p.yield_force_N, p.hardening_stiffness_N_m);
  if (p.model == AxialModel::Softening)
    return softeningSpring(p.stiffness_N_m, p.yield_force_N, p.softening_onset_m, p.softening_stiffness_N_m,
                           p.residual_force_N);
  return {p.stiffness_N_m, p.yield_force_N, 0.0, 0.0, 0.0, 0.0};
}

/// The law ready for a step loop: the spring, its densification and its lock-up.
struct CellSpring {
  ElasticPlasticParams spring;
  double onset_m = std::numeric_limits<double>::infinity();   ///< u_d (m)
  double densify_N_m = 0.0;                                   ///< k_d (N/m)
  double lockup_m = std::numeric_limits<double>::infinity();  ///< u_L (m)
  double lockup_N_m = 0.0;                                    ///< k_L (N/m)
  double rate_N_s2_m2 = 0.0;                                  ///< c (N s^2/m^2)
  double rate_growth_m = 0.0;                                 ///< u_a (m)
  double compaction_N_m = 0.0;       ///< k_u = k_d + k_L with plastic densification; 0: G is elastic
  double dense_unloading_N_m = 0.0;  ///< k_r: the densification alone unloads along it, the lock-up elastic (above)
  double viscosity_N_s_m = 0.0;      ///< eta (N s/m): the dashpot in parallel (the caller applies it, fillRateForce)
  double flux_kg_m = 0.0;            ///< c_m (kg/m): the momentum flux (the caller applies it, fillRateForce)
  double flux_growth_m = 0.0;        ///< u_a (m)
  /// The fill's rate term at shortening u and rate r on top of the law's force F (fillRateForce).
  double rateForce(double u_m, double rate_m_s, double law_force_N) const {
    return fillRateForce(viscosity_N_s_m, flux_kg_m, flux_growth_m, u_m, rate_m_s, law_force_N);
  }
  bool hasRateForce() const { return viscosity_N_s_m > 0.0 || flux_kg_m > 0.0; }
};

inline CellSpring cellSpring(const AxialLawParams& p) {
  const bool densifies = p.model == AxialModel::Densifying;
  return {axialSpring(p),
          densifies ? p.densification_onset_m : std::numeric_limits<double>::infinity(),
          densifies ? p.densification_stiffness_N_m : 0.0,
          p.lockup_shortening_m,
          p.lockup_stiffness_N_m,
          p.rate_coefficient_N_s2_m2,
          p.rate_growth_m,
          densifies && p.plastic_densification ? p.densification_stiffness_N_m + p.lockup_stiffness_N_m : 0.0,
          densifies && p.plastic_densification ? p.densification_unloading_stiffness_N_m : 0.0,
          p.viscosity_N_s_m,
          p.momentum_flux_kg_m,
          p.momentum_flux_growth_m};
}

/// G(m): the densification and lock-up force on first loading (N).
inline double denseForce(const CellSpring& c, double m) {
  return c.densify_N_m * (m > c.onset_m ? m - c.onset_m : 0.0) + c.lockup_N_m * (m > c.lockup_m ? m - c.lockup_m : 0.0);
}

/// D(m) = A(m) - G(m)^2 / (2 k_u): what plastic densification has
/// dissipated once compacted to m (J).
inline double compactionWork(const CellSpring& c, double m) {
  const double a = m > c.onset_m ? m - c.onset_m : 0.0, b = m > c.lockup_m ? m - c.lockup_m : 0.0;
  const double g = denseForce(c, m);
  return 0.5 * (c.densify_N_m * a * a + c.lockup_N_m * b * b) - 0.5 * g * g / c.compaction_N_m;
}

/// Result of one evaluation: the force (N), the updated plastic shortening
/// (m), the plastic work of the update (J) and the elastic energy stored at
/// the new state (J).
struct AxialResponse {
  double force_N = 0.0;
  double plastic_m = 0.0;
  double plastic_work_J = 0.0;
  double elastic_J = 0.0;
};

/// Force for shortening `u_m` given the plastic shortening `plastic_m` carried
/// from the previous evaluation (return mapping; exact for any step size), at
/// the shortening rate `rate_m_s` (m/s; only a law with a rate coefficient
/// reads it). The overstress c r^2 g(u) shifts the yield force and the residual
/// alike, so the same return mapping gives the force, and the plastic work
/// it integrates is the shifted yield force's. A caller stepping in time
/// passes `overstress_N`: in, the overstress of its previous evaluation; out,
/// this one's. The plastic work then takes the overstress at the mean of the
/// two (the trapezoidal rule over the step, as the leapfrog's work of the
/// force), not this step's alone, which would leave an error of
/// (s_old - s_new) du_p / 2 a step in the energy balance while the rate
/// changes fast.
inline AxialResponse cellResponse(const CellSpring& c, double u_m, double plastic_m, double rate_m_s = 0.0,
                                  double* overstress_N = nullptr) {
  ElasticPlasticParams spring = c.spring;
  const double r_pos = rate_m_s > 0.0 ? rate_m_s : 0.0;
  const double overstress = c.rate_N_s2_m2 * r_pos * r_pos * rateGrowth(u_m, c.rate_growth_m);
  spring.yield_force_N += overstress;
  spring.residual_force_N += overstress;
  auto r = elasticPlasticResponse(spring, u_m, plastic_m);
  if (overstress_N) {
    r.plastic_work_J += 0.5 * (*overstress_N - overstress) * (r.plastic_m - plastic_m);
    *overstress_N = overstress;
  }
  if (c.compaction_N_m > 0.0) {  // plastic densification: the compaction m from the plastic part (above)
    const ElasticPlasticParams& e = c.spring;
    const auto reached = [&](double up) {
      return up > 0.0 ? up + (e.yield_force_N + e.hardening_N_m * up) / e.stiffness_N_m : 0.0;
    };
    const double m_old = reached(plastic_m), m_new = reached(r.plastic_m), m = m_new > u_m ? m_new : u_m;
    if (const double kr = c.dense_unloading_N_m; kr > 0.0) {  // the dense part along k_r, the lock-up elastic
      const auto dense = [&](double x) { return c.densify_N_m * (x > c.onset_m ? x - c.onset_m : 0.0); };
      const auto work = [&](double x) {
        const double a = x > c.onset_m ? x - c.onset_m : 0.0, g = dense(x);
        return 0.5 * c.densify_N_m * a * a - 0.5 * g * g / kr;
      };
      const double fr = dense(m) - kr * (m - u_m), f = fr > 0.0 ? fr : 0.0;
      const double over = u_m > c.lockup_m ? u_m - c.lockup_m : 0.0, fl = c.lockup_N_m * over;
      return {r.force_N + f + fl, r.plastic_m, r.plastic_work_J + work(m) - work(m_old),
              elasticPlasticEnergy(e, r.force_N) + 0.5 * f * f / kr + 0.5 * fl * over};
    }
    const double fd = denseForce(c, m) - c.compaction_N_m * (m - u_m);
    const double f = fd > 0.0 ? fd : 0.0;
    return {r.force_N + f, r.plastic_m, r.plastic_work_J + compactionWork(c, m) - compactionWork(c, m_old),
            elasticPlasticEnergy(e, r.force_N) + 0.5 * f * f / c.compaction_N_m};
  }
  const double dense = u_m > c.onset_m ? u_m - c.onset_m : 0.0;
  const double over = u_m > c.lockup_m ? u_m - c.lockup_m : 0.0;
  const double fd = c.densify_N_m * dense, fl = c.lockup_N_m * over;
  return {r.force_N + fd + fl, r.plastic_m, r.plastic_work_J,
          elasticPlasticEnergy(c.spring, r.force_N) + 0.5 * (fd * dense + fl * over)};
}

inline AxialResponse axialResponse(const AxialLawParams& p, double u_m, double plastic_m, double rate_m_s = 0.0) {
  return cellResponse(cellSpring(p), u_m, plastic_m, rate_m_s);
}

/// The stiffest tangent the law can show (unloading past lock-up),
/// k + k_d + k_L (N/m): the one the critical time step must hold.
inline double maxTangentStiffness(const AxialLawParams& p) {
  const CellSpring c = cellSpring(p);
  const double dense = c.dense_unloading_N_m > c.densify_N_m ? c.dense_unloading_N_m : c.densify_N_m;
  return c.spring.stiffness_N_m + (std::isfinite(c.onset_m) ? dense : 0.0) +
         (std::isfinite(c.lockup_m) ? c.lockup_N_m : 0.0);
}

}  // namespace gabion::bridge
