#include "micro/rigid_body.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <queue>
#include <stdexcept>
#include <string>

#include "bridge/small_angle.hpp"

namespace gabion::micro {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kTwoPi = 2.0 * kPi;

// ---------------------------------------------------------------------------
// Slice moments. A plane x = const cuts the cluster into a union of disks in
// the (y, z) plane. By Green's theorem the integral of f over the union is a
// sum over the boundary arcs of the disks that no other disk covers; the same
// sum over the *covered* arcs of every disk is (sum of full disks) - (union),
// the overlap correction we integrate. For f in {1, y, z, y^2, z^2, yz} the
// arc integrals are closed-form trigonometric polynomials in the arc angle.
using Slice6 = std::array<double, 6>;  // A, Sy, Sz, Syy, Szz, Syz (m^2 .. m^4)

/// Antiderivative in the arc angle t of the Green's forms (area: (y dz - z dy)/2,
/// Sy: y^2/2 dz, Sz: -z^2/2 dy, Syy: y^3/3 dz, Szz: -z^3/3 dy, Syz: y^2 z/2 dz)
/// on the circle y = cy + r cos t, z = cz + r sin t.
Slice6 arcAntiderivative(double cy, double cz, double r, double t) {
  const double s = std::sin(t), c = std::cos(t);
  const double s2 = 2.0 * s * c, c2 = c * c - s * s, s4 = 2.0 * s2 * c2;
  const double Ic = s, Is = -c;                            // int cos, int sin
  const double Icc = 0.5 * t + 0.25 * s2;                  // int cos^2
  const double Iss = 0.5 * t - 0.25 * s2;                  // int sin^2
  const double Iccc = s - s * s * s / 3.0;                 // int cos^3
  const double Isss = -c + c * c * c / 3.0;                // int sin^3
  const double Icccc = 0.375 * t + 0.25 * s2 + s4 / 32.0;  // int cos^4
  const double Issss = 0.375 * t - 0.25 * s2 + s4 / 32.0;  // int sin^4
  const double Isc = 0.5 * s * s;                          // int sin cos
  const double Iscc = -c * c * c / 3.0;                    // int sin cos^2
  const double Isccc = -c * c * c * c / 4.0;               // int sin cos^3
  const double r2 = r * r, r3 = r2 * r;
  Slice6 F;
  F[0] = 0.5 * (r2 * t + r * cy * Ic + r * cz * Is);
  F[1] = 0.5 * r * (cy * cy * Ic + 2.0 * cy * r * Icc + r2 * Iccc);
  F[2] = 0.5 * r * (cz * cz * Is + 2.0 * cz * r * Iss + r2 * Isss);
  F[3] = r / 3.0 * (cy * cy * cy * Ic + 3.0 * cy * cy * r * Icc + 3.0 * cy * r2 * Iccc + r3 * Icccc);
  F[4] = r / 3.0 * (cz * cz * cz * Is + 3.0 * cz * cz * r * Iss + 3.0 * cz * r2 * Isss + r3 * Issss);
  F[5] = 0.5 * r *
         (cy * cy * cz * Ic + cy * cy * r * Isc + 2.0 * cy * cz * r * Icc + 2.0 * cy * r2 * Iscc + r2 * cz * Iccc +
          r3 * Isccc);
  return F;
}

/// Moments of a full disk of radius r centred at (cy, cz).
Slice6 fullDisk(double cy, double cz, double r) {
  const double A = kPi * r * r, q = 0.25 * r * r;
  return {A, A * cy, A * cz, A * (cy * cy + q), A * (cz * cz + q), A * cy * cz};
}

struct Sphere {
  Eigen::Vector3d c;
  double r;
};

/// Evaluates the overlap correction of one slice; keeps its buffers between calls.
class OverlapSlicer {
 public:
  OverlapSlicer(const std::vector<Sphere>& spheres, std::vector<std::vector<int>> neighbours)
      : spheres_(spheres), neighbours_(std::move(neighbours)) {
    disk_r_.assign(spheres_.size(), 0.0);
  }

