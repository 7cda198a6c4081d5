// Each contact law is written once (bridge/laws); every path that evaluates a
// contact must give the same numbers. A table of kinematics (overlaps below,
// at and above the F_lim cap, loading and unloading with plastic memory,
// sticking and sliding shear, shear history to rotate, zero and non-zero
// damping, approaching and separating) goes through
//   1. the bridge laws called one by one (the reference),
//   2. laneContact called on one contact (scalar code),
//   3. laneContact inside a `#pragma omp simd` loop over the table (the vector
//      code of the kernels; this file is compiled with -fopenmp-simd like
//      micro), in each of its eight compile-time variants on the rows where
//      the variant applies,
//   4. evaluateContact, measuring and not.
// Forces, the updated history and the energy increments agree to 1e-14
// relative. The absolute floor: a force component or an energy near zero is
// the difference of terms much larger than itself (-F_n n_x + k_s u_x;
// work - stored energy), whose rounding is relative to those terms, so the
// tolerance is 1e-14 times the larger of the value and the magnitude of the
// terms it is made of (about 90 ulps of them).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "bridge/laws/contact_damping.hpp"
#include "bridge/laws/contact_normal.hpp"
#include "bridge/laws/contact_tangential.hpp"
#include "micro/contact.hpp"

namespace {

using namespace gabion;
constexpr double kInf = std::numeric_limits<double>::infinity();

// One contact: the pair's law, the kinematics and the history it starts from.
struct Row {
  double kn, ks, friction, flim, zeta, inv_mass_sum, dt;
  double n[3], overlap, v[3];
  double u[3], plastic, viscous;
};

// What a path gives: the force on i, the history after, the energy increments.
struct Out {
  double f[3], u[3], plastic, viscous, fel;
  double friction_J, plastic_J, viscous_J, elastic_J;
};

// The normal states: overlap, plastic overlap, F_lim (k_n = 1e5 N/m).
struct NormalState {
  const char* what;
  double overlap, plastic, flim;
};
// The shear states: history (in the tangent plane along t1, t2 and along n)
// and the tangential velocity along t1, t2; friction coefficient.
struct ShearState {
  const char* what;
  double u1, u2, un, vt1, vt2, friction;
};
// The damping states: ratio, normal relative velocity (< 0: approaching),
// the dashpot force of the previous step.
struct DampingState {
  const char* what;
  double zeta, vn, viscous;
};

std::vector<Row> table() {
  const double kn = 1e5, ks = 2.5e4, dt = 1e-5;
  const NormalState normals[] = {
      {"elastic below the cap", 1e-4, 0.0, 40.0},
      {"exactly at the cap", 4e-4, 0.0, kn * 4e-4},
      {"above the cap, first yield", 1e-3, 0.0, 40.0},
      {"above the cap, plastic memory", 1.2e-3, 3e-4, 40.0},
      {"unloading from the plastic overlap", 8e-4, 6e-4, 40.0},
      {"inside the plastic overlap: no tension", 5e-4, 6e-4, 40.0},
      {"no cap", 1e-3, 0.0, kInf},
      {"no cap, not touching", -1e-5, 0.0, kInf},
  };
  const ShearState shears[] = {
      {"fresh, sticking", 0.0, 0.0, 0.0, 1.0, -0.5, 0.5},
      {"fresh, sliding", 0.0, 0.0, 0.0, 60.0, 20.0, 0.5},
      {"history in plane, sticking", 2e-4, -1e-4, 0.0, -1.0, 2.0, 0.5},
      {"history out of plane, rotated, sliding", 5e-4, 3e-4, 2e-4, 40.0, 0.0, 0.5},
      {"history along n only", 0.0, 0.0, 3e-4, 2.0, 1.0, 0.5},
      {"no friction", 1e-4, 1e-4, 1e-5, 5.0, 5.0, 0.0},
  };
  const DampingState dampings[] = {
      {"no damping, approaching", 0.0, -0.05, 0.0},
      {"damped, approaching", 0.3, -0.05, 0.2},
      {"damped, separating", 0.3, 0.08, -0.1},
  };
  // Unit normals with tangent bases (t1, t2 orthonormal to n).
  const double normal_dirs[][3] = {{0, 0, 1}, {1.0 / 3, 2.0 / 3, -2.0 / 3}, {-0.6, 0.0, 0.8}, {0.48, -0.6, 0.64}};
  std::vector<Row> rows;
  int k = 0;
  for (const auto& N : normals)
    for (const auto& S : shears)
      for (const auto& D : dampings) {
        const double* d = normal_dirs[k++ % 4];
        const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        const double n[3] = {d[0] / len, d[1] / len, d[2] / len};
        // t1 = (a x n) / |a x n| with a the axis least aligned with n; t2 = n x t1
        const double a[3] = {std::fabs(n[0]) < 0.6 ? 1.0 : 0.0, std::fabs(n[0]) < 0.6 ? 0.0 : 1.0, 0.0};
        double t1[3] = {a[1] * n[2] - a[2] * n[1], a[2] * n[0] - a[0] * n[2], a[0] * n[1] - a[1] * n[0]};
        const double l1 = std::sqrt(t1[0] * t1[0] + t1[1] * t1[1] + t1[2] * t1[2]);
        for (double& c : t1) c /= l1;
        const double t2[3] = {n[1] * t1[2] - n[2] * t1[1], n[2] * t1[0] - n[0] * t1[2], n[0] * t1[1] - n[1] * t1[0]};
        Row r{};
        r.kn = kn, r.ks = ks, r.friction = S.friction, r.flim = N.flim, r.zeta = D.zeta;
        r.inv_mass_sum = 1.0 / 0.02 + 1.0 / 0.05, r.dt = dt;
        r.overlap = N.overlap, r.plastic = N.plastic, r.viscous = D.viscous;
        for (int c = 0; c < 3; ++c) {
          r.n[c] = n[c];
          r.v[c] = S.vt1 * t1[c] + S.vt2 * t2[c] + D.vn * n[c];
          r.u[c] = S.u1 * t1[c] + S.u2 * t2[c] + S.un * n[c];
        }
        rows.push_back(r);
      }
  return rows;
}

double muKs(const Row& r) {
  return bridge::shearSpring({r.ks, r.friction}).reach_m_N;
}

// 1. The reference: the bridge laws called one by one, in the order of the
// contact (normal spring, dashpot, shear history turned, Coulomb update).
Out viaBridge(const Row& r) {
  const bridge::Xyz n{r.n[0], r.n[1], r.n[2]}, v{r.v[0], r.v[1], r.v[2]};
  const bridge::NormalContactParams np{r.kn, r.flim};
  const auto normal = bridge::normalContactForce(np, r.overlap, r.plastic);
  const auto dashpot =
      bridge::viscousNormalDashpot({r.zeta}, r.kn, r.inv_mass_sum, -bridge::dot(v, n), r.dt, r.viscous);
  const auto shear = bridge::shearSpring({r.ks, r.friction});
  const auto turned = bridge::rotateShearIntoPlane({r.u[0], r.u[1], r.u[2]}, n);
  const auto slip = bridge::coulombShearUpdate(shear, normal.force_N, turned, bridge::shearIncrement(v, n, r.dt));
  const double fn = normal.force_N + dashpot.force_N;
  Out o{};
  o.f[0] = -fn * n.x + r.ks * slip.u.x, o.f[1] = -fn * n.y + r.ks * slip.u.y, o.f[2] = -fn * n.z + r.ks * slip.u.z;
  o.u[0] = slip.u.x, o.u[1] = slip.u.y, o.u[2] = slip.u.z;
  o.plastic = normal.plastic_m, o.viscous = dashpot.force_N, o.fel = normal.force_N;
  o.friction_J = slip.friction_work_J, o.plastic_J = normal.plastic_work_J, o.viscous_J = dashpot.work_J;
  o.elastic_J = bridge::normalElasticEnergy(np, normal.force_N) + bridge::tangentialElasticEnergy(shear, slip.u);
  return o;
}

Out fromLane(const micro::LaneContact& c, const double u[3], double plastic, double viscous) {
  Out o{};
  o.f[0] = c.fx, o.f[1] = c.fy, o.f[2] = c.fz;
  o.u[0] = u[0], o.u[1] = u[1], o.u[2] = u[2];
  o.plastic = plastic, o.viscous = viscous, o.fel = c.elastic_normal_N;
  o.friction_J = c.friction_J, o.plastic_J = c.plastic_J, o.viscous_J = c.viscous_J, o.elastic_J = c.elastic_J;
  return o;
}

// 2. laneContact on one contact, kept out of line so that it is scalar code.
[[gnu::noinline]] Out viaLaneScalar(const Row& r) {
  double u[3] = {r.u[0], r.u[1], r.u[2]}, plastic = r.plastic, viscous = r.viscous;
  const auto c = micro::laneContact<true, true, true>(
      r.n[0], r.n[1], r.n[2], r.overlap, r.v[0], r.v[1], r.v[2], r.kn, r.ks, muKs(r), r.flim,
      bridge::dashpotCoefficient({r.zeta}, r.kn, r.inv_mass_sum), r.dt, u[0], u[1], u[2], plastic, viscous);
  return fromLane(c, u, plastic, viscous);
}

// 3. laneContact in a SIMD loop over the table, held as the kernels hold
// their data: one array per input and output (structure of arrays).
struct Lanes {
  std::vector<double> nx, ny, nz, overlap, vx, vy, vz, kn, ks, mu_ks, flim, zeta, inv_mass_sum, dt;
  std::vector<double> ux, uy, uz, plastic, viscous;                              // history, updated
  std::vector<double> fx, fy, fz, fel, friction, plastic_w, viscous_w, elastic;  // results
};

Lanes lanes(const std::vector<Row>& rows) {
  Lanes L;
  for (const Row& r : rows) {
    L.nx.push_back(r.n[0]), L.ny.push_back(r.n[1]), L.nz.push_back(r.n[2]), L.overlap.push_back(r.overlap);
    L.vx.push_back(r.v[0]), L.vy.push_back(r.v[1]), L.vz.push_back(r.v[2]);
    L.kn.push_back(r.kn), L.ks.push_back(r.ks), L.mu_ks.push_back(muKs(r)), L.flim.push_back(r.flim);
    L.zeta.push_back(r.zeta), L.inv_mass_sum.push_back(r.inv_mass_sum), L.dt.push_back(r.dt);
    L.ux.push_back(r.u[0]), L.uy.push_back(r.u[1]), L.uz.push_back(r.u[2]);
    L.plastic.push_back(r.plastic), L.viscous.push_back(r.viscous);
  }
  for (auto* v : {&L.fx, &L.fy, &L.fz, &L.fel, &L.friction, &L.plastic_w, &L.viscous_w, &L.elastic})
    v->assign(rows.size(), 0.0);
  return L;
}

template <bool kMeasure, bool kViscous, bool kPlastic>
std::vector<Out> viaLaneSimd(const std::vector<Row>& rows) {
  Lanes L = lanes(rows);
  const double *nx = L.nx.data(), *ny = L.ny.data(), *nz = L.nz.data(), *ov = L.overlap.data();
  const double *vx = L.vx.data(), *vy = L.vy.data(), *vz = L.vz.data();
  const double *kn = L.kn.data(), *ks = L.ks.data(), *mu = L.mu_ks.data(), *fl = L.flim.data();
  const double *ze = L.zeta.data(), *im = L.inv_mass_sum.data(), *dt = L.dt.data();
  double *hux = L.ux.data(), *huy = L.uy.data(), *huz = L.uz.data(), *hpl = L.plastic.data(), *hvi = L.viscous.data();
  double *fx = L.fx.data(), *fy = L.fy.data(), *fz = L.fz.data(), *fe = L.fel.data();
  double *wf = L.friction.data(), *wp = L.plastic_w.data(), *wv = L.viscous_w.data(), *we = L.elastic.data();
  const std::size_t m = rows.size();
#pragma omp simd
  for (std::size_t k = 0; k < m; ++k) {
    double ux = hux[k], uy = huy[k], uz = huz[k], pl = hpl[k], vi = hvi[k];
    const micro::LaneContact c = micro::laneContact<kMeasure, kViscous, kPlastic>(
        nx[k], ny[k], nz[k], ov[k], vx[k], vy[k], vz[k], kn[k], ks[k], mu[k], fl[k],
        bridge::dashpotCoefficient({ze[k]}, kn[k], im[k]), dt[k], ux, uy, uz, pl, vi);
    hux[k] = ux, huy[k] = uy, huz[k] = uz, hpl[k] = pl, hvi[k] = vi;
    fx[k] = c.fx, fy[k] = c.fy, fz[k] = c.fz, fe[k] = c.elastic_normal_N;
    wf[k] = c.friction_J, wp[k] = c.plastic_J, wv[k] = c.viscous_J, we[k] = c.elastic_J;
  }
  std::vector<Out> outs(m);
  for (std::size_t k = 0; k < m; ++k) {
    const micro::LaneContact c{fx[k], fy[k], fz[k], fe[k], wf[k], wp[k], wv[k], we[k]};
    const double u[3] = {hux[k], huy[k], huz[k]};
    outs[k] = fromLane(c, u, hpl[k], hvi[k]);
  }
  return outs;
}

// 4. evaluateContact.
Out viaEvaluateContact(const Row& r, bool measure) {
  micro::PairLaw law;
  law.normal = {r.kn, r.flim};
  law.tangential = {r.ks, r.friction};
  law.damping_ratio = r.zeta;
  double u[3] = {r.u[0], r.u[1], r.u[2]}, plastic = r.plastic, viscous = r.viscous, f[3];
  micro::ContactEnergy e;
  micro::evaluateContact(law, r.inv_mass_sum, r.n, r.overlap, r.v, r.dt, u, plastic, viscous, f, e, measure);
  Out o{};
  o.f[0] = f[0], o.f[1] = f[1], o.f[2] = f[2];
  o.u[0] = u[0], o.u[1] = u[1], o.u[2] = u[2];
  o.plastic = plastic, o.viscous = viscous, o.fel = std::nan("");  // not returned by this path
  o.friction_J = e.friction_J, o.plastic_J = e.plastic_J, o.viscous_J = e.viscous_J, o.elastic_J = e.elastic_J;
  return o;
}

// Counts of compared values, and of those that are exactly equal.
struct Tally {
  int compared = 0, identical = 0;
};

// `which` selects the quantities a variant gives: measure (elastic energy),
// viscous (dashpot history and work), plastic (plastic memory and work).
void expectSame(const Out& ref, const Out& got, const Row& r, const std::string& where, bool measure, bool viscous,
                bool plastic, Tally& tally) {
  const double fscale = std::fabs(ref.fel) + std::fabs(ref.viscous) +
                        r.ks * std::sqrt(ref.u[0] * ref.u[0] + ref.u[1] * ref.u[1] + ref.u[2] * ref.u[2]);
  const double uscale = std::sqrt(r.u[0] * r.u[0] + r.u[1] * r.u[1] + r.u[2] * r.u[2]) +
                        std::sqrt(r.v[0] * r.v[0] + r.v[1] * r.v[1] + r.v[2] * r.v[2]) * r.dt + std::fabs(r.overlap) +
                        std::fabs(r.plastic);
  const double escale = (fscale + std::fabs(r.viscous)) * uscale;
  const auto check = [&](double a, double b, double scale, const char* what) {
    ++tally.compared;
    if (a == b) {  // (+0 and -0 count as equal: a sum started at +0 turns -0 into +0)
      ++tally.identical;
      return;
    }
    const double tol = 1e-14 * std::max({std::fabs(a), std::fabs(b), scale});
    EXPECT_LE(std::fabs(a - b), tol) << where << ": " << what << " " << a << " vs " << b;
  };
  for (int c = 0; c < 3; ++c) {
    check(ref.f[c], got.f[c], fscale, "force");
    check(ref.u[c], got.u[c], uscale, "shear history");
  }
  check(ref.friction_J, got.friction_J, escale, "friction work");
  if (!std::isnan(got.fel)) check(ref.fel, got.fel, fscale, "elastic normal force");
  if (measure) check(ref.elastic_J, got.elastic_J, escale, "stored energy");
  if (viscous) {
    check(ref.viscous, got.viscous, fscale, "dashpot force");
    check(ref.viscous_J, got.viscous_J, escale, "dashpot work");
  }
  if (plastic) {
    check(ref.plastic, got.plastic, uscale, "plastic overlap");
    check(ref.plastic_J, got.plastic_J, escale, "plastic work");
  }
}

template <bool kMeasure, bool kViscous, bool kPlastic>
void expectSimdVariant(const std::vector<Row>& rows, const std::vector<Out>& ref, Tally& tally) {
  const auto got = viaLaneSimd<kMeasure, kViscous, kPlastic>(rows);
  int used = 0;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    // A variant without F_lim serves scenes with no cap (no plastic memory);
    // one without viscous damping, pairs with none.
    if (!kPlastic && (rows[k].flim != kInf || rows[k].plastic != 0.0)) continue;
    if (!kViscous && (rows[k].zeta != 0.0 || rows[k].viscous != 0.0)) continue;
    ++used;
    const std::string where = "row " + std::to_string(k) + ", SIMD laneContact<" + std::to_string(kMeasure) + "," +
                              std::to_string(kViscous) + "," + std::to_string(kPlastic) + ">";
    expectSame(ref[k], got[k], rows[k], where, kMeasure, kViscous, kPlastic, tally);
  }
  EXPECT_GT(used, 0);
}

