#pragma once
/// \file
/// Engineers' units for what people read (tables, axes, the console): a
/// quantity named with its SI unit as suffix ("displacement_m", "force_N",
/// "stiffness_N_m", "velocity_m_s") shown in mm, kN, kN/m or m/s. Files keep
/// SI; only the display converts.
#include <algorithm>
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
  static const Rule rules[] = {{"_m_s", "m/s", 1.0}, {"_N_m", "kN/m", 1e-3}, {"_N", "kN", 1e-3}, {"_m", "mm", 1e3},
                               {"_s", "s", 1.0},     {"_J", "J", 1.0},       {"_Pa", "Pa", 1.0}, {"_kg", "kg", 1.0}};
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

}  // namespace gabion::bridge
