#pragma once
/// \file
/// Acceptance criteria of an impact (the boulder held, the back face and the
/// penetration within their limits) and the capacity search built on them:
/// the largest impact a structure holds, by bisection over the boulder's
/// velocity or mass. Shared by `macro.capacity` and `macro.design`
/// (docs/macro.md, Capacity and Design).
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "macro/impact.hpp"

namespace gabion::macro {

/// The acceptance criteria; an infinite limit is not checked. "held" (not
/// perforated, not unfinished) always is.
struct Criteria {
  double max_back_face_m = std::numeric_limits<double>::infinity();
  double max_penetration_m = std::numeric_limits<double>::infinity();
};

/// What one impact says of the criteria.
struct Verdict {
  bool met = false;
  /// The criterion it failed by the most: "held", "back_face" or
  /// "penetration" (empty when met).
  std::string failed;
  double back_face_ratio = 0.0;    ///< max back-face displacement / its limit (0 without a limit)
  double penetration_ratio = 0.0;  ///< max penetration / its limit (0 without a limit)
};

/// Judges a (successful) impact against the criteria.
Verdict judge(const ImpactResult& r, const Criteria& c);
/// A criterion's name for people: "the back face's displacement", ...
const char* criterionText(const std::string& criterion);

/// One impact of a capacity search: at x (a velocity or a mass), its energy.
struct CapacityEvaluation {
  double x = 0.0, energy_J = 0.0;
  ImpactResult result;
  Verdict verdict;
};

/// The search's answer. `evaluations` in the order they ran.
struct CapacitySearch {
  enum class Kind { NoneMet, AllMet, Bracketed } kind = Kind::NoneMet;
  std::vector<CapacityEvaluation> evaluations;
  std::size_t good = 0, bad = 0;  ///< Bracketed: the highest that met, the lowest that did not; NoneMet: bad = lowest;
                                  ///< AllMet: good = highest
  bool converged = false;         ///< Bracketed: the bracket's energies within the tolerance
};

/// Bisection between x_lo and x_hi: the energy grows with x (as x^2 over
/// velocity, as x over mass), so it keeps a point that meets every criterion
/// and one that does not, halving the bracket's energy (`over_mass`: in x;
/// otherwise at the energy's midpoint) until its energies are within
/// `tolerance` of each other or `max_evaluations` impacts have run. `run`
/// runs one impact; it must return ok results (it throws otherwise).
CapacitySearch searchCapacity(const std::function<CapacityEvaluation(double)>& run, double x_lo, double x_hi,
                              bool over_mass, double tolerance, int max_evaluations);

}  // namespace gabion::macro
