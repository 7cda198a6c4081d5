#include "fitting/micro_case.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <sstream>

#include "bridge/cost.hpp"
#include "bridge/errors.hpp"
#include "bridge/manifest.hpp"
#include "bridge/plot.hpp"
#include "bridge/rows.hpp"
#include "bridge/units.hpp"
#include "fitting/calibration.hpp"
#include "fitting/case_input.hpp"
#include "fitting/sha256.hpp"
#include "gabion_version.hpp"
#include "micro/cases.hpp"

namespace gabion::fitting {

namespace fs = std::filesystem;
using bridge::Check;
using bridge::JsonReader;
using nlohmann::json;

namespace {

/// How the model curve is read from the micro run's result.h5.
struct ModelCurve {
  bool wall = false;
  WallCurve wall_curve;  ///< when `wall`
  std::string x_dataset, y_dataset;
};

struct MicroCase {
  fs::path micro_case;
  std::vector<CaseParameter> params;
  ModelCurve model;
  std::vector<CurveSource> lab;
  LossSettings loss;
  std::size_t grid_points = 100;
  CalibrationSettings search;
  bool resume = true;
};

// The base micro case with `values` written at the parameters' keys.
bridge::JsonDocument substituted(const bridge::JsonDocument& base, const MicroCase& c,
                                 const std::vector<double>& values) {
  return withParameters(base, c.params, values);
}

const bridge::CaseKind& microKind(const bridge::JsonDocument& base) {
  const std::string kind = base.root().string("kind");
  static const std::vector<bridge::CaseKind> kinds = micro::caseKinds();
  std::string known;
  for (const auto& k : kinds) {
    if (k.kind == kind) return k;
    known += (known.empty() ? "" : ", ") + k.kind;
  }
  throw bridge::InputError(
      base.file(), "/kind",
      "'" + kind + "' is not a micro case kind of this build (known: " + (known.empty() ? "none" : known) + ")");
}

MicroCase readMicroCase(const bridge::JsonDocument& doc) {
  const JsonReader root = doc.root();
  const fs::path dir = caseDirectory(doc);
  MicroCase c;
  c.micro_case = dir / root.string("micro_case");
  std::error_code ec;
  if (!fs::is_regular_file(c.micro_case, ec)) root.fail("micro_case", "no such case file " + c.micro_case.string());
  c.params = readCaseParameters(root, "materials.grain.normal_stiffness_N_m", true);
  const JsonReader m = root.object("model_curve");
  if (auto w = m.optionalObject("wall")) {
    c.model.wall = true;
    c.model.wall_curve = readWallCurve(*w);
    if (m.has("x_dataset") || m.has("y_dataset")) m.fail("wall", "give either \"wall\" or datasets, not both");
  } else {
    c.model.x_dataset = m.string("x_dataset", "/curves/axial/displacement_m");
    c.model.y_dataset = m.string("y_dataset", "/curves/axial/force_N");
  }
  const auto curves = root.objects("curves", true);
  if (curves.empty()) root.fail("curves", "at least one lab curve is required");
  for (std::size_t i = 0; i < curves.size(); ++i) {
    c.lab.push_back(readCurveSource(curves[i], {"displacement_m", "force_N", "/curves/axial", "", true}, i, dir));
    if (c.lab.back().request.path != bridge::CurvePath::Monotonic)
      curves[i].fail("path", "fit.micro compares monotonic loading curves (the model is interpolated in x)");
  }
  c.loss = readLoss(root.optionalObject("objective"), c.grid_points);
  c.search.seed = static_cast<unsigned long>(root.seed("seed", 1));
  if (auto s = root.optionalObject("search")) {
    c.search.initial_samples = static_cast<std::size_t>(s->integer("initial_samples", 8, 1));
    c.search.starts = static_cast<std::size_t>(s->integer("starts", 2, 0));
    if (c.search.starts > c.search.initial_samples) s->fail("starts", "cannot exceed initial_samples");
    c.search.local_algorithm = s->string("local", "LN_BOBYQA");
    if (!isNloptAlgorithm(c.search.local_algorithm, false))
      s->fail("local", "unknown local algorithm '" + c.search.local_algorithm + "' (LN_BOBYQA, LN_SBPLX, ...)");
    c.search.local_max_evaluations = static_cast<int>(s->integer("local_max_evaluations", 40, 1));
    c.search.xtol_rel = s->number("xtol_rel", 1e-3, Check::Positive);
    c.search.penalty = s->number("penalty", 1e6, Check::Positive);
  }
  c.search.max_new_evaluations = root.integer("max_new_evaluations", -1, -1);
  c.search.keep_evaluation_folders = root.boolean("keep_evaluation_folders", false);
  c.resume = root.boolean("resume", true);
  return c;
}

// The model curve of a finished micro run.
bridge::Curve readModelCurve(const fs::path& h5, const ModelCurve& m) {
  bridge::CurveRequest req;
  req.min_points = 3;
  req.path = bridge::CurvePath::Cyclic;  // a DEM wall may jitter back by round-off; interpolation checks below
  return m.wall ? bridge::readWallCurveH5(h5, m.wall_curve.name, m.wall_curve.direction, req)
                : bridge::readCurveH5(h5, m.x_dataset, m.y_dataset, req);
}

// Model force at the lab grid's displacements (linear interpolation in x on the
// model's loading curve, made monotone by a running maximum of x).
std::vector<double> modelAt(const bridge::Curve& model, const std::vector<double>& x) {
  std::vector<double> mx, my;
  for (std::size_t i = 0; i < model.size(); ++i) {
    if (!mx.empty() && model.x[i] <= mx.back()) continue;
    mx.push_back(model.x[i]);
    my.push_back(model.y[i]);
  }
  std::vector<double> out;
  for (double xi : x) {
    if (mx.size() < 2 || xi > mx.back() + 1e-12 * std::abs(mx.back()) || xi < mx.front())
      throw std::runtime_error("the micro run's curve does not cover the lab curve (x = " + fullPrecision(xi) +
                               " outside [" + fullPrecision(mx.empty() ? 0.0 : mx.front()) + ", " +
                               fullPrecision(mx.empty() ? 0.0 : mx.back()) + "]): lengthen the micro run");
    const auto it = std::lower_bound(mx.begin(), mx.end(), xi);
    const std::size_t j =
        it == mx.begin() ? 1 : std::min<std::size_t>(static_cast<std::size_t>(it - mx.begin()), mx.size() - 1);
    const double t = (xi - mx[j - 1]) / (mx[j] - mx[j - 1]);
    out.push_back(my[j - 1] + t * (my[j] - my[j - 1]));
  }
  return out;
}

struct MicroObjective {
  const bridge::JsonDocument* base;
  const bridge::CaseKind* kind;
  const MicroCase* c;
  std::vector<PathGrid> lab;

