// The calibration pipeline end to end on a reduced chain (a 0.3 m cell of
// about 45 blocks, short lab tests, a small wall): every stage leaves valid
// outputs, the law file it writes is fitted from the four tests, the report
// embeds every figure it names, a second run reuses every stage, and a
// changed setting reruns only the stages that depend on it. Bad input names
// the field before anything runs.
#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <regex>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "bridge/law_file.hpp"
#include "bridge/output.hpp"
#include "micro/cell/cell_file.hpp"
#include "tests/support/run_gabion.hpp"
#include "tests/support/small_cell.hpp"

using gabion::testing::runGabion;
using gabion::testing::scratchDir;
using gabion::testing::writeFile;
namespace fs = std::filesystem;

namespace {

nlohmann::json readJson(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

std::string readText(const fs::path& p) {
  std::ifstream in(p);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// The small chain's files: cell, lab tests, wall, sweep, capacity and design cases,
// and a law file whose material 'small' the pipeline replaces.
void writeSmallChain(const fs::path& dir) {
  writeFile(dir / "cell.json", gabion::testing::smallCellCase());
  const std::string head = R"({"format": "gabion.case/1", "cell": "replaced.h5", )";
  writeFile(
      dir / "cc.json",
      head + R"("kind": "micro.cc", "loading": {"velocity_m_s": 0.2, "strain": 0.05, "unload_at_strain": [0.03]}})");
  writeFile(dir / "uc.json", head + R"("kind": "micro.uc", "loading": {"velocity_m_s": 0.2, "strain": 0.03}})");
  writeFile(dir / "uci.json", head + R"("kind": "micro.uci", "velocity_m_s": 6, "boulder": {"diameter_m": 0.3},
 "run": {"duration_s": 0.03}})");
  writeFile(dir / "shear.json", head + R"("kind": "micro.shear",
 "shear": {"normal_stress_Pa": 10000, "displacement_m": 0.01, "velocity_m_s": 0.05}})");
  nlohmann::json law = readJson(std::string(GABION_SOURCE_DIR) + "/cases/laws/illustrative.json");
  nlohmann::json small = law["materials"]["front"];
  small["edge_m"] = 0.3;
  small["mass_kg"] = 40.0;
  for (const char* l : {"axial", "impact"}) small[l]["lockup_shortening_m"] = 0.075;
  law["materials"] = {{"small", small}};
  writeFile(dir / "law.json", law.dump());
  const std::string wall = R"("law_file": "law.json",
 "structure": {"cells": [3, 5, 3], "material": {"front": "small", "core": "small"}, "support": {"back": "fixed"}},
 "boulder": {"diameter_m": 0.3, "density_kg_m3": 2600, "velocity_m_s": 10, "aim_point_m": [0.75, 0.45]},
 "run": {"duration_s": 0.05})";
  writeFile(dir / "wall.json", R"({"format": "gabion.case/1", "kind": "macro.impact", )" + wall + "}");
  writeFile(dir / "sweep.json", R"({"format": "gabion.case/1", "kind": "macro.sweep", )" + wall +
                                    R"(, "sweep": {"velocity_m_s": {"from": 4, "to": 16, "count": 4}, "chart": true,
 "limits": {"max_penetration_m": 0.1}}})");
  writeFile(dir / "capacity.json", R"({"format": "gabion.case/1", "kind": "macro.capacity", )" + wall +
                                       R"(, "capacity": {"range": [2, 40], "criteria": {"max_penetration_m": 0.1}}})");
  writeFile(dir / "design.json", R"({"format": "gabion.case/1", "kind": "macro.design", )" + wall +
                                     R"(, "design": {"thickness_cells": [1, 4], "height_cells": [2, 3],
 "criteria": {"max_penetration_m": 0.15}, "residual_capacity_max_impacts": 3}})");
  writeFile(dir / "pipeline.json", R"({"format": "gabion.case/1", "kind": "pipeline", "seed": 3,
 "cell": "cell.json",
 "lab": {"cc": "cc.json", "uc": "uc.json", "uci": "uci.json", "shear": "shear.json"},
 "uci_velocities_m_s": [5, 8],
 "cc_rate_velocities_m_s": [1.5],
 "joint": {"cells_in_series": 2, "strain": 0.15},
 "structure": {"case": "wall.json", "material": "small", "velocities_m_s": [8, 12]},
 "sweep": "sweep.json", "capacity": "capacity.json", "design": "design.json"})");
}

}  // namespace

