// The macro axial law against its closed form: elastic branch, yield plateau,
// elastic unloading from the plastic state, no tension, bilinear hardening.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <vector>

#include "bridge/laws/cell_axial_law.hpp"

using namespace gabion::bridge;

namespace {
// The densifying cell of the densification tests: k 300 kN/m, F_y 1 kN,
// k_h 30 kN/m, onset 30 mm, k_d 400 kN/m, lock-up at 120 mm with 4 MN/m.
AxialLawParams densifyingCell() {
  AxialLawParams p{AxialModel::Densifying, 3e5, 1e3, 3e4};
  p.densification_onset_m = 0.03;
  p.densification_stiffness_N_m = 4e5;
  p.lockup_shortening_m = 0.12;
  p.lockup_stiffness_N_m = 4e6;
  return p;
}

// A shortening path from 0 through `ends`, in steps of at most 1e-6 m.
std::vector<double> pathThrough(std::initializer_list<double> ends) {
  std::vector<double> path;
  for (const double to : ends) {
    const double from = path.empty() ? 0.0 : path.back();
    const int n = static_cast<int>(std::lround(std::abs(to - from) / 1e-6));
    for (int i = 1; i <= n; ++i) path.push_back(from + (to - from) * i / n);
  }
  return path;
}
}  // namespace

TEST(CellAxialLaw, ElasticPerfectlyPlasticCycle) {
  const AxialLawParams p{AxialModel::ElasticPerfectlyPlastic, 1e6, 1e4, 0.0};
  double up = 0.0;
  auto r = axialResponse(p, 0.005, up);  // elastic
  EXPECT_DOUBLE_EQ(r.force_N, 5e3);
  r = axialResponse(p, 0.03, r.plastic_m);  // plateau: u_p = 0.03 - 0.01
  // the return mapping puts a perfectly plastic force exactly on F_y
  EXPECT_EQ(r.force_N, 1e4);
  EXPECT_DOUBLE_EQ(r.plastic_m, 0.02);
  EXPECT_DOUBLE_EQ(r.plastic_work_J, 1e4 * 0.02);
  up = r.plastic_m;
  // Unloading with k from u_p. u_p = u - F_y / k carries the rounding of u
  // (0.03 is not a binary fraction): k (u - u_p) is 5 kN to a few ulps.
  r = axialResponse(p, 0.025, up);
  EXPECT_NEAR(r.force_N, 5e3, 1e-14 * 5e3);
  EXPECT_EQ(r.plastic_work_J, 0.0);
  r = axialResponse(p, 0.015, up);  // below u_p: separated, no tension
  EXPECT_DOUBLE_EQ(r.force_N, 0.0);
  EXPECT_DOUBLE_EQ(r.plastic_m, 0.02);
}

TEST(CellAxialLaw, BilinearTangentAfterYield) {
  const AxialLawParams p{AxialModel::Bilinear, 1e6, 1e4, 2e5};
  // Monotonic loading in small steps must follow F = F_y + k_h (u - u_y).
  double up = 0.0;
  AxialResponse r;
  for (int i = 1; i <= 400; ++i) {
    r = axialResponse(p, 1e-4 * i, up);
    up = r.plastic_m;
  }
  const double u = 0.04, uy = 0.01;
  EXPECT_NEAR(r.force_N, 1e4 + 2e5 * (u - uy), 1e-6);
  // One big step gives the same state (return mapping is exact).
  const auto big = axialResponse(p, u, 0.0);
  EXPECT_NEAR(big.force_N, r.force_N, 1e-6);
  EXPECT_NEAR(big.plastic_m, r.plastic_m, 1e-12);
}

