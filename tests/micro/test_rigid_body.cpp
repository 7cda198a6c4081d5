// Tests of micro/rigid_body: mass properties of sphere clusters against closed
// forms, and the DLM free-rotation integrator against conservation laws and a
// high-order reference solution.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <iostream>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "micro/rigid_body.hpp"

namespace gabion::micro {
namespace {

constexpr double kPi = 3.14159265358979323846;
using Eigen::Matrix3d;
using Eigen::Quaterniond;
using Eigen::Vector3d;

double ballVolume(double r) {
  return 4.0 / 3.0 * kPi * r * r * r;
}

// Lens (intersection) of two equal balls of radius R at centre distance d:
// V = pi (4R + d) (2R - d)^2 / 12 (two spherical caps of height h = R - d/2).
double equalLensVolume(double R, double d) {
  return kPi * (4.0 * R + d) * (2.0 * R - d) * (2.0 * R - d) / 12.0;
}

// Lens of two balls r1, r2 at distance d (Weisstein, "Sphere-Sphere Intersection", MathWorld):
// V = pi (r1 + r2 - d)^2 (d^2 + 2 d r2 - 3 r2^2 + 2 d r1 + 6 r1 r2 - 3 r1^2) / (12 d).
double lensVolume(double r1, double r2, double d) {
  const double s = r1 + r2 - d;
  return kPi * s * s * (d * d + 2 * d * r2 - 3 * r2 * r2 + 2 * d * r1 + 6 * r1 * r2 - 3 * r1 * r1) / (12.0 * d);
}

// Two equal balls (radius R) centred at x = +-d/2. The lens is
// |x| <= R - d/2 with disk radius^2 rho^2(x) = R^2 - (|x| + d/2)^2.
// With u = |x| + d/2 on [d/2, R]:
//   int_lens dV          = 2 pi int (R^2 - u^2) du
//   int_lens (y^2+z^2)dV = 2 pi int rho^4 / 2 du        (disk: int r^2 dA = pi rho^4 / 2)
//   int_lens x^2 dV      = 2 pi int (u - d/2)^2 (R^2 - u^2) du
// evaluated here by exact antiderivatives of the polynomials in u.
struct LensMoments {
  double V, Iaxis_geom, Ixx_geom;  // volume; int (y^2+z^2) dV; int x^2 dV
};
LensMoments equalLensMoments(double R, double d) {
  const double a = 0.5 * d;
  auto P = [&](double u) { return R * R * u - u * u * u / 3.0; };  // int (R^2 - u^2)
  auto Q = [&](double u) {                                         // int (R^2-u^2)^2
    return R * R * R * R * u - 2.0 * R * R * u * u * u / 3.0 + std::pow(u, 5) / 5.0;
  };
  auto S = [&](double u) {  // int (u - a)^2 (R^2 - u^2) = int (u^2 - 2au + a^2)(R^2 - u^2)
    return R * R * u * u * u / 3.0 - std::pow(u, 5) / 5.0 - 2.0 * a * (R * R * u * u / 2.0 - std::pow(u, 4) / 4.0) +
           a * a * (R * R * u - u * u * u / 3.0);
  };
  return {2.0 * kPi * (P(R) - P(a)), kPi * (Q(R) - Q(a)), 2.0 * kPi * (S(R) - S(a))};
}

// Inertia relative error measure used by clusterMassProperties: Frobenius norm / trace.
double inertiaError(const Matrix3d& J, const Matrix3d& ref) {
  return (J - ref).norm() / ref.trace();
}

// ---------------------------------------------------------------- mass properties

TEST(ClusterMassProperties, SingleSphere) {
  // m = rho 4/3 pi R^3, I = 2/5 m R^2 about the centre.
  const double R = 0.013, rho = 2650.0;
  const Vector3d c(0.3, -1.2, 4.0);
  const MassProperties p = clusterMassProperties({c}, {R}, rho);
  const double m = rho * ballVolume(R);
  EXPECT_NEAR(p.mass_kg, m, 1e-14 * m);
  EXPECT_NEAR(p.volume_m3, ballVolume(R), 1e-14 * ballVolume(R));
  EXPECT_LT((p.center_m - c).norm(), 1e-14);
  const double I = 0.4 * m * R * R;
  EXPECT_LT(inertiaError(p.inertia_kg_m2, I * Matrix3d::Identity()), 1e-13);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(p.principal_moments_kg_m2[k], I, 1e-13 * I);
  EXPECT_NEAR(p.principal_axes.norm(), 1.0, 1e-15);
}

TEST(ClusterMassProperties, TwoDisjointSpheresParallelAxis) {
  // m = m1 + m2; COM = (m1 c1 + m2 c2)/m; I = sum (2/5 m_i r_i^2 1 + m_i (|d_i|^2 1 - d_i d_i^T)).
  const double rho = 1000.0;
  const std::vector<Vector3d> c{{0.0, 0.0, 0.0}, {0.3, 0.4, 0.0}};
  const std::vector<double> r{0.1, 0.2};  // distance 0.5 > 0.3: disjoint
  const MassProperties p = clusterMassProperties(c, r, rho);
  const double m1 = rho * ballVolume(r[0]), m2 = rho * ballVolume(r[1]);
  const Vector3d com = (m1 * c[0] + m2 * c[1]) / (m1 + m2);
  Matrix3d J = Matrix3d::Zero();
  for (int i = 0; i < 2; ++i) {
    const double mi = i == 0 ? m1 : m2;
    const Vector3d d = c[i] - com;
    J += 0.4 * mi * r[i] * r[i] * Matrix3d::Identity() +
         mi * (d.squaredNorm() * Matrix3d::Identity() - d * d.transpose());
  }
  EXPECT_NEAR(p.mass_kg, m1 + m2, 1e-14 * (m1 + m2));
  EXPECT_LT((p.center_m - com).norm(), 1e-14);
  EXPECT_LT(inertiaError(p.inertia_kg_m2, J), 1e-13);
  // The smallest principal axis is the line of the centres.
  const Vector3d axis = p.principal_axes * Vector3d::UnitX();
  EXPECT_NEAR(std::abs(axis.dot(Vector3d(0.6, 0.8, 0.0))), 1.0, 1e-12);
}

TEST(ClusterMassProperties, TwoOverlappingEqualSpheresLens) {
  // Union = 2 balls - lens. About the symmetry axis x: I_axis = rho (2 * 2/5 V_b R^2 - int_lens (y^2+z^2));
  // transverse (about y through the COM at 0): I_t = rho (int_union (x^2 + z^2)), with
  // int_ball (x^2+z^2) about 0 = V_b (2 R^2/5 + (d/2)^2) per ball, minus the lens part
  // int_lens x^2 + int_lens (y^2+z^2)/2 (axisymmetric lens).
  const double R = 0.01, d = 0.012, rho = 2500.0;
  const std::vector<Vector3d> c{{-0.5 * d, 0, 0}, {0.5 * d, 0, 0}};
  const LensMoments lens = equalLensMoments(R, d);
  ASSERT_NEAR(lens.V, equalLensVolume(R, d), 1e-15);  // two derivations of the lens agree
  const double Vb = ballVolume(R);
  const double V = 2.0 * Vb - lens.V;
  const double Iaxis = rho * (2.0 * 0.4 * Vb * R * R - lens.Iaxis_geom);
  const double It = rho * (2.0 * Vb * (0.4 * R * R + 0.25 * d * d) - lens.Ixx_geom - 0.5 * lens.Iaxis_geom);
  for (double tol : {1e-4, 1e-8}) {
    const MassProperties p = clusterMassProperties(c, {R, R}, rho, tol);
    EXPECT_NEAR(p.volume_m3, V, tol * V) << tol;
    EXPECT_LT(p.center_m.norm(), tol * R) << tol;
    EXPECT_NEAR(p.inertia_kg_m2(0, 0), Iaxis, tol * Iaxis) << tol;
    EXPECT_NEAR(p.inertia_kg_m2(1, 1), It, tol * It) << tol;
    EXPECT_NEAR(p.inertia_kg_m2(2, 2), It, tol * It) << tol;
    EXPECT_NEAR(p.principal_moments_kg_m2[0], Iaxis, tol * Iaxis) << tol;
  }
}

TEST(ClusterMassProperties, RelTolRespectedAndErrorShrinks) {
  // Unequal overlapping spheres along a skew line (lens volume: Weisstein's closed form),
  // and the equal-sphere lens inertia in a rotated frame.
  const double r1 = 0.01, r2 = 0.007, d = 0.012;
  const Vector3d u = Vector3d(1.0, 2.0, -0.5).normalized();
  const std::vector<Vector3d> c{Vector3d(0.1, 0.2, 0.3), Vector3d(0.1, 0.2, 0.3) + d * u};
  const double V = ballVolume(r1) + ballVolume(r2) - lensVolume(r1, r2, d);
  double previous = 1.0;
  for (double tol : {1e-2, 1e-3, 1e-4, 1e-6, 1e-8, 1e-10}) {
    const MassProperties p = clusterMassProperties(c, {r1, r2}, 1.0, tol);
    const double err = std::abs(p.volume_m3 - V) / V;
    EXPECT_LE(err, tol) << tol;
    // The error bound shrinks with tol; the error itself may already be at round-off.
    EXPECT_LE(err, std::max(previous, 1e-13)) << tol;
    previous = err;
  }
  // COM on the line of centres, on the side of the bigger sphere.
  const MassProperties p = clusterMassProperties(c, {r1, r2}, 1.0, 1e-10);
  const Vector3d rel = p.center_m - c[0];
  EXPECT_LT((rel - rel.dot(u) * u).norm(), 1e-12);
  EXPECT_GT(rel.dot(u), 0.0);
  EXPECT_LT(rel.dot(u), 0.5 * d);
}

// Box of nx x ny x nz spheres with spacings s (less than 2 r: neighbours overlap).
std::vector<Vector3d> boxCluster(int nx, int ny, int nz, const Vector3d& s) {
  std::vector<Vector3d> c;
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j)
      for (int k = 0; k < nz; ++k)
        c.emplace_back(s.x() * (i - 0.5 * (nx - 1)), s.y() * (j - 0.5 * (ny - 1)), s.z() * (k - 0.5 * (nz - 1)));
  return c;
}

TEST(ClusterMassProperties, BoxOfSpheresSymmetryAndFrameInvariance) {
  const double r = 0.01, rho = 2700.0, tol = 1e-6;
  const std::vector<Vector3d> c = boxCluster(4, 3, 2, Vector3d(0.011, 0.012, 0.013));
  const std::vector<double> radii(c.size(), r);
  const MassProperties p = clusterMassProperties(c, radii, rho, tol);
  // Mirror symmetry about the three coordinate planes: COM at 0, diagonal inertia.
  const double L = 0.03;
  EXPECT_LT(p.center_m.norm(), 10 * tol * L);
  const double tr = p.inertia_kg_m2.trace();
  EXPECT_LT(std::abs(p.inertia_kg_m2(0, 1)), tol * tr);
  EXPECT_LT(std::abs(p.inertia_kg_m2(0, 2)), tol * tr);
  EXPECT_LT(std::abs(p.inertia_kg_m2(1, 2)), tol * tr);
  // The union is smaller than the sum of the balls and larger than its core boxes.
  EXPECT_LT(p.volume_m3, c.size() * ballVolume(r));
  // Longest box axis (x) has the smallest moment: principal axis 1 = +-x, 3 = +-z.
  const Matrix3d R = p.principal_axes.toRotationMatrix();
  EXPECT_NEAR(std::abs(R(0, 0)), 1.0, 1e-9);
  EXPECT_NEAR(std::abs(R(1, 1)), 1.0, 1e-9);
  EXPECT_NEAR(std::abs(R(2, 2)), 1.0, 1e-9);
  EXPECT_NEAR(R.determinant(), 1.0, 1e-12);

  // Same body rotated and moved: COM moves along, inertia rotates (J' = Q J Q^T).
  const Quaterniond Q = Quaterniond(Eigen::AngleAxisd(0.7, Vector3d(1, -2, 0.4).normalized())).normalized();
  const Vector3d shift(1.5, -0.25, 3.0);
  std::vector<Vector3d> c2;
  for (const Vector3d& x : c) c2.push_back(Q * x + shift);
  const MassProperties p2 = clusterMassProperties(c2, radii, rho, tol);
  EXPECT_NEAR(p2.volume_m3, p.volume_m3, 2 * tol * p.volume_m3);
  EXPECT_LT((p2.center_m - shift).norm(), 10 * tol * L);
  const Matrix3d Qm = Q.toRotationMatrix();
  EXPECT_LT(inertiaError(p2.inertia_kg_m2, Qm * p.inertia_kg_m2 * Qm.transpose()), 4 * tol);
  const Matrix3d R2 = p2.principal_axes.toRotationMatrix();
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(std::abs(R2.col(k).dot(Qm.col(k))), 1.0, 1e-6) << k;
}

// Independent reference: columns along z through a fine (y, x) midpoint grid; on each
// column the union of the spheres' chords is exact (sorted intervals), and the z-integrals
// of 1, z, z^2 over it are exact. Error ~ h^1.5 from the silhouettes.
struct BruteMoments {
  double V;
  Vector3d M1;
  Matrix3d M2;
};
BruteMoments bruteColumns(const std::vector<Vector3d>& c, const std::vector<double>& r, int n) {
  Vector3d lo = c[0], hi = c[0];
  for (std::size_t i = 0; i < c.size(); ++i) {
    lo = lo.cwiseMin(c[i] - Vector3d::Constant(r[i]));
    hi = hi.cwiseMax(c[i] + Vector3d::Constant(r[i]));
  }
  const double hx = (hi.x() - lo.x()) / n, hy = (hi.y() - lo.y()) / n;
  BruteMoments m{0, Vector3d::Zero(), Matrix3d::Zero()};
  std::vector<std::pair<double, double>> iv;
  for (int ix = 0; ix < n; ++ix)
    for (int iy = 0; iy < n; ++iy) {
      const double x = lo.x() + (ix + 0.5) * hx, y = lo.y() + (iy + 0.5) * hy;
      iv.clear();
      for (std::size_t i = 0; i < c.size(); ++i) {
        const double q = r[i] * r[i] - (x - c[i].x()) * (x - c[i].x()) - (y - c[i].y()) * (y - c[i].y());
        if (q > 0) iv.emplace_back(c[i].z() - std::sqrt(q), c[i].z() + std::sqrt(q));
      }
      std::sort(iv.begin(), iv.end());
      double z0 = 0, z1 = 0, z2 = 0;  // int 1, z, z^2 dz over the union
      for (std::size_t k = 0; k < iv.size();) {
        double a = iv[k].first, b = iv[k].second;
        for (++k; k < iv.size() && iv[k].first <= b; ++k) b = std::max(b, iv[k].second);
        z0 += b - a;
        z1 += 0.5 * (b * b - a * a);
        z2 += (b * b * b - a * a * a) / 3.0;
      }
      const double w = hx * hy;
      m.V += w * z0;
      m.M1 += w * Vector3d(x * z0, y * z0, z1);
      Matrix3d S;
      S << x * x * z0, x * y * z0, x * z1, x * y * z0, y * y * z0, y * z1, x * z1, y * z1, z2;
      m.M2 += w * S;
    }
  return m;
}

TEST(ClusterMassProperties, TripleOverlapAgainstIndependentColumnIntegration) {
  // Three unequal spheres that all overlap pairwise and share a triple region.
  const std::vector<Vector3d> c{{0.0, 0.0, 0.0}, {0.012, 0.003, -0.002}, {0.005, 0.011, 0.004}};
  const std::vector<double> r{0.01, 0.009, 0.008};
  const MassProperties p = clusterMassProperties(c, r, 1.0, 1e-8);
  // The column reference differs from this result by (volume, centre/1 cm, inertia)
  // n = 400: 1.7e-6, 3.0e-6, 4.9e-6; n = 800: 1.7e-6, 1.6e-6, 2.6e-6;
  // n = 1600: 3.4e-7, 2.8e-7, 5.2e-7; n = 3200: 1.0e-7, 1.7e-8, 1.7e-7
  // (bruteColumns below at those n, against rel_tol 1e-11): it converges onto this result.
  const BruteMoments b = bruteColumns(c, r, 1600);
  const double tol = 2e-6;  // ~4x the n = 1600 difference
  EXPECT_NEAR(p.volume_m3, b.V, tol * b.V);
  const Vector3d com = b.M1 / b.V;
  EXPECT_LT((p.center_m - com).norm(), tol * 0.01);
  const Matrix3d M2c = b.M2 - b.V * com * com.transpose();
  const Matrix3d J = M2c.trace() * Matrix3d::Identity() - M2c;
  EXPECT_LT(inertiaError(p.inertia_kg_m2, J), tol);
  // The union is less than the sum of balls minus the three pairwise lenses? No:
  // inclusion-exclusion, V = sum - lenses + triple, so V > sum - lenses.
  double lenses = 0, sum = 0;
  for (int i = 0; i < 3; ++i) {
    sum += ballVolume(r[i]);
    for (int j = i + 1; j < 3; ++j) lenses += lensVolume(r[i], r[j], (c[i] - c[j]).norm());
  }
  EXPECT_GT(p.volume_m3, sum - lenses);
  EXPECT_LT(p.volume_m3, sum);
}

TEST(ClusterMassProperties, RandomClustersMeetTheirTolerance) {
  // Random overlapping clusters (5-20 spheres, radii 0.5-1.5 cm, centres in a 3 cm box):
  // the result at rel_tol must be within rel_tol of a 1e-11 reference, for volume, centre
  // (relative to the radius of gyration) and inertia (Frobenius norm / trace).
  std::mt19937 rng(12345);
  std::uniform_real_distribution<double> pos(-0.015, 0.015), rad(0.005, 0.015);
  for (int trial = 0; trial < 12; ++trial) {
    const int n = 5 + trial + (trial % 3) * 2;
    std::vector<Vector3d> c;
    std::vector<double> r;
    for (int i = 0; i < n; ++i) {
      c.emplace_back(pos(rng), pos(rng), pos(rng));
      r.push_back(rad(rng));
    }
    const MassProperties ref = clusterMassProperties(c, r, 2500.0, 1e-11);
    const double rg = std::sqrt(0.5 * ref.inertia_kg_m2.trace() / ref.mass_kg);
    for (double tol : {1e-3, 1e-4, 1e-6}) {
      const MassProperties p = clusterMassProperties(c, r, 2500.0, tol);
      EXPECT_LE(std::abs(p.volume_m3 / ref.volume_m3 - 1.0), tol) << trial << " " << tol;
      EXPECT_LE((p.center_m - ref.center_m).norm() / rg, tol) << trial << " " << tol;
      EXPECT_LE(inertiaError(p.inertia_kg_m2, ref.inertia_kg_m2), tol) << trial << " " << tol;
    }
  }
}

// Blocks as the engine builds them: a parallelepiped lattice of spheres (radius 1 cm,
// spacing s), optionally with the edge spheres removed (angularity), optionally jittered
// (centres by up to 0.9 mm, radii 0.5-1.5 cm) so that no symmetry helps.
std::vector<Vector3d> latticeBlock(int nx, int ny, int nz, double s, bool cut_edges) {
  std::vector<Vector3d> c;
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j)
      for (int k = 0; k < nz; ++k) {
        const int on_faces = (i == 0 || i == nx - 1) + (j == 0 || j == ny - 1) + (k == 0 || k == nz - 1);
        if (cut_edges && on_faces >= 2) continue;
        c.emplace_back(s * i, s * j, s * k);
      }
  return c;
}

