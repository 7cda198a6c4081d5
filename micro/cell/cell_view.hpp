#pragma once
/// \file
/// The picture of a cell: its blocks (each member sphere, in stone tones that
/// tell neighbouring blocks apart) and its netting (nodes and wires), drawn
/// headless (bridge::writeSceneViewPng) for the cell's outputs and reports.
#include <filesystem>
#include <string>

#include "micro/scene.hpp"

namespace gabion::micro {

/// Draws the bodies and links of `scene` as they are placed, seen from
/// azimuth 35 deg and elevation 25 deg, into a PNG file (netting nodes at a
/// third of their contact radius).
void writeCellView(const std::filesystem::path& file, const Scene& scene, const std::string& title);

}  // namespace gabion::micro