  // Misfit between a model curve and the lab grids (same loss as the macro fit).
  double misfitOf(const bridge::Curve& model) const {
    double total = 0.0, n = 0.0;
    for (const auto& g : lab) {
      const auto y = modelAt(model, g.x);
      const double a = g.effectivePoints() / static_cast<double>(g.x.size());
      for (std::size_t i = 0; i < y.size(); ++i) total += a * lossValue((y[i] - g.y[i]) / g.scale, c->loss);
      n += g.effectivePoints();
    }
    return total / n;
  }

  double operator()(const std::vector<double>& values, const fs::path& scratch) const {
    bridge::JsonDocument doc = substituted(*base, *c, values);
    bridge::RunContext ctx;
    ctx.outdir = scratch;
    ctx.threads = 1;  // parallelism is across evaluations
    ctx.case_file = base->file();
    bridge::RunOutcome outcome;
    try {
      outcome = kind->run(doc, ctx);
    } catch (const bridge::NumericalError& e) {
      throw std::runtime_error(std::string("numerical failure: ") + e.what());
    }
    if (outcome.status != bridge::RunOutcome::Status::Ok)
      throw std::runtime_error("numerical failure: " + outcome.message);
    return misfitOf(readModelCurve(scratch / "result.h5", c->model));
  }
};

std::vector<PathGrid> labGrids(const MicroCase& c) {
  std::vector<PathGrid> grids;
  for (const auto& s : c.lab) {
    PathGrid g = resampleOnPath(loadCurve(s), c.grid_points);
    g.replicate = s.replicate;
    grids.push_back(std::move(g));
  }
  return grids;
}

std::vector<double> midpoint(const MicroCase& c) {
  return midpoint(c.params);
}

void checkCase(const bridge::JsonDocument& doc) {
  const MicroCase c = readMicroCase(doc);
  labGrids(c);
  const bridge::JsonDocument base = bridge::JsonDocument::load(c.micro_case);
  const auto& kind = microKind(base);
  // The base case with parameters substituted must be a valid micro case;
  // an error there is the user's case's: it names the parameter whose `set`
  // it comes from, or the micro_case.
  const bridge::JsonDocument trial = substituted(base, c, midpoint(c));
  try {
    kind.check(trial);
    if (trial.root().has("description")) trial.root().string("description");
    trial.root().string("format");
    trial.root().string("kind");
    trial.finish();
  } catch (const bridge::InputError& e) {
    std::string at = "/micro_case";
    for (std::size_t k = 0; k < c.params.size(); ++k)
      for (const std::string& set : c.params[k].set)
        if (setPathMatches(set, e.pointer())) at = "/parameters/" + std::to_string(k) + "/set";
    throw bridge::InputError(
        doc.file(), at,
        "the micro case with the parameters at the middle of their bounds is not valid: " + std::string(e.what()));
  }
}

// At most: the micro case (at the middle of the parameter box) once per
// evaluation of the search's budget (samples, then each local search's
// limit), and once more for the best point; fewer with max_new_evaluations.
std::optional<bridge::Estimate> estimateCase(const bridge::JsonDocument& doc) {
  const MicroCase c = readMicroCase(doc);
  const bridge::JsonDocument base = bridge::JsonDocument::load(c.micro_case);
  const auto& kind = microKind(base);
  if (!kind.estimate) return std::nullopt;
  const auto one = kind.estimate(substituted(base, c, midpoint(c)));
  if (!one) return std::nullopt;
  double evaluations = static_cast<double>(c.search.initial_samples) +
                       static_cast<double>(c.search.starts) * c.search.local_max_evaluations;
  if (c.search.max_new_evaluations >= 0)
    evaluations = std::min(evaluations, static_cast<double>(c.search.max_new_evaluations));
  return bridge::times(*one, evaluations + 1.0);
}

// A hash of the case that identifies its evaluations: the effective case
// without the keys that only steer a session (budget, resume, threads).
std::string caseHash(const bridge::JsonDocument& doc, const fs::path& micro_case) {
  json j = doc.json();
  for (const char* k : {"max_new_evaluations", "resume", "keep_evaluation_folders", "description"}) j.erase(k);
  return sha256Hex(j.dump() + "\n" + sha256File(micro_case));
}

// On an MPI worker rank: evaluates the points rank 0 sends, {"evaluate":
// values, "scratch": folder} -> {"misfit"} (the serial evaluation itself).
std::function<json(const json&)> serveCase(const bridge::JsonDocument& doc) {
  struct Served {
    MicroCase c;
    bridge::JsonDocument base;
    MicroObjective objective;
  };
  auto s = std::make_shared<Served>(Served{readMicroCase(doc), bridge::JsonDocument(json::object(), ""), {}});
  s->base = bridge::JsonDocument::load(s->c.micro_case);
  s->objective = MicroObjective{&s->base, &microKind(s->base), &s->c, labGrids(s->c)};
  return [s](const json& task) {
    return json{{"misfit", s->objective(task.at("evaluate").get<std::vector<double>>(),
                                        fs::path(task.at("scratch").get<std::string>()))}};
  };
}

// The calibration's population as rows (bridge/rows.hpp): a row per
// Latin-hypercube sample, evaluated anywhere (a Slurm task, a slice), then
// collected into evaluations.jsonl, where `gabion run --resume OUTDIR` finds
// them and goes on with the local searches.
class PopulationRows final : public bridge::RowPlan {
 public:
  explicit PopulationRows(const bridge::JsonDocument& doc)
      : c_(readMicroCase(doc)), base_(bridge::JsonDocument::load(c_.micro_case)), hash_(caseHash(doc, c_.micro_case)) {
    objective_ = MicroObjective{&base_, &microKind(base_), &c_, labGrids(c_)};
    for (const auto& p : c_.params) params_.push_back(p.param), names_.push_back(p.param.name);
    points_ = initialPopulation(params_, c_.search);
  }
  std::size_t size() const override { return points_.size(); }
  json describe(std::size_t i) const override {
    json p = json::object();
    for (std::size_t k = 0; k < names_.size(); ++k) p[names_[k]] = points_[i][k];
    return {{"parameters", p}, {"seed", c_.search.seed}};
  }
  json run(std::size_t i, const bridge::RunContext&) const override {
    // (in a folder of its own, removed after, as the loop's evaluations)
    const fs::path scratch = fs::temp_directory_path() / ("gabion-fit-row-" + std::to_string(::getpid()) + "-" +
                                                          std::to_string(i) + "-" + std::to_string(nextScratch()));
    std::error_code ec;
    fs::remove_all(scratch, ec);
    fs::create_directories(scratch);
    const auto t0 = std::chrono::steady_clock::now();
    json r;
    try {
      const double error = objective_(points_[i], scratch);
      r = std::isfinite(error) ? json{{"ok", true}, {"error", error}}
                               : json{{"ok", false}, {"message", "objective is not finite"}};
    } catch (const bridge::WriteError&) {
      fs::remove_all(scratch, ec);
      throw;
    } catch (const std::exception& e) {
      r = {{"ok", false}, {"message", e.what()}};
    }
    fs::remove_all(scratch, ec);
    r["time_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return r;
  }
  double costS(std::size_t) const override { return one_s_(); }
  bridge::RunOutcome assemble(const std::vector<std::optional<json>>& rows, const bridge::RowStats& stats,
                              const bridge::RunContext& ctx) const override {
    EvaluationLog log(ctx.outdir / "evaluations.jsonl", hash_, names_, true);
    std::size_t added = 0, failed = 0;
    std::optional<std::size_t> best;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      if (!rows[i]) continue;
      const json& row = *rows[i];
      const bool ok = row.at("ok").get<bool>();
      if (!ok) ++failed;
      if (ok && (!best || row.at("error").get<double>() < rows[*best]->at("error").get<double>())) best = i;
      EvaluationRecord r;
      if (log.find(points_[i], r)) continue;
      r.id = log.nextId();
      r.parameters = points_[i];
      r.ok = ok;
      r.error = ok ? row.at("error").get<double>() : c_.search.penalty;
      r.message = ok ? "" : row.at("message").get<std::string>();
      r.time_s = row.value("time_s", 0.0);
      log.append(r);
      ++added;
    }
    bridge::RunOutcome out;
    json pop = {{"samples", rows.size()}, {"evaluated", rows.size() - stats.missing},
                {"failed", failed},       {"missing", stats.missing},
                {"added_to_log", added},  {"evaluation_log", "evaluations.jsonl"}};
    std::ostringstream answer;
    answer << "fit.micro population: " << rows.size() - stats.missing << " of " << rows.size() << " samples evaluated ("
           << failed << " failed), logged in evaluations.jsonl";
    if (best) {
      pop["best_misfit"] = rows[*best]->at("error");
      pop["best_parameters"] = describe(*best).at("parameters");
      answer << "; best misfit " << bridge::showNumber(rows[*best]->at("error").get<double>()) << " at "
             << pop["best_parameters"].dump();
    }
    answer << "\nthe search goes on from them: gabion run --resume " << fs::absolute(ctx.outdir).string() << "\n";
    out.answer = answer.str();
    out.results["population"] = pop;
    return out;
  }