TEST(ClusterMassProperties, TypicalBlocksAccuracyAndCost) {
  // Accuracy at the default rel_tol = 1e-4 against rel_tol = 1e-9; the CPU time per
  // call is printed (the numbers in docs/rigid_bodies.md), not asserted.
  struct Shape {
    int nx, ny, nz;
    double s;
    bool cut;
  };
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (bool jitter : {false, true})
    for (const Shape& g : {Shape{3, 3, 2, 0.01, false}, Shape{3, 3, 3, 0.01, false}, Shape{4, 3, 3, 0.01, true},
                           Shape{4, 3, 2, 0.015, false}, Shape{3, 3, 3, 0.007, false}, Shape{4, 4, 3, 0.012, false}}) {
      std::vector<Vector3d> c = latticeBlock(g.nx, g.ny, g.nz, g.s, g.cut);
      std::vector<double> r(c.size(), 0.01);
      if (jitter) {
        for (Vector3d& x : c) x += 0.003 * Vector3d(u(rng), u(rng), u(rng));
        for (double& v : r) v = 0.01 * (1.0 + 0.5 * u(rng) / 0.3);
      }
      const MassProperties ref = clusterMassProperties(c, r, 2500.0, 1e-9);
      const int reps = 10;
      MassProperties p;
      const std::clock_t t0 = std::clock();
      for (int n = 0; n < reps; ++n) p = clusterMassProperties(c, r, 2500.0);
      const double ms = 1000.0 * static_cast<double>(std::clock() - t0) / CLOCKS_PER_SEC / reps;
      const double rg = std::sqrt(0.5 * ref.inertia_kg_m2.trace() / ref.mass_kg);
      const double eV = std::abs(p.volume_m3 / ref.volume_m3 - 1.0);
      const double eC = (p.center_m - ref.center_m).norm() / rg;
      const double eJ = inertiaError(p.inertia_kg_m2, ref.inertia_kg_m2);
      EXPECT_LE(std::max({eV, eC, eJ}), 1e-4);
      std::cout << "[ info ] " << g.nx << "x" << g.ny << "x" << g.nz << (g.cut ? " cut" : "") << " s=" << g.s
                << (jitter ? " jittered" : " lattice") << ": " << c.size() << " spheres, " << ms << " ms CPU, errors V "
                << eV << " centre " << eC << " inertia " << eJ << "\n";
    }
}

