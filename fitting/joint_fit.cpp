#include "fitting/joint_fit.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace gabion::fitting {

double shorteningAtForce(const bridge::Curve& c, double force_N) {
  // (the running largest force and where it was reached: the first loading)
  std::size_t top = 0;
  for (std::size_t k = 0; k < c.size(); ++k) {
    if (k > 0 && c.y[k] <= c.y[top]) continue;
    if (c.y[k] >= force_N) {
      if (k == 0 || c.y[top] >= force_N) return c.x[k];
      const double w = (force_N - c.y[top]) / (c.y[k] - c.y[top]);
      return c.x[top] + w * (c.x[k] - c.x[top]);
    }
    top = k;
  }
  return NAN;
}

JointFit fitJoint(const bridge::Curve& cell, const bridge::Curve& row, int cells_in_series, std::size_t levels,
                  double lowest_fraction) {
  if (cells_in_series < 2) throw std::runtime_error("a row of at least 2 cells is needed for a joint");
  const double top =
      std::min(*std::max_element(cell.y.begin(), cell.y.end()), *std::max_element(row.y.begin(), row.y.end()));
  JointFit out;
  if (!(top > 0.0)) throw std::runtime_error("the curves carry no force");
  out.force_lo_N = lowest_fraction * top, out.force_hi_N = top;
  const double joints = cells_in_series - 1;
  double sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0, n = 0;
  for (std::size_t k = 0; k < levels; ++k) {
    const double f =
        out.force_lo_N * std::pow(top / out.force_lo_N, levels > 1 ? static_cast<double>(k) / (levels - 1) : 1.0);
    const double u_row = shorteningAtForce(row, f);
    const double c = (u_row - cells_in_series * shorteningAtForce(cell, f)) / joints;
    out.force_N.push_back(f), out.closure_m.push_back(c);
    // (a closure under a thousandth of the row's shortening is nothing the
    // curves can tell from round-off)
    const bool use = c > 1e-3 * u_row;
    out.used.push_back(use);
    if (!use) continue;
    const double x = std::log(f / 1000.0), y = std::log(c);
    sx += x, sy += y, sxx += x * x, sxy += x * y, syy += y * y, n += 1;
  }
  out.points = static_cast<std::size_t>(n);
  const double det = n * sxx - sx * sx;
  if (2 * out.points < levels || n < 3 || !(det > 0.0)) {
    std::ostringstream m;
    m << "only " << out.points << " of " << levels
      << " force levels show the row shortening more than its cells alone (by a thousandth of its shortening): no "
         "joint to fit (are the row and the cell tested along the same axis, and the row given as the row?)";
    throw std::runtime_error(m.str());
  }
  const double b = (n * sxy - sx * sy) / det, a = (sy - b * sx) / n;
  out.law.exponent = b;
  out.law.closure_at_1kN_m = std::exp(a);
  const double ss_tot = syy - sy * sy / n, ss_res = syy - a * sy - b * sxy;
  out.r2 = ss_tot > 0.0 ? 1.0 - ss_res / ss_tot : 1.0;
  if (!(b > 0.0)) {
    std::ostringstream m;
    m << "the joint's closure does not grow with the force (exponent " << b << "): the curves' scatter outweighs it";
    throw std::runtime_error(m.str());
  }
  return out;
}

std::string describeJointFit(const nlohmann::json& entry) {
  const bridge::JointLawParams law{entry.at("closure_at_1kN_m").get<double>(), entry.at("exponent").get<double>()};
  const double top = entry.at("force_range_N").at(1).get<double>();
  std::ostringstream line;
  line.precision(3);
  line << "joint (power, R2 log-log " << entry.at("r2_log_log").get<double>() << ", "
       << entry.at("levels_used").get<std::size_t>() << " of " << entry.at("levels").get<std::size_t>()
       << " force levels): closure at 1 kN " << 1e3 * law.closure_at_1kN_m << " mm, exponent " << law.exponent
       << "; closure at " << 1e-3 * top << " kN " << 1e3 * bridge::jointClosure(law, top) << " mm";
  return line.str();
}

}  // namespace gabion::fitting
