#pragma once
/// \file
/// Block sizes to a grading (docs/blocks.md): a sieve table (size -> % passing
/// by mass) or a Gaussian of the size, sampled with a seed until a target
/// mass of rock, and the grading the sample has, to set beside the target.
/// The size of a block is its sieve size, its intermediate edge.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace gabion::micro {

/// A grading curve: sieve sizes (m, strictly increasing) and the percentage
/// by mass passing each (non-decreasing, from 0 at the first sieve to 100 at
/// the last: no block is finer than the first sieve or coarser than the last).
struct GradingTable {
  std::vector<double> sieve_m, passing_percent;
};

/// What is wrong with a table (the key and index of the bad value), or empty.
struct GradingIssue {
  std::string key, message;
  int at = -1;
};
GradingIssue checkGrading(const GradingTable& g);

/// Sizes (m) whose masses add up to target_mass_kg in the proportions of the
/// table: class by class (between two sieves) blocks of sizes drawn uniformly
/// in the class are added while that brings the class's mass closer to its
/// share. `mass_of` gives a block's mass from its size. Each class j ends
/// within h_j (half its largest block) of its share, so with H_k the sum of
/// h_j up to sieve k, H the sum over all classes, T the target and P_k the
/// table's fraction, the generated % passing at sieve k is within
/// 100 (H_k + P_k H) / (T - H) of the table. The same seed gives the same sizes.
std::vector<double> sampleGrading(const GradingTable& g, double target_mass_kg,
                                  const std::function<double(double)>& mass_of, std::uint64_t seed);

/// Sizes (m) from a Gaussian of the given mean and standard deviation,
/// truncated to mean +- 2.5 sd and to sizes above a fifth of the mean, drawn
/// until their masses reach target_mass_kg (the last one is kept if that
/// brings the total closer).
std::vector<double> sampleGaussian(double mean_m, double sd_m, double target_mass_kg,
                                   const std::function<double(double)>& mass_of, std::uint64_t seed);

/// The % passing by mass of a set of blocks (sizes and masses) at each sieve.
std::vector<double> passingPercent(const std::vector<double>& sizes_m, const std::vector<double>& masses_kg,
                                   const std::vector<double>& sieve_m);

}  // namespace gabion::micro