TEST(ClusterMassProperties, SmallLensInsideAWideOverlapRangeIsNotMissed) {
  // A thin lens (A, B overlapping 0.05 % of r across y; x-width 0.063 r) in the x-range
  // of a wide lens (C, D, far away in z): a lens narrower than the Kronrod node spacing
  // must still be integrated (regression check; here adaptivity alone also finds it).
  // Exact: V = 4 balls - lens(A,B) - lens(C,D).
  const std::vector<Vector3d> c{{0, 0, 0}, {0, 1.999, 0}, {0, 0, 10}, {0.5, 0, 10}};
  const std::vector<double> r(4, 1.0);
  const double V = 4 * ballVolume(1.0) - equalLensVolume(1.0, 1.999) - equalLensVolume(1.0, 0.5);
  for (double tol : {1e-6, 1e-10}) {
    const MassProperties p = clusterMassProperties(c, r, 1.0, tol);
    EXPECT_NEAR(p.volume_m3, V, tol * V) << tol;
  }
}

TEST(ClusterMassProperties, ContainedAndDuplicateSpheresCountOnce) {
  const double R = 0.02;
  const MassProperties one = clusterMassProperties({Vector3d::Zero()}, {R}, 1.0);
  const MassProperties p =
      clusterMassProperties({Vector3d::Zero(), Vector3d::Zero(), Vector3d(0.005, 0, 0)}, {R, R, 0.01}, 1.0);
  EXPECT_NEAR(p.volume_m3, one.volume_m3, 1e-15);
  EXPECT_LT(inertiaError(p.inertia_kg_m2, one.inertia_kg_m2), 1e-14);
}

