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

// Writes the series of a named wall as micro.scene (gabion.micro.scene/2) does:
// (n, 3) force, position and displacement from the first position.
void writeWall(H5Writer& w, const std::string& name, const std::vector<double>& pos, const std::vector<double>& force) {
  const std::size_t n = pos.size() / 3;
  std::vector<double> disp(pos);
  for (std::size_t k = 0; k < disp.size(); ++k) disp[k] -= pos[k % 3];
  w.write("/series/walls/" + name + "/force_N", force, {n, 3}, "N");
  w.write("/series/walls/" + name + "/position_m", pos, {n, 3}, "m");
  w.write("/series/walls/" + name + "/displacement_m", disp, {n, 3}, "m");
}

// Expects `read` to throw an InputError for `file` whose text contains every one of `parts`.
template <class Read>
void expectInputError(Read read, const std::filesystem::path& file, const std::vector<std::string>& parts) {
  try {
    read();
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), file.string()) << e.what();
    for (const auto& p : parts) EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << p << " in " << e.what();
  }
}

TEST(CurveH5, DocumentedDatasetsAndNamedWallLayout) {
  const auto dir = testing::scratchDir("curve_h5");
  {
    H5Writer w(dir / "r.h5");
    w.write("/curves/axial/displacement_m", {0.0, 0.01, 0.02, 0.03, 0.04}, "m");
    w.write("/curves/axial/force_N", {0.0, 10.0, 20.0, 25.0, 25.0}, "N");
    w.write("/curves/axial/bad_unit_force", {0.0, 1.0, 2.0, 3.0, 4.0}, "kN");
    // The lid driven along -z into the packing; the bodies push it back (+z)
    // and push the floor down (-z).
    std::vector<double> pos, force, floor_pos, floor_force;
    for (int i = 0; i < 6; ++i) {
      pos.insert(pos.end(), {0.1, 0.2, 1.0 - 0.01 * i});
      force.insert(force.end(), {0.0, 0.0, 100.0 * i});
      floor_pos.insert(floor_pos.end(), {0.0, 0.0, 0.0});
      floor_force.insert(floor_force.end(), {0.0, 0.0, -100.0 * i});
    }
    writeWall(w, "lid", pos, force);
    writeWall(w, "z_minus", floor_pos, floor_force);
    w.attribute("/", "format", "gabion.micro.scene/2");
    w.commit();
  }
  CurveRequest req;
  const Curve a = readCurveH5(dir / "r.h5", "/curves/axial/displacement_m", "/curves/axial/force_N", req);
  EXPECT_EQ(a.y[3], 25.0);
  EXPECT_THROW(readCurveH5(dir / "r.h5", "/curves/axial/displacement_m", "/curves/axial/bad_unit_force", req),
               InputError);
  EXPECT_THROW(readCurveH5(dir / "r.h5", "/curves/axial/displacement_m", "/curves/axial/nothing", req), InputError);

  const Curve lid = readWallCurveH5(dir / "r.h5", "lid", Vec3(0, 0, -2), req);  // the direction is normalised
  ASSERT_EQ(lid.size(), 6u);
  EXPECT_NEAR(lid.x[5], 0.05, 1e-12);
  EXPECT_NEAR(lid.y[5], 500.0, 1e-12);
  EXPECT_NE(lid.source.find("/series/walls/lid"), std::string::npos) << lid.source;
  const WallSeries z_minus = readWallSeriesH5(dir / "r.h5", "z_minus");
  ASSERT_EQ(z_minus.force_N.size(), 6u);
  EXPECT_EQ(z_minus.force_N[2], Vec3(0, 0, -200.0));
  EXPECT_EQ(wallNamesH5(dir / "r.h5"), (std::vector<std::string>{"lid", "z_minus"}));
}

TEST(CurveH5, WallNotInTheFileNamesFileWallAndTheWallsThatAre) {
  const auto dir = testing::scratchDir("curve_h5_no_wall");
  {
    H5Writer w(dir / "r.h5");
    writeWall(w, "lid", {0, 0, 1, 0, 0, 0.9}, {0, 0, 0, 0, 0, 5});
    writeWall(w, "x_minus", {0, 0, 0, 0, 0, 0}, {0, 0, 0, -1, 0, 0});
    w.attribute("/", "format", "gabion.micro.scene/2");
    w.commit();
  }
  const auto file = dir / "r.h5";
  expectInputError([&] { readWallCurveH5(file, "roof", Vec3(0, 0, -1), CurveRequest{}); }, file,
                   {"/series/walls/roof", "no wall named 'roof'", "its walls: lid, x_minus"});
  // Not a wall name at all (it would address another group).
  expectInputError([&] { readWallSeriesH5(file, "../time_s"); }, file, {"not a wall name"});
}

TEST(CurveH5, IndexBasedWallLayoutOfFormat1IsRefused) {
  // gabion.micro.scene/1 wrote /series/wall_<i>_force_N and _position_m.
  const auto dir = testing::scratchDir("curve_h5_format1");
  for (const bool with_attribute : {true, false}) {
    const auto file = dir / (with_attribute ? "v1.h5" : "v1_no_format.h5");
    {
      H5Writer w(file);
      w.write("/series/wall_0_position_m", {0, 0, 1, 0, 0, 0.9}, {2, 3}, "m");
      w.write("/series/wall_0_force_N", {0, 0, 0, 0, 0, 5}, {2, 3}, "N");
      if (with_attribute) w.attribute("/", "format", "gabion.micro.scene/1");
      w.commit();
    }
    expectInputError(
        [&] { readWallCurveH5(file, "wall_0", Vec3(0, 0, -1), CurveRequest{}); }, file,
        {"wall 'wall_0' not found", "gabion.micro.scene/1", "no /series/walls group", "run the micro case again"});
  }
}

TEST(CurveH5, WallSeriesOfAnotherVersionOrIncompleteAreRefused) {
  const auto dir = testing::scratchDir("curve_h5_bad_wall");
  {
    H5Writer w(dir / "v3.h5");
    writeWall(w, "lid", {0, 0, 1, 0, 0, 0.9}, {0, 0, 0, 0, 0, 5});
    w.attribute("/", "format", "gabion.micro.scene/3");
    w.commit();
  }
  expectInputError([&] { readWallSeriesH5(dir / "v3.h5", "lid"); }, dir / "v3.h5",
                   {"'gabion.micro.scene/3'", "gabion.micro.scene/2"});
  {
    H5Writer w(dir / "partial.h5");
    w.write("/series/walls/lid/force_N", {0, 0, 0, 0, 0, 5}, {2, 3}, "N");
    w.write("/series/walls/lid/position_m", {0, 0, 1, 0, 0, 0.9}, {2, 3}, "m");
    w.commit();
  }
  expectInputError([&] { readWallSeriesH5(dir / "partial.h5", "lid"); }, dir / "partial.h5",
                   {"/series/walls/lid/displacement_m", "no displacement_m series"});
  {
    H5Writer w(dir / "not_micro.h5");
    w.write("/series/time_s", {0.0, 1.0}, "s");
    w.commit();
  }
  expectInputError([&] { readWallSeriesH5(dir / "not_micro.h5", "lid"); }, dir / "not_micro.h5",
                   {"no /series/walls group", "no format attribute"});
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
