// Charts drawn with cairo (anti-aliased paths, real fonts through
// fontconfig) and written as PNG (cairo's encoder, into memory, then an
// atomic write) or SVG. Layout: title on top, y-axis label turned along the
// left edge, tick labels, the plot frame, x-axis label at the bottom, and a
// legend in the plot corner that covers the fewest data points.
#include "bridge/plot.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "bridge/cairo_output.hpp"

namespace gabion::bridge {

PlotSeries scaledSeries(const std::string& label, const std::vector<double>& x, const std::vector<double>& y,
                        double x_scale, double y_scale, PlotSeries::Style style) {
  PlotSeries s{label, {}, {}, style};
  for (std::size_t k = 0; k < x.size() && k < y.size(); ++k)
    s.x.push_back(x_scale * x[k]), s.y.push_back(y_scale * y[k]);
  return s;
}

namespace {

struct Rgb {
  double r, g, b;
};

constexpr Rgb kText{0.08, 0.08, 0.08};
constexpr Rgb kGrid{0.89, 0.89, 0.89};
constexpr Rgb kLegendBorder{0.63, 0.63, 0.63};

// Tableau-10 order (the matplotlib default): distinct hues that stay
// distinguishable for the common forms of colour blindness.
constexpr std::array<std::uint32_t, 10> kPalette{0x1f77b4, 0xff7f0e, 0x2ca02c, 0xd62728, 0x9467bd,
                                                 0x8c564b, 0xe377c2, 0x7f7f7f, 0xbcbd22, 0x17becf};

constexpr int kMaxSidePx = 8192;
constexpr double kLineWidthPx = 1.6;
constexpr double kMarkerRadiusPx = 3.0;
constexpr double kTickLengthPx = 5.0;
constexpr double kFontPx = 12.0;
constexpr double kTitleFontPx = 17.0;
const char* const kFont = "DejaVu Sans";

// ------------------------------------------------------------- axis ranges

struct Range {
  double lo = 0.0, hi = 1.0;
};

// Data beyond this magnitude is clamped so that spans and margins stay finite.
constexpr double kHuge = 1e300;

// [min, max] of the data with a 5 % margin; a single value or constant data
// gets a range of +-10 % around it (+-1 around zero).
Range autoRange(double lo, double hi, bool any) {
  if (!any) return {0.0, 1.0};
  const double span = hi - lo;
  const double mag = std::max(std::abs(lo), std::abs(hi));
  if (span <= mag * 1e-12 || span <= std::numeric_limits<double>::min()) {
    const double mid = 0.5 * (lo + hi);
    const double half = mag > 0.0 ? 0.1 * mag : 1.0;
    return {mid - half, mid + half};
  }
  return {lo - 0.05 * span, hi + 0.05 * span};
}

struct Ticks {
  std::vector<double> values;
  int exponent = 0;  // step = {1, 2, 5} x 10^exponent
};

// Ticks on "nice" steps (1, 2 or 5 times a power of ten), at most about
// `target` of them.
Ticks niceTicks(const Range& r, int target) {
  Ticks t;
  const double raw = (r.hi - r.lo) / std::max(target, 1);
  if (!(raw > 0.0) || !std::isfinite(raw)) return t;
  int e = static_cast<int>(std::floor(std::log10(raw)));
  const double f = raw / std::pow(10.0, e);
  double m = f <= 1.0 ? 1.0 : f <= 2.0 ? 2.0 : f <= 5.0 ? 5.0 : 10.0;
  if (m == 10.0) {
    m = 1.0;
    ++e;
  }
  const double step = m * std::pow(10.0, e);
  t.exponent = e;
  const double first = std::ceil(r.lo / step - 1e-9);
  for (int i = 0; i < 100; ++i) {
    const double v = (first + i) * step;
    if (v > r.hi + 1e-9 * step) break;
    // Exact zero instead of a rounding residue such as 1e-17.
    t.values.push_back(std::abs(v) < 1e-9 * step ? 0.0 : v);
  }
  return t;
}

// Tick label with just enough digits for the step; scientific notation for
// very large or very small magnitudes.
std::string tickLabel(double v, const Ticks& ticks) {
  double mag = 0.0;
  for (double t : ticks.values) mag = std::max(mag, std::abs(t));
  char buf[64];
  if (mag >= 1e5 || (mag > 0.0 && mag < 1e-3)) {
    const int lead = static_cast<int>(std::floor(std::log10(mag)));
    const int digits = std::clamp(lead - ticks.exponent, 0, 15);
    std::snprintf(buf, sizeof buf, "%.*e", digits, v);
  } else {
    std::snprintf(buf, sizeof buf, "%.*f", std::clamp(-ticks.exponent, 0, 15), v);
  }
  return buf;
}

// ---------------------------------------------------------------- drawing

}  // namespace

int paletteColor(std::size_t index) {
  return static_cast<int>(kPalette[index % kPalette.size()]);
}

namespace {

Rgb seriesColor(const PlotSeries& s, std::size_t index) {
  const auto v = s.color_rgb >= 0 ? static_cast<std::uint32_t>(s.color_rgb) : kPalette[index % kPalette.size()];
  return {((v >> 16) & 0xFFu) / 255.0, ((v >> 8) & 0xFFu) / 255.0, (v & 0xFFu) / 255.0};
}

enum class MarkerShape { Circle, Square, Diamond };

// Cycling shapes keep series apart where colours are hard to tell apart.
MarkerShape seriesMarker(std::size_t index) {
  constexpr std::array<MarkerShape, 3> shapes{MarkerShape::Circle, MarkerShape::Square, MarkerShape::Diamond};
  return shapes[index % shapes.size()];
}

bool hasLine(PlotSeries::Style s) {
  return s == PlotSeries::Style::Line || s == PlotSeries::Style::LineMarkers || s == PlotSeries::Style::Dashed;
}
// Sets the dash pattern of a series' line (none for a solid one).
void setDash(cairo_t* cr, PlotSeries::Style s) {
  static const double dash[] = {7.0, 5.0};
  if (s == PlotSeries::Style::Dashed)
    cairo_set_dash(cr, dash, 2, 0.0);
  else
    cairo_set_dash(cr, nullptr, 0, 0.0);
}
bool hasMarkers(PlotSeries::Style s) {
  return s == PlotSeries::Style::Markers || s == PlotSeries::Style::LineMarkers;
}
constexpr double kBandAlpha = 0.22;

// Pixel coordinates far outside the image are clamped (cairo works in
// fixed point: huge values would wrap).
double clampPx(double v) {
  return std::clamp(v, -1e6, 1e6);
}

class Painter {
 public:
  explicit Painter(cairo_t* cr) : cr_(cr) {
    cairo_select_font_face(cr_, kFont, CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  }
  void color(const Rgb& c, double alpha = 1.0) { cairo_set_source_rgba(cr_, c.r, c.g, c.b, alpha); }
  void rect(double x0, double y0, double x1, double y1) { cairo_rectangle(cr_, x0, y0, x1 - x0, y1 - y0); }
  // A crisp 1 px line between pixel centres (x + 0.5).
  void hairline(double x0, double y0, double x1, double y1) {
    cairo_set_line_width(cr_, 1.0);
    cairo_move_to(cr_, x0 + 0.5, y0 + 0.5);
    cairo_line_to(cr_, x1 + 0.5, y1 + 0.5);
    cairo_stroke(cr_);
  }
  void marker(double x, double y, MarkerShape shape) {
    const double r = kMarkerRadiusPx;
    switch (shape) {
      case MarkerShape::Circle:
        cairo_new_sub_path(cr_);
        cairo_arc(cr_, x, y, r, 0.0, 2.0 * M_PI);
        break;
      case MarkerShape::Square:
        cairo_rectangle(cr_, x - 0.85 * r, y - 0.85 * r, 1.7 * r, 1.7 * r);
        break;
      case MarkerShape::Diamond:
        cairo_move_to(cr_, x, y - 1.2 * r);
        cairo_line_to(cr_, x + 1.2 * r, y);
        cairo_line_to(cr_, x, y + 1.2 * r);
        cairo_line_to(cr_, x - 1.2 * r, y);
        cairo_close_path(cr_);
        break;
    }
    cairo_fill(cr_);
  }
  double textWidth(const std::string& t, double size) {
    cairo_set_font_size(cr_, size);
    cairo_text_extents_t e;
    cairo_text_extents(cr_, t.c_str(), &e);
    return e.x_advance;
  }
  // Text with its baseline's left end at (x, y); `up`: turned to read bottom to top.
  void text(double x, double y, const std::string& t, double size, bool up = false) {
    cairo_set_font_size(cr_, size);
    cairo_save(cr_);
    cairo_move_to(cr_, x, y);
    if (up) cairo_rotate(cr_, -M_PI / 2.0);
    cairo_show_text(cr_, t.c_str());
    cairo_restore(cr_);
    cairo_new_path(cr_);
  }
  cairo_t* raw() { return cr_; }

 private:
  cairo_t* cr_;
};

struct Frame {
  double left, top, right, bottom;  // pixel rows/columns of the frame lines
};

void drawLegend(Painter& p, const PlotSpec& spec, const Frame& f, const std::vector<std::array<double, 2>>& points) {
  std::vector<std::size_t> entries;
  double label_w = 0.0;
  for (std::size_t i = 0; i < spec.series.size(); ++i)
    if (!spec.series[i].label.empty()) {
      entries.push_back(i);
      label_w = std::max(label_w, p.textWidth(spec.series[i].label, kFontPx));
    }
  if (entries.empty()) return;
  constexpr double pad = 6.0, sample_w = 24.0, row_h = 16.0, inset = 8.0;
  const double box_w = pad + sample_w + pad + label_w + pad;
  const double box_h = 2.0 * pad + static_cast<double>(entries.size()) * row_h - 4.0;
  // The corner whose box would hide the fewest data points (ties: top right,
  // top left, bottom right, bottom left).
  const std::array<std::array<double, 2>, 4> corners{{{f.right - inset - box_w, f.top + inset},
                                                      {f.left + inset, f.top + inset},
                                                      {f.right - inset - box_w, f.bottom - inset - box_h},
                                                      {f.left + inset, f.bottom - inset - box_h}}};
  std::size_t best = std::numeric_limits<std::size_t>::max();
  double bx = corners[0][0], by = corners[0][1];
  for (const auto& c : corners) {
    std::size_t n = 0;
    for (const auto& q : points)
      n += q[0] >= c[0] - 2.0 && q[0] <= c[0] + box_w + 2.0 && q[1] >= c[1] - 2.0 && q[1] <= c[1] + box_h + 2.0;
    if (n < best) best = n, bx = c[0], by = c[1];
  }
  bx = std::round(bx), by = std::round(by);
  p.color({1.0, 1.0, 1.0}, 0.88);
  p.rect(bx, by, bx + box_w, by + box_h);
  cairo_fill(p.raw());
  p.color(kLegendBorder);
  cairo_set_line_width(p.raw(), 1.0);
  cairo_rectangle(p.raw(), bx + 0.5, by + 0.5, box_w, box_h);
  cairo_stroke(p.raw());
  double y = by + pad + row_h / 2.0;
  for (std::size_t i : entries) {
    const PlotSeries& s = spec.series[i];
    p.color(seriesColor(s, i));
    if (hasLine(s.style)) {
      cairo_set_line_width(p.raw(), kLineWidthPx);
      cairo_move_to(p.raw(), bx + pad, y);
      cairo_line_to(p.raw(), bx + pad + sample_w, y);
      setDash(p.raw(), s.style);
      cairo_stroke(p.raw());
      setDash(p.raw(), PlotSeries::Style::Line);
    }
    if (hasMarkers(s.style)) p.marker(bx + pad + sample_w / 2.0, y, seriesMarker(i));
    if (s.style == PlotSeries::Style::Band) {
      p.color(seriesColor(s, i), kBandAlpha);
      p.rect(bx + pad, y - 5.0, bx + pad + sample_w, y + 5.0);
      cairo_fill(p.raw());
    }
    p.color(kText);
    p.text(bx + pad + sample_w + pad, y + 0.36 * kFontPx, s.label, kFontPx);
    y += row_h;
  }
}

void validate(const std::filesystem::path& path, const PlotSpec& spec) {
  if (spec.width_px < 1 || spec.height_px < 1 || spec.width_px > kMaxSidePx || spec.height_px > kMaxSidePx)
    throw std::invalid_argument("plot " + path.string() + ": size " + std::to_string(spec.width_px) + "x" +
                                std::to_string(spec.height_px) + " px outside 1.." + std::to_string(kMaxSidePx));
  for (const PlotSeries& s : spec.series) {
    if (s.x.size() != s.y.size())
      throw std::invalid_argument("plot " + path.string() + ": series '" + s.label + "' has " +
                                  std::to_string(s.x.size()) + " x but " + std::to_string(s.y.size()) + " y values");
    if (s.style == PlotSeries::Style::Band && s.y_upper.size() != s.x.size())
      throw std::invalid_argument("plot " + path.string() + ": band '" + s.label + "' has " +
                                  std::to_string(s.x.size()) + " x but " + std::to_string(s.y_upper.size()) +
                                  " upper values");
  }
}

// Draws the chart on `cr`, a W x H canvas.
void render(cairo_t* cr, const PlotSpec& spec) {
  const double W = spec.width_px, H = spec.height_px;
  Painter p(cr);
  p.color({1.0, 1.0, 1.0});
  cairo_paint(cr);

  // Data ranges over the finite points of all series.
  double xmin = kHuge, xmax = -kHuge, ymin = kHuge, ymax = -kHuge;
  bool any = false;
  for (const PlotSeries& s : spec.series)
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      const double x = std::clamp(s.x[i], -kHuge, kHuge), y = std::clamp(s.y[i], -kHuge, kHuge);
      xmin = std::min(xmin, x), xmax = std::max(xmax, x), ymin = std::min(ymin, y), ymax = std::max(ymax, y);
      if (s.style == PlotSeries::Style::Band && std::isfinite(s.y_upper[i]))
        ymax = std::max(ymax, std::clamp(s.y_upper[i], -kHuge, kHuge));
      any = true;
    }
  const Range xr = autoRange(xmin, xmax, any), yr = autoRange(ymin, ymax, any);