// Loading far beyond yield: past the lock-up shortening the force follows
// F_y + k_L (u - u_L) (the dense fill's spring on top of the plateau), the
// work done equals the plastic work plus the stored energy at every step
// (trapezoidal work of a piecewise-linear path: exact up to the kinks), and
// unloading gives the lock-up's energy back (no plastic work while unloading).
TEST(CellAxialLaw, LockupStopsShorteningAndBalancesEnergy) {
  AxialLawParams p{AxialModel::ElasticPerfectlyPlastic, 1e6, 1e4, 0.0};
  p.lockup_shortening_m = 0.1;
  p.lockup_stiffness_N_m = 1e7;
  double up = 0.0, work = 0.0, plastic = 0.0, f_prev = 0.0;
  const double du = 1e-5;
  AxialResponse r;
  for (int i = 1; i <= 12000; ++i) {  // to u = 0.12
    r = axialResponse(p, du * i, up);
    up = r.plastic_m;
    plastic += r.plastic_work_J;
    work += 0.5 * (f_prev + r.force_N) * du;
    f_prev = r.force_N;
  }
  EXPECT_NEAR(r.force_N, 1e4 + 1e7 * 0.02, 1e-6 * r.force_N);
  EXPECT_NEAR(r.elastic_J, 0.5 * 1e4 * 1e4 / 1e6 + 0.5 * 1e7 * 0.02 * 0.02, 1e-9);
  // The trapezoid is exact on each linear piece; the only error is the yield
  // kink inside one step: at most F_y du / 2.
  EXPECT_NEAR(work, plastic + r.elastic_J, 0.5 * 1e4 * du);
  // Back to u_L: the dense spring is unloaded, the plateau force too (k is
  // the unloading stiffness of the loose part): F = F_y - k (0.02) < 0 -> 0.
  const auto back = axialResponse(p, 0.1, up);
  EXPECT_EQ(back.plastic_work_J, 0.0);
  EXPECT_DOUBLE_EQ(back.force_N, 0.0);
  EXPECT_DOUBLE_EQ(maxTangentStiffness(p), 1.1e7);
}

// The densifying model: the bilinear spring plus k_d (u - u_d) past its onset,
// below the lock-up.
TEST(CellAxialLaw, DensifyingAddsItsTermPastTheOnset) {
  AxialLawParams p{AxialModel::Densifying, 1e6, 1e4, 2e5};
  p.densification_onset_m = 0.05;
  p.densification_stiffness_N_m = 3e6;
  p.lockup_shortening_m = 0.2;
  p.lockup_stiffness_N_m = 1e8;
  const auto at = [&](double u) { return axialResponse(p, u, 0.0).force_N; };
  EXPECT_NEAR(at(0.04), 1e4 + 2e5 * 0.03, 1e-6);  // bilinear only
  EXPECT_NEAR(at(0.08), 1e4 + 2e5 * 0.07 + 3e6 * 0.03, 1e-6);
  EXPECT_NEAR(at(0.21), 1e4 + 2e5 * 0.2 + 3e6 * 0.16 + 1e8 * 0.01, 1e-5);
  // A bilinear law ignores the densification keys.
  p.model = AxialModel::Bilinear;
  EXPECT_NEAR(at(0.08), 1e4 + 2e5 * 0.07, 1e-6);
  EXPECT_DOUBLE_EQ(maxTangentStiffness(p), 1e6 + 1e8);
}

