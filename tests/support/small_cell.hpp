#pragma once
// The 0.3 m cell the lab and pipeline tests start from: about 45 blocks of
// 60-90 mm in a netting basket, with short stages (a few seconds to build).
#include <string>

namespace gabion::testing {

inline std::string smallCellCase() {
  return R"({"format": "gabion.case/1", "kind": "micro.cell", "edge_m": 0.3, "seed": 3,
 "rock": {"density_kg_m3": 2600, "normal_stiffness_N_m": 1e6, "shear_stiffness_N_m": 2.5e5, "friction": 0.5,
          "local_damping": 0.1, "viscous_damping_ratio": 0.1},
 "blocks": {"grading": {"sieve_m": [0.06, 0.075, 0.09], "passing_percent": [0, 50, 100]}},
 "netting": {"contact": {"normal_stiffness_N_m": 1e6, "shear_stiffness_N_m": 2.5e5, "friction": 0.5, "local_damping": 0.1}},
 "fill": {"max_duration_s": 0.35, "friction": 0.1},
 "vibration": {"max_duration_s": 0.1, "check_interval_s": 0.05},
 "closing": {"max_duration_s": 0.1},
 "standing": {"max_duration_s": 0.1},
 "run": {"output_interval_s": 0.05, "series_interval_s": 0.005}})";
}

}  // namespace gabion::testing