  /// (sum of disks) - (union of disks) on the plane x, as 10 integrand
  /// components: A, xA, Sy, Sz, x^2 A, Syy, Szz, x Sy, x Sz, Syz.
  std::array<double, 10> correction(double x) {
    const std::size_t n = spheres_.size();
    for (std::size_t i = 0; i < n; ++i) {
      const double dx = x - spheres_[i].c.x();
      const double r2 = spheres_[i].r * spheres_[i].r - dx * dx;
      disk_r_[i] = r2 > 0.0 ? std::sqrt(r2) : 0.0;
    }
    Slice6 C{};
    for (std::size_t i = 0; i < n; ++i) {
      const double ri = disk_r_[i];
      if (ri <= 0.0 || neighbours_[i].empty()) continue;
      const double yi = spheres_[i].c.y(), zi = spheres_[i].c.z();
      arcs_.clear();
      bool fully_covered = false;
      for (int j : neighbours_[i]) {
        const double rj = disk_r_[static_cast<std::size_t>(j)];
        if (rj <= 0.0) continue;
        const double dy = spheres_[static_cast<std::size_t>(j)].c.y() - yi;
        const double dz = spheres_[static_cast<std::size_t>(j)].c.z() - zi;
        const double d = std::sqrt(dy * dy + dz * dz);
        if (d >= ri + rj) continue;  // disjoint disks
        if (d + ri <= rj) {
          // Disk i inside disk j. Identical disks: the lower index covers.
          if (d + rj <= ri && j > static_cast<int>(i)) continue;
          fully_covered = true;
          break;
        }
        if (d + rj <= ri) continue;  // j inside i covers no boundary of i
        const double cos_a = std::clamp((ri * ri + d * d - rj * rj) / (2.0 * ri * d), -1.0, 1.0);
        const double half = std::acos(cos_a);
        const double mid = std::atan2(dz, dy);
        addArc(mid - half, mid + half);
      }
      if (fully_covered) {
        const Slice6 D = fullDisk(yi, zi, ri);
        for (int k = 0; k < 6; ++k) C[k] += D[k];
        continue;
      }
      if (arcs_.empty()) continue;
      std::sort(arcs_.begin(), arcs_.end());
      double a = arcs_[0].first, b = arcs_[0].second;
      for (std::size_t k = 1; k <= arcs_.size(); ++k) {
        if (k < arcs_.size() && arcs_[k].first <= b) {
          b = std::max(b, arcs_[k].second);
          continue;
        }
        const Slice6 Fb = arcAntiderivative(yi, zi, ri, b);
        const Slice6 Fa = arcAntiderivative(yi, zi, ri, a);
        for (int m = 0; m < 6; ++m) C[m] += Fb[m] - Fa[m];
        if (k < arcs_.size()) {
          a = arcs_[k].first;
          b = arcs_[k].second;
        }
      }
    }
    return {C[0], x * C[0], C[1], C[2], x * x * C[0], C[3], C[4], x * C[1], x * C[2], C[5]};
  }

 private:
  // Arcs are kept in [-pi, 3pi) after wrapping into [0, 2pi) starts.
  void addArc(double a, double b) {
    while (a < 0.0) {
      a += kTwoPi;
      b += kTwoPi;
    }
    while (a >= kTwoPi) {
      a -= kTwoPi;
      b -= kTwoPi;
    }
    if (b > kTwoPi) {
      arcs_.emplace_back(a, kTwoPi);
      arcs_.emplace_back(0.0, b - kTwoPi);
    } else {
      arcs_.emplace_back(a, b);
    }
  }

