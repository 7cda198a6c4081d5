// PNG charts: a small rasteriser (anti-aliased lines and markers, bitmap
// text) and a PNG encoder on top of zlib. Layout: title on top, y-axis label
// rotated along the left edge, tick labels, the plot frame, x-axis label at
// the bottom, and a legend in the plot corner that covers the least data.
#include "bridge/plot.hpp"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "bridge/output.hpp"
#include "bridge/plot_font.hpp"

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
  std::uint8_t r, g, b;
};

constexpr Rgb kWhite{255, 255, 255};
constexpr Rgb kBlack{0, 0, 0};
constexpr Rgb kText{20, 20, 20};
constexpr Rgb kGrid{228, 228, 228};
constexpr Rgb kLegendBorder{160, 160, 160};

// Tableau-10 order (the matplotlib default): distinct hues that stay
// distinguishable for the common forms of colour blindness.
constexpr std::array<Rgb, 10> kPalette{{{31, 119, 180},
                                        {255, 127, 14},
                                        {44, 160, 44},
                                        {214, 39, 40},
                                        {148, 103, 189},
                                        {140, 86, 75},
                                        {227, 119, 194},
                                        {127, 127, 127},
                                        {188, 189, 34},
                                        {23, 190, 207}}};

constexpr int kMaxSidePx = 8192;
constexpr double kLineHalfWidthPx = 0.8;  // 1.6 px lines
constexpr double kMarkerRadiusPx = 3.0;
constexpr int kTickLengthPx = 5;
constexpr int kTitleScale = 2;

// ------------------------------------------------------------------ canvas

class Canvas {
 public:
  Canvas(int width, int height)
      : w_(width), h_(height), px_(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 3, 255) {}
  int width() const { return w_; }
  int height() const { return h_; }

  // Mixes `c` into the pixel with opacity `alpha` in [0, 1]; outside: ignored.
  void blend(int x, int y, Rgb c, double alpha) {
    if (x < 0 || y < 0 || x >= w_ || y >= h_ || !(alpha > 0.0)) return;
    alpha = std::min(alpha, 1.0);
    std::uint8_t* p =
        &px_[(static_cast<std::size_t>(y) * static_cast<std::size_t>(w_) + static_cast<std::size_t>(x)) * 3];
    const std::array<std::uint8_t, 3> src{c.r, c.g, c.b};
    for (int k = 0; k < 3; ++k) p[k] = static_cast<std::uint8_t>(std::lround(p[k] + (src[k] - p[k]) * alpha));
  }
  void set(int x, int y, Rgb c) { blend(x, y, c, 1.0); }
  // Inclusive rectangle.
  void fill(int x0, int y0, int x1, int y1, Rgb c, double alpha = 1.0) {
    for (int y = std::max(y0, 0); y <= std::min(y1, h_ - 1); ++y)
      for (int x = std::max(x0, 0); x <= std::min(x1, w_ - 1); ++x) blend(x, y, c, alpha);
  }
  void outline(int x0, int y0, int x1, int y1, Rgb c) {
    fill(x0, y0, x1, y0, c);
    fill(x0, y1, x1, y1, c);
    fill(x0, y0, x0, y1, c);
    fill(x1, y0, x1, y1, c);
  }
  const std::vector<std::uint8_t>& pixels() const { return px_; }

 private:
  int w_, h_;
  std::vector<std::uint8_t> px_;  // RGB, row-major, top row first
};

// -------------------------------------------------------------------- text

int textWidth(const std::string& text, int scale) {
  const auto n = static_cast<int>(plot_font::decodeUtf8(text).size());
  return n == 0 ? 0 : (n * plot_font::kAdvance - 1) * scale;
}
int textHeight(int scale) {
  return plot_font::kGlyphHeight * scale;
}

