#include "micro/blocks/grading.hpp"

#include <algorithm>
#include <cmath>
#include <random>

namespace gabion::micro {
namespace {

// A uniform number in [0, 1) from the generator's top 53 bits (the same
// sequence on every platform, unlike std::uniform_real_distribution).
double uniform(std::mt19937_64& rng) {
  return static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

// A standard normal number (Box-Muller from two portable uniforms).
double normal(std::mt19937_64& rng) {
  const double u1 = 1.0 - uniform(rng), u2 = uniform(rng);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * 3.14159265358979323846 * u2);
}

}  // namespace

GradingIssue checkGrading(const GradingTable& g) {
  if (g.sieve_m.size() < 2 || g.sieve_m.size() != g.passing_percent.size())
    return {"passing_percent", "needs at least two sieves and one percentage per sieve", -1};
  for (std::size_t k = 0; k < g.sieve_m.size(); ++k) {
    const int i = static_cast<int>(k);
    if (!(g.sieve_m[k] > 0.0) || !std::isfinite(g.sieve_m[k])) return {"sieve_m", "must be finite and > 0", i};
    if (k > 0 && !(g.sieve_m[k] > g.sieve_m[k - 1])) return {"sieve_m", "sieve sizes must increase strictly", i};
    const double p = g.passing_percent[k];
    if (!(p >= 0.0 && p <= 100.0)) return {"passing_percent", "must be in [0, 100]", i};
    if (k > 0 && p < g.passing_percent[k - 1]) return {"passing_percent", "must not decrease", i};
  }
  if (g.passing_percent.front() != 0.0)
    return {"passing_percent", "the first sieve must pass 0 % (no block finer than it is made)", 0};
  if (g.passing_percent.back() != 100.0)
    return {"passing_percent", "the last sieve must pass 100 % (no block coarser than it is made)",
            static_cast<int>(g.passing_percent.size()) - 1};
  return {};
}

std::vector<double> sampleGrading(const GradingTable& g, double target_mass_kg,
                                  const std::function<double(double)>& mass_of, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<double> sizes;
  for (std::size_t k = 1; k < g.sieve_m.size(); ++k) {
    const double share = (g.passing_percent[k] - g.passing_percent[k - 1]) / 100.0 * target_mass_kg;
    double mass = 0.0;
    while (true) {
      const double d = g.sieve_m[k - 1] + (g.sieve_m[k] - g.sieve_m[k - 1]) * uniform(rng);
      const double m = mass_of(d);
      if (mass + 0.5 * m > share) break;  // it would take the class further from its share
      sizes.push_back(d);
      mass += m;
    }
  }
  return sizes;
}

std::vector<double> sampleGaussian(double mean_m, double sd_m, double target_mass_kg,
                                   const std::function<double(double)>& mass_of, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const double lo = std::max(0.2 * mean_m, mean_m - 2.5 * sd_m), hi = mean_m + 2.5 * sd_m;
  std::vector<double> sizes;
  double mass = 0.0;
  while (true) {
    double d = mean_m + sd_m * normal(rng);
    if (d < lo || d > hi) continue;
    const double m = mass_of(d);
    if (mass + 0.5 * m > target_mass_kg) break;
    sizes.push_back(d);
    mass += m;
  }
  return sizes;
}

std::vector<double> passingPercent(const std::vector<double>& sizes_m, const std::vector<double>& masses_kg,
                                   const std::vector<double>& sieve_m) {
  double total = 0.0;
  for (const double m : masses_kg) total += m;
  std::vector<double> out;
  for (const double s : sieve_m) {
    double passing = 0.0;
    for (std::size_t b = 0; b < sizes_m.size(); ++b)
      if (sizes_m[b] <= s) passing += masses_kg[b];
    out.push_back(total > 0.0 ? 100.0 * passing / total : 0.0);
  }
  return out;
}

}  // namespace gabion::micro