  // Margins from the text that surrounds the frame.
  const double title_h = spec.title.empty() ? 0.0 : kTitleFontPx + 12.0;
  const double top = std::round(12.0 + title_h);
  const double bottom =
      std::round(H - 1.0 - (8.0 + (spec.x_label.empty() ? 0.0 : kFontPx + 8.0) + kFontPx + kTickLengthPx + 6.0));
  const Ticks yt = niceTicks(yr, std::clamp(static_cast<int>((bottom - top) / 45.0), 2, 12));
  double ylabel_w = 0.0;
  for (double v : yt.values) ylabel_w = std::max(ylabel_w, p.textWidth(tickLabel(v, yt), kFontPx));
  const double left = std::round(10.0 + (spec.y_label.empty() ? 0.0 : kFontPx + 8.0) + ylabel_w + kTickLengthPx + 4.0);
  // The last x tick label may sit on the right frame line: leave room for half of it.
  auto xTicksFor = [&](double right_px) {
    return niceTicks(xr, std::clamp(static_cast<int>((right_px - left) / 75.0), 2, 14));
  };
  double xlabel_w = 0.0;
  const Ticks xt_guess = xTicksFor(W - 17.0);
  for (double v : xt_guess.values) xlabel_w = std::max(xlabel_w, p.textWidth(tickLabel(v, xt_guess), kFontPx));
  const double right = std::round(W - 1.0 - std::max(16.0, xlabel_w / 2.0 + 4.0));
  const Frame f{left, top, std::max(right, left + 2.0), std::max(bottom, top + 2.0)};
  const Ticks xt = xTicksFor(f.right);

