// The cell file: a packed state written and read back is the same state
// (bodies, block poses, wire states), and files that are not cell files of
// this version are input errors naming the file.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "../support/run_gabion.hpp"
#include "bridge/errors.hpp"
#include "bridge/laws/wire.hpp"
#include "bridge/output.hpp"
#include "micro/blocks/angular_block.hpp"
#include "micro/cell/cell_file.hpp"
#include "micro/engine.hpp"
#include "micro_test_util.hpp"

namespace {

using namespace gabion::micro;

// Spheres, two angular blocks and a wire pulled into its plastic range by a
// driven node, run for a while: a state with velocities, rotations and a
// wire that remembers its plastic strain.
Scene movingScene() {
  Scene s;
  s.gravity_m_s2 = Vec3(0, 0, -9.81);
  Material rock = test::material(1e6, 2.5e5, 0.5, 0.1);
  rock.density_kg_m3 = 2600;
  rock.name = "rock";
  Material steel = test::material(2e6, 5e5, 0.3);
  steel.density_kg_m3 = 7850;
  steel.name = "a_steel";  // sorts before "rock": the file must keep the index order
  s.materials = {rock, steel};
  s.walls.push_back({});  // the floor z = 0
  for (int k = 0; k < 4; ++k) s.spheres.push_back(test::sphere(Vec3(0.05 * k, 0.0, 0.05), 0.02));
  for (int k = 0; k < 2; ++k) {
    const BlockGeometry g = angularBlock({}, 0.06);
    BlockSpec b;
    b.member_centers_m = g.centers_m;
    b.member_radii_m = g.radii_m;
    b.position_m = Vec3(0.1 * k, 0.2, 0.1);
    b.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3 + k, Vec3(1, 2, 3).normalized()));
    b.angular_velocity_rad_s = Vec3(1.0, -2.0, 0.5);
    s.blocks.push_back(b);
  }
  SphereSpec anchor = test::sphere(Vec3(0.5, 0.0, 0.5), 0.005, true),
             pulled = test::sphere(Vec3(0.55, 0, 0.5), 0.005, true);
  pulled.velocity_m_s = Vec3(0.5, 0, 0);
  s.spheres.push_back(anchor), s.spheres.push_back(pulled);
  LinkSpec wire;
  wire.a = 4, wire.b = 5;
  wire.law = LinkSpec::Law::Wire;
  wire.wire.rest_length_m = 0.05;
  wire.wire.curve = gabion::bridge::wireCurve(gabion::bridge::defaultWireTable(), 0.0022);
  s.links.push_back(wire);
  return s;
}

TEST(CellFile, ReadsBackToTheSameState) {
  const auto dir = gabion::testing::scratchDir("cell_file");
  const Scene a = movingScene();
  Engine ea(a, 1);
  ea.setDt(0.2 * ea.criticalDt());
  // Until the wire is well into its plastic range (it breaks at 35 %).
  for (int n = 0; n < 1000000 && ea.linkWireState(0).reached_strain < 0.1; ++n)
    ASSERT_EQ(ea.step(n % 100 == 0), StepStatus::Ok);
  ASSERT_GT(ea.linkWireState(0).plastic_strain, 0.05);
  ASSERT_FALSE(ea.linkBroken(0));
  writeCellFile(dir / "cell.h5", a, ea, {{"note", "test"}});

  Scene b;
  b.gravity_m_s2 = a.gravity_m_s2;
  b.walls = a.walls;
  loadCellFile(dir / "cell.h5", b);
  ASSERT_EQ(b.spheres.size(), a.spheres.size());
  ASSERT_EQ(b.blocks.size(), a.blocks.size());
  ASSERT_EQ(b.links.size(), 1u);
  ASSERT_EQ(b.materials.size(), 2u);
  EXPECT_EQ(b.materials[0].name, "rock");
  EXPECT_EQ(b.materials[0].friction, 0.5);
  EXPECT_EQ(b.materials[1].friction, 0.3);
  for (std::size_t k = 0; k < a.spheres.size(); ++k) EXPECT_EQ(b.spheres[k].material, a.spheres[k].material) << k;
  Engine eb(b, 1);
  for (std::size_t k = 0; k < ea.bodyCount(); ++k) {
    const BodyState x = ea.body(k), y = eb.body(k);
    EXPECT_LT((x.position_m - y.position_m).norm(), 1e-12) << "body " << k;
    EXPECT_EQ(x.velocity_m_s, y.velocity_m_s) << "body " << k;
    EXPECT_LT((x.angular_velocity_rad_s - y.angular_velocity_rad_s).norm(),
              1e-12 * std::max(1.0, x.angular_velocity_rad_s.norm()))
        << "body " << k;
  }
  for (std::size_t k = 0; k < ea.blockCount(); ++k)
    EXPECT_LT((ea.blockOrientation(k).toRotationMatrix() - eb.blockOrientation(k).toRotationMatrix()).norm(), 1e-12);
  EXPECT_EQ(eb.linkWireState(0).plastic_strain, ea.linkWireState(0).plastic_strain);
  EXPECT_EQ(eb.linkWireState(0).reached_strain, ea.linkWireState(0).reached_strain);
  // Every member sphere where it was.
  std::vector<Vec3> ca, cb;
  std::vector<double> ra, rb;
  ea.sphereGeometry(ca, ra), eb.sphereGeometry(cb, rb);
  ASSERT_EQ(ca.size(), cb.size());
  for (std::size_t k = 0; k < ca.size(); ++k) EXPECT_LT((ca[k] - cb[k]).norm(), 1e-12) << "sphere " << k;
  EXPECT_EQ(ra, rb);
}

