#pragma once
/// \file
/// Engineers' units for what people read (tables, axes, the console): a
/// quantity named with its SI unit as suffix ("displacement_m", "force_N",
/// "stiffness_N_m", "velocity_m_s") shown in mm, kN, kN/m or m/s. Files keep
/// SI; only the display converts.
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>

namespace gabion::bridge {

/// How a quantity is shown: its name without the unit, the unit, and the
/// factor from SI to it.
struct DisplayUnit {
  std::string stem;    ///< "displacement", "tangential stiffness"
  std::string unit;    ///< "mm", "kN", "kN/m", "m/s", "s", "J", "Pa", "kg"; "-" when dimensionless
  double scale = 1.0;  ///< shown value = scale x SI value
};

inline DisplayUnit displayUnit(const std::string& name) {
  struct Rule {
    const char* suffix;
    const char* unit;
    double scale;
  };
  // Longest suffixes first: "_N_m" before "_m", "_m_s" before "_s".
  // (N s^2/m^2, a rate coefficient, is a mass per length: kg/m; N s/m, a
  // viscosity, is shown in kN s/m as a stiffness in kN/m)
  static const Rule rules[] = {{"_N_s2_m2", "kg/m", 1.0}, {"_kg_m", "kg/m", 1.0}, {"_N_s_m", "kN s/m", 1e-3},
                               {"_m_s", "m/s", 1.0},      {"_N_m", "kN/m", 1e-3}, {"_N", "kN", 1e-3},
                               {"_m", "mm", 1e3},         {"_s", "s", 1.0},       {"_J", "J", 1.0},
                               {"_Pa", "Pa", 1.0},        {"_kg", "kg", 1.0}};
  const auto spaced = [](std::string s) {
    std::replace(s.begin(), s.end(), '_', ' ');
    return s;
  };
  for (const Rule& r : rules) {
    const std::string suffix = r.suffix;
    if (name.size() > suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0)
      return {spaced(name.substr(0, name.size() - suffix.size())), r.unit, r.scale};
  }
  return {spaced(name), "-", 1.0};
}

/// A number for people: `significant` digits in plain notation (4890 kN,
/// 0.0425 mm, 14960 kN/m), scientific only below 1e-3 or from 1e9 on.
inline std::string showNumber(double v, int significant = 3) {
  if (!std::isfinite(v)) return std::isnan(v) ? "NaN" : (v > 0 ? "inf" : "-inf");
  const double a = std::fabs(v);
  std::ostringstream o;
  if (a == 0.0) return "0";
  if (a >= 1e-3 && a < 1e9) {
    const int before = static_cast<int>(std::floor(std::log10(a))) + 1;  // digits before the point
    o << std::fixed << std::setprecision(std::max(0, significant - before)) << v;
  } else {
    o << std::setprecision(significant) << v;
  }
  return o.str();
}

}  // namespace gabion::bridge