  const std::vector<Sphere>& spheres_;
  std::vector<std::vector<int>> neighbours_;
  std::vector<double> disk_r_;
  std::vector<std::pair<double, double>> arcs_;
};

// ---------------------------------------------------------------------------
// Adaptive Gauss-Kronrod (7-15) along x with a global priority queue
// (QUADPACK QAG strategy), vector-valued integrand, per-group tolerances.
constexpr int kComponents = 10;
using Vec10 = std::array<double, kComponents>;

// Kronrod 15-point nodes (positive half, descending) and weights; Gauss 7-point weights.
constexpr double kXgk[8] = {0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
                            0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
                            0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
                            0.207784955007898467600689403773245, 0.000000000000000000000000000000000};
constexpr double kWgk[8] = {0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
                            0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
                            0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
                            0.204432940075298892414161999234649, 0.209482141084727828012999174891714};
constexpr double kWg[4] = {0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
                           0.381830050505118944950369775488975, 0.417959183673469387755102040816327};

struct Segment {
  double a, b;
  Vec10 value, error;
  double priority;
  bool operator<(const Segment& o) const { return priority < o.priority; }
};

Segment integrateSegment(OverlapSlicer& slicer, double a, double b) {
  const double mid = 0.5 * (a + b), half = 0.5 * (b - a);
  Vec10 kron{}, gauss{};
  const Vec10 fc = slicer.correction(mid);
  for (int k = 0; k < kComponents; ++k) {
    kron[k] = kWgk[7] * fc[k];
    gauss[k] = kWg[3] * fc[k];
  }
  for (int j = 0; j < 7; ++j) {
    const Vec10 f1 = slicer.correction(mid - half * kXgk[j]);
    const Vec10 f2 = slicer.correction(mid + half * kXgk[j]);
    for (int k = 0; k < kComponents; ++k) {
      const double s = f1[k] + f2[k];
      kron[k] += kWgk[j] * s;
      if (j % 2 == 1) gauss[k] += kWg[j / 2] * s;
    }
  }
  Segment seg{a, b, {}, {}, 0.0};
  for (int k = 0; k < kComponents; ++k) {
    seg.value[k] = kron[k] * half;
    seg.error[k] = std::abs((kron[k] - gauss[k]) * half);
  }
  return seg;
}

// Component groups of the 10-vector: volume (0), first moments (1-3), second moments (4-9).
constexpr int kGroup[kComponents] = {0, 1, 1, 1, 2, 2, 2, 2, 2, 2};

struct Moments {
  double V = 0;
  Eigen::Vector3d M1 = Eigen::Vector3d::Zero();  // int x dV
  Eigen::Matrix3d M2 = Eigen::Matrix3d::Zero();  // int x x^T dV
};

Moments subtract(const Moments& sum, const Vec10& C) {
  Moments m = sum;
  m.V -= C[0];
  m.M1 -= Eigen::Vector3d(C[1], C[2], C[3]);
  m.M2(0, 0) -= C[4];
  m.M2(1, 1) -= C[5];
  m.M2(2, 2) -= C[6];
  m.M2(0, 1) -= C[7];
  m.M2(0, 2) -= C[8];
  m.M2(1, 2) -= C[9];
  m.M2(1, 0) = m.M2(0, 1);
  m.M2(2, 0) = m.M2(0, 2);
  m.M2(2, 1) = m.M2(1, 2);
  return m;
}

/// Absolute error targets per group from the current estimate of the union.
std::array<double, 3> targets(const Moments& m, double rel_tol) {
  // A grossly wrong early estimate (V <= 0) gives tiny targets: refinement goes on.
  constexpr double tiny = std::numeric_limits<double>::min();
  const double V = std::max(m.V, tiny);
  const Eigen::Vector3d c = m.M1 / V;
  const double trace_c = std::max((m.M2 - V * c * c.transpose()).trace(), 0.0);
  const double rg = std::sqrt(trace_c / V);
  // Half the tolerance: the error estimate is itself only an estimate.
  return {std::max(0.5 * rel_tol * V, tiny), std::max(0.5 * rel_tol * V * rg, tiny),
          std::max(0.5 * rel_tol * trace_c, tiny)};
}

double priorityOf(const Vec10& err, const std::array<double, 3>& t) {
  double p = 0.0;
  for (int k = 0; k < kComponents; ++k) p += err[k] / t[kGroup[k]];
  return p;
}

void requireFinite(double v, const std::string& what) {
  if (!std::isfinite(v)) throw std::invalid_argument(what + " must be finite");
}

}  // namespace

