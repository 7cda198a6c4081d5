// Curves of several runs side by side, for the validation and speed-vs-error
// pages (bench/lab/run.sh):
//   bench_curves plot OUT.png TITLE XLABEL YLABEL LABEL=FILE.h5:XDS:YDS[:XSCALE:YSCALE] ...
//     draws each run's curve (dataset YDS against XDS, each times its scale)
//     on one chart;
//   bench_curves points OUT.png TITLE XLABEL YLABEL LABEL=X:Y,X:Y,... ...
//     draws each labelled list of points, joined, with markers (a table
//     drawn as a chart: bench/resolved/table.py);
//   bench_curves scatter OUT.png TITLE XLABEL YLABEL LABEL=X:Y,X:Y,... ...
//     the same, markers only (runs that are not a sequence:
//     bench/resolved/joint.sh); a series given as line:LABEL=... is drawn
//     dashed (a reference, such as a target's edge);
//   bench_curves error REF.h5 RUN.h5 XDS YDS [WINDOW [XMAX]]
//     prints, as JSON, how far RUN's curve is from REF's: both taken on their
//     first loading (x while it increases), each averaged over a moving
//     window of WINDOW in x (0: as they are; the chatter of force chains
//     that form and give way is not the same in any two runs), RUN's
//     interpolated at REF's points over the x range both cover (up to XMAX
//     if given); the RMS and
//     the largest difference over the largest |y| of REF in that range;
//   bench_curves at FILE.h5 XDS YDS X
//     prints YDS at XDS = X on the curve's first loading, interpolated (a
//     number for a table: bench/resolved/cc_rate.sh).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "bridge/output.hpp"
#include "bridge/plot.hpp"

namespace {

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out(1);
  for (const char c : s) {
    if (c == sep)
      out.emplace_back();
    else
      out.back().push_back(c);
  }
  return out;
}

// The first loading of (x, y): the points while x increases.
void firstLoading(std::vector<double>& x, std::vector<double>& y) {
  std::size_t n = 1;
  while (n < x.size() && x[n] >= x[n - 1]) ++n;
  x.resize(std::min(n, x.size())), y.resize(x.size());
}

// The moving average of y over x - w/2 .. x + w/2 at each point.
std::vector<double> smooth(const std::vector<double>& x, const std::vector<double>& y, double w) {
  if (!(w > 0.0)) return y;
  std::vector<double> out(y.size());
  std::size_t lo = 0, hi = 0;
  double sum = 0.0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    while (hi < x.size() && x[hi] <= x[k] + 0.5 * w) sum += y[hi++];
    while (lo < hi && x[lo] < x[k] - 0.5 * w) sum -= y[lo++];
    out[k] = sum / static_cast<double>(hi - lo);
  }
  return out;
}

double interpolate(const std::vector<double>& x, const std::vector<double>& y, double at) {
  const auto it = std::lower_bound(x.begin(), x.end(), at);
  if (it == x.begin()) return y.front();
  if (it == x.end()) return y.back();
  const std::size_t k = static_cast<std::size_t>(it - x.begin());
  const double w = x[k] > x[k - 1] ? (at - x[k - 1]) / (x[k] - x[k - 1]) : 1.0;
  return y[k - 1] + w * (y[k] - y[k - 1]);
}

// The chart of `plot` and `points`: OUT.png TITLE XLABEL YLABEL from argv[2..5].
gabion::bridge::PlotSpec chart(char** argv) {
  gabion::bridge::PlotSpec spec;
  spec.title = argv[3];
  spec.x_label = argv[4];
  spec.y_label = argv[5];
  return spec;
}

int plot(int argc, char** argv) {
  if (argc < 7) return 2;
  gabion::bridge::PlotSpec spec = chart(argv);
  for (int a = 6; a < argc; ++a) {
    const std::string arg = argv[a];
    const auto eq = arg.find('=');
    const std::vector<std::string> f = split(arg.substr(eq + 1), ':');
    if (eq == std::string::npos || f.size() < 3) return 2;
    const double xs = f.size() > 3 ? std::atof(f[3].c_str()) : 1.0, ys = f.size() > 4 ? std::atof(f[4].c_str()) : 1.0;
    const gabion::bridge::H5Reader h(f[0]);
    gabion::bridge::PlotSeries s{arg.substr(0, eq), h.read(f[1]), h.read(f[2]),
                                 gabion::bridge::PlotSeries::Style::Line};
    for (double& v : s.x) v *= xs;
    for (double& v : s.y) v *= ys;
    spec.series.push_back(s);
  }
  gabion::bridge::writePlotPng(argv[2], spec);
  return 0;
}

