// The input contract, table-driven: malformed inputs of every case kind and
// every file type (cases, law files, CSV curves, HDF5 cells), each given to
// `gabion check` and to `gabion run`. Each must exit 2 with a message that
// names the file and the field (JSON pointer, or line and column), and the
// rejected run must write nothing.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/support/run_gabion.hpp"

namespace {

namespace fs = std::filesystem;
using gabion::testing::runGabion;
using gabion::testing::scratchDir;
using gabion::testing::writeFile;

struct BadInput {
  std::string name;
  std::string args;      // after `gabion check` / `gabion run`
  std::string file;      // the file the message must name
  std::string expected;  // the field and what is wrong with it
};

std::string source(const std::string& relative) {
  return std::string(GABION_SOURCE_DIR) + "/" + relative;
}

// `case` with --set overrides, the message naming `case` and `expected`.
BadInput set(const std::string& name, const std::string& case_name, const std::vector<std::string>& sets,
             const std::string& expected) {
  BadInput b{name, source("cases/" + case_name), source("cases/" + case_name), expected};
  for (const auto& s : sets) b.args += " --set '" + s + "'";
  return b;
}

std::vector<BadInput> badInputs(const fs::path& dir) {
  const auto file = [&](const std::string& name, const std::string& text) {
    writeFile(dir / name, text);
    return (dir / name).string();
  };
  nlohmann::json law = nlohmann::json::parse(std::ifstream(source("cases/laws/illustrative.json")));
  law["materials"]["front"]["edge_m"] = -1;
  const std::string law_negative = file("law_negative.json", law.dump());
  const std::string law_format = file("law_format.json", R"({"format": "gabion.law/9", "materials": {}})");
  const std::string law_torn = file("law_torn.json", R"({"format": "gabion.law/2", "materials": {)");
  const std::string law_dup = file("law_dup.json", R"({"format": "gabion.law/2", "format": "gabion.law/2"})");
  const std::string header = "time_s,displacement_m,force_N\n";
  const std::string csv_text = file("text.csv", header + "0,0,1\n1,0.001,2\n2,abc,3\n3,0.003,4\n4,0.004,5\n");
  const std::string csv_short = file("short.csv", header + "0,0,1\n1,0.001,2\n2,0.002\n3,0.003,4\n4,0.004,5\n");
  const std::string csv_nan = file("nan.csv", header + "0,0,1\n1,0.001,2\n2,nan,3\n3,0.003,4\n4,0.004,5\n");
  const std::string csv_columns = file("columns.csv", "a,b\n0,0\n1,1\n2,2\n3,3\n4,4\n5,5\n");
  const std::string csv_empty = file("empty.csv", "");
  const std::string h5_fake = file("cell.h5", "not an HDF5 file");
  const std::string case_dup = file("dup.json", R"({"format": "gabion.case/1", "kind": "micro.scene", "kind": "x"})");
  const std::string case_deep = file("deep.json", R"({"format": "gabion.case/1", "kind": "micro.scene", "d": )" +
                                                      std::string(100, '[') + std::string(100, ']') + "}");
  const std::string case_torn = file("torn.json", R"({"format": "gabion.case/1", "kind": )");
  const std::string case_array = file("array.json", "[1, 2]");
  const std::string case_kind = file("kind.json", R"({"format": "gabion.case/1", "kind": "micro.nothing"})");
  const std::string case_format = file("format.json", R"({"format": "gabion.case/7", "kind": "micro.scene"})");
  const std::string case_big = file("big.json", R"({"format": "gabion.case/1", "kind": "macro.impact", "x": 1e400})");
  const std::string case_long =
      file("long.json", R"({"format": "gabion.case/1", "kind": "micro.scene", "description": ")" +
                            std::string(std::size_t{2} << 20, 'x') + "\"}");
  const std::string fifo = (dir / "fifo.json").string();
  mkfifo(fifo.c_str(), 0600);
  const std::string curve = "axial.curves.0.file=";