MassProperties clusterMassProperties(const std::vector<Eigen::Vector3d>& centers, const std::vector<double>& radii,
                                     double density_kg_m3, double rel_tol) {
  if (centers.empty()) throw std::invalid_argument("clusterMassProperties: no spheres");
  if (centers.size() != radii.size())
    throw std::invalid_argument("clusterMassProperties: " + std::to_string(centers.size()) + " centres but " +
                                std::to_string(radii.size()) + " radii");
  requireFinite(density_kg_m3, "clusterMassProperties: density");
  if (density_kg_m3 <= 0.0) throw std::invalid_argument("clusterMassProperties: density must be > 0");
  if (!(rel_tol >= 1e-12 && rel_tol <= 0.1))
    throw std::invalid_argument("clusterMassProperties: rel_tol must be in [1e-12, 0.1]");
  for (std::size_t i = 0; i < centers.size(); ++i) {
    const std::string tag = "clusterMassProperties: sphere " + std::to_string(i);
    for (int k = 0; k < 3; ++k) requireFinite(centers[i][k], tag + " centre");
    requireFinite(radii[i], tag + " radius");
    if (radii[i] <= 0.0) throw std::invalid_argument(tag + " radius must be > 0");
  }

  // Work about the volume-weighted mean of the centres: keeps the second
  // moments free of cancellation for a cluster far from the origin.
  Eigen::Vector3d p0 = Eigen::Vector3d::Zero();
  double wsum = 0.0;
  for (std::size_t i = 0; i < centers.size(); ++i) {
    const double w = radii[i] * radii[i] * radii[i];
    p0 += w * centers[i];
    wsum += w;
  }
  p0 /= wsum;

  // Drop spheres inside another one (they add nothing to the union); of two
  // identical spheres the first is kept.
  std::vector<Sphere> spheres;
  for (std::size_t i = 0; i < centers.size(); ++i) {
    bool inside = false;
    for (std::size_t j = 0; j < centers.size() && !inside; ++j) {
      if (j == i) continue;
      const double d = (centers[i] - centers[j]).norm();
      const bool identical = d == 0.0 && radii[i] == radii[j];
      inside = identical ? j < i : d + radii[i] <= radii[j];
    }
    if (!inside) spheres.push_back({centers[i] - p0, radii[i]});
  }

  // Exact sum over the spheres: int x x^T over a ball = V (c c^T + r^2/5 I).
  Moments sum;
  for (const Sphere& s : spheres) {
    const double V = sphereVolume(s.r);
    sum.V += V;
    sum.M1 += V * s.c;
    sum.M2 += V * (s.c * s.c.transpose() + 0.2 * s.r * s.r * Eigen::Matrix3d::Identity());
  }

  // Overlapping pairs, the x-ranges of their lenses (where the correction is
  // non-zero) and the first segment ends: ball ends, where the slice
  // correction has kinks, and the ends of narrow lenses.
  std::vector<std::vector<int>> neighbours(spheres.size());
  std::vector<std::pair<double, double>> supports;
  std::vector<double> breaks;
  double r_max = 0.0;
  for (const Sphere& s : spheres) {
    r_max = std::max(r_max, s.r);
    breaks.push_back(s.c.x() - s.r);
    breaks.push_back(s.c.x() + s.r);
  }
  // Segments are at most 2 r_max wide; the widest gap of the 15 Kronrod nodes
  // is 0.104 of the segment.
  const double small_lens_m = 0.25 * r_max;
  for (std::size_t i = 0; i < spheres.size(); ++i) {
    for (std::size_t j = i + 1; j < spheres.size(); ++j) {
      const Sphere &si = spheres[i], &sj = spheres[j];
      const Eigen::Vector3d dv = sj.c - si.c;
      const double d = dv.norm();
      if (d >= si.r + sj.r) continue;
      neighbours[i].push_back(static_cast<int>(j));
      neighbours[j].push_back(static_cast<int>(i));
      // x-range of the lens: its extremes lie on the intersection circle or
      // are a ball's own extreme point that lies inside the other ball.
      const Eigen::Vector3d n = dv / d;
      const double a = (d * d + si.r * si.r - sj.r * sj.r) / (2.0 * d);
      const double rho = std::sqrt(std::max(0.0, si.r * si.r - a * a));
      const double cx = si.c.x() + a * n.x();
      const double ext = rho * std::sqrt(std::max(0.0, 1.0 - n.x() * n.x()));
      double lo = cx - ext, hi = cx + ext;
      for (const auto& [p, q] : {std::pair{&si, &sj}, std::pair{&sj, &si}}) {
        const Eigen::Vector3d ex = Eigen::Vector3d::UnitX() * p->r;
        if ((p->c - ex - q->c).norm() < q->r) lo = std::min(lo, p->c.x() - p->r);
        if ((p->c + ex - q->c).norm() < q->r) hi = std::max(hi, p->c.x() + p->r);
      }
      supports.emplace_back(lo, hi);
      // A lens narrower than the node spacing of one Gauss-Kronrod segment
      // could fall between the nodes: it gets its own segment.
      if (hi - lo < small_lens_m) {
        breaks.push_back(lo);
        breaks.push_back(hi);
      }
    }
  }

  Moments uni = sum;
  if (!supports.empty()) {
    // Merge the supports, then split them at every event inside.
    std::sort(supports.begin(), supports.end());
    std::vector<std::pair<double, double>> merged{supports.front()};
    for (const auto& s : supports) {
      if (s.first <= merged.back().second)
        merged.back().second = std::max(merged.back().second, s.second);
      else
        merged.push_back(s);
    }
    std::sort(breaks.begin(), breaks.end());
    OverlapSlicer slicer(spheres, std::move(neighbours));
    std::vector<Segment> initial;
    for (const auto& [lo, hi] : merged) {
      double a = lo;
      for (double b : breaks) {
        if (b <= a || b >= hi) continue;
        initial.push_back(integrateSegment(slicer, a, b));
        a = b;
      }
      initial.push_back(integrateSegment(slicer, a, hi));
    }
    Vec10 total{}, error{};
    for (const Segment& s : initial)
      for (int k = 0; k < kComponents; ++k) {
        total[k] += s.value[k];
        error[k] += s.error[k];
      }
    const std::array<double, 3> t0 = targets(subtract(sum, total), rel_tol);
    std::priority_queue<Segment> queue;
    for (Segment& s : initial) {
      s.priority = priorityOf(s.error, t0);
      queue.push(s);
    }
    const double min_width = 1e-13 * std::sqrt(sum.M2.trace() / sum.V);
    constexpr int kMaxSegments = 50000;
    for (;;) {
      const std::array<double, 3> t = targets(subtract(sum, total), rel_tol);
      bool done = true;
      for (int k = 0; k < kComponents; ++k) done = done && error[k] <= t[kGroup[k]];
      if (done) break;
      if (static_cast<int>(queue.size()) >= kMaxSegments || queue.top().b - queue.top().a < min_width)
        throw std::runtime_error("clusterMassProperties: rel_tol " + std::to_string(rel_tol) + " not reached");
      const Segment worst = queue.top();
      queue.pop();
      const double m = 0.5 * (worst.a + worst.b);
      Segment left = integrateSegment(slicer, worst.a, m);
      Segment right = integrateSegment(slicer, m, worst.b);
      for (int k = 0; k < kComponents; ++k) {
        total[k] += left.value[k] + right.value[k] - worst.value[k];
        error[k] += left.error[k] + right.error[k] - worst.error[k];
      }
      left.priority = priorityOf(left.error, t0);
      right.priority = priorityOf(right.error, t0);
      queue.push(left);
      queue.push(right);
    }
    uni = subtract(sum, total);
  }

  MassProperties out;
  out.volume_m3 = uni.V;
  out.mass_kg = density_kg_m3 * uni.V;
  const Eigen::Vector3d c = uni.M1 / uni.V;
  out.center_m = p0 + c;
  const Eigen::Matrix3d M2c = uni.M2 - uni.V * c * c.transpose();
  Eigen::Matrix3d J = density_kg_m3 * (M2c.trace() * Eigen::Matrix3d::Identity() - M2c);
  J = 0.5 * (J + J.transpose()).eval();
  out.inertia_kg_m2 = J;

  // Eigenvalues ascending; degenerate moments still give an orthonormal basis.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(J);
  if (eig.info() != Eigen::Success) throw std::runtime_error("clusterMassProperties: eigen-solver failed");
  Eigen::Matrix3d R = eig.eigenvectors();
  if (R.determinant() < 0.0) R.col(2) = -R.col(2);
  out.principal_moments_kg_m2 = eig.eigenvalues();
  out.principal_axes = Eigen::Quaterniond(R).normalized();
  return out;
}