TEST(ClusterMassProperties, DegenerateInertiaGivesRightHandedBasis) {
  // A cube of 2x2x2 overlapping spheres has cubic symmetry: isotropic inertia.
  const std::vector<Vector3d> c = boxCluster(2, 2, 2, Vector3d::Constant(0.012));
  const MassProperties p = clusterMassProperties(c, std::vector<double>(8, 0.01), 1.0);
  const Vector3d& I = p.principal_moments_kg_m2;
  EXPECT_NEAR(I[0], I[2], 1e-4 * I[2]);
  EXPECT_LE(I[0], I[1]);
  EXPECT_LE(I[1], I[2]);
  EXPECT_NEAR(p.principal_axes.norm(), 1.0, 1e-15);
  const Matrix3d R = p.principal_axes.toRotationMatrix();
  EXPECT_LT((R.transpose() * R - Matrix3d::Identity()).norm(), 1e-14);
  EXPECT_NEAR(R.determinant(), 1.0, 1e-14);
  // The principal frame diagonalises the inertia.
  const Matrix3d D = R.transpose() * p.inertia_kg_m2 * R;
  EXPECT_LT((D - Matrix3d(I.asDiagonal())).norm(), 1e-12 * I[2]);
}

TEST(ClusterMassProperties, PrincipalFrameOffsetsRebuildTheBody) {
  const std::vector<Vector3d> c{{0.0, 0.0, 0.0}, {0.012, 0.003, -0.002}, {0.005, 0.011, 0.004}};
  const MassProperties p = clusterMassProperties(c, {0.01, 0.009, 0.008}, 2000.0, 1e-10);
  const std::vector<Vector3d> off = principalFrameOffsets(p, c);
  for (std::size_t i = 0; i < c.size(); ++i) EXPECT_LT((p.center_m + p.principal_axes * off[i] - c[i]).norm(), 1e-15);
  // In the principal frame the same cluster has diagonal inertia and COM 0.
  const MassProperties q = clusterMassProperties(off, {0.01, 0.009, 0.008}, 2000.0, 1e-10);
  EXPECT_LT(q.center_m.norm(), 1e-10 * 0.01);
  const double off_diag =
      std::abs(q.inertia_kg_m2(0, 1)) + std::abs(q.inertia_kg_m2(0, 2)) + std::abs(q.inertia_kg_m2(1, 2));
  EXPECT_LT(off_diag, 1e-9 * q.inertia_kg_m2.trace());
}