  // Data to pixel centres: the data range spans the frame lines exactly.
  auto px = [&](double x) {
    return clampPx(f.left + 0.5 + (std::clamp(x, -kHuge, kHuge) - xr.lo) / (xr.hi - xr.lo) * (f.right - f.left));
  };
  auto py = [&](double y) {
    return clampPx(f.bottom + 0.5 - (std::clamp(y, -kHuge, kHuge) - yr.lo) / (yr.hi - yr.lo) * (f.bottom - f.top));
  };

  // Grid, series (clipped to the frame), frame, ticks, labels, legend.
  p.color(kGrid);
  for (double v : xt.values) {
    const double x = std::round(px(v) - 0.5);
    if (x > f.left && x < f.right) p.hairline(x, f.top + 1.0, x, f.bottom - 1.0);
  }
  for (double v : yt.values) {
    const double y = std::round(py(v) - 0.5);
    if (y > f.top && y < f.bottom) p.hairline(f.left + 1.0, y, f.right - 1.0, y);
  }

  std::vector<std::array<double, 2>> points;  // every drawn point, for the legend's placement
  cairo_save(cr);
  cairo_rectangle(cr, f.left + 1.0, f.top + 1.0, f.right - f.left - 1.0, f.bottom - f.top - 1.0);
  cairo_clip(cr);
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
  for (std::size_t k = 0; k < spec.series.size(); ++k) {
    const PlotSeries& s = spec.series[k];
    if (s.style == PlotSeries::Style::Band) {
      // One filled polygon per run of finite points: along the lower edge,
      // back along the upper one.
      p.color(seriesColor(s, k), kBandAlpha);
      std::size_t i = 0;
      while (i < s.x.size()) {
        const auto finite = [&](std::size_t j) {
          return std::isfinite(s.x[j]) && std::isfinite(s.y[j]) && std::isfinite(s.y_upper[j]);
        };
        while (i < s.x.size() && !finite(i)) ++i;
        std::size_t end = i;
        while (end < s.x.size() && finite(end)) ++end;
        if (end > i + 1) {
          cairo_move_to(cr, px(s.x[i]), py(s.y[i]));
          for (std::size_t j = i + 1; j < end; ++j) cairo_line_to(cr, px(s.x[j]), py(s.y[j]));
          for (std::size_t j = end; j-- > i;) cairo_line_to(cr, px(s.x[j]), py(s.y_upper[j]));
          cairo_close_path(cr);
          cairo_fill(cr);
        }
        i = end;
      }
      continue;
    }
    p.color(seriesColor(s, k));
    cairo_set_line_width(cr, kLineWidthPx);
    bool have_prev = false;
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) {
        have_prev = false;  // a gap in the line, not a jump across it
        continue;
      }
      const double x = px(s.x[i]), y = py(s.y[i]);
      points.push_back({x, y});
      if (hasLine(s.style)) {
        // A lone point (no neighbour on either side) still shows as a dot.
        const bool next_finite = i + 1 < s.x.size() && std::isfinite(s.x[i + 1]) && std::isfinite(s.y[i + 1]);
        if (have_prev) {
          cairo_line_to(cr, x, y);
        } else {
          cairo_move_to(cr, x, y);
          if (!next_finite) {
            cairo_new_sub_path(cr);
            cairo_arc(cr, x, y, 0.8 * kMarkerRadiusPx, 0.0, 2.0 * M_PI);
            cairo_fill(cr);
          }
        }
      }
      have_prev = true;
    }
    setDash(cr, s.style);
    if (hasLine(s.style)) cairo_stroke(cr);
    setDash(cr, PlotSeries::Style::Line);
    cairo_new_path(cr);
    if (hasMarkers(s.style))
      for (std::size_t i = 0; i < s.x.size(); ++i)
        if (std::isfinite(s.x[i]) && std::isfinite(s.y[i])) p.marker(px(s.x[i]), py(s.y[i]), seriesMarker(k));
  }
  cairo_restore(cr);