std::vector<Eigen::Vector3d> principalFrameOffsets(const MassProperties& props,
                                                   const std::vector<Eigen::Vector3d>& centers) {
  const Eigen::Matrix3d Rt = props.principal_axes.toRotationMatrix().transpose();
  std::vector<Eigen::Vector3d> out;
  out.reserve(centers.size());
  for (const Eigen::Vector3d& c : centers) out.push_back(Rt * (c - props.center_m));
  return out;
}

namespace {

/// Exact flow of L_i^2/(2 I_i) for a time with body-axis rotation angle
/// `angle`: the body turns about its axis i (q <- q * rot_i(angle)) while the
/// body-frame momentum turns the other way so that q Lb stays the same.
inline void rotateAboutBodyAxis(int i, double angle, Eigen::Quaterniond& q, Eigen::Vector3d& Lb) {
  double sh = 0.0, ch = 1.0;
  bridge::stepSinCos(0.5 * angle, sh, ch);  // (a step turns a block by far less than 1e-3 rad)
  // q * (ch, sh e_i): (w ch - sh u_i, ch u + sh (w e_i + u x e_i)).
  const int j = (i + 1) % 3, k = (i + 2) % 3;
  const double w = q.w(), ui = q.vec()[i], uj = q.vec()[j], uk = q.vec()[k];
  q.w() = w * ch - sh * ui;
  q.vec()[i] = ui * ch + sh * w;
  q.vec()[j] = uj * ch + sh * uk;  // (u x e_i)_j = u_k
  q.vec()[k] = uk * ch - sh * uj;  // (u x e_i)_k = -u_j
  const double c = ch * ch - sh * sh, s = 2.0 * sh * ch;
  const double lj = Lb[j], lk = Lb[k];
  Lb[j] = c * lj + s * lk;
  Lb[k] = -s * lj + c * lk;
}

void requirePositiveInertia(const Eigen::Vector3d& I) {
  for (int k = 0; k < 3; ++k)
    if (!(std::isfinite(I[k]) && I[k] > 0.0))
      throw std::invalid_argument("rigid body: principal moments must be finite and > 0");
}

}  // namespace

