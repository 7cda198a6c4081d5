#pragma once
/// \file
/// The bitmap font of the PNG charts (bridge/plot.cpp): 5x8-pixel glyphs for
/// printable ASCII plus a few symbols common in axis labels (degree, micro,
/// superscript 2 and 3); anything else is drawn as '?'.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace gabion::bridge::plot_font {

constexpr int kGlyphWidth = 5;   ///< glyph columns (px at scale 1)
constexpr int kGlyphHeight = 8;  ///< glyph rows incl. one descender row (px at scale 1)
constexpr int kAdvance = 6;      ///< pen advance per character (px at scale 1)

/// Columns of one glyph, left to right; bit r of a column is row r (row 0 on top).
using Glyph = std::array<std::uint8_t, kGlyphWidth>;

/// The glyph of a Unicode code point ('?' when the font has none).
const Glyph& glyph(char32_t code_point);

/// Decodes UTF-8 into code points; malformed bytes become U+FFFD.
std::vector<char32_t> decodeUtf8(const std::string& text);

}  // namespace gabion::bridge::plot_font
