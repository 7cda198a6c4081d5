#include "fitting/fit_case.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <set>
#include <sstream>

#include "bridge/errors.hpp"
#include "bridge/law_file.hpp"
#include "bridge/output.hpp"
#include "bridge/plot.hpp"
#include "bridge/units.hpp"
#include "fitting/case_input.hpp"
#include "fitting/joint_fit.hpp"
#include "fitting/sha256.hpp"
#include "gabion_version.hpp"

namespace gabion::fitting {

namespace fs = std::filesystem;
using bridge::Check;
using bridge::JsonReader;
using nlohmann::json;

namespace {

/// The four laws a `fit` case may identify, in the order they are run.
const std::vector<std::string> kTests = {"axial", "lateral", "interface", "impact"};
/// Parameters with default bounds (set from the curves or the other bounds
/// at run time): the densifying model's beyond the bilinear ones, and the
/// softening (and softening_rate) model's beyond the elastic-perfectly
/// plastic ones.
const char* const kDefaultedParameters[] = {"densification_onset_m",  "densification_stiffness_N_m",
                                            "softening_onset_m",      "softening_stiffness_N_m",
                                            "residual_ratio",         "rate_coefficient_N_s2_m2",
                                            "rate_growth_m",          "momentum_flux_kg_m",
                                            "momentum_flux_growth_m", "densification_unloading_stiffness_N_m"};

// The largest x of the curves (the furthest shortening or indentation).
double largestX(const std::vector<PathGrid>& grids) {
  double reach = 0.0;
  for (const auto& g : grids)
    for (double x : g.x) reach = std::max(reach, x);
  return reach;
}

// The largest rate dx/dt of the curves (0 where none is positive or they
// have no time axis), and their largest force (the normalisation scale):
// what the upper bound of a rate-squared term is set from.
double largestRate(const std::vector<PathGrid>& grids) {
  double rate = 0.0;
  for (const auto& g : grids)
    for (double r : g.rate) rate = std::max(rate, r);
  return rate;
}
double largestForce(const std::vector<PathGrid>& grids) {
  double force = 0.0;
  for (const auto& g : grids) force = std::max(force, g.scale);
  return force;
}

// Bounds of the densification where the case gives none: the onset anywhere
// from 0 to the largest shortening of the curves (an onset beyond them cannot
// be seen) or the lock-up, whichever comes first; its stiffness from a
// hundredth of the smallest to ten times the largest stiffness allowed.
void defaultDensificationBounds(Bounds& b, const std::vector<PathGrid>& grids, double lockup_m) {
  const double reach = largestX(grids);
  if (b.count("densification_onset_m") == 0) b["densification_onset_m"] = {0.0, std::min(reach, 0.999 * lockup_m)};
  if (b.count("densification_stiffness_N_m") == 0) {
    const auto& k = b.at("stiffness_N_m");
    b["densification_stiffness_N_m"] = {0.01 * k.first, 10.0 * k.second};
  }
  // (the dense part's unloading: from the softest densification to ten
  // times the stiffest; below the densification it is infeasible)
  if (b.count("densification_unloading_stiffness_N_m") == 0) {
    const auto& kd = b.at("densification_stiffness_N_m");
    b["densification_unloading_stiffness_N_m"] = {kd.first, 10.0 * kd.second};
  }
}

// Bounds of the softening where the case gives none: its onset from 0 to the
// largest indentation of the curves; the falling tangent from a thousandth of
// the smallest to the largest stiffness allowed; the residual ratio F_r / F_y
// from 0 to 1; the rate coefficient (curves with a time axis) from 0 to the
// one whose overstress alone, at the curves' largest rate, is twice their
// largest force.
void defaultSofteningBounds(Bounds& b, const std::vector<PathGrid>& grids) {
  if (b.count("softening_onset_m") == 0) b["softening_onset_m"] = {0.0, largestX(grids)};
  const auto& k = b.at("stiffness_N_m");
  if (b.count("softening_stiffness_N_m") == 0) b["softening_stiffness_N_m"] = {1e-3 * k.first, k.second};
  if (b.count("residual_ratio") == 0) b["residual_ratio"] = {0.0, 1.0};
  double rate = largestRate(grids);
  if (!(rate > 0.0)) rate = 1.0;  // (curves that never indent: any bound; the data cannot see the term)
  if (b.count("rate_coefficient_N_s2_m2") == 0)
    b["rate_coefficient_N_s2_m2"] = {0.0, 2.0 * largestForce(grids) / (rate * rate)};
  if (b.count("rate_growth_m") == 0) b["rate_growth_m"] = {0.0, largestX(grids)};
}

CurveDefaults defaultsFor(const std::string& test) {
  if (test == "axial") return {"displacement_m", "force_N", "/curves/axial", "", true};
  if (test == "lateral") return {"axial_force_N", "lateral_force_N", "/curves/lateral", "", true};
  if (test == "interface") return {"displacement_m", "force_N", "/curves/shear", "normal_force_N", false};
  return {"penetration_m", "force_N", "/curves/impact", "velocity_m_s", false};
}

struct TestSpec {
  std::string name;
  std::vector<LawModel> candidates;
  std::vector<CurveSource> curves;
  /// axial only: curves at other plate speeds, with their time axis; the
  /// momentum flux is fitted on them with the law from `curves` held.
  std::vector<CurveSource> rate_curves;
  Bounds bounds;
  std::string pointer;
};

/// The joint between two cells (fitting/joint_fit.hpp): a confined
/// compression of one cell and of a row of them along the same axis.
struct JointSpec {
  CurveSource cell, row;
  int cells_in_series = 2;
  std::string pointer;
};

struct FitCase {
  std::optional<JointSpec> joint;
  std::string material;
  double lockup_strain = bridge::kDefaultLockupStrain;  ///< of the cell edge
  double lockup_ratio = bridge::kDefaultLockupStiffnessRatio;
  json lockup_source;  ///< how the lock-up strain was set (for provenance)
  std::optional<double> edge_m, mass_kg;
  std::optional<fs::path> base_law;
  std::string base_material;
  LawFitSettings settings;
  std::size_t grid_points = 200;
  bool plots = true;
  std::vector<TestSpec> tests;
};

std::vector<LawModel> readModels(const JsonReader& t, const std::string& test) {
  if (test == "lateral") return {LawModel::LateralLinear};
  if (test == "interface") return {LawModel::InterfaceSlider};
  std::vector<LawModel> out{LawModel::ElasticPerfectlyPlastic, LawModel::Bilinear, LawModel::Densifying};
  if (!t.has("models")) return out;
  const json& v = t.raw("models");
  if (!v.is_array() || v.empty()) t.fail("models", "must be a non-empty array of model names");
  out.clear();
  for (const auto& m : v) {
    if (!m.is_string()) t.fail("models", "entries must be strings");
    const std::string s = m.get<std::string>();
    if (s == "elastic_perfectly_plastic")
      out.push_back(LawModel::ElasticPerfectlyPlastic);
    else if (s == "bilinear")
      out.push_back(LawModel::Bilinear);
    else if (s == "densifying")
      out.push_back(LawModel::Densifying);
    else if (s == "densifying_plastic" && test == "axial")
      out.push_back(LawModel::DensifyingPlastic);
    else if (s == "softening" && test == "impact")
      out.push_back(LawModel::Softening);
    else if (s == "softening_rate" && test == "impact")
      out.push_back(LawModel::SofteningRate);
    else if (s == "softening" || s == "softening_rate")
      t.fail("models", "'" + s + "' is a model of the impact law only");
    else if (s == "densifying_plastic")
      t.fail("models", "'densifying_plastic' is a model of the axial law only (plastic densification)");
    else
      t.fail("models", "unknown model '" + s + "' (elastic_perfectly_plastic, bilinear, densifying" +
                           (test == "impact" ? ", softening, softening_rate)" : ", densifying_plastic)"));
  }
  return out;
}

FitCase readFitCase(const bridge::JsonDocument& doc) {
  const JsonReader root = doc.root();
  const fs::path dir = caseDirectory(doc);
  FitCase c;
  const auto seed = static_cast<unsigned long>(root.seed("seed", 1));
  c.settings.optimizer = readOptimizer(root.optionalObject("optimizer"), seed, OptimizerSettings{});
  c.settings.loss = readLoss(root.optionalObject("objective"), c.grid_points);
  if (auto u = root.optionalObject("uncertainty")) c.settings.profile = u->boolean("profile", true);
  c.settings.criterion = root.choice("criterion", {"bic", "aicc"}, "bic") == "aicc" ? Criterion::Aicc : Criterion::Bic;
  c.plots = root.boolean("plots", true);

  const JsonReader mat = root.object("material");
  c.material = mat.string("name");
  if (c.material.empty()) mat.fail("name", "must not be empty");
  if (mat.has("edge_m")) c.edge_m = mat.number("edge_m", Check::Positive);
  if (mat.has("mass_kg")) c.mass_kg = mat.number("mass_kg", Check::Positive);
  if (auto base = root.optionalObject("base_law")) {
    c.base_law = dir / base->string("file");
    c.base_material = base->string("material");
  }
  c.lockup_source = {{"strain", c.lockup_strain}, {"from", "default (docs/formats.md)"}};
  if (auto lock = root.optionalObject("lockup")) {
    if (lock->has("strain") && lock->has("porosity")) lock->fail("porosity", "give either 'strain' or 'porosity'");
    if (lock->has("strain")) {
      c.lockup_strain = lock->number("strain", Check::Positive);
      if (c.lockup_strain >= 1.0) lock->fail("strain", "must be below 1");
      c.lockup_source = {{"strain", c.lockup_strain}, {"from", "given"}};
    } else if (lock->has("porosity")) {
      const double n = lock->number("porosity", Check::Positive);
      if (n >= 1.0) lock->fail("porosity", "must be below 1");
      const double nd = lock->optionalNumber("densest_porosity", Check::NonNegative).value_or(0.25);
      if (nd >= n) lock->fail("densest_porosity", "must be below porosity (" + std::to_string(n) + ")");
      c.lockup_strain = bridge::lockupStrain(n, nd);
      c.lockup_source = {{"strain", c.lockup_strain}, {"from", "porosity"}, {"porosity", n}, {"densest_porosity", nd}};
    }
    c.lockup_ratio = lock->optionalNumber("stiffness_ratio", Check::Positive).value_or(c.lockup_ratio);
  }
  c.lockup_source["stiffness_ratio"] = c.lockup_ratio;

  for (const auto& test : kTests) {
    auto t = root.optionalObject(test);
    if (!t) continue;
    TestSpec spec;
    spec.name = test;
    spec.pointer = t->pointer();
    spec.candidates = readModels(*t, test);
    const auto curves = t->objects("curves", true);
    if (curves.empty()) t->fail("curves", "at least one curve is required");
    const bool rate = std::any_of(spec.candidates.begin(), spec.candidates.end(), readsRate);
    for (std::size_t i = 0; i < curves.size(); ++i) {
      spec.curves.push_back(readCurveSource(curves[i], defaultsFor(test), i, dir));
      const CurveSource& s = spec.curves.back();
      if (rate && s.t_dataset.empty() && s.t_column.empty())
        curves[i].fail(s.kind == CurveSource::Kind::Csv ? "t_column" : "t_dataset",
                       s.kind == CurveSource::Kind::H5Wall
                           ? "the model softening_rate reads the indentation rate: give the curve as x_dataset, "
                             "y_dataset and t_dataset (its time axis)"
                           : "required by the model softening_rate (the curve's time axis: it reads the "
                             "indentation rate)");
    }
    if (test == "axial") {
      const auto fast = t->objects("rate_curves", false);
      for (std::size_t i = 0; i < fast.size(); ++i) {
        spec.rate_curves.push_back(readCurveSource(fast[i], defaultsFor(test), i, dir));
        CurveSource& s = spec.rate_curves.back();
        // (a micro.cc result carries its time axis beside the curve)
        if (s.kind == CurveSource::Kind::H5Datasets && s.t_dataset.empty()) s.t_dataset = "/curves/axial/time_s";
        if (s.kind == CurveSource::Kind::H5Wall)
          fast[i].fail("wall", "a rate curve needs its time axis: give x_dataset, y_dataset and t_dataset");
        if (s.kind == CurveSource::Kind::Csv && s.t_column.empty())
          fast[i].fail("t_column",
                       "required for a rate curve (its time axis: the momentum flux reads the plate speed)");
      }
    } else if (t->has("rate_curves")) {
      t->fail("rate_curves", "only for the axial law (confined compressions at several plate speeds)");
    }
    std::set<std::string> names;
    for (LawModel m : spec.candidates)
      for (const auto& n : parameterNames(m)) names.insert(n);
    if (!spec.rate_curves.empty()) names.insert({"momentum_flux_kg_m", "momentum_flux_growth_m"});
    const JsonReader b = t->object("bounds");
    // The densification's and the softening's bounds have defaults (set at run time).
    for (const char* n : kDefaultedParameters)
      if (!b.has(n)) names.erase(n);
    spec.bounds = readBounds(b, std::vector<std::string>(names.begin(), names.end()));
    for (const auto& [name, lu] : spec.bounds) {
      const bool may_be_zero =
          name == "hardening_stiffness_N_m" || name == "reaction_coefficient" || name == "densification_onset_m" ||
          name == "residual_ratio" || name == "softening_onset_m" || name == "rate_coefficient_N_s2_m2" ||
          name == "rate_growth_m" || name == "momentum_flux_kg_m" || name == "momentum_flux_growth_m";
      if (may_be_zero ? lu.first < 0.0 : !(lu.first > 0.0))
        b.fail(name, may_be_zero ? "lower bound must be >= 0" : "lower bound must be > 0");
    }
    c.tests.push_back(std::move(spec));
  }
  if (const auto j = root.optionalObject("joint")) {
    JointSpec spec;
    spec.pointer = j->pointer();
    // (the first loading is read from each curve: unloading cycles may be in it)
    spec.cell = readCurveSource(j->object("cell"), defaultsFor("axial"), 0, dir);
    spec.row = readCurveSource(j->object("row"), defaultsFor("axial"), 0, dir);
    spec.cell.request.path = spec.row.request.path = bridge::CurvePath::Cyclic;
    spec.cells_in_series = static_cast<int>(j->integer("cells_in_series", 2, 2));
    c.joint = spec;
  }
  if (c.tests.empty() && !c.joint)
    root.failHere("nothing to fit: give at least one of axial, lateral, interface, impact, joint");

  const bool complete = c.tests.size() == kTests.size();
  if (!complete && !c.base_law)
    root.fail("base_law",
              "required: law.json needs every law, and this case fits only some; give "
              "{\"file\", \"material\"} for the others");
  if (!c.base_law && (!c.edge_m || !c.mass_kg))
    mat.fail(c.edge_m ? "mass_kg" : "edge_m", "required without a base_law");
  return c;
}

// Loads and checks every curve of a list (InputError names file, line, column).
std::vector<PathGrid> loadGrids(const std::vector<CurveSource>& curves, std::size_t grid_points) {
  std::vector<PathGrid> grids;
  for (const auto& s : curves) {
    PathGrid g = resampleOnPath(loadCurve(s), grid_points);
    g.condition = curveCondition(s);
    g.replicate = s.replicate;
    grids.push_back(std::move(g));
  }
  return grids;
}

// A dataset name and its engineers' unit on a chart (bridge::displayUnit):
// "displacement_m" -> {"displacement (mm)", 1e3}, "force_N" -> {"force (kN)", 1e-3}.
std::pair<std::string, double> axisOf(const std::string& name) {
  const bridge::DisplayUnit u = bridge::displayUnit(name);
  return {u.stem + " (" + u.unit + ")", u.scale};
}

// The fitted curve's pointwise 95 % confidence band on a grid: the model
// +- t sqrt(g' C g), g its gradient in the parameters (central differences),
// C their covariance. Empty where it cannot be had (singular covariance, a
// parameter at the edge of the model's domain).
std::pair<std::vector<double>, std::vector<double>> confidenceBand(const LawFitResult& r, const PathGrid& g,
                                                                   const CurveSet& set) {
  const ModelFit& fit = r.best();
  const std::size_t p = fit.theta.size(), n = g.x.size();
  const double dof = r.effective_observations - static_cast<double>(p);
  if (r.covariance.size() != p * p || !(dof >= 1.0)) return {};
  std::vector<double> model;
  evaluateSet(set, fit.theta, g, model);
  std::vector<std::vector<double>> grad(p);
  try {
    for (std::size_t j = 0; j < p; ++j) {
      const double h = std::max(1e-6 * std::abs(fit.theta[j]), 1e-12);
      auto plus = fit.theta, minus = fit.theta;
      plus[j] += h, minus[j] -= h;
      std::vector<double> fp, fm;
      evaluateSet(set, plus, g, fp);
      evaluateSet(set, minus, g, fm);
      grad[j].resize(n);
      for (std::size_t i = 0; i < n; ++i) grad[j][i] = (fp[i] - fm[i]) / (2.0 * h);
    }
  } catch (const Infeasible&) {
    return {};
  }
  const double t = studentT975(dof);
  std::vector<double> lo(n), hi(n);
  for (std::size_t i = 0; i < n; ++i) {
    double var = 0.0;
    for (std::size_t a = 0; a < p; ++a)
      for (std::size_t b = 0; b < p; ++b) var += grad[a][i] * r.covariance[a * p + b] * grad[b][i];
    const double half = t * std::sqrt(std::max(var, 0.0));
    lo[i] = model[i] - half, hi[i] = model[i] + half;
  }
  return {lo, hi};
}

// The data of `curves` (on `grids`), the fitted law and its 95 % band; for
// the momentum flux (set.model MomentumFlux), also the law without it, dashed.
void plotFit(const fs::path& file, const TestSpec& t, const std::vector<CurveSource>& curves,
             const std::vector<PathGrid>& grids, const LawFitResult& r, const CurveSet& set) {
  const ModelFit& fit = r.best();
  bridge::PlotSpec spec;
  std::ostringstream nrms;
  nrms.precision(3);
  nrms << fit.nrms;
  spec.title =
      t.name + ": data and the fitted " + modelName(fit.model) + " law (normalised RMS error " + nrms.str() + ")";
  const auto d = defaultsFor(t.name);
  const auto [x_label, x_scale] = axisOf(curves.front().request.x_name);
  const auto [y_label, y_scale] = axisOf(curves.front().request.y_name);
  const bool rate = set.model == LawModel::MomentumFlux;
  if (rate) spec.title = "momentum flux at other plate speeds (normalised RMS error " + nrms.str() + ")";
  spec.x_label = x_label;
  spec.y_label = y_label;
  std::vector<double> model;
  for (std::size_t i = 0; i < grids.size(); ++i) {
    const auto& g = grids[i];
    std::string tag = grids.size() > 1 ? "curve " + std::to_string(i + 1) : "";
    if (rate && !g.rate.empty()) {  // (the plate speed: the largest rate of the curve)
      std::ostringstream c;
      c.precision(3);
      c << largestRate({g}) << " m/s";
      tag = c.str();
    }
    if (!d.condition_key.empty() && !rate) {
      const auto [cond, cond_scale] = axisOf(d.condition_key);
      std::ostringstream c;
      c.precision(4);
      const auto open = cond.find(" (");
      c << cond.substr(0, open) << " " << g.condition * cond_scale << " "
        << cond.substr(open + 2, cond.size() - open - 3);
      tag = c.str();
    }
    // Each curve in one colour: its data (markers), the fit (line) and the
    // fit's 95 % band behind it.
    const int colour = bridge::paletteColor(i);
    spec.series.push_back(
        bridge::scaledSeries("data " + tag, g.x, g.y, x_scale, y_scale, bridge::PlotSeries::Style::Markers));
    spec.series.back().color_rgb = colour;
    const auto [lo, hi] = confidenceBand(r, g, set);
    if (!lo.empty()) {
      bridge::PlotSeries band = bridge::scaledSeries(i == 0 ? "95 % band of the fit" : "", g.x, lo, x_scale, y_scale,
                                                     bridge::PlotSeries::Style::Band);
      band.y_upper = hi;
      for (double& y : band.y_upper) y *= y_scale;
      band.color_rgb = colour;
      spec.series.push_back(band);
    }
    evaluateSet(set, fit.theta, g, model);
    spec.series.push_back(bridge::scaledSeries("fit " + tag, g.x, model, x_scale, y_scale));
    spec.series.back().color_rgb = colour;
    if (rate && i == 0) {  // (the law alone does not depend on the rate: one line for every curve)
      std::vector<double> still;
      evaluateSet(set, {0.0, 0.0}, g, still);
      spec.series.push_back(bridge::scaledSeries("the law without the flux", g.x, still, x_scale, y_scale,
                                                 bridge::PlotSeries::Style::Dashed));
      spec.series.back().color_rgb = 0x555555;
    }
  }
  bridge::writePlotPng(file, spec);
}

void checkCase(const bridge::JsonDocument& doc) {
  const FitCase c = readFitCase(doc);
  for (const auto& t : c.tests) {
    loadGrids(t.curves, c.grid_points);
    loadGrids(t.rate_curves, c.grid_points);
  }
  if (c.joint) loadCurve(c.joint->cell), loadCurve(c.joint->row);
  if (c.base_law) {
    const auto base = bridge::loadLawFile(*c.base_law);
    if (base.materials.count(c.base_material) == 0)
      throw bridge::InputError(doc.file(), "/base_law/material",
                               "no material '" + c.base_material + "' in " + c.base_law->string());
  }
}

bridge::RunOutcome runCase(const bridge::JsonDocument& doc, const bridge::RunContext& ctx) {
  const FitCase c = readFitCase(doc);
  bridge::RunOutcome outcome;

  bridge::CellMaterial material;
  json provenance = json::object();
  std::string base_status;
  if (c.base_law) {
    const auto base = bridge::loadLawFile(*c.base_law);
    const auto it = base.materials.find(c.base_material);
    if (it == base.materials.end())
      throw bridge::InputError(doc.file(), "/base_law/material",
                               "no material '" + c.base_material + "' in " + c.base_law->string());
    material = it->second;
    base_status = it->second.provenance.value("status", "illustrative");
    json from = {{"file", c.base_law->string()},
                 {"sha256", sha256File(*c.base_law)},
                 {"material", c.base_material},
                 {"status", base_status},
                 {"laws", json::array()}};
    for (const auto& name : kTests) {
      bool fitted = false;
      for (const auto& t : c.tests) fitted = fitted || t.name == name;
      if (!fitted) from["laws"].push_back(name);
    }
    provenance["from_base_law"] = from;
  }
  if (c.edge_m) material.edge_m = *c.edge_m;
  if (c.mass_kg) material.mass_kg = *c.mass_kg;
  LawFitSettings settings = c.settings;
  settings.lockup = {c.lockup_strain * material.edge_m, c.lockup_ratio};

  json results = json::object();
  json fitted = json::object();
  json plots = json::array();
  int evaluations = 0;
  double fit_time = 0.0;
  for (const auto& t : c.tests) {
    const auto grids = loadGrids(t.curves, c.grid_points);
    Bounds bounds = t.bounds;
    const bool axial_kind = t.name == "axial" || t.name == "impact";
    if (axial_kind) defaultDensificationBounds(bounds, grids, settings.lockup.shortening_m);
    if (t.name == "impact") defaultSofteningBounds(bounds, grids);
    // The impact law is fitted without its lock-up: a UCI test is unconfined,
    // the cell spreads sideways and its boulder sinks past the lock-up
    // shortening. The law written carries it, for the confined cells of a
    // structure (docs/fitting.md).
    LawFitSettings law_settings = settings;
    if (t.name == "impact") law_settings.lockup = Lockup{};
    LawFitResult r;
    try {
      r = fitLaw(t.candidates, grids, bounds, law_settings);
    } catch (const Infeasible& e) {
      throw bridge::InputError(doc.file(), t.pointer + "/bounds", e.what());
    }
    evaluations += r.evaluations;
    fit_time += r.wall_time_s;
    json entry = toJson(r, c.settings.criterion);
    json inputs = json::array();
    for (std::size_t i = 0; i < t.curves.size(); ++i) {
      json in = {{"file", t.curves[i].file.string()},
                 {"sha256", sha256File(t.curves[i].file)},
                 {"points", grids[i].raw_points},
                 {"replicate", grids[i].replicate}};
      if (grids[i].condition != 0.0) in[defaultsFor(t.name).condition_key] = grids[i].condition;
      inputs.push_back(in);
    }
    entry["inputs"] = inputs;
    entry["algorithm"] = {{"global", c.settings.optimizer.global_algorithm},
                          {"local", c.settings.optimizer.local_algorithm},
                          {"xtol_rel", c.settings.optimizer.xtol_rel},
                          {"seed", c.settings.optimizer.seed},
                          {"loss", c.settings.loss.kind == LossSettings::Kind::SoftL1  ? "soft_l1"
                                   : c.settings.loss.kind == LossSettings::Kind::Huber ? "huber"
                                                                                       : "l2"},
                          {"loss_scale", c.settings.loss.scale},
                          {"grid_points", c.grid_points}};
    results[t.name] = entry;
    fitted[t.name] = entry;

    const ModelFit& best = r.best();
    if (t.name == "axial") material.axial = axialLaw(best.model, best.theta, settings.lockup);
    if (t.name == "impact") material.impact = axialLaw(best.model, best.theta, settings.lockup);
    if (t.name == "lateral") material.lateral.reaction_coefficient = best.theta[0];
    if (t.name == "interface") {
      material.interface.friction = best.theta[0];
      material.interface.tangential_stiffness_N_m = best.theta[1];
    }
    if (c.plots) {
      const std::string png = "fit_" + t.name + ".png";
      plotFit(ctx.outdir / png, t, t.curves, grids, r,
              CurveSet{best.model, {}, c.settings.loss, law_settings.lockup, {}});
      plots.push_back(png);
    }
    if (!t.rate_curves.empty()) {
      // The momentum flux: fitted on the curves at other plate speeds with
      // the law just identified held (docs/fitting.md, "Momentum flux").
      const auto fast = loadGrids(t.rate_curves, c.grid_points);
      Bounds rb = bounds;
      if (rb.count("momentum_flux_kg_m") == 0) {
        // from 0 to the coefficient whose flux alone, at the curves'
        // largest rate, is twice their largest force
        const double speed = largestRate(fast);
        if (!(speed > 0.0))
          throw bridge::InputError(doc.file(), t.pointer + "/rate_curves", "no curve is loaded at a positive rate");
        rb["momentum_flux_kg_m"] = {0.0, 2.0 * largestForce(fast) / (speed * speed)};
      }
      if (rb.count("momentum_flux_growth_m") == 0) rb["momentum_flux_growth_m"] = {0.0, largestX(fast)};
      LawFitSettings rate_settings = law_settings;
      rate_settings.flux_base = material.axial;
      LawFitResult rr;
      try {
        rr = fitLaw({LawModel::MomentumFlux}, fast, rb, rate_settings);
      } catch (const Infeasible& e) {
        throw bridge::InputError(doc.file(), t.pointer + "/bounds", e.what());
      }
      evaluations += rr.evaluations;
      fit_time += rr.wall_time_s;
      material.axial.momentum_flux_kg_m = rr.best().theta[0];
      material.axial.momentum_flux_growth_m = rr.best().theta[1];
      json rentry = toJson(rr, c.settings.criterion);
      json rin = json::array();
      for (std::size_t i = 0; i < t.rate_curves.size(); ++i) {
        rin.push_back({{"file", t.rate_curves[i].file.string()},
                       {"sha256", sha256File(t.rate_curves[i].file)},
                       {"points", fast[i].raw_points},
                       {"largest_rate_m_s", largestRate({fast[i]})}});
      }
      rentry["inputs"] = rin;
      results["momentum_flux"] = rentry;
      fitted["momentum_flux"] = rentry;
      if (c.plots) {
        const std::string png = "fit_momentum_flux.png";
        plotFit(ctx.outdir / png, t, t.rate_curves, fast, rr,
                CurveSet{LawModel::MomentumFlux, {}, c.settings.loss, law_settings.lockup, material.axial});
        plots.push_back(png);
      }
    }
  }

  if (c.joint) {
    const JointSpec& js = *c.joint;
    JointFit jf;
    try {
      jf = fitJoint(loadCurve(js.cell), loadCurve(js.row), js.cells_in_series);
    } catch (const std::runtime_error& e) {
      throw bridge::InputError(doc.file(), js.pointer, e.what());
    }
    material.joint = jf.law;
    json entry = {{"model", "power"},
                  {"closure_at_1kN_m", jf.law.closure_at_1kN_m},
                  {"exponent", jf.law.exponent},
                  {"r2_log_log", jf.r2},
                  {"levels_used", jf.points},
                  {"levels", jf.force_N.size()},
                  {"force_range_N", {jf.force_lo_N, jf.force_hi_N}},
                  {"cells_in_series", js.cells_in_series},
                  {"inputs",
                   {{{"role", "cell"}, {"file", js.cell.file.string()}, {"sha256", sha256File(js.cell.file)}},
                    {{"role", "row"}, {"file", js.row.file.string()}, {"sha256", sha256File(js.row.file)}}}}};
    material.joint_info = {{"force_range_N", {jf.force_lo_N, jf.force_hi_N}},
                           {"provenance",
                            {{"fitted_from", entry["inputs"]},
                             {"cells_in_series", js.cells_in_series},
                             {"r2_log_log", jf.r2},
                             {"method", "row less cells_in_series x cell at each force level, power law in log-log"}}}};
    results["joint"] = entry;
    fitted["joint"] = entry;
    if (c.plots) {
      bridge::PlotSpec plot;
      plot.title = "Joint between two cells: closure against force";
      plot.x_label = "force across the joint (kN)";
      plot.y_label = "closure of one joint (mm)";
      bridge::PlotSeries pts{
          "row less " + std::to_string(js.cells_in_series) + " x cell", {}, {}, bridge::PlotSeries::Style::Markers};
      bridge::PlotSeries law{"c = c1 (F / 1 kN)^b", {}, {}, bridge::PlotSeries::Style::Line};
      for (std::size_t k = 0; k < jf.force_N.size(); ++k) {
        if (std::isfinite(jf.closure_m[k]))
          pts.x.push_back(1e-3 * jf.force_N[k]), pts.y.push_back(1e3 * jf.closure_m[k]);
        law.x.push_back(1e-3 * jf.force_N[k]), law.y.push_back(1e3 * bridge::jointClosure(jf.law, jf.force_N[k]));
      }
      plot.series = {pts, law};
      bridge::writePlotPng(ctx.outdir / "fit_joint.png", plot);
      plots.push_back("fit_joint.png");
    }
  }

  // A law file is only "fitted" if no part of it is illustrative.
  provenance["status"] = c.tests.size() == kTests.size() || base_status != "illustrative" ? "fitted" : "illustrative";
  provenance["software"] = std::string("gabion ") + gabion::kVersion;
  provenance["method"] =
      "fit case: NLopt global stage then local polish; 95 % intervals from the Jacobian, the "
      "profile likelihood and the replicate spread (docs/fitting.md)";
  provenance["case_file"] = ctx.case_file.string();
  provenance["fitted"] = fitted;
  provenance["lockup"] = c.lockup_source;
  provenance["lockup"]["shortening_m"] = settings.lockup.shortening_m;
  material.provenance = provenance;

  bridge::LawFile law;
  law.materials.emplace(c.material, material);
  json law_json = bridge::toJson(law);
  law_json["description"] = "Cell laws identified by `gabion run " + ctx.case_file.string() + "`";
  bridge::writeJsonAtomic(ctx.outdir / "law.json", law_json);
  // Read back through the validating reader: what we write must be a valid law file.
  bridge::loadLawFile(ctx.outdir / "law.json");

  outcome.results["fit"] = results;
  for (const auto& [name, entry] : results.items())
    outcome.answer += "fit: " + (name == "joint" ? describeJointFit(entry) : describeFit(name, entry)) + "\n";
  outcome.results["law_file"] = "law.json";
  outcome.results["law_status"] = provenance["status"];
  outcome.results["plots"] = plots;
  outcome.results["evaluations"] = evaluations;
  outcome.results["fit_wall_time_s"] = fit_time;
  return outcome;
}

}  // namespace

bridge::CaseKind fitCaseKind() {
  return {"fit",
          "identify the macro cell laws (axial, lateral, interface, impact) from curves with NLopt, and the joint "
          "between two cells",
          checkCase, runCase, nullptr};
}

}  // namespace gabion::fitting
