// Curve input: CSV and HDF5 readers accept good curves and reject bad ones with
// the file, the line and the column of the first bad value.
#include <gtest/gtest.h>

#include <filesystem>

#include "bridge/curve.hpp"
#include "bridge/errors.hpp"
#include "bridge/output.hpp"
#include "fitting/curve_model.hpp"
#include "tests/support/run_gabion.hpp"

namespace gabion::bridge {
namespace {

const std::filesystem::path kData = std::filesystem::path(GABION_TEST_DATA_DIR) / "fitting";

// Reads `file` expecting an InputError whose location contains `where` and
// whose message contains `what`.
void expectError(const std::string& file, const std::string& where, const std::string& what,
                 CurvePath path = CurvePath::Monotonic) {
  CurveRequest req;
  req.path = path;
  try {
    readCurveCsv(kData / file, req);
    FAIL() << file << ": no error";
  } catch (const InputError& e) {
    EXPECT_NE(e.file().find(file), std::string::npos) << e.what();
    EXPECT_NE(e.pointer().find(where), std::string::npos) << e.what();
    EXPECT_NE(e.message().find(what), std::string::npos) << e.what();
  }
}

TEST(CurveCsv, BadDataNamesFileLineAndColumn) {
  expectError("empty.csv", "line 1", "empty file");
  expectError("header_only.csv", "line 1", "no data rows");
  expectError("non_numeric.csv", "line 4, column 2 (force_N)", "not a number: 'abc'");
  expectError("unsorted.csv", "line 5, column 1 (displacement_m)", "unsorted");
  expectError("nan.csv", "line 5, column 2 (force_N)", "not finite");
  expectError("wrong_units.csv", "line 1, column 1 (displacement_mm)", "wrong unit");
  expectError("too_short.csv", "line 4", "too short");
  expectError("time_unsorted.csv", "line 4, column 1 (time_s)", "time_s must increase", CurvePath::Cyclic);
  expectError("missing.csv", "", "does not exist");
}

TEST(CurveCsv, CyclicCurveWithTimeColumnIsRead) {
  CurveRequest req;
  req.path = CurvePath::Cyclic;
  const Curve c = readCurveCsv(kData / "cyclic_ok.csv", req);
  ASSERT_EQ(c.size(), 6u);
  EXPECT_DOUBLE_EQ(c.x[3], 0.0015);
  EXPECT_DOUBLE_EQ(c.y[4], 5000.0);
  // The same file as a monotonic curve is unsorted at its unloading row.
  expectError("cyclic_ok.csv", "line 6, column 2 (displacement_m)", "unsorted");
}

TEST(CurveCsv, WriteReadRoundTripIsExact) {
  const auto dir = testing::scratchDir("curve_roundtrip");
  Curve c{"mem", "displacement_m", "force_N", {0.0, 0.1, 0.2, 0.3, 0.4}, {0.0, 1.0 / 3.0, 2.0, 2.5, 1e-17}};
  writeCurveCsv(dir / "c.csv", c);
  const Curve r = readCurveCsv(dir / "c.csv", CurveRequest{});
  EXPECT_EQ(r.x, c.x);
  EXPECT_EQ(r.y, c.y);
}

TEST(CurveH5, DocumentedDatasetsAndWallLayout) {
  const auto dir = testing::scratchDir("curve_h5");
  {
    H5Writer w(dir / "r.h5");
    w.write("/curves/axial/displacement_m", {0.0, 0.01, 0.02, 0.03, 0.04}, "m");
    w.write("/curves/axial/force_N", {0.0, 10.0, 20.0, 25.0, 25.0}, "N");
    w.write("/curves/axial/bad_unit_force", {0.0, 1.0, 2.0, 3.0, 4.0}, "kN");
    // Wall 1 driven along -z into the packing; the bodies push it back (+z).
    std::vector<double> pos, force;
    for (int i = 0; i < 6; ++i) {
      pos.insert(pos.end(), {0.0, 0.0, 1.0 - 0.01 * i});
      force.insert(force.end(), {0.0, 0.0, 100.0 * i});
    }
    w.write("/series/wall_1_position_m", pos, {6, 3}, "m");
    w.write("/series/wall_1_force_N", force, {6, 3}, "N");
    w.commit();
  }
  CurveRequest req;
  const Curve a = readCurveH5(dir / "r.h5", "/curves/axial/displacement_m", "/curves/axial/force_N", req);
  EXPECT_EQ(a.y[3], 25.0);
  EXPECT_THROW(readCurveH5(dir / "r.h5", "/curves/axial/displacement_m", "/curves/axial/bad_unit_force", req),
               InputError);
  EXPECT_THROW(readCurveH5(dir / "r.h5", "/curves/axial/displacement_m", "/curves/axial/nothing", req), InputError);
  const Curve wall = readWallCurveH5(dir / "r.h5", 1, Vec3(0, 0, -1), req);
  ASSERT_EQ(wall.size(), 6u);
  EXPECT_NEAR(wall.x[5], 0.05, 1e-12);
  EXPECT_NEAR(wall.y[5], 500.0, 1e-12);
  EXPECT_THROW(readWallCurveH5(dir / "r.h5", 2, Vec3(0, 0, -1), req), InputError);
}

TEST(PathGrid, LoadingUnloadingKeepsTurningPoints) {
  Curve c{"mem", "displacement_m", "force_N", {0.0, 0.5, 1.0, 0.7, 1.3}, {0.0, 5.0, 10.0, 7.0, 13.0}};
  const auto g = fitting::resampleOnPath(c, 7);  // path length 1.9; the turn at s = 1.0 is not on the uniform grid
  bool has_peak = false;
  for (std::size_t i = 0; i < g.x.size(); ++i) has_peak = has_peak || (g.x[i] == 1.0 && g.y[i] == 10.0);
  EXPECT_TRUE(has_peak);
  EXPECT_EQ(g.x.front(), 0.0);
  EXPECT_EQ(g.x.back(), 1.3);
  EXPECT_EQ(g.scale, 13.0);
}

}  // namespace
}  // namespace gabion::bridge

#include "fitting/sha256.hpp"

namespace gabion::fitting {
namespace {

TEST(Sha256, KnownVectorsOfFips180) {
  EXPECT_EQ(sha256Hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(sha256Hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(sha256Hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
}

}  // namespace
}  // namespace gabion::fitting