  std::vector<BadInput> v = {
      // micro.scene
      set("scene radius", "micro_box_compression.json", {"blocks.0.spheres.0.radius_m=-1"},
          "/blocks/0/spheres/0/radius_m: must be > 0 (got -1)"),
      set("scene material name", "micro_box_compression.json", {"blocks.0.material=\"nope\""},
          "/blocks/0/material: unknown material 'nope'"),
      set("scene density", "micro_box_compression.json", {"materials.limestone.density_kg_m3=0"},
          "/materials/limestone/density_kg_m3: must be > 0"),
      set("scene friction", "micro_box_compression.json", {"materials.limestone.friction=-0.1"},
          "/materials/limestone/friction"),
      set("scene damping", "micro_box_compression.json", {"materials.limestone.local_damping=1"},
          "/materials/limestone/local_damping"),
      set("scene zero normal", "micro_box_compression.json", {"walls.0.normal=[0,0,0]"},
          "/walls/0/normal: must not be the zero vector"),
      set("scene unknown key", "micro_box_compression.json", {"run.dt_seconds=1"},
          "/run/dt_seconds: unknown key 'dt_seconds'"),
      set("scene dt above critical", "micro_box_compression.json", {"run.dt_s=1"},
          "/run/dt_s: dt_s = 1 s is above the critical time step"),
      set("scene duration", "micro_box_compression.json", {"run.duration_s=0"}, "/run/duration_s: must be > 0"),
      set("scene center type", "micro_box_compression.json", {"walls.0.point_m=\"x\""},
          "/walls/0/point_m: expected an array of 3 numbers"),
      set("scene center length", "micro_box_compression.json", {"walls.0.point_m=[1,2]"},
          "/walls/0/point_m: expected an array of 3 numbers"),
      set("scene runaway factor", "micro_box_compression.json", {"run.energy_runaway_factor=1"},
          "/run/energy_runaway_factor: must be > 1"),
      set("scene output interval", "micro_box_compression.json", {"run.output_interval_s=-1"},
          "/run/output_interval_s: must be > 0"),
      set("scene gravity", "micro_box_compression.json", {"gravity_m_s2=[0,0]"},
          "/gravity_m_s2: expected an array of 3 numbers"),
      set("scene wall key", "micro_box_compression.json", {"walls.0.program=\"wobble\""},
          "/walls/0/program: unknown key 'program'"),
      set("scene centuries", "micro_box_compression.json", {"run.duration_s=3e8"}, "/run/duration_s: the time step"),
      // micro.netting_tensile, micro.cell
      set("netting opening", "micro_netting_tensile.json", {"netting.opening_m=-1"}, "/netting/opening_m"),
      set("netting pull", "micro_netting_tensile.json", {"test.pull_speed_m_s=0"}, "/test/pull_speed_m_s"),
      set("cell porosity", "micro_cell.json", {"target_porosity=1.2"}, "/target_porosity: must be below 1"),
      set("cell edge", "micro_cell.json", {"edge_m=0"}, "/edge_m: must be > 0"),
      set("cell seed", "micro_cell.json", {"seed=-1"}, "/seed: must be >= 0"),
      set("cell grading type", "micro_cell.json", {"blocks.grading=[]"}, "/blocks/grading: expected an object"),
      set("cell vibration", "micro_cell.json", {"vibration.frequency_hz=-5"}, "/vibration/frequency_hz: must be > 0"),
      // lab tests
      set("uci velocity", "micro_uci.json", {"velocities_m_s=[-8]"}, "/velocities_m_s/0: must be > 0"),
      set("uci no velocity", "micro_uci.json", {"velocities_m_s=[]"}, "/velocities_m_s: expected at least 1 value"),
      set("uci boulder", "micro_uci.json", {"boulder.diameter_m=0"}, "/boulder/diameter_m: must be > 0"),
      set("uci cell case", "micro_uci.json", {"cell={\"case\": \"nope.json\"}"}, "/cell/case: no such case file"),
      set("uc cell file", "micro_uc.json", {"cell=\"nope.h5\""}, "/cell: no cell file"),
      set("cc replicates", "micro_cc.json", {"replicates=0"}, "/replicates: must be >= 1"),
      set("shear stress", "micro_shear.json", {"shear.normal_stress_Pa=-1"}, "/shear/normal_stress_Pa"),
      set("shear unknown key", "micro_shear.json", {"normal_forces_N=[1]"}, "/normal_forces_N: unknown key"),
      // macro
      set("impact velocity", "wall_impact.json", {"boulder.velocity_m_s=-3"}, "/boulder/velocity_m_s: must be > 0"),
      set("impact cells", "wall_impact.json", {"structure.cells=[0,1,1]"}, "/structure/cells/0: must be > 0"),
      set("impact cells length", "wall_impact.json", {"structure.cells=[4,11]"},
          "/structure/cells: expected at least 3 values"),
      set("impact aim", "wall_impact.json", {"boulder.aim_point_m=[100,100]"},
          "/boulder/aim_point_m: the aim point is outside the front face"),
      set("impact material", "wall_impact.json", {"structure.material.front=\"nope\""},
          "/structure/material/front: material 'nope' is not in the laws"),
      set("impact law file", "wall_impact.json", {"law_file=\"nope.json\""}, "/law_file: no such law file"),
      set("impact kinematics", "wall_impact.json", {"run.kinematics=\"6d\""}, "/run/kinematics: '6d' is not one of"),
      set("impact step fraction", "wall_impact.json", {"run.time_step_fraction=2"},
          "/run/time_step_fraction: must be <= 1"),
      set("impact support", "wall_impact.json", {"structure.support.back=\"glued\""},
          "/structure/support/back: 'glued' is not one of"),
      set("impact series", "wall_impact.json", {"run.series_every_steps=0"}, "/run/series_every_steps: must be >= 1"),
      set("impact integer range", "wall_impact.json", {"run.series_every_steps=4294967296"},
          "/run/series_every_steps: must be <= 2147483647"),
      set("impact endless", "wall_impact.json", {"run.duration_s=1e9"}, "/run/duration_s: an impact of up to"),
      set("impact huge structure", "wall_impact.json", {"structure.cells=[1000,1000,1000]"},
          "/structure/cells: 1e+09 cells, more than 10000000"),
      set("sweep count", "macro_sweep.json", {"sweep.velocity_m_s.count=0"}, "/sweep/velocity_m_s/count: must be >= 1"),
      set("sweep axis type", "macro_sweep.json", {"sweep.velocity_m_s=\"fast\""},
          "/sweep/velocity_m_s: expected an array of numbers"),
      set("sweep size", "macro_sweep.json", {"sweep.cells=[[0,1,1]]"}, "/sweep/cells/0: expected [x, y, z] integers"),
      set("sweep endless", "macro_sweep.json", {"run.duration_s=1e9"}, "/run/duration_s: an impact of up to"),
      set("capacity range", "macro_capacity.json", {"capacity.range=[30,10]"},
          "/capacity/range: the lowest must be below the highest"),
      set("capacity over", "macro_capacity.json", {"capacity.over=\"height\""}, "/capacity/over: 'height' is not one"),
      set("capacity tolerance", "macro_capacity.json", {"capacity.tolerance=0.7"},
          "/capacity/tolerance: must be < 0.5"),
      set("design thickness", "macro_design.json", {"design.thickness_cells=[5,2]"},
          "/design/thickness_cells: inverted"),
      set("design material", "macro_design.json", {"design.front_materials=[\"nope\"]"},
          "/design/front_materials/0: material 'nope' is not in the law file"),
      set("design probability", "macro_design.json", {"design.acceptance_probability=1.5"},
          "/design/acceptance_probability: must be in (0, 1]"),
      set("3-D offsets", "macro_sloped_wall_3d.json", {"structure.front_offset_cells=[0]"},
          "/structure/front_offset_cells: expected one offset per z layer"),
      // fit, fit.micro, pipeline
      set("fit optimizer", "fit_lab_cc.json", {"optimizer.global=\"NO_SUCH\""},
          "/optimizer/global: unknown global algorithm 'NO_SUCH'"),
      set("fit material name", "fit_lab_cc.json", {"material.name=\"\""}, "/material/name: must not be empty"),
      set("fit softening axial", "fit_lab_cc.json", {"axial.models=[\"softening\"]"},
          "/axial/models: 'softening' is a model of the impact law only"),
      set("fit rate law without time", "fit_cell_laws.json", {"impact.models=[\"softening_rate\"]"},
          "/impact/curves/0/t_column: required by the model softening_rate"),
      set("fit curve extension", "fit_lab_cc.json", {curve + "\"cc.txt\""}, "/axial/curves/0/file: must end in .csv"),
      set("fit.micro case file", "fit_micro_wall.json", {"micro_case=\"nope.json\""}, "/micro_case: no such case file"),
      set("fit.micro bounds", "fit_micro_wall.json", {"parameters.0.bounds=[5,1]"},
          "/parameters/0/bounds: must be [lower, upper] with upper > lower"),
      set("fit.micro set path", "fit_micro_wall.json", {"parameters.0.set=\"run.no_such_key\""},
          "/parameters/0/set: the micro case with the parameters at the middle of their bounds is not valid"),
      set("pipeline cell", "pipeline.json", {"cell=\"nope.json\""}, "/cell: "),
      set("pipeline material", "pipeline.json", {"structure.material=\"nope\""},
          "/structure/material: no material 'nope'"),
      set("pipeline velocity", "pipeline.json", {"structure.velocities_m_s=[-1]"},
          "/structure/velocities_m_s/0: must be > 0"),
      set("pipeline lab case", "pipeline.json", {"lab.cc=\"nope.json\""}, "/lab/cc: "),
      // law files
      {"law negative edge", source("cases/wall_impact.json") + " --set 'law_file=\"" + law_negative + "\"'",
       law_negative, "/materials/front/edge_m: must be > 0"},
      {"law format", source("cases/wall_impact.json") + " --set 'law_file=\"" + law_format + "\"'", law_format,
       "/format: expected 'gabion.law/2'"},
      {"law torn", source("cases/wall_impact.json") + " --set 'law_file=\"" + law_torn + "\"'", law_torn,
       "invalid JSON: parse error at line 1"},
      {"law duplicate key", source("cases/wall_impact.json") + " --set 'law_file=\"" + law_dup + "\"'", law_dup,
       "/format: duplicate key 'format'"},
      {"law --law missing", source("cases/wall_impact.json") + " --law " + (dir / "no_law.json").string(),
       (dir / "no_law.json").string(), "--law: no such file"},
      // CSV curves: line and column
      {"csv text", source("cases/fit_lab_cc.json") + " --set '" + curve + "\"" + csv_text + "\"'", csv_text,
       "line 4, column 2 (displacement_m): not a number: 'abc'"},
      {"csv short row", source("cases/fit_lab_cc.json") + " --set '" + curve + "\"" + csv_short + "\"'", csv_short,
       "line 4, column 3: row has 2 cells, the header has 3"},
      {"csv nan", source("cases/fit_lab_cc.json") + " --set '" + curve + "\"" + csv_nan + "\"'", csv_nan,
       "line 4, column 2 (displacement_m): value is not finite"},
      {"csv columns", source("cases/fit_lab_cc.json") + " --set '" + curve + "\"" + csv_columns + "\"'", csv_columns,
       "line 1: missing column 'displacement_m'"},
      {"csv empty", source("cases/fit_lab_cc.json") + " --set '" + curve + "\"" + csv_empty + "\"'", csv_empty,
       "line 1: empty file"},
      // HDF5 cell
      {"cell not HDF5", source("cases/micro_uc.json") + " --set 'cell=\"" + h5_fake + "\"'", h5_fake,
       "not an HDF5 file"},
      // case files themselves
      {"duplicate key", case_dup, case_dup, "/kind: duplicate key 'kind'"},
      {"nested too deep", case_deep, case_deep, "nested deeper than 64 levels"},
      {"torn JSON", case_torn, case_torn, "invalid JSON"},
      {"not an object", case_array, case_array, "top level must be a JSON object"},
      {"unknown kind", case_kind, case_kind, "/kind: unknown case kind"},
      {"unknown format", case_format, case_format, "/format: expected 'gabion.case/1'"},
      {"number overflow", case_big, case_big, "number overflow"},
      {"free text too long", case_long, case_long, "/description: a string of 2097152 bytes, more than 1048576"},
      {"FIFO", fifo, fifo, "not a regular file"},
      {"directory", dir.string(), dir.string(), "is a directory"},
      {"missing case", (dir / "missing.json").string(), (dir / "missing.json").string(), "does not exist"},
  };
  return v;
}

TEST(BadInputs, EachExitsTwoNamingTheFileAndTheFieldAndWritesNothing) {
  const auto dir = scratchDir("bad_inputs");
  const auto cases = badInputs(dir);
  EXPECT_GE(cases.size(), 60u);
  for (const BadInput& b : cases) {
    const auto checked = runGabion("check " + b.args);
    EXPECT_EQ(checked.exit_code, 2) << b.name << ": " << checked.output;
    EXPECT_NE(checked.output.find(b.file), std::string::npos) << b.name << ": names no file: " << checked.output;
    EXPECT_NE(checked.output.find(b.expected), std::string::npos) << b.name << ": " << checked.output;
    const auto out = dir / "out";
    const auto ran = runGabion("run " + b.args + " -q -o " + out.string());
    EXPECT_EQ(ran.exit_code, 2) << b.name << ": " << ran.output;
    EXPECT_EQ(ran.output, checked.output) << b.name << ": run and check disagree";
    EXPECT_FALSE(fs::exists(out)) << b.name << ": a rejected case must write nothing";
  }
}

}  // namespace
