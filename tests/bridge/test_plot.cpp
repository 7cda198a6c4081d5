// PNG charts: the file is a valid PNG (signature, IHDR size, chunk CRCs, IDAT
// inflating to the expected scanlines) and the picture shows the data where
// the axes say it is.
#include <gtest/gtest.h>
#include <zlib.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "bridge/plot.hpp"
#include "bridge/scene_view.hpp"

using namespace gabion::bridge;
namespace fs = std::filesystem;

namespace {

std::uint32_t be32(const std::string& s, std::size_t at) {
  std::uint32_t v = 0;
  for (std::size_t k = 0; k < 4; ++k) v = (v << 8) | static_cast<unsigned char>(s[at + k]);
  return v;
}

struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  // row-major, top row first
  std::array<int, 3> at(int x, int y) const {
    const std::size_t i =
        (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)) * 3;
    return {rgb[i], rgb[i + 1], rgb[i + 2]};
  }
};

int paeth(int a, int b, int c) {
  const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
}

// Reads an 8-bit RGB PNG, checking its structure with gtest assertions on the way.
Image readPng(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  Image img;
  EXPECT_GE(file.size(), 8u);
  if (file.size() < 8) return img;
  EXPECT_EQ(file.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  std::string idat;
  std::size_t pos = 8;
  bool seen_end = false, seen_header = false;
  while (pos + 12 <= file.size()) {
    const std::uint32_t len = be32(file, pos);
    const std::string type = file.substr(pos + 4, 4);
    EXPECT_LE(pos + 12 + len, file.size()) << type;
    if (pos + 12 + len > file.size()) return img;
    const std::string data = file.substr(pos + 8, len);
    const uLong crc = crc32(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(file.data() + pos + 4), len + 4);
    EXPECT_EQ(be32(file, pos + 8 + len), static_cast<std::uint32_t>(crc)) << "CRC of chunk " << type;
    if (type == "IHDR") {
      EXPECT_EQ(pos, 8u) << "IHDR must be the first chunk";
      EXPECT_EQ(len, 13u);
      img.width = static_cast<int>(be32(data, 0));
      img.height = static_cast<int>(be32(data, 4));
      EXPECT_EQ(data[8], 8) << "bit depth";
      EXPECT_EQ(data[9], 2) << "colour type RGB";
      EXPECT_EQ(data.substr(10, 3), std::string(3, '\0'));
      seen_header = true;
    } else if (type == "IDAT") {
      idat += data;
    } else if (type == "IEND") {
      EXPECT_EQ(len, 0u);
      seen_end = true;
      EXPECT_EQ(pos + 12, file.size()) << "bytes after IEND";
    }
    pos += 12 + len;
  }
  EXPECT_TRUE(seen_header);
  EXPECT_TRUE(seen_end);
  const std::size_t stride = 3 * static_cast<std::size_t>(img.width);
  const std::size_t expected = static_cast<std::size_t>(img.height) * (1 + stride);
  std::vector<std::uint8_t> raw(expected + 16);
  uLongf raw_len = static_cast<uLongf>(raw.size());
  EXPECT_EQ(
      uncompress(raw.data(), &raw_len, reinterpret_cast<const Bytef*>(idat.data()), static_cast<uLong>(idat.size())),
      Z_OK);
  EXPECT_EQ(raw_len, expected) << "IDAT inflates to height*(1+3*width) bytes";
  if (raw_len != expected) return img;

  img.rgb.assign(static_cast<std::size_t>(img.height) * stride, 0);
  for (std::size_t y = 0; y < static_cast<std::size_t>(img.height); ++y) {
    const std::uint8_t filter = raw[y * (1 + stride)];
    EXPECT_LE(filter, 4) << "row " << y;
    const std::uint8_t* src = &raw[y * (1 + stride) + 1];
    std::uint8_t* dst = &img.rgb[y * stride];
    const std::uint8_t* up = y > 0 ? &img.rgb[(y - 1) * stride] : nullptr;
    for (std::size_t i = 0; i < stride; ++i) {
      const int a = i >= 3 ? dst[i - 3] : 0, b = up ? up[i] : 0, c = (up && i >= 3) ? up[i - 3] : 0;
      int pred = 0;
      switch (filter) {
        case 1:
          pred = a;
          break;
        case 2:
          pred = b;
          break;
        case 3:
          pred = (a + b) / 2;
          break;
        case 4:
          pred = paeth(a, b, c);
          break;
        default:
          break;
      }
      dst[i] = static_cast<std::uint8_t>(src[i] + pred);
    }
  }
  return img;
}

bool isDark(const std::array<int, 3>& p) {
  return p[0] < 80 && p[1] < 80 && p[2] < 80;
}
bool isReddish(const std::array<int, 3>& p) {
  return p[0] > 150 && p[1] < 110 && p[2] < 110;
}
bool isBluish(const std::array<int, 3>& p) {
  return p[2] > 150 && p[0] < 110 && p[1] < 110;
}

// The frame: the rows and columns that are dark over more than half the image
// (text never makes runs that long).
struct FrameBox {
  int left = -1, top = -1, right = -1, bottom = -1;
};
FrameBox findFrame(const Image& img) {
  FrameBox f;
  for (int y = 0; y < img.height; ++y) {
    int dark = 0;
    for (int x = 0; x < img.width; ++x) dark += isDark(img.at(x, y));
    if (dark > img.width / 2) {
      if (f.top < 0) f.top = y;
      f.bottom = y;
    }
  }
  for (int x = 0; x < img.width; ++x) {
    int dark = 0;
    for (int y = 0; y < img.height; ++y) dark += isDark(img.at(x, y));
    if (dark > img.height / 2) {
      if (f.left < 0) f.left = x;
      f.right = x;
    }
  }
  return f;
}

fs::path tempPng(const std::string& name) {
  const fs::path p = fs::path(::testing::TempDir()) / name;
  fs::remove(p);
  return p;
}

// A single-series chart (plus `extra`) drawn to a PNG and read back, with its frame.
struct Drawn {
  Image img;
  FrameBox frame;
};
Drawn draw(const std::string& name, const PlotSeries& series, const std::vector<PlotSeries>& extra = {}) {
  PlotSpec spec;
  spec.series.push_back(series);
  for (const PlotSeries& e : extra) spec.series.push_back(e);
  const fs::path path = tempPng(name);
  writePlotPng(path, spec);
  Drawn d{readPng(path), {}};
  d.frame = findFrame(d.img);
  return d;
}

}  // namespace

