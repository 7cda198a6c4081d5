#include "macro/criteria.hpp"

#include <cmath>

namespace gabion::macro {

Verdict judge(const ImpactResult& r, const Criteria& c) {
  Verdict v;
  const bool held = r.outcome == Outcome::Stopped || r.outcome == Outcome::Rebounded;
  v.back_face_ratio = std::isfinite(c.max_back_face_m) ? r.max_back_face_displacement_m / c.max_back_face_m : 0.0;
  v.penetration_ratio = std::isfinite(c.max_penetration_m) ? r.max_penetration_m / c.max_penetration_m : 0.0;
  v.met = held && v.back_face_ratio <= 1.0 && v.penetration_ratio <= 1.0;
  if (!held)
    v.failed = "held";
  else if (!v.met)
    v.failed = v.back_face_ratio >= v.penetration_ratio ? "back_face" : "penetration";
  return v;
}

const char* criterionText(const std::string& criterion) {
  if (criterion == "held") return "holding the boulder (not perforated, finished)";
  if (criterion == "back_face") return "the back face's displacement";
  if (criterion == "height") return "the wall's height (the boulder passes over it)";
  return "the penetration";
}

CapacitySearch searchCapacity(const std::function<CapacityEvaluation(double)>& run, double x_lo, double x_hi,
                              bool over_mass, double tolerance, int max_evaluations) {
  CapacitySearch s;
  auto& e = s.evaluations;
  e.push_back(run(x_lo));
  if (!e.back().verdict.met) {
    s.kind = CapacitySearch::Kind::NoneMet;
    s.bad = 0;
    return s;
  }
  e.push_back(run(x_hi));
  if (e.back().verdict.met) {
    s.kind = CapacitySearch::Kind::AllMet;
    s.good = 1;
    return s;
  }
  s.kind = CapacitySearch::Kind::Bracketed;
  s.good = 0, s.bad = 1;
  double a = x_lo, b = x_hi;
  const auto width = [&] { return e[s.bad].energy_J - e[s.good].energy_J; };
  while (width() > tolerance * e[s.good].energy_J && static_cast<int>(e.size()) < max_evaluations) {
    const double mid = over_mass ? 0.5 * (a + b) : std::sqrt(0.5 * (a * a + b * b));  // (mid-energy)
    e.push_back(run(mid));
    if (e.back().verdict.met)
      a = mid, s.good = e.size() - 1;
    else
      b = mid, s.bad = e.size() - 1;
  }
  s.converged = width() <= tolerance * e[s.good].energy_J;
  return s;
}

}  // namespace gabion::macro