TEST(ClusterMassProperties, InvalidInputThrows) {
  const std::vector<Vector3d> c{{0, 0, 0}};
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_THROW(clusterMassProperties({}, {}, 1.0), std::invalid_argument);
  EXPECT_THROW(clusterMassProperties(c, {0.1, 0.2}, 1.0), std::invalid_argument);
  EXPECT_THROW(clusterMassProperties(c, {0.0}, 1.0), std::invalid_argument);
  EXPECT_THROW(clusterMassProperties(c, {-0.1}, 1.0), std::invalid_argument);
  EXPECT_THROW(clusterMassProperties(c, {nan}, 1.0), std::invalid_argument);
  EXPECT_THROW(clusterMassProperties(c, {inf}, 1.0), std::invalid_argument);
  EXPECT_THROW(clusterMassProperties({Vector3d(nan, 0, 0)}, {0.1}, 1.0), std::invalid_argument);
  EXPECT_THROW(clusterMassProperties(c, {0.1}, 0.0), std::invalid_argument);
  EXPECT_THROW(clusterMassProperties(c, {0.1}, -5.0), std::invalid_argument);
  EXPECT_THROW(clusterMassProperties(c, {0.1}, nan), std::invalid_argument);
  EXPECT_THROW(clusterMassProperties(c, {0.1}, 1.0, 0.0), std::invalid_argument);
  EXPECT_THROW(clusterMassProperties(c, {0.1}, 1.0, nan), std::invalid_argument);
  Quaterniond q = Quaterniond::Identity();
  EXPECT_THROW(freeRotate(q, Vector3d(1, 0, 0), Vector3d(1, 0, 2), 0.1), std::invalid_argument);
  EXPECT_THROW(freeRotate(q, Vector3d(1, 0, 0), Vector3d(1, nan, 2), 0.1), std::invalid_argument);
}

