// Result files: HDF5 round trip, atomic replacement, corrupt files reported.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "bridge/errors.hpp"
#include "bridge/output.hpp"

using namespace gabion::bridge;
namespace fs = std::filesystem;

TEST(Output, Hdf5RoundTripAndAtomicRename) {
  const fs::path path = fs::path(::testing::TempDir()) / "roundtrip.h5";
  fs::remove(path);
  {
    H5Writer w(path);
    w.write("/series/time_s", {0.0, 0.5, 1.0}, "s");
    w.write("/bodies/position_m", {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12}, {2, 2, 3}, "m");
    EXPECT_FALSE(fs::exists(path));  // only the .part file exists until commit
    w.commit();
  }
  ASSERT_TRUE(fs::exists(path));
  H5Reader r(path);
  EXPECT_EQ(r.read("/series/time_s"), (std::vector<double>{0.0, 0.5, 1.0}));
  EXPECT_EQ(r.dims("/bodies/position_m"), (std::vector<std::size_t>{2, 2, 3}));
  EXPECT_EQ(r.attribute("/series/time_s", "unit"), "s");
  EXPECT_FALSE(r.has("/nothing/here"));
  EXPECT_THROW(r.read("/nothing/here"), InputError);
}

TEST(Output, AppendedRowsGrowTheFirstDimension) {
  const fs::path path = fs::path(::testing::TempDir()) / "append.h5";
  fs::remove(path);
  {
    H5Writer w(path);
    w.appendRow("/bodies/position_m", {1, 2, 3, 4, 5, 6}, {2, 3}, "m");
    w.appendRow("/bodies/position_m", {7, 8, 9, 10, 11, 12}, {2, 3}, "m");
    w.appendRow("/bodies/position_m", {13, 14, 15, 16, 17, 18}, {2, 3}, "m");
    EXPECT_THROW(w.appendRow("/bodies/position_m", {1, 2}, {2, 3}), std::logic_error);
    w.commit();
  }
  H5Reader r(path);
  EXPECT_EQ(r.dims("/bodies/position_m"), (std::vector<std::size_t>{3, 2, 3}));
  const std::vector<double> all = r.read("/bodies/position_m");
  ASSERT_EQ(all.size(), 18u);
  for (std::size_t k = 0; k < all.size(); ++k) EXPECT_EQ(all[k], static_cast<double>(k + 1));
  EXPECT_EQ(r.attribute("/bodies/position_m", "unit"), "m");
}

TEST(Output, UncommittedWriterLeavesNoFile) {
  const fs::path path = fs::path(::testing::TempDir()) / "abandoned.h5";
  fs::remove(path);
  {
    H5Writer w(path);
    w.write("/a", {1.0});
  }
  EXPECT_FALSE(fs::exists(path));
  EXPECT_FALSE(fs::exists(path.string() + ".part"));
}

TEST(Output, CorruptHdf5IsInputError) {
  const fs::path path = fs::path(::testing::TempDir()) / "corrupt.h5";
  std::ofstream(path) << "this is not hdf5";
  try {
    H5Reader r(path);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path.string());
    EXPECT_NE(std::string(e.what()).find("not an HDF5 file"), std::string::npos);
  }
}