TEST(CellFile, ForeignTruncatedAndNewerFilesAreInputErrorsNamingTheFile) {
  const auto dir = gabion::testing::scratchDir("cell_file_bad");
  const Scene a = movingScene();
  Engine ea(a, 1);
  writeCellFile(dir / "cell.h5", a, ea, {});
  // Truncated: the first kilobyte of a good file.
  {
    std::ifstream in(dir / "cell.h5", std::ios::binary);
    std::string bytes(1024, '\0');
    in.read(bytes.data(), 1024);
    std::ofstream(dir / "truncated.h5", std::ios::binary) << bytes;
  }
  // Foreign: an HDF5 file of another kind; newer: a cell of another version.
  {
    gabion::bridge::H5Writer w(dir / "foreign.h5");
    w.write("/series/time_s", {0.0, 1.0}, "s");
    w.attribute("/", "format", "gabion.micro.scene/2");
    w.commit();
    gabion::bridge::H5Writer v(dir / "newer.h5");
    v.write("/spheres/radius_m", {0.01}, "m");
    v.attribute("/", "format", "gabion.cell/2");
    v.commit();
  }
  for (const std::string name : {"truncated.h5", "foreign.h5", "newer.h5", "missing.h5"}) {
    Scene s;
    try {
      loadCellFile(dir / name, s);
      ADD_FAILURE() << name << " was read";
    } catch (const gabion::bridge::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
  // Through a case: exit 2, naming the cell file.
  gabion::testing::writeFile(dir / "case.json", R"({"format": "gabion.case/1", "kind": "micro.scene",
    "gravity_m_s2": [0, 0, -9.81], "materials": {}, "from_cell": "foreign.h5", "run": {"duration_s": 0.01}})");
  const auto r = gabion::testing::runGabion("check " + (dir / "case.json").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("foreign.h5"), std::string::npos) << r.output;
}

}  // namespace

namespace {

// Through the command line: a run that saves its cell, and a run that starts
// from it with the case's own material of the same name winning.
TEST(CellFile, ARunSavesItsCellAndAnotherStartsFromIt) {
  const auto dir = gabion::testing::scratchDir("cell_file_cli");
  gabion::testing::writeFile(dir / "make.json", R"({"format": "gabion.case/1", "kind": "micro.scene",
    "gravity_m_s2": [0, 0, -9.81],
    "materials": {"rock": {"density_kg_m3": 2600, "normal_stiffness_N_m": 1e6, "shear_stiffness_N_m": 2.5e5, "friction": 0.5}},
    "spheres": [{"center_m": [0, 0, 0.05], "radius_m": 0.02, "material": "rock"},
                {"center_m": [0.03, 0, 0.1], "radius_m": 0.02, "material": "rock"}],
    "walls": [{"point_m": [0, 0, 0], "normal": [0, 0, 1], "material": "rock"}],
    "porosity": {"min_m": [-0.1, -0.1, 0], "max_m": [0.1, 0.1, 0.1]},
    "save_cell": true, "run": {"duration_s": 0.05}})");
  auto r = gabion::testing::runGabion("run " + (dir / "make.json").string() + " -q -o " + (dir / "made").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const gabion::bridge::H5Reader cell(dir / "made" / "cell.h5");
  EXPECT_EQ(cell.attribute("/", "format"), "gabion.cell/2");
  EXPECT_NE(cell.attribute("/", "summary").find("porosity"), std::string::npos);
  gabion::testing::writeFile(dir / "use.json", R"({"format": "gabion.case/1", "kind": "micro.scene",
    "gravity_m_s2": [0, 0, -9.81],
    "materials": {"rock": {"density_kg_m3": 2600, "normal_stiffness_N_m": 1e6, "shear_stiffness_N_m": 2.5e5, "friction": 0.2}},
    "walls": [{"point_m": [0, 0, 0], "normal": [0, 0, 1], "material": "rock"}],
    "from_cell": "made/cell.h5", "run": {"duration_s": 0.001}})");
  r = gabion::testing::runGabion("run " + (dir / "use.json").string() + " -q -o " + (dir / "used").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const gabion::bridge::H5Reader made(dir / "made" / "result.h5"), used(dir / "used" / "result.h5");
  const std::vector<double> end = made.read("/bodies/position_m"), start = used.read("/bodies/position_m");
  const std::size_t last = made.dims("/bodies/position_m")[0] - 1;
  for (std::size_t k = 0; k < 6; ++k) EXPECT_EQ(start[k], end[last * 6 + k]) << k;  // 2 spheres x 3
}

}  // namespace