void freeRotate(Eigen::Quaterniond& q, const Eigen::Vector3d& L_world, const Eigen::Vector3d& I_principal, double dt) {
  requirePositiveInertia(I_principal);
  const double Imax = I_principal.maxCoeff(), Imin = I_principal.minCoeff();
  if (Imax - Imin <= 1e-12 * Imax) {
    // Isotropic: omega = L / I is constant in the world; rotate exactly.
    const double Lnorm = L_world.norm();
    if (Lnorm > 0.0) q = Eigen::Quaterniond(Eigen::AngleAxisd(Lnorm / Imax * dt, L_world / Lnorm)) * q;
    q.normalize();
    return;
  }
  Eigen::Vector3d Lb = q.conjugate() * L_world;
  // Strang splitting T1/2, T2/2, T3, T2/2, T1/2 (DLM 1997): each angle uses
  // the current Lb_i, which the rotation about axis i leaves unchanged.
  rotateAboutBodyAxis(0, 0.5 * dt * Lb[0] / I_principal[0], q, Lb);
  rotateAboutBodyAxis(1, 0.5 * dt * Lb[1] / I_principal[1], q, Lb);
  rotateAboutBodyAxis(2, dt * Lb[2] / I_principal[2], q, Lb);
  rotateAboutBodyAxis(1, 0.5 * dt * Lb[1] / I_principal[1], q, Lb);
  rotateAboutBodyAxis(0, 0.5 * dt * Lb[0] / I_principal[0], q, Lb);
  q.normalize();
}

Eigen::Vector3d angularVelocityWorld(const Eigen::Quaterniond& q, const Eigen::Vector3d& L_world,
                                     const Eigen::Vector3d& I_principal) {
  const Eigen::Vector3d Lb = q.conjugate() * L_world;
  return q * Lb.cwiseQuotient(I_principal);
}

double rotationalKineticEnergy(const Eigen::Quaterniond& q, const Eigen::Vector3d& L_world,
                               const Eigen::Vector3d& I_principal) {
  const Eigen::Vector3d Lb = q.conjugate() * L_world;
  return 0.5 * Lb.dot(Lb.cwiseQuotient(I_principal));
}

}  // namespace gabion::micro
