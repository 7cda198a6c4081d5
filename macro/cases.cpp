#include "macro/cases.hpp"

#include "macro/runs.hpp"

namespace gabion::macro {

std::vector<bridge::CaseKind> caseKinds() {
  return {
      {"macro.impact", "boulder impact(s) on a cellular structure, one node per cell (laws from a gabion.law/2 file)",
       checkImpactCase, runImpactCase, estimateImpactCase},
      {"macro.sweep", "a grid of macro impacts (velocity, mass, aim point, structure size) run in parallel",
       checkSweepCase, runSweepCase, estimateSweepCase, sweepRows},
      {"macro.capacity",
       "the largest impact energy a structure holds with the acceptance criteria met (bisection over velocity or mass)",
       checkCapacityCase, runCapacityCase, estimateCapacityCase},
      {"macro.design",
       "the smallest structure (thickness, height, front material) that holds the design impacts with the criteria met",
       checkDesignCase, runDesignCase, estimateDesignCase, designRows},
  };
}

}  // namespace gabion::macro