  p.color({0.0, 0.0, 0.0});
  cairo_set_line_width(cr, 1.0);
  cairo_rectangle(cr, f.left + 0.5, f.top + 0.5, f.right - f.left, f.bottom - f.top);
  cairo_stroke(cr);
  for (double v : xt.values) {
    const double x = std::round(px(v) - 0.5);
    p.color({0.0, 0.0, 0.0});
    p.hairline(x, f.bottom + 1.0, x, f.bottom + kTickLengthPx);
    const std::string label = tickLabel(v, xt);
    p.color(kText);
    p.text(x + 0.5 - p.textWidth(label, kFontPx) / 2.0, f.bottom + kTickLengthPx + 4.0 + kFontPx, label, kFontPx);
  }
  for (double v : yt.values) {
    const double y = std::round(py(v) - 0.5);
    p.color({0.0, 0.0, 0.0});
    p.hairline(f.left - kTickLengthPx, y, f.left - 1.0, y);
    const std::string label = tickLabel(v, yt);
    p.color(kText);
    p.text(f.left - kTickLengthPx - 4.0 - p.textWidth(label, kFontPx), y + 0.5 + 0.36 * kFontPx, label, kFontPx);
  }
  p.color(kText);
  if (!spec.title.empty())
    p.text((f.left + f.right) / 2.0 - p.textWidth(spec.title, kTitleFontPx) / 2.0, 10.0 + kTitleFontPx, spec.title,
           kTitleFontPx);
  if (!spec.x_label.empty())
    p.text((f.left + f.right) / 2.0 - p.textWidth(spec.x_label, kFontPx) / 2.0,
           f.bottom + kTickLengthPx + 4.0 + 2.0 * kFontPx + 8.0, spec.x_label, kFontPx);
  if (!spec.y_label.empty())
    p.text(10.0 + kFontPx, (f.top + f.bottom) / 2.0 + p.textWidth(spec.y_label, kFontPx) / 2.0, spec.y_label, kFontPx,
           true);
  drawLegend(p, spec, f, points);
}

}  // namespace

void writePlotPng(const std::filesystem::path& path, const PlotSpec& spec) {
  validate(path, spec);
  writeCairoPng(path, spec.width_px, spec.height_px, [&](cairo_t* cr) { render(cr, spec); });
}

void writePlotSvg(const std::filesystem::path& path, const PlotSpec& spec) {
  validate(path, spec);
  writeCairoSvg(path, spec.width_px, spec.height_px, [&](cairo_t* cr) { render(cr, spec); });
}

}  // namespace gabion::bridge