int error(int argc, char** argv) {
  const gabion::bridge::H5Reader ref(argv[2]), run(argv[3]);
  std::vector<double> xr = ref.read(argv[4]), yr = ref.read(argv[5]), xu = run.read(argv[4]), yu = run.read(argv[5]);
  firstLoading(xr, yr);
  firstLoading(xu, yu);
  const double window = argc > 6 ? std::atof(argv[6]) : 0.0;
  yr = smooth(xr, yr, window);
  yu = smooth(xu, yu, window);
  double hi = std::min(xr.back(), xu.back());
  if (argc > 7) hi = std::min(hi, std::atof(argv[7]));
  double scale = 0.0;  // (over the range compared)
  for (std::size_t k = 0; k < xr.size() && xr[k] <= hi; ++k) scale = std::max(scale, std::fabs(yr[k]));
  double sum = 0.0, worst = 0.0;
  std::size_t n = 0;
  for (std::size_t k = 0; k < xr.size() && xr[k] <= hi; ++k) {
    const double d = interpolate(xu, yu, xr[k]) - yr[k];
    sum += d * d, worst = std::max(worst, std::fabs(d)), ++n;
  }
  std::printf("{\"rms_rel\": %.6g, \"max_rel\": %.6g, \"points\": %zu, \"x_max\": %.6g}\n",
              n > 0 ? std::sqrt(sum / static_cast<double>(n)) / scale : NAN, worst / scale, n, hi);
  return 0;
}

int at(char** argv) {
  const gabion::bridge::H5Reader h(argv[2]);
  std::vector<double> x = h.read(argv[3]), y = h.read(argv[4]);
  firstLoading(x, y);
  if (x.empty()) throw std::runtime_error(std::string(argv[2]) + ": empty curve");
  const double at_x = std::atof(argv[5]);
  if (at_x < x.front() || at_x > x.back())  // (not the end value in place of a point the curve never reached)
    throw std::runtime_error(std::string(argv[2]) + ": " + argv[5] + " is outside the first loading, " +
                             std::to_string(x.front()) + " to " + std::to_string(x.back()));
  std::printf("%.6g\n", interpolate(x, y, at_x));
  return 0;
}

}  // namespace

int points(int argc, char** argv, gabion::bridge::PlotSeries::Style style) {
  if (argc < 7) return 2;
  gabion::bridge::PlotSpec spec = chart(argv);
  for (int a = 6; a < argc; ++a) {
    const std::string arg = argv[a];
    const auto eq = arg.find('=');
    if (eq == std::string::npos) return 2;
    const bool reference = style == gabion::bridge::PlotSeries::Style::Markers && arg.rfind("line:", 0) == 0;
    const std::size_t from = reference ? 5 : 0;
    gabion::bridge::PlotSeries s{
        arg.substr(from, eq - from), {}, {}, reference ? gabion::bridge::PlotSeries::Style::Dashed : style};
    for (const std::string& xy : split(arg.substr(eq + 1), ',')) {
      const auto parts = split(xy, ':');
      if (parts.size() != 2) return 2;
      s.x.push_back(std::stod(parts[0]));
      s.y.push_back(std::stod(parts[1]));
    }
    spec.series.push_back(s);
  }
  gabion::bridge::writePlotPng(argv[2], spec);
  return 0;
}

int main(int argc, char** argv) {
  const std::string verb = argc > 1 ? argv[1] : "";
  int rc = 2;
  try {
    if (verb == "plot") rc = plot(argc, argv);
    if (verb == "points") rc = points(argc, argv, gabion::bridge::PlotSeries::Style::LineMarkers);
    if (verb == "scatter") rc = points(argc, argv, gabion::bridge::PlotSeries::Style::Markers);
    if (verb == "error" && argc >= 6 && argc <= 8) rc = error(argc, argv);
    if (verb == "at" && argc == 6) rc = at(argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_curves: %s\n", e.what());
    return 1;
  }
  if (rc == 2)
    std::fprintf(stderr,
                 "usage: bench_curves plot OUT.png TITLE XLABEL YLABEL LABEL=FILE.h5:XDS:YDS[:XSCALE:YSCALE] ...\n"
                 "       bench_curves points OUT.png TITLE XLABEL YLABEL LABEL=X:Y,X:Y,... ...\n"
                 "       bench_curves scatter OUT.png TITLE XLABEL YLABEL [line:]LABEL=X:Y,X:Y,... ...\n"
                 "       bench_curves error REF.h5 RUN.h5 XDS YDS [WINDOW [XMAX]]\n"
                 "       bench_curves at FILE.h5 XDS YDS X\n");
  return rc;
}