TEST(Plot, ValidPngWithRequestedSize) {
  PlotSpec spec;
  spec.title = "Force - displacement";
  spec.x_label = "displacement (m)";
  spec.y_label = "force (kN)";
  spec.width_px = 640;
  spec.height_px = 420;
  for (int k = 0; k < 3; ++k) {
    PlotSeries s;
    s.label = "series " + std::to_string(k);
    s.style = static_cast<PlotSeries::Style>(k);
    for (int i = 0; i <= 40; ++i) {
      s.x.push_back(0.01 * i);
      s.y.push_back(std::sin(0.2 * i + k) * 100.0 * (k + 1));
    }
    spec.series.push_back(s);
  }
  const fs::path path = tempPng("valid.png");
  writePlotPng(path, spec);
  EXPECT_FALSE(fs::exists(path.string() + ".part"));
  const Image img = readPng(path);
  EXPECT_EQ(img.width, 640);
  EXPECT_EQ(img.height, 420);
}

TEST(Plot, RedHorizontalLineOnItsRowAndWhiteBackground) {
  PlotSpec spec;
  spec.x_label = "time (s)";
  spec.y_label = "value (-)";
  PlotSeries s;  // no label: no legend over the line
  s.color_rgb = 0xFF0000;
  s.x = {0.0, 1.0, 2.0};
  s.y = {0.5, 0.5, 0.5};  // constant: the range is centred on 0.5
  spec.series.push_back(s);
  const fs::path path = tempPng("red_line.png");
  writePlotPng(path, spec);
  const Image img = readPng(path);
  ASSERT_EQ(img.width, 900);
  ASSERT_EQ(img.height, 600);

  EXPECT_EQ(img.at(0, 0), (std::array<int, 3>{255, 255, 255}));
  EXPECT_EQ(img.at(899, 599), (std::array<int, 3>{255, 255, 255}));
  const FrameBox f = findFrame(img);
  ASSERT_GE(f.top, 0);
  ASSERT_GE(f.left, 0);
  ASSERT_GT(f.bottom - f.top, 300);
  ASSERT_GT(f.right - f.left, 600);

  // The line runs at mid-height of the frame (within a pixel of rounding),
  // from 5 % to 95 % of the frame width (the auto-range margin).
  const int row = (f.top + f.bottom) / 2;
  for (int x = f.left + (f.right - f.left) / 10; x < f.right - (f.right - f.left) / 10; x += 7) {
    const bool red = isReddish(img.at(x, row)) || isReddish(img.at(x, row - 1)) || isReddish(img.at(x, row + 1));
    EXPECT_TRUE(red) << "column " << x << " row " << row;
    EXPECT_FALSE(isReddish(img.at(x, row - 4)));
    EXPECT_FALSE(isReddish(img.at(x, row + 4)));
  }
  // Nothing red outside the line's extent.
  EXPECT_FALSE(isReddish(img.at(f.left + 3, row)));
  EXPECT_FALSE(isReddish(img.at(f.right - 3, row)));
}

