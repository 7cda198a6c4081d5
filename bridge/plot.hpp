#pragma once
/// \file
/// Charts as PNG or SVG files (line and marker plots with axes, ticks, labels
/// and a legend), drawn with cairo, so that every run can leave a plot a
/// person can look at without extra tools.
#include <filesystem>
#include <string>
#include <vector>

namespace gabion::bridge {

/// One data series of a chart.
struct PlotSeries {
  /// Band: the region between y (lower edge) and y_upper, filled pale.
  /// Dashed: a line drawn in dashes (a reference beside the solid lines).
  enum class Style { Line, Markers, LineMarkers, Band, Dashed };
  std::string label;         ///< legend text (empty: not in the legend)
  std::vector<double> x, y;  ///< same length; non-finite points are skipped
  Style style = Style::Line;
  int color_rgb = -1;                ///< 0xRRGGBB, or -1: the palette colour of the series' index
  std::vector<double> y_upper = {};  ///< Band only: the upper edge, as long as x
};

/// The palette colour (0xRRGGBB) a series at `index` gets by default: to
/// draw a band in the colour of the line it belongs to.
int paletteColor(std::size_t index);

/// A series of (x_scale * x[k], y_scale * y[k]): data in SI units drawn in
/// the chart's (mm, kN, ...).
PlotSeries scaledSeries(const std::string& label, const std::vector<double>& x, const std::vector<double>& y,
                        double x_scale, double y_scale, PlotSeries::Style style = PlotSeries::Style::Line);

/// A 2-D chart.
struct PlotSpec {
  std::string title;
  std::string x_label;  ///< with unit, e.g. "displacement (m)"
  std::string y_label;
  std::vector<PlotSeries> series;
  int width_px = 900;
  int height_px = 600;
};

/// Renders `spec` to a PNG file at `path` (8-bit RGB, written atomically).
/// Throws std::invalid_argument for an invalid spec, std::runtime_error when
/// the file cannot be drawn or written.
void writePlotPng(const std::filesystem::path& path, const PlotSpec& spec);
/// The same chart as an SVG file (vector paths and text).
void writePlotSvg(const std::filesystem::path& path, const PlotSpec& spec);

}  // namespace gabion::bridge