// Plastic densification against a reference that tracks the largest
// shortening m explicitly: F = F_ep(u, u_p) + max(0, G(m) - k_u (m - u)),
// k_u = k_d + k_L, along a path that loads past the onset, unloads, reloads
// past where it turned, unloads to separation, loads past the lock-up and
// unloads again (forces equal to round-off: the law reads m from u_p). The
// work of the path (trapezoids of 1e-6 m) is the plastic work plus the
// stored energy; past the lock-up the compaction dissipates nothing more
// (the lock-up is elastic); unloading is stiffer than loading, k + k_u
// against k_h + k_d, and the critical tangent is unchanged.
TEST(CellAxialLaw, PlasticDensificationKeepsTheCompaction) {
  AxialLawParams p = densifyingCell();
  const AxialLawParams elastic = p;
  p.plastic_densification = true;
  const double ku = 4e5 + 4e6;
  const auto G = [&](double m) { return 4e5 * std::max(0.0, m - 0.03) + 4e6 * std::max(0.0, m - 0.12); };
  const CellSpring law = cellSpring(p);
  const std::vector<double> path = pathThrough({0.08, 0.06, 0.1, 0.0, 0.13, 0.11});
  double up = 0.0, up_ref = 0.0, m_ref = 0.0, work = 0.0, plastic = 0.0, f_prev = 0.0, u_prev = 0.0;
  double worst = 0.0;
  AxialResponse r;
  for (const double u : path) {
    r = cellResponse(law, u, up);
    const auto ep = elasticPlasticResponse(law.spring, u, up_ref);
    up_ref = ep.plastic_m;
    m_ref = std::max(m_ref, u);
    const double ref = ep.force_N + std::max(0.0, G(m_ref) - ku * (m_ref - u));
    worst = std::max(worst, std::abs(r.force_N - ref) / std::max(1.0, ref));
    plastic += r.plastic_work_J;
    work += 0.5 * (f_prev + r.force_N) * (u - u_prev);
    f_prev = r.force_N, u_prev = u, up = r.plastic_m;
  }
  EXPECT_LT(worst, 1e-9);
  EXPECT_NEAR(work, plastic + r.elastic_J, 1e-6 * plastic);
  // Unloading from m = 0.08: k + k_u, against the loading tangent k_h + k_d.
  double u8 = 0.0;
  for (int i = 1; i <= 80; ++i) u8 = cellResponse(law, 1e-3 * i, u8).plastic_m;
  const double f8 = cellResponse(law, 0.08, u8).force_N, f8b = cellResponse(law, 0.08 - 1e-4, u8).force_N;
  EXPECT_NEAR((f8 - f8b) / 1e-4, 3e5 + ku, 1e-6 * ku);
  const double f8e = axialResponse(elastic, 0.08, 0.0).force_N;
  EXPECT_NEAR(f8, f8e, 1e-9 * f8e);  // (the same first loading as the elastic law)
  // What the compaction has dissipated at m: D(m) = A(m) - G(m)^2 / (2 k_u),
  // and not a joule more past the lock-up.
  const auto D = [&](double m) {
    const double a = std::max(0.0, m - 0.03), b = std::max(0.0, m - 0.12);
    return 0.5 * 4e5 * a * a + 0.5 * 4e6 * b * b - 0.5 * G(m) * G(m) / ku;
  };
  EXPECT_NEAR(compactionWork(law, 0.1), D(0.1), 1e-9 * D(0.1));
  EXPECT_NEAR(compactionWork(law, 0.13), compactionWork(law, 0.12), 1e-9 * D(0.12));
  EXPECT_DOUBLE_EQ(maxTangentStiffness(p), maxTangentStiffness(elastic));
}

