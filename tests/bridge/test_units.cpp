// Engineers' units for display: the SI suffix of a name decides the unit and
// the factor; the longer suffix wins ("_N_m" over "_m", "_m_s" over "_s").
#include <gtest/gtest.h>

#include "bridge/units.hpp"

using gabion::bridge::displayUnit;

TEST(DisplayUnit, SiSuffixToEngineersUnit) {
  const struct {
    const char* name;
    const char* stem;
    const char* unit;
    double scale;
  } cases[] = {{"displacement_m", "displacement", "mm", 1e3},
               {"yield_force_N", "yield force", "kN", 1e-3},
               {"tangential_stiffness_N_m", "tangential stiffness", "kN/m", 1e-3},
               {"velocity_m_s", "velocity", "m/s", 1.0},
               {"time_s", "time", "s", 1.0},
               {"reaction_coefficient", "reaction coefficient", "-", 1.0},
               {"friction", "friction", "-", 1.0}};
  for (const auto& c : cases) {
    const auto u = displayUnit(c.name);
    EXPECT_EQ(u.stem, c.stem) << c.name;
    EXPECT_EQ(u.unit, c.unit) << c.name;
    EXPECT_EQ(u.scale, c.scale) << c.name;
  }
}
