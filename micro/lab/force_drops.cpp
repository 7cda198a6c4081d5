#include "micro/lab/force_drops.hpp"

namespace gabion::micro::lab {

std::vector<ForceDrop> forceDrops(const std::vector<double>& t, const std::vector<double>& u,
                                  const std::vector<double>& f, double min_fraction, double window_s,
                                  double min_force_N) {
  std::vector<ForceDrop> out;
  const std::size_t n = f.size();
  std::size_t from = 0;  // the window never reaches back before the end of the last drop
  for (std::size_t k = 1; k < n; ++k) {
    // The largest force of the last window_s before k.
    std::size_t peak = k;
    for (std::size_t j = k; j-- > from && t[k] - t[j] <= window_s;)
      if (f[j] > f[peak]) peak = j;
    if (peak == k) continue;
    const double fall = f[peak] - f[k];
    if (fall < min_fraction * f[peak] || fall < min_force_N) continue;
    // It goes on falling, through the chatter of the contacts, until the
    // force has risen from its lowest by half the least drop, or the
    // lowest is a window old.
    std::size_t low = k;
    for (std::size_t j = k + 1; j < n; ++j) {
      if (f[j] < f[low])
        low = j;
      else if (f[j] - f[low] > 0.5 * min_fraction * f[peak] || t[j] - t[low] > window_s)
        break;
    }
    out.push_back({t[peak], u[peak], f[peak], f[low]});
    from = low;
    k = low;
  }
  return out;
}

}  // namespace gabion::micro::lab
