// Fitting with the micro model: a macro law fitted from a curve written by a
// micro.scene run reproduces that curve, and the fit.micro loop recovers the
// contact parameters of a synthetic "lab" curve made by the DEM itself, resumes
// an interrupted calibration, and records failed DEM runs without stopping.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "bridge/curve.hpp"
#include "bridge/errors.hpp"
#include "bridge/json_reader.hpp"
#include "fitting/cases.hpp"
#include "fitting/law_fit.hpp"
#include "micro/cases.hpp"
#include "tests/support/run_gabion.hpp"

namespace gabion::fitting {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const fs::path kBase = fs::path(GABION_SOURCE_DIR) / "cases/data/fit/micro_wall_compression.json";

const bridge::CaseKind& kindNamed(const std::vector<bridge::CaseKind>& kinds, const std::string& name) {
  static std::vector<bridge::CaseKind> keep;
  keep = kinds;
  for (const auto& k : keep)
    if (k.kind == name) return k;
  throw std::runtime_error("no case kind " + name);
}

// Runs the base wall-compression scene with the given contact parameters and
// returns the top wall's force-displacement curve.
bridge::Curve microWallCurve(double k_n, double f_lim, const fs::path& dir) {
  bridge::JsonDocument doc = bridge::JsonDocument::load(kBase);
  doc.applySet("materials.grain.normal_stiffness_N_m=" + std::to_string(k_n));
  doc.applySet("materials.grain.normal_force_limit_N=" + std::to_string(f_lim));
  fs::create_directories(dir);
  bridge::RunContext ctx;
  ctx.outdir = dir;
  const auto& scene = kindNamed(micro::caseKinds(), "micro.scene");
  const auto outcome = scene.run(doc, ctx);
  EXPECT_EQ(outcome.status, bridge::RunOutcome::Status::Ok) << outcome.message;
  return bridge::readWallCurveH5(dir / "result.h5", "lid", bridge::Vec3(0, 0, -1), bridge::CurveRequest{});
}

TEST(MicroFit, LawFittedFromMicroCurveReproducesIt) {
  const auto dir = testing::scratchDir("micro_law");
  const bridge::Curve curve = microWallCurve(1e5, 20.0, dir);
  const Bounds b = {
      {"stiffness_N_m", {1e3, 1e7}}, {"yield_force_N", {1.0, 1e4}}, {"hardening_stiffness_N_m", {0.0, 1e5}}};
  const std::vector<PathGrid> grids = {resampleOnPath(curve, 200)};
  const auto r = fitLaw({LawModel::ElasticPerfectlyPlastic, LawModel::Bilinear}, grids, b, LawFitSettings{});
  // The packing caps every contact at F_lim: an elastic-perfectly-plastic cell
  // with plateau 4 F_lim = 80 N (four columns).
  EXPECT_EQ(r.best().model, LawModel::ElasticPerfectlyPlastic);
  EXPECT_NEAR(r.parameters[1].value, 80.0, 0.5);
  // Quasi-static series springs: 4 k_n / 3; the DEM run is not perfectly static (1 %).
  EXPECT_NEAR(r.parameters[0].value, 4e5 / 3.0, 0.01 * 4e5 / 3.0);
  // The fitted law on the raw micro curve: error within the reported one.
  std::vector<double> model;
  PathGrid raw = resampleOnPath(curve, curve.size());
  raw.x = curve.x;
  raw.y = curve.y;
  evaluateModel(r.best().model, r.best().theta, raw, model);
  double sum = 0.0;
  for (std::size_t i = 0; i < model.size(); ++i) sum += std::pow((model[i] - curve.y[i]) / raw.scale, 2);
  const double rms = std::sqrt(sum / static_cast<double>(model.size()));
  EXPECT_LT(r.best().nrms, 0.01);
  EXPECT_LT(rms, 1.5 * r.best().nrms) << "reported " << r.best().nrms;

  // The run's walls are read by name; another name is an input error that
  // names the file, the wall asked for and the walls the run has.
  try {
    bridge::readWallCurveH5(dir / "result.h5", "roof", bridge::Vec3(0, 0, -1), bridge::CurveRequest{});
    ADD_FAILURE() << "no error for a wall the run does not have";
  } catch (const bridge::InputError& e) {
    EXPECT_EQ(e.file(), (dir / "result.h5").string());
    EXPECT_NE(e.message().find("no wall named 'roof'"), std::string::npos) << e.what();
    EXPECT_NE(e.message().find("lid, z_minus"), std::string::npos) << e.what();
  }
}

json microFitCase(const fs::path& lab) {
  return {{"format", "gabion.case/1"},
          {"kind", "fit.micro"},
          {"seed", 4},
          {"micro_case", kBase.string()},
          {"parameters",
           {{{"name", "k_n"}, {"set", "materials.grain.normal_stiffness_N_m"}, {"bounds", {2e4, 5e5}}},
            {{"name", "F_lim"}, {"set", "materials.grain.normal_force_limit_N"}, {"bounds", {5.0, 60.0}}}}},
          {"model_curve", {{"wall", {{"name", "lid"}, {"direction", {0, 0, -1}}}}}},
          {"curves", {{{"file", lab.string()}}}},
          {"objective", {{"grid_points", 60}}},
          {"search", {{"initial_samples", 6}, {"starts", 2}, {"local_max_evaluations", 40}, {"xtol_rel", 1e-4}}}};
}

json runFitMicro(const json& c, const fs::path& out, int threads = 1) {
  const auto& kind = kindNamed(caseKinds(), "fit.micro");
  fs::create_directories(out);
  bridge::JsonDocument doc(c, (out / "case.json").string());
  kind.check(doc);
  bridge::JsonDocument run_doc(c, (out / "case.json").string());
  bridge::RunContext ctx;
  ctx.outdir = out;
  ctx.threads = threads;
  const auto outcome = kind.run(run_doc, ctx);
  EXPECT_EQ(outcome.status, bridge::RunOutcome::Status::Ok) << outcome.message;
  return outcome.results.at("fit_micro");
}

TEST(MicroFit, WallIsNamedNotIndexed) {
  const auto dir = testing::scratchDir("micro_wall_index");
  const auto& kind = kindNamed(caseKinds(), "fit.micro");
  json c = microFitCase(fs::path(GABION_SOURCE_DIR) / "cases/data/fit/micro_wall_lab.csv");
  kind.check(bridge::JsonDocument(c, (dir / "case.json").string()));
  // A case of the index-based layout (gabion.micro.scene/1) is told to name the wall.
  c["model_curve"]["wall"] = {{"index", 1}, {"direction", {0, 0, -1}}};
  try {
    kind.check(bridge::JsonDocument(c, (dir / "case.json").string()));
    ADD_FAILURE() << "an index was accepted";
  } catch (const bridge::InputError& e) {
    EXPECT_EQ(e.pointer(), "/model_curve/wall/index");
    EXPECT_NE(e.message().find("by name"), std::string::npos) << e.what();
    EXPECT_NE(e.message().find("\"wall_1\""), std::string::npos) << e.what();
  }
  c["model_curve"]["wall"] = {{"name", "the lid"}, {"direction", {0, 0, -1}}};
  EXPECT_THROW(kind.check(bridge::JsonDocument(c, (dir / "case.json").string())), bridge::InputError);
}

TEST(MicroFit, RecoversContactParametersOfASyntheticLabCurve) {
  const auto dir = testing::scratchDir("micro_fit");
  // "Lab" curve: the DEM itself at k_n = 7e4 N/m, F_lim = 15 N, first 90 % of the run.
  bridge::Curve lab = microWallCurve(7e4, 15.0, dir / "truth");
  const std::size_t keep = lab.size() * 9 / 10;
  lab.x.resize(keep);
  lab.y.resize(keep);
  bridge::writeCurveCsv(dir / "lab.csv", lab);
  const json r = runFitMicro(microFitCase(dir / "lab.csv"), dir / "out", 2);
  EXPECT_NEAR(r.at("parameters").at("k_n").get<double>(), 7e4, 0.01 * 7e4);
  EXPECT_NEAR(r.at("parameters").at("F_lim").get<double>(), 15.0, 0.01 * 15.0);
  EXPECT_LT(r.at("nrms").get<double>(), 0.01);
  EXPECT_TRUE(fs::exists(dir / "out/evaluations.jsonl"));
  EXPECT_TRUE(fs::exists(dir / "out/fit_micro.png"));
}

TEST(MicroFit, InterruptedCalibrationResumesFromItsLog) {
  const auto dir = testing::scratchDir("micro_resume");
  bridge::Curve lab = microWallCurve(7e4, 15.0, dir / "truth");
  lab.x.resize(lab.size() * 9 / 10);
  lab.y.resize(lab.x.size());
  bridge::writeCurveCsv(dir / "lab.csv", lab);
  json c = microFitCase(dir / "lab.csv");
  const json full = runFitMicro(c, dir / "full");
  c["max_new_evaluations"] = 9;
  const json first = runFitMicro(c, dir / "resumed");
  EXPECT_TRUE(first.at("interrupted").get<bool>());
  EXPECT_EQ(first.at("new_evaluations").get<long long>(), 9);
  c.erase("max_new_evaluations");
  // A best/ folder without a manifest is not a run's: it is left alone.
  EXPECT_EQ(first.at("best_run"), "best/result.h5");
  fs::remove(dir / "resumed" / "best" / "manifest.json");
  std::ofstream(dir / "resumed" / "best" / "notes.txt") << "the user's";
  const json second = runFitMicro(c, dir / "resumed");
  EXPECT_EQ(second.at("best_run"), "best_1/result.h5");
  EXPECT_TRUE(fs::exists(dir / "resumed" / "best" / "notes.txt"));
  EXPECT_TRUE(fs::exists(dir / "resumed" / "best_1" / "result.h5"));
  EXPECT_FALSE(second.at("interrupted").get<bool>());
  EXPECT_EQ(second.at("resumed_from_log").get<long long>(), 9);
  EXPECT_EQ(first.at("new_evaluations").get<long long>() + second.at("new_evaluations").get<long long>(),
            full.at("new_evaluations").get<long long>());
  EXPECT_EQ(second.at("parameters"), full.at("parameters"));
}

TEST(MicroFit, FailedDemRunIsRecordedNotFatal) {
  // A third parameter, the time step, makes the DEM blow up above the critical
  // step: those runs end in a numerical failure that must be logged.
  const auto dir = testing::scratchDir("micro_failure");
  bridge::Curve lab = microWallCurve(1e5, 20.0, dir / "truth");
  lab.x.resize(lab.size() * 9 / 10);
  lab.y.resize(lab.x.size());
  bridge::writeCurveCsv(dir / "lab.csv", lab);
  json base = json::parse(std::ifstream(kBase));
  base["run"]["dt_s"] = 1e-5;
  base["run"]["allow_dt_above_critical"] = true;
  std::ofstream(dir / "base.json") << base.dump(2);
  json c = microFitCase(dir / "lab.csv");
  c["micro_case"] = (dir / "base.json").string();
  c["parameters"].push_back({{"name", "dt_s"}, {"set", "run.dt_s"}, {"bounds", {1e-5, 3e-3}}, {"scale", "log"}});
  c["search"]["local_max_evaluations"] = 10;
  const json r = runFitMicro(c, dir / "out");
  EXPECT_GT(r.at("failed_evaluations").get<long long>(), 0);
  std::ifstream log(dir / "out/evaluations.jsonl");
  bool saw_failure = false;
  for (std::string line; std::getline(log, line);)
    saw_failure = saw_failure || (line.find("\"status\":\"failed\"") != std::string::npos &&
                                  line.find("numerical failure") != std::string::npos);
  EXPECT_TRUE(saw_failure);
}

}  // namespace
}  // namespace gabion::fitting
