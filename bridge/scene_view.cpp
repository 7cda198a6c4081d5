#include "bridge/scene_view.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "bridge/cairo_output.hpp"

namespace gabion::bridge {

namespace {

// One thing to paint: its depth (larger: nearer the viewer) and which.
struct Item {
  double depth;
  bool sphere;
  std::size_t index;
};

}  // namespace

void writeSceneViewPng(const std::filesystem::path& path, const SceneView& v) {
  if (v.spheres.empty() && v.segments.empty())
    throw std::invalid_argument("view " + path.string() + ": nothing to draw");
  if (v.width_px < 16 || v.height_px < 16 || v.width_px > 8192 || v.height_px > 8192)
    throw std::invalid_argument("view " + path.string() + ": size outside 16..8192 px");
  // Screen axes: right (u), up (w), and towards the viewer (d).
  const double az = v.azimuth_deg * M_PI / 180.0, el = v.elevation_deg * M_PI / 180.0;
  const Eigen::Vector3d toward(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  const Eigen::Vector3d right = Eigen::Vector3d::UnitZ().cross(toward).normalized();
  const Eigen::Vector3d up = toward.cross(right);
  const auto screen = [&](const Eigen::Vector3d& p) { return Eigen::Vector3d(p.dot(right), p.dot(up), p.dot(toward)); };

  // Bounds on the screen plane, to fit the picture with a margin.
  double u0 = std::numeric_limits<double>::infinity(), u1 = -u0, w0 = u0, w1 = -u0;
  const auto grow = [&](const Eigen::Vector3d& s, double r) {
    u0 = std::min(u0, s.x() - r), u1 = std::max(u1, s.x() + r), w0 = std::min(w0, s.y() - r),
    w1 = std::max(w1, s.y() + r);
  };
  for (const auto& s : v.spheres) grow(screen(s.center_m), s.radius_m);
  for (const auto& g : v.segments) grow(screen(g.a_m), 0.0), grow(screen(g.b_m), 0.0);
  const double title_px = v.title.empty() ? 0.0 : 34.0, margin = 16.0;
  const double scale = std::min((v.width_px - 2.0 * margin) / std::max(u1 - u0, 1e-12),
                                (v.height_px - 2.0 * margin - title_px) / std::max(w1 - w0, 1e-12));
  const double cu = 0.5 * (u0 + u1), cw = 0.5 * (w0 + w1);
  const auto px = [&](const Eigen::Vector3d& s) {
    return std::array<double, 2>{0.5 * v.width_px + (s.x() - cu) * scale,
                                 title_px + 0.5 * (v.height_px - title_px) - (s.y() - cw) * scale};
  };

  std::vector<Item> items;
  for (std::size_t i = 0; i < v.spheres.size(); ++i) items.push_back({screen(v.spheres[i].center_m).z(), true, i});
  for (std::size_t i = 0; i < v.segments.size(); ++i)
    items.push_back({0.5 * (screen(v.segments[i].a_m).z() + screen(v.segments[i].b_m).z()), false, i});
  std::stable_sort(items.begin(), items.end(), [](const Item& a, const Item& b) { return a.depth < b.depth; });
  double d0 = std::numeric_limits<double>::infinity(), d1 = -d0;
  for (const auto& it : items) d0 = std::min(d0, it.depth), d1 = std::max(d1, it.depth);

  writeCairoPng(path, v.width_px, v.height_px, [&](cairo_t* cr) {
    cairo_set_source_rgb(cr, 1.0, 1.0, 1.0);
    cairo_paint(cr);
    cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
    for (const Item& it : items) {
      // Farther things a little paler: a cue of depth in an orthographic view.
      const double fade = d1 > d0 ? 0.25 * (d1 - it.depth) / (d1 - d0) : 0.0;
      const auto rgb = [&](int c) {
        const double r = ((c >> 16) & 255) / 255.0, g = ((c >> 8) & 255) / 255.0, b = (c & 255) / 255.0;
        return std::array<double, 3>{r + (1.0 - r) * fade, g + (1.0 - g) * fade, b + (1.0 - b) * fade};
      };
      if (it.sphere) {
        const auto& s = v.spheres[it.index];
        const auto c = px(screen(s.center_m));
        const double r = std::max(s.radius_m * scale, 0.5);
        const auto col = rgb(s.color);
        // Lit from the upper left: a radial gradient from a highlight to the rim.
        cairo_pattern_t* shade = cairo_pattern_create_radial(c[0] - 0.35 * r, c[1] - 0.35 * r, 0.1 * r, c[0], c[1], r);
        cairo_pattern_add_color_stop_rgb(shade, 0.0, std::min(1.0, col[0] + 0.15), std::min(1.0, col[1] + 0.15),
                                         std::min(1.0, col[2] + 0.15));
        cairo_pattern_add_color_stop_rgb(shade, 1.0, 0.5 * col[0], 0.5 * col[1], 0.5 * col[2]);
        cairo_set_source(cr, shade);
        cairo_arc(cr, c[0], c[1], r, 0.0, 2.0 * M_PI);
        cairo_fill(cr);
        cairo_pattern_destroy(shade);
      } else {
        const auto& g = v.segments[it.index];
        const auto a = px(screen(g.a_m)), b = px(screen(g.b_m));
        const auto col = rgb(g.color);
        cairo_set_source_rgb(cr, col[0], col[1], col[2]);
        cairo_set_line_width(cr, g.width_px);
        cairo_move_to(cr, a[0], a[1]);
        cairo_line_to(cr, b[0], b[1]);
        cairo_stroke(cr);
      }
    }
    if (!v.title.empty()) {
      cairo_select_font_face(cr, "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
      cairo_set_font_size(cr, 17.0);
      cairo_text_extents_t e;
      cairo_text_extents(cr, v.title.c_str(), &e);
      cairo_set_source_rgb(cr, 0.08, 0.08, 0.08);
      cairo_move_to(cr, 0.5 * (v.width_px - e.x_advance), 26.0);
      cairo_show_text(cr, v.title.c_str());
    }
  });
}

}  // namespace gabion::bridge