// ---------------------------------------------------------------- free rotation

// Reference: Euler's equations in the body frame, I dw/dt = (I w) x w, with
// dq/dt = q (0, w)/2 (q: body -> world), integrated by classical RK4.
struct RefState {
  Vector3d Lb;
  Quaterniond q;
};
RefState derivative(const RefState& s, const Vector3d& I) {
  const Vector3d w = s.Lb.cwiseQuotient(I);
  RefState d;
  d.Lb = s.Lb.cross(w);  // dLb/dt = Lb x w (torque-free)
  const Quaterniond wq(0.0, w.x(), w.y(), w.z());
  d.q.coeffs() = 0.5 * (s.q * wq).coeffs();
  return d;
}
RefState axpy(const RefState& s, double h, const RefState& d) {
  RefState r;
  r.Lb = s.Lb + h * d.Lb;
  r.q.coeffs() = s.q.coeffs() + h * d.q.coeffs();
  return r;
}
Quaterniond referenceRotation(Quaterniond q, const Vector3d& Lw, const Vector3d& I, double T, int steps) {
  RefState s{q.conjugate() * Lw, q};
  const double h = T / steps;
  for (int n = 0; n < steps; ++n) {
    const RefState k1 = derivative(s, I);
    const RefState k2 = derivative(axpy(s, 0.5 * h, k1), I);
    const RefState k3 = derivative(axpy(s, 0.5 * h, k2), I);
    const RefState k4 = derivative(axpy(s, h, k3), I);
    s.Lb += h / 6.0 * (k1.Lb + 2 * k2.Lb + 2 * k3.Lb + k4.Lb);
    s.q.coeffs() += h / 6.0 * (k1.q.coeffs() + 2 * k2.q.coeffs() + 2 * k3.q.coeffs() + k4.q.coeffs());
  }
  return s.q.normalized();
}

