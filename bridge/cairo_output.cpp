#include "bridge/cairo_output.hpp"

#include <cairo-svg.h>

#include <stdexcept>
#include <string>

#include "bridge/output.hpp"

namespace gabion::bridge {

namespace {

cairo_status_t appendBytes(void* closure, const unsigned char* data, unsigned int length) {
  static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
  return CAIRO_STATUS_SUCCESS;
}

void check(cairo_status_t st, const std::filesystem::path& path) {
  if (st != CAIRO_STATUS_SUCCESS)
    throw std::runtime_error("figure " + path.string() + ": cairo: " + cairo_status_to_string(st));
}

// Draws on `surface`, returns the drawing's status.
cairo_status_t drawOn(cairo_surface_t* surface, const CairoDraw& draw) {
  cairo_t* cr = cairo_create(surface);
  draw(cr);
  const cairo_status_t st = cairo_status(cr);
  cairo_destroy(cr);
  return st;
}

}  // namespace

void writeCairoPng(const std::filesystem::path& path, int width_px, int height_px, const CairoDraw& draw) {
  cairo_surface_t* surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, width_px, height_px);
  const cairo_status_t drawn = drawOn(surface, draw);
  std::string png;
  const cairo_status_t written =
      drawn == CAIRO_STATUS_SUCCESS ? cairo_surface_write_to_png_stream(surface, appendBytes, &png) : drawn;
  cairo_surface_destroy(surface);
  check(written, path);
  writeTextAtomic(path, png);
}

void writeCairoSvg(const std::filesystem::path& path, int width_px, int height_px, const CairoDraw& draw) {
  std::string svg;
  cairo_surface_t* surface = cairo_svg_surface_create_for_stream(appendBytes, &svg, width_px, height_px);
  const cairo_status_t drawn = drawOn(surface, draw);
  cairo_surface_finish(surface);
  const cairo_status_t finished = cairo_surface_status(surface);
  cairo_surface_destroy(surface);
  check(drawn != CAIRO_STATUS_SUCCESS ? drawn : finished, path);
  writeTextAtomic(path, svg);
}

}  // namespace gabion::bridge
