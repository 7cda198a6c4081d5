// Engineers' units for display: the SI suffix of a name decides the unit and
// the factor; the longer suffix wins ("_N_m" over "_m", "_m_s" over "_s").
#include <gtest/gtest.h>

#include <cmath>

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
               {"viscosity_N_s_m", "viscosity", "kN s/m", 1e-3},
               {"rate_coefficient_N_s2_m2", "rate coefficient", "kg/m", 1.0},
               {"momentum_flux_kg_m", "momentum flux", "kg/m", 1.0},
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

// Numbers for people: plain notation with the significant digits asked for
// (no "4.89e+03 kN"), scientific only for the very small or very large.
TEST(DisplayUnit, NumbersInPlainNotation) {
  using gabion::bridge::showNumber;
  EXPECT_EQ(showNumber(4886.2), "4886");
  EXPECT_EQ(showNumber(14964.3, 4), "14964");
  EXPECT_EQ(showNumber(472.04), "472");
  EXPECT_EQ(showNumber(5.886), "5.89");
  EXPECT_EQ(showNumber(0.0426), "0.0426");
  EXPECT_EQ(showNumber(-12.345, 4), "-12.35");
  EXPECT_EQ(showNumber(0.0), "0");
  EXPECT_EQ(showNumber(6.2e-4, 2), "0.00062");
  EXPECT_EQ(showNumber(3.1e12), "3.1e+12");
  EXPECT_EQ(showNumber(std::nan("")), "NaN");
}