// Horizontal text with its top-left corner at (x, y).
void drawText(Canvas& canvas, int x, int y, const std::string& text, Rgb c, int scale) {
  for (char32_t cp : plot_font::decodeUtf8(text)) {
    const plot_font::Glyph& g = plot_font::glyph(cp);
    for (int col = 0; col < plot_font::kGlyphWidth; ++col)
      for (int row = 0; row < plot_font::kGlyphHeight; ++row)
        if (g[static_cast<std::size_t>(col)] & (1u << row))
          canvas.fill(x + col * scale, y + row * scale, x + col * scale + scale - 1, y + row * scale + scale - 1, c);
    x += plot_font::kAdvance * scale;
  }
}

// Text turned 90 degrees counter-clockwise (read bottom to top); the glyph
// tops face left; (x, y) is the bottom-left corner of the turned text.
void drawTextUp(Canvas& canvas, int x, int y, const std::string& text, Rgb c, int scale) {
  for (char32_t cp : plot_font::decodeUtf8(text)) {
    const plot_font::Glyph& g = plot_font::glyph(cp);
    for (int col = 0; col < plot_font::kGlyphWidth; ++col)
      for (int row = 0; row < plot_font::kGlyphHeight; ++row)
        if (g[static_cast<std::size_t>(col)] & (1u << row)) {
          const int px = x + row * scale, py = y - col * scale;
          canvas.fill(px, py - scale + 1, px + scale - 1, py, c);
        }
    y -= plot_font::kAdvance * scale;
  }
}

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

// ------------------------------------------------------- coverage (series)

enum class MarkerShape { Circle, Square, Diamond };

// Per-series coverage of the plot interior in [0, 1]; a series is stamped
// here first and composited once, so overlapping segments of one polyline
// do not darken their joints.
class Coverage {
 public:
  Coverage(int x0, int y0, int x1, int y1)
      : x0_(x0),
        y0_(y0),
        x1_(x1),
        y1_(y1),
        w_(std::max(x1 - x0 + 1, 0)),
        a_(static_cast<std::size_t>(w_) * static_cast<std::size_t>(std::max(y1 - y0 + 1, 0)), 0.0f) {}
  void clear() { std::fill(a_.begin(), a_.end(), 0.0f); }
  void put(int x, int y, double c) {
    if (x < x0_ || x > x1_ || y < y0_ || y > y1_ || !(c > 0.0)) return;
    float& a = a_[index(x, y)];
    a = std::max(a, static_cast<float>(std::min(c, 1.0)));
  }
  double at(int x, int y) const { return a_[index(x, y)]; }
  int x0() const { return x0_; }
  int y0() const { return y0_; }
  int x1() const { return x1_; }
  int y1() const { return y1_; }

 private:
  std::size_t index(int x, int y) const {
    return static_cast<std::size_t>(y - y0_) * static_cast<std::size_t>(w_) + static_cast<std::size_t>(x - x0_);
  }
  int x0_, y0_, x1_, y1_, w_;
  std::vector<float> a_;
};

double clampPx(double v) {
  return std::clamp(v, -1e6, 1e6);
}

// Anti-aliased thick segment: coverage from the distance of each pixel centre
// to the segment (round caps). Only a band of a few pixels around the segment
// is visited, walking along its major axis.
void stampSegment(Coverage& cov, double ax, double ay, double bx, double by, double hw) {
  const double dx = bx - ax, dy = by - ay;
  const double len2 = dx * dx + dy * dy;
  const double inv_len2 = len2 > 0.0 ? 1.0 / len2 : 0.0;
  const double reach = hw + 0.5;  // beyond this distance the coverage is zero
  auto eval = [&](int x, int y) {
    const double t = std::clamp(((x - ax) * dx + (y - ay) * dy) * inv_len2, 0.0, 1.0);
    const double ex = x - (ax + t * dx), ey = y - (ay + t * dy);
    const double d2 = ex * ex + ey * ey;
    if (d2 < reach * reach) cov.put(x, y, reach - std::sqrt(d2));
  };
  // Across the major axis the band is at most reach * sqrt(2) from the
  // centre line, plus rounding of the centre.
  const int band = static_cast<int>(std::ceil(reach * std::sqrt(2.0) + 0.5));
  if (std::abs(dx) >= std::abs(dy)) {
    const int xa = std::max(static_cast<int>(std::floor(std::min(ax, bx) - reach)), cov.x0());
    const int xb = std::min(static_cast<int>(std::ceil(std::max(ax, bx) + reach)), cov.x1());
    for (int x = xa; x <= xb; ++x) {
      const double t = dx != 0.0 ? std::clamp((x - ax) / dx, 0.0, 1.0) : 0.0;
      const int yc = static_cast<int>(std::lround(ay + t * dy));
      for (int y = std::max(yc - band, cov.y0()); y <= std::min(yc + band, cov.y1()); ++y) eval(x, y);
    }
  } else {
    const int ya = std::max(static_cast<int>(std::floor(std::min(ay, by) - reach)), cov.y0());
    const int yb = std::min(static_cast<int>(std::ceil(std::max(ay, by) + reach)), cov.y1());
    for (int y = ya; y <= yb; ++y) {
      const double t = std::clamp((y - ay) / dy, 0.0, 1.0);
      const int xc = static_cast<int>(std::lround(ax + t * dx));
      for (int x = std::max(xc - band, cov.x0()); x <= std::min(xc + band, cov.x1()); ++x) eval(x, y);
    }
  }
}

