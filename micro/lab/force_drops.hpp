#pragma once
/// \file
/// Sudden drops of a test's force (docs/lab.md, Force drops): in an
/// unconfined compression a force chain that gives way drops the force by a
/// part of its value within milliseconds, then the cell takes load again.
#include <vector>

namespace gabion::micro::lab {

struct ForceDrop {
  double time_s = 0.0;          ///< when the force began to fall
  double displacement_m = 0.0;  ///< the plate's displacement then
  double force_before_N = 0.0;  ///< the force it fell from
  double force_after_N = 0.0;   ///< the lowest force it fell to
  double size_N() const { return force_before_N - force_after_N; }
};

/// Drops of the series (t, u, f): the force falls from the largest value of
/// the last `window_s` by at least `min_fraction` of it and by at least
/// `min_force_N`. The drop runs on to the lowest force before the force
/// rises again by half of min_fraction of where it fell from (the chatter
/// of the contacts does not split one drop in several), or to a lowest that
/// stays the lowest for a window. A slow softening (a fall spread over more
/// than the window) is no drop.
std::vector<ForceDrop> forceDrops(const std::vector<double>& t, const std::vector<double>& u,
                                  const std::vector<double>& f, double min_fraction, double window_s,
                                  double min_force_N);

}  // namespace gabion::micro::lab