double angleBetween(const Quaterniond& a, const Quaterniond& b) {
  return a.angularDistance(b);
}

TEST(FreeRotate, AsymmetricBodyConservesEnergyAndMomentum) {
  // I = (1, 2, 3); |omega| ~ 1.2 rad/s; dt = period/500 -> 1e5 steps ~ 200 turns.
  const Vector3d I(1.0, 2.0, 3.0);
  Quaterniond q = Quaterniond(Eigen::AngleAxisd(0.3, Vector3d(1, 1, 0).normalized()));
  const Vector3d Lw = q * Vector3d(0.6, 1.2, 3.0);  // body L between the stable axes 3 and the separatrix
  const double E0 = rotationalKineticEnergy(q, Lw, I);
  const double omega = angularVelocityWorld(q, Lw, I).norm();
  const double dt = 2.0 * kPi / omega / 500.0;
  const int steps = 100000;
  double max_dev = 0.0, first = 0.0, last = 0.0;
  const int window = 10000;  // ~20 turns: averages the bounded O(dt^2) oscillation
  for (int n = 0; n < steps; ++n) {
    freeRotate(q, Lw, I, dt);
    const double e = rotationalKineticEnergy(q, Lw, I) / E0 - 1.0;
    max_dev = std::max(max_dev, std::abs(e));
    if (n < window) first += e / window;
    if (n >= steps - window) last += e / window;
  }
  // Secular drift (difference of the window means) and the bounded oscillation.
  EXPECT_LT(std::abs(last - first), 1e-6) << "oscillation amplitude " << max_dev;
  EXPECT_LT(max_dev, 1e-4);
  // q stays a unit quaternion; omega and L stay consistent: L = q I q^-1 omega.
  EXPECT_NEAR(q.norm(), 1.0, 1e-14);
  const Vector3d w = angularVelocityWorld(q, Lw, I);
  const Vector3d L_back = q * (I.cwiseProduct(q.conjugate() * w));
  EXPECT_LT((L_back - Lw).norm(), 1e-12 * Lw.norm());
  std::cout << "[ info ] KE relative oscillation " << max_dev << ", window drift " << (last - first) << "\n";
}

TEST(FreeRotate, EnergyOscillationShrinksAsDtSquared) {
  // The bounded energy error of a second-order symplectic scheme scales as dt^2.
  const Vector3d I(1.0, 2.0, 3.0), Lw(0.6, 1.2, 3.0);
  auto amplitude = [&](double dt) {
    Quaterniond q = Quaterniond::Identity();
    const double E0 = rotationalKineticEnergy(q, Lw, I);
    double m = 0;
    for (int n = 0; n < static_cast<int>(20.0 / dt); ++n) {
      freeRotate(q, Lw, I, dt);
      m = std::max(m, std::abs(rotationalKineticEnergy(q, Lw, I) / E0 - 1.0));
    }
    return m;
  };
  const double a1 = amplitude(0.02), a2 = amplitude(0.01);
  EXPECT_NEAR(a1 / a2, 4.0, 0.4);
}