void stampMarker(Coverage& cov, double cx, double cy, MarkerShape shape) {
  const int r = static_cast<int>(std::ceil(kMarkerRadiusPx * 1.4)) + 1;
  const int ix = static_cast<int>(std::lround(cx)), iy = static_cast<int>(std::lround(cy));
  for (int y = iy - r; y <= iy + r; ++y)
    for (int x = ix - r; x <= ix + r; ++x) {
      const double ex = std::abs(x - cx), ey = std::abs(y - cy);
      double outside = 0.0;  // signed distance to the shape's edge (px)
      switch (shape) {
        case MarkerShape::Circle:
          outside = std::sqrt(ex * ex + ey * ey) - kMarkerRadiusPx;
          break;
        case MarkerShape::Square:
          outside = std::max(ex, ey) - 0.85 * kMarkerRadiusPx;
          break;
        case MarkerShape::Diamond:
          outside = (ex + ey - 1.25 * kMarkerRadiusPx) / std::sqrt(2.0);
          break;
      }
      cov.put(x, y, 0.5 - outside);
    }
}

// Blends the coverage into the canvas and records where the series inked
// (for the legend placement).
void composite(Canvas& canvas, const Coverage& cov, Rgb c, std::vector<std::uint8_t>& ink) {
  // Tiny images can push the plot area past the canvas edge.
  for (int y = std::max(cov.y0(), 0); y <= std::min(cov.y1(), canvas.height() - 1); ++y)
    for (int x = std::max(cov.x0(), 0); x <= std::min(cov.x1(), canvas.width() - 1); ++x) {
      const double a = cov.at(x, y);
      if (a <= 0.0) continue;
      canvas.blend(x, y, c, a);
      if (a > 0.25)
        ink[static_cast<std::size_t>(y) * static_cast<std::size_t>(canvas.width()) + static_cast<std::size_t>(x)] = 1;
    }
}

// --------------------------------------------------------------- PNG file

void putBe32(std::string& out, std::uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) out.push_back(static_cast<char>((v >> s) & 0xFFu));
}

void appendChunk(std::string& out, const char (&type)[5], const std::string& data) {
  putBe32(out, static_cast<std::uint32_t>(data.size()));
  const std::size_t start = out.size();
  out.append(type, 4);
  out += data;
  const auto* bytes = reinterpret_cast<const Bytef*>(out.data() + start);
  const uLong crc = crc32(crc32(0L, Z_NULL, 0), bytes, static_cast<uInt>(out.size() - start));
  putBe32(out, static_cast<std::uint32_t>(crc));
}