TEST(Plot, AutoRangeKeepsEveryPointInsideTheFrame) {
  PlotSeries s;
  s.color_rgb = 0x0000FF;
  s.style = PlotSeries::Style::Markers;
  s.x = {-3.0, 7.0};
  s.y = {1e-3, 2e-3};
  const auto [img, f] = draw("corners.png", s);
  ASSERT_GE(f.left, 0);
  // A 5 % margin puts the points 1/22 of the frame in from two corners.
  const double fx = (f.right - f.left) / 22.0, fy = (f.bottom - f.top) / 22.0;
  const int x0 = static_cast<int>(std::lround(f.left + fx)), y0 = static_cast<int>(std::lround(f.bottom - fy));
  const int x1 = static_cast<int>(std::lround(f.right - fx)), y1 = static_cast<int>(std::lround(f.top + fy));
  EXPECT_TRUE(isBluish(img.at(x0, y0)));
  EXPECT_TRUE(isBluish(img.at(x1, y1)));
  EXPECT_FALSE(isBluish(img.at(x0, y1)));
  EXPECT_FALSE(isBluish(img.at(x1, y0)));
}

TEST(Plot, DefaultColoursDifferBetweenSeries) {
  PlotSpec spec;
  for (double level : {0.0, 1.0}) {
    PlotSeries s;
    s.x = {0.0, 1.0};
    s.y = {level, level};
    spec.series.push_back(s);
  }
  const fs::path path = tempPng("two_lines.png");
  writePlotPng(path, spec);
  const Image img = readPng(path);
  const FrameBox f = findFrame(img);
  ASSERT_GE(f.left, 0);
  const int x = (f.left + f.right) / 2;
  // The most saturated pixel near each line's row (1/22 of the frame inside).
  auto lineColour = [&](int row) {
    std::array<int, 3> best{255, 255, 255};
    int best_sat = -1;
    for (int y = row - 2; y <= row + 2; ++y) {
      const auto p = img.at(x, y);
      const int sat = std::max({p[0], p[1], p[2]}) - std::min({p[0], p[1], p[2]});
      if (sat > best_sat) best_sat = sat, best = p;
    }
    EXPECT_GT(best_sat, 60) << "no coloured line near row " << row;
    return best;
  };
  const double fy = (f.bottom - f.top) / 22.0;
  const auto low = lineColour(static_cast<int>(std::lround(f.bottom - fy)));
  const auto high = lineColour(static_cast<int>(std::lround(f.top + fy)));
  EXPECT_GT(std::abs(low[0] - high[0]) + std::abs(low[1] - high[1]) + std::abs(low[2] - high[2]), 100);
}

TEST(Plot, NonFiniteSinglePointAndEmptyChartsAreValid) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  PlotSpec gaps;
  gaps.title = "gaps";
  PlotSeries s;
  s.label = "with gaps";
  s.style = PlotSeries::Style::LineMarkers;
  s.x = {0.0, 1.0, nan, 3.0, 4.0, inf};
  s.y = {1.0, inf, 2.0, -1.0, nan, 0.0};
  gaps.series.push_back(s);
  PlotSeries all_bad;
  all_bad.label = "nothing finite";
  all_bad.x = {nan, inf};
  all_bad.y = {1.0, 2.0};
  gaps.series.push_back(all_bad);

  PlotSpec single;
  PlotSeries one;
  one.label = "one point";
  one.x = {2.0};
  one.y = {-5.0};
  single.series.push_back(one);

  PlotSpec constant_zero;
  PlotSeries zeros;
  zeros.x = {0.0, 0.0, 0.0};
  zeros.y = {0.0, 0.0, 0.0};
  constant_zero.series.push_back(zeros);

  PlotSpec empty;
  empty.title = "nothing to show";
  empty.width_px = 320;
  empty.height_px = 200;

  PlotSpec tiny;  // smaller than its own margins: clipped, never out of bounds
  tiny.title = "a title much wider than the image";
  tiny.width_px = 20;
  tiny.height_px = 10;
  tiny.series.push_back(s);

  int n = 0;
  for (const PlotSpec* spec : {&gaps, &single, &constant_zero, &empty, &tiny}) {
    const fs::path path = tempPng("edge" + std::to_string(n++) + ".png");
    ASSERT_NO_THROW(writePlotPng(path, *spec));
    const Image img = readPng(path);
    EXPECT_EQ(img.width, spec->width_px);
    EXPECT_EQ(img.height, spec->height_px);
    if (spec == &empty) {
      const FrameBox f = findFrame(img);
      EXPECT_GE(f.top, 0) << "an empty chart still has its frame";
      EXPECT_GE(f.left, 0);
    }
  }
}