TEST(Pipeline, ReducedChainRunsEveryStageThenReusesThem) {
  const auto dir = scratchDir("pipeline_small");
  writeSmallChain(dir);
  const fs::path out = dir / "out";
  auto r = runGabion("run " + (dir / "pipeline.json").string() + " --threads 2 -o " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // The console's headline: fitted parameters with intervals, the answers, the report.
  for (const char* line : {"fitted laws of 'small'", "joint (power",
                           "pipeline: capacity:", "pipeline: design:", "report.html", "one draw of its packing"})
    EXPECT_NE(r.output.find(line), std::string::npos) << line << "\n" << r.output;

  const auto s = readJson(out / "summary.json");
  EXPECT_EQ(s.at("status"), "ok");
  EXPECT_EQ(s.at("stages_reused"), 0);
  // Every stage left an ok summary and the files the next one reads.
  for (const auto& st : s.at("stages")) {
    const fs::path d = out / st.at("folder").get<std::string>();
    EXPECT_EQ(readJson(d / "summary.json").at("status"), "ok") << d;
    EXPECT_TRUE(fs::exists(d / "stage.json")) << d;
  }
  for (const char* f :
       {"1_cell/cell.h5", "2_cc/result.h5", "2_cc_rate_1.5_m_s/result.h5", "2_cc_x/result.h5", "2_cc_x_row/result.h5",
        "3_fit/fit_joint.png", "2_uc/result.h5", "2_uci/v5/result.h5", "2_uci/v8/result.h5", "2_shear/result.h5",
        "3_fit/law.json", "4_impact_8_m_s/result.h5", "4_sweep/sweep.csv", "figures/sweep_chart_penetration.png",
        "5_capacity/capacity.png", "6_design/capacity_vs_thickness.png", "law.json", "report.html"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  // Each lab test estimated its cost before it ran (the ETA's ground), and
  // none took more steps than estimated.
  for (const auto& st : s.at("stages")) {
    const std::string folder = st.at("folder").get<std::string>();
    if (folder.rfind("2_", 0) != 0) continue;
    ASSERT_TRUE(st.contains("estimated_body_steps")) << folder;
    EXPECT_GT(st.at("estimated_body_steps").get<double>(), 0.0) << folder;
  }
  {
    const auto cc = readJson(out / "2_cc" / "summary.json");
    EXPECT_GE(s.at("stages")[1].at("estimated_body_steps").get<double>(),
              cc.at("steps").get<double>() * cc.at("spheres").get<double>());
  }

  // The law file: 'small' replaced by the law fitted from the four tests,
  // with its lock-up from the generated cell's porosity.
  const auto laws = gabion::bridge::loadLawFile(out / "law.json");
  const auto& m = laws.materials.at("small");
  for (const char* law : {"axial", "momentum_flux", "lateral", "interface", "impact"})
    EXPECT_TRUE(m.provenance.at("fitted").contains(law)) << law;
  // The axial law's momentum flux from the compression at 1.5 m/s: its
  // curve is the fit's input, at that plate speed, without unloading.
  const auto& flux_inputs = m.provenance.at("fitted").at("momentum_flux").at("inputs");
  ASSERT_EQ(flux_inputs.size(), 1u);
  EXPECT_NEAR(flux_inputs[0].at("largest_rate_m_s").get<double>(), 1.5, 0.05);
  const auto fast = readJson(out / "2_cc_rate_1.5_m_s" / "case.json");
  EXPECT_EQ(fast.at("loading").at("velocity_m_s"), 1.5);
  EXPECT_TRUE(fast.at("loading").at("unload_at_strain").empty());
  EXPECT_EQ(fast.at("loading").at("strain"), readJson(out / "2_cc" / "case.json").at("loading").at("strain"));
  EXPECT_GE(m.axial.momentum_flux_kg_m, 0.0);
  // The joint from the compressions along x of one cell and of a row of
  // two, to the joint's strain, without unloading: in the law file.
  for (const auto& [folder, n] : {std::make_pair("2_cc_x", 1), std::make_pair("2_cc_x_row", 2)}) {
    const auto loading = readJson(out / folder / "case.json").at("loading");
    EXPECT_EQ(loading.at("axis"), "x") << folder;
    EXPECT_EQ(loading.at("cells_in_series"), n) << folder;
    EXPECT_EQ(loading.at("strain"), 0.15) << folder;
    EXPECT_TRUE(loading.at("unload_at_strain").empty()) << folder;
  }
  ASSERT_TRUE(m.joint.has_value());
  EXPECT_GT(m.joint->closure_at_1kN_m, 0.0);
  EXPECT_GT(m.joint->exponent, 0.0);
  EXPECT_TRUE(m.provenance.at("fitted").contains("joint"));
  EXPECT_EQ(m.joint_info.at("provenance").at("cells_in_series"), 2);
  EXPECT_TRUE(fs::exists(out / "3_fit" / "fit_momentum_flux.png"));
  EXPECT_EQ(m.provenance.at("lockup").at("from"), "porosity");
  EXPECT_DOUBLE_EQ(m.edge_m, 0.3);

  // The report embeds every figure it lists, each also a file in figures/.
  const std::string html = readText(out / "report.html");
  EXPECT_NE(html.find("The joint between two cells"), std::string::npos);
  const auto figures = s.at("figures");
  EXPECT_GE(figures.size(), 10u);
  std::size_t embedded = 0;
  for (std::size_t at = html.find("data:image/png;base64,"); at != std::string::npos;
       at = html.find("data:image/png;base64,", at + 1))
    ++embedded;
  EXPECT_EQ(embedded, figures.size());
  for (const auto& f : figures) EXPECT_GT(fs::file_size(out / f.get<std::string>()), 1000u) << f;

  // The report as a person sees it: opened in headless Chromium, every
  // figure loads and none is blank (the page's own check, kImageCheck in
  // app/pipeline.cpp, sets these attributes once it has loaded).
  const bool have_chromium = fs::exists("/usr/bin/chromium");
  if (have_chromium) {
    const auto dom = gabion::testing::runCommand(
        "timeout 120 /usr/bin/chromium --headless --no-sandbox --disable-gpu --user-data-dir=" +
        (dir / "chromium").string() + " --dump-dom file://" + (out / "report.html").string());
    std::smatch found;
    ASSERT_TRUE(std::regex_search(
        dom.output, found,
        std::regex(R"re(data-images="(\d+)" data-broken-images="(\d+)" data-blank-images="(\d+)")re")))
        << dom.output.substr(0, 2000);
    EXPECT_EQ(std::stoul(found[1]), figures.size());
    EXPECT_EQ(found[2], "0") << "figures that did not load";
    EXPECT_EQ(found[3], "0") << "blank figures";
  }

  // A second run reuses every stage; the answers are the same.
  r = runGabion("run " + (dir / "pipeline.json").string() + " -q --threads 2 -o " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto again = readJson(out / "summary.json");
  EXPECT_EQ(again.at("stages_reused"), again.at("stages").size());
  EXPECT_EQ(again.at("design"), s.at("design"));
  EXPECT_EQ(again.at("fit"), s.at("fit"));

  // A changed structure velocity reruns that impact only.
  r = runGabion("run " + (dir / "pipeline.json").string() + " -q --threads 2 -o " + out.string() +
                " --set structure.velocities_m_s=[8,14]");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto third = readJson(out / "summary.json");
  for (const auto& st : third.at("stages"))
    EXPECT_EQ(st.at("reused").get<bool>(), st.at("folder") != "4_impact_14_m_s") << st.at("folder");
  // The pipeline's manifest lists every stage's files, reused or run.
  const auto manifest = readJson(out / "manifest.json");
  std::set<std::string> listed;
  for (const auto& f : manifest.at("files")) listed.insert(f.at("path").get<std::string>());
  for (const auto& st : third.at("stages")) {
    const std::string folder = st.at("folder").get<std::string>();
    EXPECT_EQ(listed.count(folder + "/summary.json"), 1u) << folder;
  }
  // A stage whose folder lost its manifest (a run killed while it wrote
  // there) is run again, even with its key unchanged.
  fs::remove(out / "4_impact_8_m_s" / "manifest.json");
  r = runGabion("run " + (dir / "pipeline.json").string() + " -q --threads 2 -o " + out.string() +
                " --set structure.velocities_m_s=[8,14]");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const auto& st : readJson(out / "summary.json").at("stages"))
    EXPECT_EQ(st.at("reused").get<bool>(), st.at("folder") != "4_impact_8_m_s") << st.at("folder");
  if (!have_chromium)
    GTEST_SKIP() << "chromium is not installed (scripts/deps.sh --tests installs it): the report was checked as files, "
                    "not opened in a browser";
}

// Replicate cells: two seeds, every lab test on each, and the fitted laws
// report the scatter between the cells (the replicate mean's interval)
// beside the fit's own, in the summary, the console and the report.
TEST(Pipeline, ReplicateCellsGiveTheScatterOfTheFit) {
  const auto dir = scratchDir("pipeline_replicates");
  writeSmallChain(dir);
  auto j = readJson(dir / "pipeline.json");
  j["replicates"] = 2;
  j.erase("sweep"), j.erase("capacity"), j.erase("design"), j.erase("joint");
  j["structure"]["velocities_m_s"] = {8};
  writeFile(dir / "pipeline.json", j.dump());
  const fs::path out = dir / "out";
  const auto r = runGabion("run " + (dir / "pipeline.json").string() + " -q --threads 2 -o " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f : {"1_cell_seed3/cell.h5", "1_cell_seed4/cell.h5", "2_cc/replicate_0/result.h5",
                        "2_cc/replicate_1/result.h5", "2_uci/v8_replicate_1/result.h5"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  const auto s = readJson(out / "summary.json");
  for (const char* law : {"axial", "lateral", "interface", "impact"}) {
    const auto& fit = s.at("fit").at(law);
    EXPECT_EQ(fit.at("replicates").size(), 2u) << law;
    for (const auto& [name, p] : fit.at("parameters").items()) {
      ASSERT_TRUE(p.contains("replicate_mean_95")) << law << " " << name;
      EXPECT_EQ(p.at("replicate_values").size(), 2u) << law << " " << name;
    }
  }
  EXPECT_NE(r.output.find("between replicates"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("one draw of its packing"), std::string::npos) << r.output;
  EXPECT_NE(readText(out / "report.html").find("interval of the mean over 2 cells"), std::string::npos);
  // The report draws each cell and each cell's lab curves, from their
  // replicate folders; none is missing.
  for (const auto& w : s.at("warnings")) EXPECT_EQ(w.get<std::string>().find("figure missing"), std::string::npos) << w;
  const auto figures = s.at("figures");
  for (const char* f : {"figures/cell_view_seed3.png", "figures/cell_view_seed4.png", "figures/cc_curve_seed3.png",
                        "figures/cc_curve_seed4.png", "figures/uc_curve_seed4.png", "figures/shear_curve_seed4.png"}) {
    EXPECT_NE(std::find(figures.begin(), figures.end(), f), figures.end()) << f;
    EXPECT_GT(fs::file_size(out / f), 1000u) << f;
  }
  EXPECT_NE(readText(out / "report.html").find("blocks taken off at closing"), std::string::npos);
  EXPECT_NE(readText(out / "report.html").find("The first of 2 cells (seed 3"), std::string::npos);
  EXPECT_TRUE(s.at("dropped_runs").empty());

  // One cell's runs fail (its second block moved onto its first: the
  // overlap check stops each of its runs at once): the lab stages go on
  // without them, loudly, and the fit has the other cell's curves.
  {
    const fs::path cell = out / "1_cell_seed4" / "cell.h5";
    const std::string summary = gabion::bridge::H5Reader(cell).attribute("/", "summary");
    gabion::micro::Scene scene;
    gabion::micro::loadCellFile(cell, scene);
    ASSERT_GE(scene.blocks.size(), 2u);
    scene.blocks[1].position_m = scene.blocks[0].position_m;
    const gabion::micro::Engine engine(scene, 1);
    gabion::micro::writeCellFile(cell, scene, engine, nlohmann::json::parse(summary));
  }
  const auto again = runGabion("run " + (dir / "pipeline.json").string() + " -q --threads 2 -o " + out.string());
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_NE(again.output.find("warning: stage 'uci': run v8_replicate_1 failed and is left out of the fit"),
            std::string::npos)
      << again.output;
  const auto d = readJson(out / "summary.json");
  std::set<std::string> dropped;
  for (const auto& run : d.at("dropped_runs")) {
    dropped.insert(fs::path(run.at("folder").get<std::string>()).lexically_relative(out).generic_string());
    EXPECT_NE(run.at("message").get<std::string>().find("overlap"), std::string::npos) << run;
  }
  EXPECT_EQ(dropped,
            (std::set<std::string>{"2_cc/replicate_1", "2_uc/replicate_1", "2_uci/v5_replicate_1",
                                   "2_uci/v8_replicate_1", "2_shear/replicate_1", "2_cc_rate_1.5_m_s/replicate_1"}));
  // The fit reads the first cell's curves alone: no spread between cells.
  std::size_t curves = 0;
  const std::function<void(const nlohmann::json&)> onlyFirstCell = [&](const nlohmann::json& node) {
    if (node.is_object() && node.contains("file") && node.contains("replicate")) {
      ++curves;
      EXPECT_EQ(node.at("replicate"), "0") << node;
      EXPECT_EQ(node.at("file").get<std::string>().find("replicate_1"), std::string::npos) << node;
    }
    if (node.is_structured())
      for (const auto& e : node) onlyFirstCell(e);
  };
  onlyFirstCell(readJson(out / "3_fit" / "case.json"));
  EXPECT_GE(curves, 5u);
  for (const char* law : {"axial", "lateral", "interface", "impact"})
    EXPECT_FALSE(d.at("fit").at(law).contains("replicates")) << law;
  bool warned = false;
  for (const auto& w : d.at("warnings"))
    warned = warned || w.get<std::string>().find("run v8_replicate_1 failed") != std::string::npos;
  EXPECT_TRUE(warned) << d.at("warnings");
  EXPECT_NE(readText(out / "report.html").find("the fit has the other 1 of its 2 runs"), std::string::npos);
  EXPECT_EQ(readText(out / "report.html").find("cc_curve_seed4.png"), std::string::npos);
  // A run after it reuses the stages that went on without their failed
  // runs, and still says so.
  const auto third = runGabion("run " + (dir / "pipeline.json").string() + " --threads 2 -o " + out.string());
  ASSERT_EQ(third.exit_code, 0) << third.output;
  EXPECT_NE(third.output.find("(9 stages, 9 reused)"), std::string::npos) << third.output;
  EXPECT_NE(third.output.find("warning: uci: run v8_replicate_1 failed (step 0"), std::string::npos) << third.output;
  EXPECT_EQ(readJson(out / "summary.json").at("dropped_runs").size(), 6u);
}

TEST(Pipeline, BadInputNamesTheField) {
  const auto dir = scratchDir("pipeline_bad");
  writeSmallChain(dir);
  auto j = readJson(dir / "pipeline.json");
  j["structure"]["case"] = "no_such_case.json";
  writeFile(dir / "missing_structure.json", j.dump());
  auto r = runGabion("check " + (dir / "missing_structure.json").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("/structure/case"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("no_such_case.json: file does not exist"), std::string::npos) << r.output;

  j = readJson(dir / "pipeline.json");
  j["structure"]["material"] = "granite";
  writeFile(dir / "bad_material.json", j.dump());
  r = runGabion("run " + (dir / "bad_material.json").string() + " -q -o " + (dir / "out").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("/structure/material"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));

  // A lab case with an error is named by its own file and pointer.
  writeFile(dir / "uc.json", R"({"format": "gabion.case/1", "cell": "replaced.h5", "kind": "micro.uc",
 "loading": {"velocity_m_s": -1}})");
  r = runGabion("check " + (dir / "pipeline.json").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("uc.json: /loading/velocity_m_s"), std::string::npos) << r.output;

  j = readJson(dir / "pipeline.json");
  j["stage_settings"] = {{"ccc", {"loading.strain=0.1"}}};
  writeFile(dir / "bad_stage.json", j.dump());
  r = runGabion("check " + (dir / "bad_stage.json").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("/stage_settings/ccc"), std::string::npos) << r.output;

  j = readJson(dir / "pipeline.json");
  j["cc_rate_velocities_m_s"] = {2, -1};
  writeFile(dir / "bad_rate.json", j.dump());
  r = runGabion("check " + (dir / "bad_rate.json").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("/cc_rate_velocities_m_s"), std::string::npos) << r.output;

  for (const auto& [key, value] : {std::make_pair("cells_in_series", 7.0), std::make_pair("strain", -0.1)}) {
    j = readJson(dir / "pipeline.json");
    j["joint"][key] = value;
    writeFile(dir / "bad_joint.json", j.dump());
    r = runGabion("check " + (dir / "bad_joint.json").string());
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(std::string("/joint/") + key), std::string::npos) << r.output;
  }
}
