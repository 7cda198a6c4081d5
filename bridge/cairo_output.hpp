#pragma once
/// \file
/// Writing what cairo draws: a W x H canvas handed to a drawing function,
/// then encoded as PNG (8-bit RGB) or SVG into memory and written
/// atomically. Shared by the charts (plot.cpp) and the scene views
/// (scene_view.cpp); internal to bridge.
#include <cairo.h>

#include <filesystem>
#include <functional>

namespace gabion::bridge {

using CairoDraw = std::function<void(cairo_t*)>;

/// Throws std::runtime_error naming `path` when cairo fails.
void writeCairoPng(const std::filesystem::path& path, int width_px, int height_px, const CairoDraw& draw);
void writeCairoSvg(const std::filesystem::path& path, int width_px, int height_px, const CairoDraw& draw);

}  // namespace gabion::bridge