TEST(ContactLawEquivalence, EveryPathGivesTheSameForcesHistoryAndEnergy) {
  const std::vector<Row> rows = table();
  std::vector<Out> ref;
  for (const Row& r : rows) ref.push_back(viaBridge(r));

  // The table covers what it claims: capped, plastic flow, no tension,
  // sliding, sticking, damping work.
  int capped = 0, flowing = 0, untouched = 0, sliding = 0, sticking = 0, damped = 0;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    capped += ref[k].fel == rows[k].flim;
    flowing += ref[k].plastic_J > 0.0;
    untouched += ref[k].fel == 0.0;
    sliding += ref[k].friction_J != 0.0;
    sticking += ref[k].friction_J == 0.0 && rows[k].friction > 0.0 && ref[k].fel > 0.0;
    damped += ref[k].viscous_J != 0.0;
  }
  EXPECT_GT(capped, 0);
  EXPECT_GT(flowing, 0);
  EXPECT_GT(untouched, 0);
  EXPECT_GT(sliding, 0);
  EXPECT_GT(sticking, 0);
  EXPECT_GT(damped, 0);

  Tally tally;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const std::string row = "row " + std::to_string(k);
    expectSame(ref[k], viaLaneScalar(rows[k]), rows[k], row + ", scalar laneContact", true, true, true, tally);
    expectSame(ref[k], viaEvaluateContact(rows[k], true), rows[k], row + ", evaluateContact", true, true, true, tally);
    expectSame(ref[k], viaEvaluateContact(rows[k], false), rows[k], row + ", evaluateContact (not measuring)", false,
               true, true, tally);
  }
  expectSimdVariant<true, true, true>(rows, ref, tally);
  expectSimdVariant<true, true, false>(rows, ref, tally);
  expectSimdVariant<true, false, true>(rows, ref, tally);
  expectSimdVariant<true, false, false>(rows, ref, tally);
  expectSimdVariant<false, true, true>(rows, ref, tally);
  expectSimdVariant<false, true, false>(rows, ref, tally);
  expectSimdVariant<false, false, true>(rows, ref, tally);
  expectSimdVariant<false, false, false>(rows, ref, tally);
  std::printf("%zu contacts, %d values compared, %d exactly equal to the bridge laws called one by one\n", rows.size(),
              tally.compared, tally.identical);
}

}  // namespace