TEST(FreeRotate, SecondOrderConvergenceAgainstRk4Reference) {
  const Vector3d I(1.0, 2.0, 3.0);
  const Quaterniond q0 = Quaterniond(Eigen::AngleAxisd(1.1, Vector3d(0.2, -1, 0.5).normalized()));
  const Vector3d Lw(1.0, -2.0, 1.5);
  const double T = 2.0;
  const Quaterniond ref = referenceRotation(q0, Lw, I, T, 200000);  // RK4 error ~ h^4 ~ 1e-20
  std::vector<double> err;
  for (int steps : {25, 50, 100, 200}) {
    Quaterniond q = q0;
    for (int n = 0; n < steps; ++n) freeRotate(q, Lw, I, T / steps);
    err.push_back(angleBetween(q, ref));
  }
  for (std::size_t k = 1; k < err.size(); ++k) {
    const double order = std::log2(err[k - 1] / err[k]);
    EXPECT_NEAR(order, 2.0, 0.1) << "errors " << err[k - 1] << " -> " << err[k];
  }
}

TEST(FreeRotate, IntermediateAxisFlipsMajorAndMinorAxesStay) {
  // Tennis-racket (Dzhanibekov) effect: rotation near the intermediate axis 2 is
  // unstable, the body's axis 2 flips against L; near axes 1 and 3 it is stable.
  const Vector3d I(1.0, 2.0, 3.0);
  auto minAlignment = [&](int axis) {
    Vector3d Lb = Vector3d::Constant(1e-3);
    Lb[axis] = 1.0;
    Quaterniond q = Quaterniond::Identity();
    const Vector3d Lw = q * Lb;
    double lowest = 1.0;
    for (int n = 0; n < 20000; ++n) {  // dt = 0.01 s, 200 s (omega ~ 0.5-1 rad/s)
      freeRotate(q, Lw, I, 0.01);
      const Vector3d e = q * Vector3d::Unit(axis);
      lowest = std::min(lowest, e.dot(Lw.normalized()));
    }
    return lowest;
  };
  EXPECT_LT(minAlignment(1), -0.9);  // flips
  EXPECT_GT(minAlignment(0), 0.99);  // stable
  EXPECT_GT(minAlignment(2), 0.99);  // stable
}

TEST(FreeRotate, PrincipalAxisRotationIsSteady) {
  // L along a principal axis: uniform rotation about it, exactly omega = L / I_k.
  const Vector3d I(1.0, 2.0, 3.0);
  for (int axis = 0; axis < 3; ++axis) {
    const Quaterniond q0 = Quaterniond(Eigen::AngleAxisd(0.4, Vector3d(1, 2, 3).normalized()));
    const Vector3d Lw = q0 * (0.7 * Vector3d::Unit(axis));
    Quaterniond q = q0;
    const double dt = 0.013;
    const int steps = 1000;
    for (int n = 0; n < steps; ++n) freeRotate(q, Lw, I, dt);
    const Quaterniond exact = Quaterniond(Eigen::AngleAxisd(0.7 / I[axis] * dt * steps, Lw.normalized())) * q0;
    EXPECT_LT(angleBetween(q, exact), 1e-11) << axis;
  }
}

TEST(FreeRotate, SphericalInertiaRotatesExactlyAtConstantOmega) {
  const Vector3d I = Vector3d::Constant(2.5);
  const Quaterniond q0 = Quaterniond(Eigen::AngleAxisd(2.0, Vector3d(-1, 0.3, 0.8).normalized()));
  const Vector3d Lw(1.0, -3.0, 2.0);
  const Vector3d w = angularVelocityWorld(q0, Lw, I);
  EXPECT_LT((w - Lw / 2.5).norm(), 1e-15);
  Quaterniond q = q0;
  const double dt = 0.05;
  const int steps = 10000;
  for (int n = 0; n < steps; ++n) freeRotate(q, Lw, I, dt);
  const double angle = std::fmod(w.norm() * dt * steps, 2.0 * kPi);
  const Quaterniond exact = Quaterniond(Eigen::AngleAxisd(angle, w.normalized())) * q0;
  EXPECT_LT(angleBetween(q, exact), 1e-10);
  EXPECT_LT((angularVelocityWorld(q, Lw, I) - w).norm(), 1e-14);
}

TEST(FreeRotate, DeterministicAndZeroMomentumIsAtRest) {
  const Vector3d I(0.5, 0.9, 1.3);
  Quaterniond a = Quaterniond(Eigen::AngleAxisd(0.3, Vector3d::UnitY())), b = a;
  const Quaterniond start = a;
  freeRotate(a, Vector3d::Zero(), I, 0.1);
  EXPECT_LT((a.coeffs() - start.coeffs()).norm(), 1e-15);
  b = a;
  for (int n = 0; n < 100; ++n) {
    freeRotate(a, Vector3d(0.1, 0.2, 0.3), I, 0.01);
    freeRotate(b, Vector3d(0.1, 0.2, 0.3), I, 0.01);
  }
  EXPECT_EQ(a.coeffs(), b.coeffs());
}

}  // namespace
}  // namespace gabion::micro