std::string encodePng(const Canvas& canvas) {
  const auto w = static_cast<std::size_t>(canvas.width()), h = static_cast<std::size_t>(canvas.height());
  // Filter type 0 (None) on every row: flat chart areas deflate well as is.
  std::vector<std::uint8_t> raw;
  raw.reserve(h * (1 + 3 * w));
  for (std::size_t y = 0; y < h; ++y) {
    raw.push_back(0);
    const auto row = canvas.pixels().begin() + static_cast<std::ptrdiff_t>(y * w * 3);
    raw.insert(raw.end(), row, row + static_cast<std::ptrdiff_t>(w * 3));
  }
  uLongf packed_size = compressBound(static_cast<uLong>(raw.size()));
  std::string packed(packed_size, '\0');
  const int rc =
      compress2(reinterpret_cast<Bytef*>(packed.data()), &packed_size, raw.data(), static_cast<uLong>(raw.size()), 6);
  if (rc != Z_OK) throw std::runtime_error("PNG encoding: zlib compress2 failed (code " + std::to_string(rc) + ")");
  packed.resize(packed_size);

  std::string ihdr;
  putBe32(ihdr, static_cast<std::uint32_t>(w));
  putBe32(ihdr, static_cast<std::uint32_t>(h));
  ihdr += std::string{8, 2, 0, 0, 0};  // bit depth 8, colour type 2 (RGB), deflate, filter 0, no interlace

  std::string png("\x89PNG\r\n\x1a\n", 8);
  appendChunk(png, "IHDR", ihdr);
  appendChunk(png, "IDAT", packed);
  appendChunk(png, "IEND", std::string());
  return png;
}

// ------------------------------------------------------------------ layout

Rgb seriesColor(const PlotSeries& s, std::size_t index) {
  if (s.color_rgb >= 0) {
    const auto v = static_cast<std::uint32_t>(s.color_rgb);
    return {static_cast<std::uint8_t>((v >> 16) & 0xFFu), static_cast<std::uint8_t>((v >> 8) & 0xFFu),
            static_cast<std::uint8_t>(v & 0xFFu)};
  }
  return kPalette[index % kPalette.size()];
}

// Cycling shapes keep series apart where colours are hard to tell apart.
MarkerShape seriesMarker(std::size_t index) {
  constexpr std::array<MarkerShape, 3> shapes{MarkerShape::Circle, MarkerShape::Square, MarkerShape::Diamond};
  return shapes[index % shapes.size()];
}

bool hasLine(PlotSeries::Style s) {
  return s != PlotSeries::Style::Markers;
}
bool hasMarkers(PlotSeries::Style s) {
  return s != PlotSeries::Style::Line;
}

struct Frame {
  int left, top, right, bottom;  // pixel columns/rows of the frame lines
};

void drawLegend(Canvas& canvas, const PlotSpec& spec, const Frame& f, const std::vector<std::uint8_t>& ink) {
  std::vector<std::size_t> entries;
  int label_w = 0;
  for (std::size_t i = 0; i < spec.series.size(); ++i)
    if (!spec.series[i].label.empty()) {
      entries.push_back(i);
      label_w = std::max(label_w, textWidth(spec.series[i].label, 1));
    }
  if (entries.empty()) return;
  constexpr int pad = 6, sample_w = 24, row_h = 14, inset = 8;
  const int box_w = pad + sample_w + pad + label_w + pad;
  const int box_h = pad + static_cast<int>(entries.size()) * row_h - (row_h - textHeight(1)) + pad;

  // The corner whose box would hide the fewest series pixels (ties: top right,
  // top left, bottom right, bottom left).
  const std::array<std::array<int, 2>, 4> corners{{{f.right - inset - box_w, f.top + inset},
                                                   {f.left + inset, f.top + inset},
                                                   {f.right - inset - box_w, f.bottom - inset - box_h},
                                                   {f.left + inset, f.bottom - inset - box_h}}};
  long best = -1;
  int bx = corners[0][0], by = corners[0][1];
  for (const auto& c : corners) {
    long count = 0;
    for (int y = std::max(c[1], 0); y <= std::min(c[1] + box_h, canvas.height() - 1); ++y)
      for (int x = std::max(c[0], 0); x <= std::min(c[0] + box_w, canvas.width() - 1); ++x)
        count +=
            ink[static_cast<std::size_t>(y) * static_cast<std::size_t>(canvas.width()) + static_cast<std::size_t>(x)];
    if (best < 0 || count < best) {
      best = count;
      bx = c[0];
      by = c[1];
    }
  }

  canvas.fill(bx, by, bx + box_w, by + box_h, kWhite, 0.88);
  canvas.outline(bx, by, bx + box_w, by + box_h, kLegendBorder);
  Coverage cov(std::max(bx + 1, 0), std::max(by + 1, 0), std::min(bx + box_w - 1, canvas.width() - 1),
               std::min(by + box_h - 1, canvas.height() - 1));
  std::vector<std::uint8_t> scratch(ink.size(), 0);
  int y = by + pad;
  for (std::size_t i : entries) {
    const PlotSeries& s = spec.series[i];
    const double mid = y + 3.0;  // centre of the x-height of the 7-row glyph
    cov.clear();
    if (hasLine(s.style)) stampSegment(cov, bx + pad, mid, bx + pad + sample_w, mid, kLineHalfWidthPx);
    if (hasMarkers(s.style)) stampMarker(cov, bx + pad + sample_w / 2.0, mid, seriesMarker(i));
    composite(canvas, cov, seriesColor(s, i), scratch);
    drawText(canvas, bx + pad + sample_w + pad, y, s.label, kText, 1);
    y += row_h;
  }
}

}  // namespace