 private:
  static std::size_t nextScratch() {
    static std::atomic<std::size_t> n{0};
    return n++;
  }
  MicroCase c_;
  bridge::JsonDocument base_;
  std::string hash_;
  MicroObjective objective_{};
  std::vector<Parameter> params_;
  std::vector<std::string> names_;
  std::vector<std::vector<double>> points_;
  // (the micro case at the middle of the parameter box, once)
  bridge::Lazy<double> one_s_{[this] {
    const auto& kind = microKind(base_);
    const auto one = kind.estimate ? kind.estimate(substituted(base_, c_, midpoint(c_))) : std::nullopt;
    return one ? one->wall_time_s : 600.0;
  }};
};

bridge::RunOutcome runCase(const bridge::JsonDocument& doc, const bridge::RunContext& ctx) {
  const MicroCase c = readMicroCase(doc);
  const bridge::JsonDocument base = bridge::JsonDocument::load(c.micro_case);
  const auto& kind = microKind(base);
  MicroObjective objective{&base, &kind, &c, labGrids(c)};
  // Under mpirun the evaluations run on the worker ranks, each as it would here.
  const Evaluator here = [&](const std::vector<double>& v, const fs::path& scratch) { return objective(v, scratch); };
  const Evaluator on_workers = [&](const std::vector<double>& v, const fs::path& scratch) {
    return ctx.workers->call({{"evaluate", v}, {"scratch", fs::absolute(scratch).string()}}).at("misfit").get<double>();
  };

  std::vector<Parameter> params;
  std::vector<std::string> names;
  for (const auto& p : c.params) params.push_back(p.param), names.push_back(p.param.name);
  EvaluationLog log(ctx.outdir / "evaluations.jsonl", caseHash(doc, c.micro_case), names, c.resume);
  CalibrationSettings search = c.search;
  search.threads = ctx.workers != nullptr ? ctx.workers->size() : ctx.threads;
  bridge::Progress progress(ctx, "fit.micro");
  const auto result =
      calibrate(params, ctx.workers != nullptr ? on_workers : here, search, log, ctx.outdir / "evaluations", &progress);
  progress.finish();
  std::error_code ec;
  if (!c.search.keep_evaluation_folders) fs::remove(ctx.outdir / "evaluations", ec);

  bridge::RunOutcome outcome;
  json res;
  res["evaluation_log"] = "evaluations.jsonl";
  res["new_evaluations"] = result.new_evaluations;
  res["reused_evaluations"] = result.reused_evaluations;
  res["resumed_from_log"] = log.resumed();
  res["failed_evaluations"] = result.failed_evaluations;
  res["interrupted"] = result.interrupted;
  res["local_status"] = result.local_status;
  res["calibration_wall_time_s"] = result.wall_time_s;
  res["micro_case"] = {{"file", c.micro_case.string()}, {"sha256", sha256File(c.micro_case)}, {"kind", kind.kind}};
  json inputs = json::array();
  for (const auto& s : c.lab) inputs.push_back({{"file", s.file.string()}, {"sha256", sha256File(s.file)}});
  res["inputs"] = inputs;
  res["software"] = std::string("gabion ") + gabion::kVersion;
  if (result.best.empty()) {
    outcome.status = bridge::RunOutcome::Status::NumericalFailure;
    outcome.message = result.interrupted ? "interrupted before any successful evaluation; run again to resume"
                                         : "every micro evaluation failed (see evaluations.jsonl)";
    outcome.results["fit_micro"] = res;
    return outcome;
  }
  json best = json::object();
  for (std::size_t i = 0; i < params.size(); ++i) best[params[i].name] = result.best[i];
  res["parameters"] = best;
  res["misfit"] = result.best_error;

  // Re-run the best point once, kept, to report its curve and plot it.
  // Into best/, replacing only a folder an earlier run made (it has a
  // manifest): a best/ of the user's is left alone and best_1/, best_2/, ...
  // taken instead.
  fs::path best_dir = ctx.outdir / "best";
  for (int k = 1; fs::exists(best_dir) && !fs::exists(best_dir / "manifest.json"); ++k)
    best_dir = ctx.outdir / ("best_" + std::to_string(k));
  fs::remove_all(best_dir, ec);
  fs::create_directories(best_dir);
  objective(result.best, best_dir);
  bridge::writeManifest(best_dir, "ok");
  const bridge::Curve model = readModelCurve(best_dir / "result.h5", c.model);
  double sum = 0.0, count = 0.0;
  bridge::PlotSpec plot;
  plot.title = "fit.micro: lab curves and the micro run at the best parameters";
  plot.x_label = "displacement (m)";
  plot.y_label = "force (N)";
  for (std::size_t k = 0; k < objective.lab.size(); ++k) {
    const auto& g = objective.lab[k];
    const auto y = modelAt(model, g.x);
    for (std::size_t i = 0; i < y.size(); ++i) sum += std::pow((y[i] - g.y[i]) / g.scale, 2), count += 1.0;
    plot.series.push_back({"lab curve " + std::to_string(k + 1), g.x, g.y, bridge::PlotSeries::Style::Markers});
  }
  plot.series.push_back({"micro run (best)", model.x, model.y, bridge::PlotSeries::Style::Line});
  res["nrms"] = std::sqrt(sum / count);
  res["best_run"] = (best_dir.filename() / "result.h5").generic_string();
  bridge::writePlotPng(ctx.outdir / "fit_micro.png", plot);
  res["plots"] = json::array({"fit_micro.png"});
  outcome.results["fit_micro"] = res;
  return outcome;
}

}  // namespace

bridge::CaseKind fitMicroCaseKind() {
  return {"fit.micro",
          "identify micro contact parameters so that a micro case matches lab curves (DEM in the loop, resumable)",
          checkCase,
          runCase,
          estimateCase,
          [](const bridge::JsonDocument& doc) { return std::make_shared<const PopulationRows>(doc); },
          serveCase};
}

}  // namespace gabion::fitting