TEST(Plot, UnwritablePathThrows) {
  PlotSpec spec;
  EXPECT_THROW(writePlotPng(fs::path(::testing::TempDir()) / "no_such_dir" / "x" / "plot.png", spec),
               std::runtime_error);
}

// A band (the fitted curve's confidence band) fills pale between its lower
// and upper edges and nowhere else; the auto-range includes its upper edge.
TEST(Plot, BandFillsBetweenItsEdges) {
  PlotSeries band;
  band.style = PlotSeries::Style::Band;
  band.color_rgb = 0x0000FF;
  band.x = {0.0, 1.0};
  band.y = {0.0, 0.0};
  band.y_upper = {1.0, 1.0};
  PlotSeries below;  // (a point at -1 so that the band does not start at the frame's bottom)
  below.style = PlotSeries::Style::Markers;
  below.color_rgb = 0xFFFFFF;
  below.x = {0.5};
  below.y = {-1.0};
  const auto drawn = draw("band.png", band, {below});
  const Image& img = drawn.img;
  const FrameBox& f = drawn.frame;
  ASSERT_GE(f.left, 0);
  // x from 0 to 1 and y from -1 to 1, with 5 % margins; points off the grid lines.
  const auto at = [&](double x, double y) {
    return img.at(static_cast<int>(std::lround(f.left + (x + 0.05) / 1.1 * (f.right - f.left))),
                  static_cast<int>(std::lround(f.bottom - (y + 1.1) / 2.2 * (f.bottom - f.top))));
  };
  const auto inside = at(0.53, 0.65), outside = at(0.53, -0.35);
  EXPECT_GT(inside[2], inside[0] + 40) << "pale blue inside the band";
  EXPECT_GT(inside[0], 120) << "pale, not solid";
  EXPECT_EQ(outside, (std::array<int, 3>{255, 255, 255})) << "white below the band";
  band.y_upper = {1.0};
  PlotSpec bad;
  bad.series = {band};
  EXPECT_THROW(writePlotPng(tempPng("bad_band.png"), bad), std::invalid_argument);
}

TEST(Plot, InvalidSpecThrows) {
  PlotSpec spec;
  spec.width_px = 0;
  EXPECT_THROW(writePlotPng(tempPng("bad.png"), spec), std::invalid_argument);
  PlotSpec mismatch;
  PlotSeries s;
  s.x = {1.0, 2.0};
  s.y = {1.0};
  mismatch.series.push_back(s);
  EXPECT_THROW(writePlotPng(tempPng("bad.png"), mismatch), std::invalid_argument);
}

// The scene view (bridge/scene_view.hpp): a red sphere and a blue one side
// by side along the screen's right axis are drawn where the projection puts
// them, on a white ground; an empty view is refused.
TEST(SceneView, SpheresLandWhereTheProjectionPutsThem) {
  gabion::bridge::SceneView v;
  v.azimuth_deg = 0.0;  // looking from +x: screen right is +y, up is +z
  v.elevation_deg = 0.0;
  v.spheres.push_back({Eigen::Vector3d(0.0, -1.0, 0.0), 0.5, 0xdd2020});
  v.spheres.push_back({Eigen::Vector3d(0.0, 1.0, 0.0), 0.5, 0x2020dd});
  v.width_px = 400;
  v.height_px = 200;
  const auto path = tempPng("view.png");
  gabion::bridge::writeSceneViewPng(path, v);
  const Image img = readPng(path);
  ASSERT_EQ(img.width, 400);
  ASSERT_EQ(img.height, 200);
  // Fitted with a 16 px margin: the spheres' centres at a quarter and three
  // quarters of the width, half the height (the shading is lit from the
  // upper left: sample a little up and left of each centre).
  EXPECT_TRUE(isReddish(img.at(96, 92))) << img.at(96, 92)[0] << " " << img.at(96, 92)[1];
  EXPECT_TRUE(isBluish(img.at(296, 92))) << img.at(296, 92)[2];
  const auto corner = img.at(2, 2);
  EXPECT_EQ(corner[0] + corner[1] + corner[2], 3 * 255);
  EXPECT_THROW(gabion::bridge::writeSceneViewPng(path, gabion::bridge::SceneView{}), std::invalid_argument);
}
