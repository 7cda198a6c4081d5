#pragma once
// Synthetic curves from known law parameters plus Gaussian noise, for the
// recovery tests of the fitting. The model is evaluated with the same pure
// functions the fit uses (bridge::axialResponse), so the truth is exact.
#include <random>
#include <vector>

#include "bridge/curve.hpp"
#include "bridge/laws/cell_axial_law.hpp"

namespace gabion::testing {

/// A loading path 0 -> a, back to b, then to c, with `n` points per leg.
inline std::vector<double> cyclicPath(double a, double b, double c, int n) {
  std::vector<double> u;
  for (int i = 0; i <= n; ++i) u.push_back(a * i / n);
  for (int i = 1; i <= n; ++i) u.push_back(a + (b - a) * i / n);
  for (int i = 1; i <= n; ++i) u.push_back(b + (c - b) * i / n);
  return u;
}

inline std::vector<double> monotonicPath(double a, int n) {
  std::vector<double> u;
  for (int i = 0; i <= n; ++i) u.push_back(a * i / n);
  return u;
}

/// Axial-law curve along `path` with noise of standard deviation `sigma_N`.
inline bridge::Curve axialCurve(const bridge::AxialLawParams& p, const std::vector<double>& path, double sigma_N,
                                unsigned seed, const std::string& x_name = "displacement_m") {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  bridge::Curve c;
  c.source = "synthetic";
  c.x_name = x_name;
  c.y_name = "force_N";
  double plastic = 0.0;
  for (double u : path) {
    const auto r = bridge::axialResponse(p, u, plastic);
    plastic = r.plastic_m;
    c.x.push_back(u);
    c.y.push_back(r.force_N + sigma_N * noise(rng));
  }
  return c;
}

/// A confined compression at the constant plate speed `v` to `u_max`, with
/// its time axis: the axial law `p` plus its momentum flux at that rate
/// (bridge::fillRateForce), as the macro model adds them, with noise of
/// standard deviation `sigma_N`; `n` points.
inline bridge::Curve compressionAtSpeed(const bridge::AxialLawParams& p, double v, double u_max, int n, double sigma_N,
                                        unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  bridge::Curve c;
  c.source = "synthetic compression";
  c.x_name = "displacement_m";
  c.y_name = "force_N";
  double plastic = 0.0;
  for (int i = 0; i <= n; ++i) {
    const double u = u_max * i / n;
    const auto r = bridge::axialResponse(p, u, plastic);
    plastic = r.plastic_m;
    const double flux = bridge::fillRateForce(0.0, p.momentum_flux_kg_m, p.momentum_flux_growth_m, u, v, r.force_N);
    c.t.push_back(u / v);
    c.x.push_back(u);
    c.y.push_back(r.force_N + flux + sigma_N * noise(rng));
  }
  return c;
}

/// An impact's indentation curve with its time axis: u(t) = v0 (t - t^2 / (2T))
/// over [0, T], a boulder slowing at a constant rate from v0 to rest, the
/// force the law `p` gives at the rate du/dt (its rate term, if any), with
/// noise of standard deviation `sigma_N`; `n` points.
inline bridge::Curve impactCurve(const bridge::AxialLawParams& p, double v0, double T, int n, double sigma_N,
                                 unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  bridge::Curve c;
  c.source = "synthetic impact";
  c.x_name = "indentation_m";
  c.y_name = "force_N";
  double plastic = 0.0;
  for (int i = 0; i <= n; ++i) {
    const double t = T * i / n, u = v0 * (t - 0.5 * t * t / T), rate = v0 * (1.0 - t / T);
    const auto r = bridge::axialResponse(p, u, plastic, rate);
    plastic = r.plastic_m;
    c.t.push_back(t);
    c.x.push_back(u);
    c.y.push_back(r.force_N + sigma_N * noise(rng));
  }
  return c;
}

inline bridge::AxialLawParams epp(double k, double fy) {
  bridge::AxialLawParams p;
  p.stiffness_N_m = k;
  p.yield_force_N = fy;
  return p;
}

inline bridge::AxialLawParams bilinear(double k, double fy, double kh) {
  bridge::AxialLawParams p = epp(k, fy);
  p.model = bridge::AxialModel::Bilinear;
  p.hardening_stiffness_N_m = kh;
  return p;
}

}  // namespace gabion::testing