// Plastic densification with the dense part's own unloading stiffness k_r:
// along a path loaded past the onset, unloaded, reloaded and loaded past
// the lock-up, the force is the elastic-plastic part plus
// max(0, G_d(m) - k_r (m - u)) (G_d the densification alone, m the largest
// shortening) plus the lock-up's k_L (u - u_L), elastic; first loading is
// the elastic law's; the unloading tangent below the lock-up is k + k_r; the
// work of the force is the plastic work plus the stored energy; the
// stiffest tangent counts k_r.
TEST(CellAxialLaw, TheDensePartUnloadsAlongItsOwnStiffness) {
  AxialLawParams p = densifyingCell();
  const AxialLawParams elastic = p;
  p.plastic_densification = true;
  const double kr = 9e5;
  p.densification_unloading_stiffness_N_m = kr;
  const CellSpring law = cellSpring(p);
  const auto Gd = [&](double m) { return 4e5 * std::max(0.0, m - 0.03); };
  const std::vector<double> path = pathThrough({0.08, 0.05, 0.1, 0.0, 0.13, 0.115});
  double up = 0.0, up_ref = 0.0, m_ref = 0.0, work = 0.0, plastic = 0.0, f_prev = 0.0, u_prev = 0.0;
  double worst = 0.0, dissipated_min = 0.0;
  AxialResponse r;
  for (const double u : path) {
    r = cellResponse(law, u, up);
    const auto ep = elasticPlasticResponse(law.spring, u, up_ref);
    up_ref = ep.plastic_m;
    m_ref = std::max(m_ref, u);
    const double ref = ep.force_N + std::max(0.0, Gd(m_ref) - kr * (m_ref - u)) + 4e6 * std::max(0.0, u - 0.12);
    worst = std::max(worst, std::abs(r.force_N - ref) / std::max(1.0, ref));
    dissipated_min = std::min(dissipated_min, r.plastic_work_J);
    plastic += r.plastic_work_J;
    work += 0.5 * (f_prev + r.force_N) * (u - u_prev);
    f_prev = r.force_N, u_prev = u, up = r.plastic_m;
  }
  EXPECT_LT(worst, 1e-9);
  EXPECT_GE(dissipated_min, -1e-12) << "no step gives back more than it took";
  EXPECT_NEAR(work, plastic + r.elastic_J, 1e-6 * plastic);
  // First loading: the elastic densification's; unloading from 0.08: k + k_r.
  double u8 = 0.0;
  for (int i = 1; i <= 80; ++i) u8 = cellResponse(law, 1e-3 * i, u8).plastic_m;
  const double f8 = cellResponse(law, 0.08, u8).force_N, f8b = cellResponse(law, 0.08 - 1e-4, u8).force_N;
  EXPECT_NEAR(f8, axialResponse(elastic, 0.08, 0.0).force_N, 1e-9 * f8);
  EXPECT_NEAR((f8 - f8b) / 1e-4, 3e5 + kr, 1e-6 * kr);
  EXPECT_DOUBLE_EQ(maxTangentStiffness(p), 3e5 + kr + 4e6);
}

// What the fill's rate adds to an axial law's force: the dashpot eta r and
// the momentum flux c_m r^2 min(1, u / u_a), the flux only while the cell
// shortens, nothing while it is out of contact, and never so much pull that
// the total turns negative.
TEST(CellAxialLaw, FillRateForceAddsTheDashpotAndTheMomentumFlux) {
  const double c = 1500.0, ua = 0.04, F = 5e3;
  EXPECT_DOUBLE_EQ(fillRateForce(0.0, c, ua, 0.06, 3.0, F), c * 9.0);
  EXPECT_DOUBLE_EQ(fillRateForce(0.0, c, ua, 0.02, 3.0, F), c * 9.0 * 0.5);
  EXPECT_DOUBLE_EQ(fillRateForce(0.0, c, 0.0, 0.001, 3.0, F), c * 9.0);  // (u_a = 0: grown at once)
  EXPECT_DOUBLE_EQ(fillRateForce(0.0, c, ua, 0.06, -3.0, F), 0.0);       // unloading: no flux
  EXPECT_DOUBLE_EQ(fillRateForce(0.0, c, ua, 0.06, 3.0, 0.0), 0.0);      // out of contact
  EXPECT_DOUBLE_EQ(fillRateForce(2e3, c, ua, 0.06, 3.0, F), 2e3 * 3.0 + c * 9.0);
  EXPECT_DOUBLE_EQ(fillRateForce(2e3, 0.0, 0.0, 0.06, -3.0, F), -F);  // the dashpot never pulls
  AxialLawParams p{AxialModel::Bilinear, 3e5, 1e3, 3e4};
  p.momentum_flux_kg_m = c;
  p.momentum_flux_growth_m = ua;
  p.viscosity_N_s_m = 2e3;
  const CellSpring s = cellSpring(p);
  EXPECT_TRUE(s.hasRateForce());
  EXPECT_DOUBLE_EQ(s.rateForce(0.02, 3.0, F), fillRateForce(2e3, c, ua, 0.02, 3.0, F));
  EXPECT_FALSE(cellSpring(AxialLawParams{AxialModel::Bilinear, 3e5, 1e3, 3e4}).hasRateForce());
  // It is not part of the law's static response, nor of its stiffness.
  AxialLawParams still = p;
  still.momentum_flux_kg_m = still.viscosity_N_s_m = 0.0;
  EXPECT_EQ(axialResponse(p, 0.05, 0.0, 3.0).force_N, axialResponse(still, 0.05, 0.0, 3.0).force_N);
  EXPECT_EQ(maxTangentStiffness(p), maxTangentStiffness(still));
}