void writePlotPng(const std::filesystem::path& path, const PlotSpec& spec) {
  if (spec.width_px < 1 || spec.height_px < 1 || spec.width_px > kMaxSidePx || spec.height_px > kMaxSidePx)
    throw std::invalid_argument("plot " + path.string() + ": size " + std::to_string(spec.width_px) + "x" +
                                std::to_string(spec.height_px) + " px outside 1.." + std::to_string(kMaxSidePx));
  for (const PlotSeries& s : spec.series)
    if (s.x.size() != s.y.size())
      throw std::invalid_argument("plot " + path.string() + ": series '" + s.label + "' has " +
                                  std::to_string(s.x.size()) + " x but " + std::to_string(s.y.size()) + " y values");

  // Data ranges over the finite points of all series.
  double xmin = kHuge, xmax = -kHuge, ymin = kHuge, ymax = -kHuge;
  bool any = false;
  for (const PlotSeries& s : spec.series)
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      const double x = std::clamp(s.x[i], -kHuge, kHuge), y = std::clamp(s.y[i], -kHuge, kHuge);
      xmin = std::min(xmin, x), xmax = std::max(xmax, x), ymin = std::min(ymin, y), ymax = std::max(ymax, y);
      any = true;
    }
  const Range xr = autoRange(xmin, xmax, any), yr = autoRange(ymin, ymax, any);

  Canvas canvas(spec.width_px, spec.height_px);
  const int W = canvas.width(), H = canvas.height();
  const int th = textHeight(1);

  // Margins from the text that surrounds the frame.
  const int title_h = spec.title.empty() ? 0 : textHeight(kTitleScale) + 10;
  const int top = 12 + title_h;
  const int bottom = H - 1 - (8 + (spec.x_label.empty() ? 0 : th + 8) + th + kTickLengthPx + 4);
  const Ticks yt = niceTicks(yr, std::clamp((bottom - top) / 45, 2, 12));
  int ylabel_w = 0;
  for (double v : yt.values) ylabel_w = std::max(ylabel_w, textWidth(tickLabel(v, yt), 1));
  const int left = 10 + (spec.y_label.empty() ? 0 : th + 8) + ylabel_w + kTickLengthPx + 4;
  // The last x tick label may sit on the right frame line: leave room for half of it.
  auto xTicksFor = [&](int right_px) { return niceTicks(xr, std::clamp((right_px - left) / 75, 2, 14)); };
  int xlabel_w = 0;
  const Ticks xt_guess = xTicksFor(W - 1 - 16);
  for (double v : xt_guess.values) xlabel_w = std::max(xlabel_w, textWidth(tickLabel(v, xt_guess), 1));
  const int right = W - 1 - std::max(16, xlabel_w / 2 + 4);
  const Frame f{left, top, std::max(right, left + 2), std::max(bottom, top + 2)};
  const Ticks xt = xTicksFor(f.right);

  // Data to pixel centres: the data range spans the frame lines exactly.
  auto px = [&](double x) {
    return clampPx(f.left + (std::clamp(x, -kHuge, kHuge) - xr.lo) / (xr.hi - xr.lo) * (f.right - f.left));
  };
  auto py = [&](double y) {
    return clampPx(f.bottom - (std::clamp(y, -kHuge, kHuge) - yr.lo) / (yr.hi - yr.lo) * (f.bottom - f.top));
  };

  // Grid, series, frame, ticks, labels, legend: later layers on top.
  for (double v : xt.values) {
    const int x = static_cast<int>(std::lround(px(v)));
    if (x > f.left && x < f.right) canvas.fill(x, f.top + 1, x, f.bottom - 1, kGrid);
  }
  for (double v : yt.values) {
    const int y = static_cast<int>(std::lround(py(v)));
    if (y > f.top && y < f.bottom) canvas.fill(f.left + 1, y, f.right - 1, y, kGrid);
  }

  std::vector<std::uint8_t> ink(static_cast<std::size_t>(W) * static_cast<std::size_t>(H), 0);
  Coverage cov(f.left + 1, f.top + 1, f.right - 1, f.bottom - 1);
  for (std::size_t k = 0; k < spec.series.size(); ++k) {
    const PlotSeries& s = spec.series[k];
    cov.clear();
    bool have_prev = false;
    double prev_x = 0.0, prev_y = 0.0;
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) {
        have_prev = false;  // a gap in the line, not a jump across it
        continue;
      }
      const double x = px(s.x[i]), y = py(s.y[i]);
      if (hasLine(s.style)) {
        // A lone point (no neighbour on either side) still shows as a dot.
        const bool next_finite = i + 1 < s.x.size() && std::isfinite(s.x[i + 1]) && std::isfinite(s.y[i + 1]);
        if (have_prev)
          stampSegment(cov, prev_x, prev_y, x, y, kLineHalfWidthPx);
        else if (!next_finite)
          stampSegment(cov, x, y, x, y, 0.8 * kMarkerRadiusPx);
      }
      if (hasMarkers(s.style)) stampMarker(cov, x, y, seriesMarker(k));
      have_prev = true;
      prev_x = x;
      prev_y = y;
    }
    composite(canvas, cov, seriesColor(s, k), ink);
  }

  canvas.outline(f.left, f.top, f.right, f.bottom, kBlack);
  for (double v : xt.values) {
    const int x = static_cast<int>(std::lround(px(v)));
    canvas.fill(x, f.bottom + 1, x, f.bottom + kTickLengthPx, kBlack);
    const std::string label = tickLabel(v, xt);
    drawText(canvas, x - textWidth(label, 1) / 2, f.bottom + kTickLengthPx + 4, label, kText, 1);
  }
  for (double v : yt.values) {
    const int y = static_cast<int>(std::lround(py(v)));
    canvas.fill(f.left - kTickLengthPx, y, f.left - 1, y, kBlack);
    const std::string label = tickLabel(v, yt);
    drawText(canvas, f.left - kTickLengthPx - 4 - textWidth(label, 1), y - 3, label, kText, 1);
  }

  if (!spec.title.empty())
    drawText(canvas, (f.left + f.right) / 2 - textWidth(spec.title, kTitleScale) / 2, 10, spec.title, kText,
             kTitleScale);
  if (!spec.x_label.empty())
    drawText(canvas, (f.left + f.right) / 2 - textWidth(spec.x_label, 1) / 2, f.bottom + kTickLengthPx + 4 + th + 8,
             spec.x_label, kText, 1);
  if (!spec.y_label.empty())
    drawTextUp(canvas, 10, (f.top + f.bottom) / 2 + textWidth(spec.y_label, 1) / 2, spec.y_label, kText, 1);

  drawLegend(canvas, spec, f, ink);

  writeTextAtomic(path, encodePng(canvas));
}

}  // namespace gabion::bridge
