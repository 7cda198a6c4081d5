#pragma once
/// \file
/// The sine and cosine of an angle turned in one step. Below 1e-3 rad the
/// series s = x (1 - x^2/6 (1 - x^2/20)), c = 1 - x^2/2 (1 - x^2/12) is
/// exact to rounding (the first terms left out, x^7/5040 and x^6/720, are
/// below 2e-21 of the result) and costs a few multiplications where sin
/// and cos cost a call each; it has no branch, so a loop that takes only
/// the series vectorises. The wires' twist (bridge/laws/wire_beam.hpp) and
/// the blocks' turn (micro/rigid_body.cpp) take it.
#include <cmath>

namespace gabion::bridge {

/// Below it the series is exact to rounding (rad).
constexpr double kSmallAngle = 1e-3;

/// The series alone: for |x| < kSmallAngle.
[[gnu::always_inline]] inline void smallAngleSinCos(double x, double& s, double& c) {
  const double x2 = x * x;
  s = x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0)), c = 1.0 - 0.5 * x2 * (1.0 - x2 / 12.0);
}

/// Any angle: the series below kSmallAngle, sin and cos above.
inline void stepSinCos(double x, double& s, double& c) {
  if (std::fabs(x) < kSmallAngle) {
    smallAngleSinCos(x, s, c);
  } else {
    s = std::sin(x), c = std::cos(x);
  }
}

}  // namespace gabion::bridge