// The softening impact law: elastic up to the peak F_y, held there over a
// plastic shortening u_s, the falling tangent -k_s to the residual F_r, then
// flow at F_r; unloading and reloading with k.
// Loading in steps of any size ends on the backbone (the return mapping is
// exact), and the plastic work plus the stored energy is the work of the
// backbone, the area under it, to round-off: the onset and the knee where
// softening meets the residual are integrated exactly inside a step that
// crosses them.
TEST(CellAxialLaw, SofteningFallsToTheResidualAndBalancesEnergy) {
  for (double us : {0.0, 0.012}) {
    AxialLawParams p{AxialModel::Softening, 1e6, 1e4, 0.0};
    p.softening_stiffness_N_m = 2e5;
    p.residual_force_N = 2e3;
    p.softening_onset_m = us;
    const double k = 1e6, fy = 1e4, ks = 2e5, fr = 2e3;
    const double uy = fy / k, uf = uy + us, ur = uf + (fy - fr) / ks;  // peak from 0.01 m, falls from uf to ur
    const auto backbone = [&](double u) { return u <= uy ? k * u : u <= uf ? fy : std::max(fr, fy - ks * (u - uf)); };
    const auto area = [&](double u) {  // the integral of the backbone from 0 to u (u >= ur)
      return 0.5 * fy * uy + fy * us + 0.5 * (fy + fr) * (ur - uf) + fr * (u - ur);
    };
    for (double step : {1e-4, 7.3e-3, 0.031, 0.08}) {  // fine steps, and steps across the peak, onset and knee
      double up = 0.0, plastic = 0.0, u = 0.0;
      AxialResponse r;
      while (u < 0.08) {
        u = std::min(0.08, u + step);
        r = axialResponse(p, u, up);
        up = r.plastic_m;
        plastic += r.plastic_work_J;
        EXPECT_NEAR(r.force_N, backbone(u), 1e-9 * fy) << "step " << step << " u " << u;
      }
      EXPECT_NEAR(plastic + r.elastic_J, area(0.08), 1e-12 * area(0.08)) << "step " << step;
    }
    // On the falling branch: unloading is elastic with k, reloading returns to
    // the yield force where it left it, with no plastic work on the way.
    const double u = uf + 0.01;
    const auto soft = axialResponse(p, u, 0.0);
    EXPECT_NEAR(soft.force_N, fy - ks * (u - uf), 1e-9 * fy);
    const auto un = axialResponse(p, u - 0.004, soft.plastic_m);
    EXPECT_NEAR(un.force_N, soft.force_N - k * 0.004, 1e-9 * fy);
    EXPECT_EQ(un.plastic_work_J, 0.0);
    const auto back = axialResponse(p, u, un.plastic_m);
    EXPECT_NEAR(back.force_N, soft.force_N, 1e-9 * fy);
    EXPECT_EQ(back.plastic_work_J, 0.0);
    // The stiffest tangent is still k (the time step's), the law is not "hardening".
    EXPECT_EQ(maxTangentStiffness(p), k);
    EXPECT_FALSE(hardens(p.model));
  }
}

// The rate term: while the cell flows at the shortening rate r, its yield
// force (and a softening law's residual) is raised by c r^2, and the plastic
// work of the step is the raised yield force times the plastic increment; a
// rate of zero or of unloading (r < 0) gives the rate-independent law; the
// elastic line is never left (k (u - u_p) bounds the force).
TEST(CellAxialLaw, RateOverstressRaisesTheYieldForceWhileTheCellFlows) {
  const double k = 1e6, fy = 1e4, c = 50.0, r = 8.0, s = c * r * r;  // 3.2 kN overstress
  for (AxialModel m : {AxialModel::ElasticPerfectlyPlastic, AxialModel::Bilinear, AxialModel::Softening}) {
    AxialLawParams p{m, k, fy, 0.0};
    p.rate_coefficient_N_s2_m2 = c;
    if (m == AxialModel::Bilinear) p.hardening_stiffness_N_m = 1e5;
    if (m == AxialModel::Softening) {
      p.softening_stiffness_N_m = 2e5;
      p.residual_force_N = 2e3;
    }
    AxialLawParams still = p;
    still.rate_coefficient_N_s2_m2 = 0.0;
    // (well past the peak: on the hardening line, or on the softening's residual)
    const double u = 0.1;
    const auto slow = axialResponse(still, u, 0.0);
    const auto fast = axialResponse(p, u, 0.0, r);
    const double H = m == AxialModel::Bilinear ? k * 1e5 / (k - 1e5) : 0.0;
    // hardening: F = Y(u_p) + s with u_p = u - F / k, so the force rises by s k / (k + H)
    const double rise = m == AxialModel::Bilinear ? s * k / (k + H) : s;
    EXPECT_NEAR(fast.force_N, slow.force_N + rise, 1e-9 * fy) << static_cast<int>(m);
    EXPECT_NEAR(fast.plastic_m, u - fast.force_N / k, 1e-15);
    EXPECT_NEAR(axialResponse(p, u, 0.0, 0.0).force_N, slow.force_N, 1e-12 * fy);
    EXPECT_NEAR(axialResponse(p, u, 0.0, -r).force_N, slow.force_N, 1e-12 * fy);
    // Elastic below the raised yield force: the rate changes nothing there.
    const double ue = 0.5 * fy / k;
    EXPECT_NEAR(axialResponse(p, ue, 0.0, r).force_N, k * ue, 1e-9 * fy);
    // A step that flows at a constant rate: the work is the yield force raised
    // by s, integrated over the plastic increment (EPP: (F_y + s) du_p).
    if (m == AxialModel::ElasticPerfectlyPlastic) {
      const auto a = axialResponse(p, 0.05, 0.0, r), b = axialResponse(p, 0.06, a.plastic_m, r);
      EXPECT_NEAR(b.plastic_work_J, (fy + s) * (b.plastic_m - a.plastic_m), 1e-12 * fy);
      EXPECT_NEAR(b.plastic_m - a.plastic_m, 0.01, 1e-15);
    }
  }
  // The rate term adds no stiffness: the critical time step's tangent is k.
  AxialLawParams p{AxialModel::ElasticPerfectlyPlastic, k, fy, 0.0};
  p.rate_coefficient_N_s2_m2 = c;
  EXPECT_EQ(maxTangentStiffness(p), k);
  // With a growth indentation u_a the overstress is c r^2 min(1, u / u_a):
  // the part of the boulder's section in contact grows with its indentation.
  p.rate_growth_m = 0.04;
  for (double u : {0.02, 0.03, 0.05}) {
    const double grown = std::min(1.0, u / 0.04);
    EXPECT_NEAR(axialResponse(p, u, 0.0, r).force_N, fy + s * grown, 1e-9 * fy) << u;
  }
}
