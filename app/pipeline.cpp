#include "app/pipeline.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include "app/registry.hpp"
#include "bridge/curve.hpp"
#include "bridge/errors.hpp"
#include "bridge/law_file.hpp"
#include "bridge/output.hpp"
#include "bridge/plot.hpp"
#include "micro/packing.hpp"

namespace gabion::app {

namespace {

namespace fs = std::filesystem;
using bridge::Check;
using bridge::JsonDocument;
using bridge::JsonReader;
using nlohmann::json;

constexpr double kPi = 3.14159265358979323846;
constexpr double kGravity = 9.81;  // m/s2, along -z

/// Everything a pipeline case says (defaults in docs/pipeline.md).
struct PipelineCase {
  unsigned long seed = 1;
  // The cell and its grains (the CC sample is one cell).
  double edge_m = 0.5;
  double mean_radius_m = 0.03;
  double radius_std_rel = 0.15;
  double density_kg_m3 = 2600.0;
  double loose_solid_fraction = 0.25;
  double target_porosity = 0.436;
  double normal_stiffness_N_m = 0.0;
  double shear_stiffness_N_m = 0.0;
  double friction = 0.5;
  double wall_friction = 0.0;
  double settle_friction = 0.0;
  std::optional<double> normal_force_limit_N;
  double local_damping = 0.3;
  double settle_duration_s = 1.0;
  // The CC test.
  double strain = 0.04;
  double lid_velocity_m_s = 0.05;
  int samples = 200;
  double seating_force_fraction = 0.02;
  // The structure.
  fs::path structure_case;
  std::string structure_material = "front";
  std::vector<double> velocities_m_s;
};

PipelineCase readPipeline(const JsonDocument& doc) {
  const JsonReader root = doc.root();
  PipelineCase c;
  c.seed = static_cast<unsigned long>(root.integer("seed", 1, 0));

  const JsonReader cell = root.object("cell");
  c.edge_m = cell.number("edge_m", Check::Positive);
  const JsonReader grains = cell.object("grains");
  c.mean_radius_m = grains.number("mean_radius_m", Check::Positive);
  c.radius_std_rel = grains.number("radius_std_rel", c.radius_std_rel, Check::NonNegative);
  if (c.radius_std_rel >= 0.5) grains.fail("radius_std_rel", "must be < 0.5");
  c.density_kg_m3 = grains.number("density_kg_m3", Check::Positive);
  c.loose_solid_fraction = grains.number("loose_solid_fraction", c.loose_solid_fraction, Check::Positive);
  if (c.loose_solid_fraction > 0.35)
    grains.fail("loose_solid_fraction", "must be <= 0.35 (random sequential addition)");
  c.target_porosity = cell.number("target_porosity", c.target_porosity, Check::Fraction);
  if (c.mean_radius_m * 6.0 > c.edge_m) grains.fail("mean_radius_m", "grains must be at most edge_m / 6");

  const JsonReader contact = cell.object("contact");
  c.normal_stiffness_N_m = contact.number("normal_stiffness_N_m", Check::Positive);
  c.shear_stiffness_N_m = contact.number("shear_stiffness_N_m", Check::Positive);
  c.friction = contact.number("friction", Check::NonNegative);
  c.wall_friction = contact.number("wall_friction", c.wall_friction, Check::NonNegative);
  if (contact.has("normal_force_limit_N"))
    c.normal_force_limit_N = contact.number("normal_force_limit_N", Check::Positive);
  c.local_damping = contact.number("local_damping", c.local_damping, Check::UnitOpen);
  c.settle_duration_s = cell.number("settle_duration_s", c.settle_duration_s, Check::Positive);
  c.settle_friction = cell.number("settle_friction", c.settle_friction, Check::NonNegative);

  const JsonReader cc = root.object("compression");
  c.strain = cc.number("strain", Check::Positive);
  if (c.strain > 0.2) cc.fail("strain", "must be <= 0.2 (the CC test of a cell)");
  c.lid_velocity_m_s = cc.number("velocity_m_s", Check::Positive);
  c.samples = static_cast<int>(cc.integer("samples", c.samples, 20));
  c.seating_force_fraction = cc.number("seating_force_fraction", c.seating_force_fraction, Check::UnitOpen);

  const JsonReader st = root.object("structure");
  c.structure_case = fs::path(doc.file()).parent_path() / st.string("case");
  c.structure_material = st.string("material", c.structure_material);
  c.velocities_m_s = st.numbers("velocities_m_s", Check::Positive, 1);
  return c;
}

/// A stage that stopped on numerical trouble: the pipeline stops and reports it.
struct StageFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Runs one case of another kind through its public CaseKind, in its own
// folder, with its own summary; a numerical failure stops the pipeline.
bridge::RunOutcome runStage(const std::string& stage, const std::string& kind, JsonDocument& doc,
                            const bridge::RunContext& parent, const fs::path& dir,
                            const std::optional<fs::path>& law = std::nullopt) {
  const bridge::CaseKind* k = &checkCase(doc, kind);
  fs::create_directories(dir);
  bridge::RunContext ctx = parent;
  ctx.outdir = dir;
  ctx.case_file = doc.file();
  ctx.law_file = law;
  if (parent.progress) std::printf("pipeline: %s\n", stage.c_str());
  std::fflush(stdout);
  bridge::RunOutcome out = k->run(doc, ctx);
  json summary = out.results;
  summary["format"] = "gabion.summary/1";
  summary["kind"] = kind;
  summary["status"] = out.status == bridge::RunOutcome::Status::Ok ? "ok" : "numerical_failure";
  summary["case"] = doc.json();
  bridge::writeJsonAtomic(dir / "summary.json", summary);
  if (out.status != bridge::RunOutcome::Status::Ok)
    throw StageFailure("pipeline stage '" + stage + "' (" + dir.string() + "): " + out.message);
  return out;
}

// Writes a generated case to `dir/case.json` and loads it back, so that every
// stage's input is on disk beside its output (and relative paths resolve).
JsonDocument stageCase(const fs::path& dir, const json& value) {
  fs::create_directories(dir);
  bridge::writeJsonAtomic(dir / "case.json", value);
  return JsonDocument::load(dir / "case.json");
}

json material(const PipelineCase& c, double friction) {
  json m = {{"density_kg_m3", c.density_kg_m3},
            {"normal_stiffness_N_m", c.normal_stiffness_N_m},
            {"shear_stiffness_N_m", c.shear_stiffness_N_m},
            {"friction", friction},
            {"local_damping", c.local_damping}};
  if (c.normal_force_limit_N) m["normal_force_limit_N"] = *c.normal_force_limit_N;
  return m;
}

json wall(const std::string& name, const Eigen::Vector3d& p, const Eigen::Vector3d& n,
          const Eigen::Vector3d& v = Eigen::Vector3d::Zero()) {
  json w = {
      {"name", name}, {"point_m", {p.x(), p.y(), p.z()}}, {"normal", {n.x(), n.y(), n.z()}}, {"material", "wall"}};
  if (v.squaredNorm() > 0) w["velocity_m_s"] = {v.x(), v.y(), v.z()};
  return w;
}

/// The lateral walls of the cell, each with its inward normal; the CC test
/// reads their series by these names.
struct LateralWall {
  const char* name;
  Eigen::Vector3d normal;
};
const LateralWall kLateralWalls[4] = {
    {"x_minus", {1, 0, 0}}, {"x_plus", {-1, 0, 0}}, {"y_minus", {0, 1, 0}}, {"y_plus", {0, -1, 0}}};
constexpr const char* kLid = "lid";

/// The floor and the four lateral walls of the cell (named, so the results
/// are read by name: docs/pipeline.md).
json cellWalls(double a) {
  json walls = json::array({wall("z_minus", {0, 0, 0}, {0, 0, 1})});
  for (const auto& w : kLateralWalls) {
    // A wall facing -x or -y sits at the far side of the cell.
    const Eigen::Vector3d p(w.normal.x() < 0 ? a : 0.0, w.normal.y() < 0 ? a : 0.0, 0.0);
    walls.push_back(wall(w.name, p, w.normal));
  }
  return walls;
}

json microScene(const PipelineCase& c, const std::vector<Eigen::Vector3d>& centers, const std::vector<double>& radii,
                json walls, double duration_s, double series_interval_s, double friction) {
  json spheres = json::array();
  for (std::size_t i = 0; i < radii.size(); ++i)
    spheres.push_back(
        {{"center_m", {centers[i].x(), centers[i].y(), centers[i].z()}}, {"radius_m", radii[i]}, {"material", "rock"}});
  return {{"format", "gabion.case/1"},
          {"kind", "micro.scene"},
          {"gravity_m_s2", {0.0, 0.0, -kGravity}},
          {"materials", {{"rock", material(c, friction)}, {"wall", material(c, c.wall_friction)}}},
          {"spheres", spheres},
          {"walls", walls},
          {"run",
           {{"duration_s", duration_s},
            {"output_interval_s", duration_s / 10.0},
            {"series_interval_s", series_interval_s}}}};
}

/// Row `t` of a (times, rows, 3) dataset as vectors.
std::vector<Eigen::Vector3d> frame(const bridge::H5Reader& h5, const std::string& ds, std::size_t t) {
  const auto d = h5.dims(ds);
  const auto v = h5.read(ds);
  std::vector<Eigen::Vector3d> out(d.at(1));
  for (std::size_t i = 0; i < out.size(); ++i)
    out[i] = Eigen::Vector3d(v[(t * d[1] + i) * 3], v[(t * d[1] + i) * 3 + 1], v[(t * d[1] + i) * 3 + 2]);
  return out;
}

std::string fmt(double x, int digits = 4) {
  std::ostringstream os;
  os << std::setprecision(digits) << x;
  return os.str();
}

/// What the CC test gave: the two curves for the fitting and the cell state.
struct CcCurves {
  bridge::Curve axial;    ///< displacement_m (scaled to the cell edge, seating removed) -> force_N
  bridge::Curve lateral;  ///< axial_force_N -> mean lateral wall force lateral_force_N
  double seating_m = 0.0;
};

CcCurves ccCurves(const PipelineCase& c, const fs::path& h5file, double height_m) {
  const bridge::WallSeries lid = bridge::readWallSeriesH5(h5file, kLid);
  const std::vector<Eigen::Vector3d>& lid_p = lid.position_m;
  const std::vector<Eigen::Vector3d>& lid_f = lid.force_N;
  std::vector<std::vector<Eigen::Vector3d>> side;
  for (const auto& w : kLateralWalls) side.push_back(bridge::readWallSeriesH5(h5file, w.name).force_N);
  for (const auto& f : side)
    if (f.size() != lid_f.size()) throw std::logic_error("pipeline: the CC walls' series differ in length");

  // The bodies push the lid up (+z) while it moves down: the force on the
  // lid along +z is the axial force.
  double fmax = 0.0;
  for (const auto& f : lid_f) fmax = std::max(fmax, f.z());
  if (!(fmax > 0.0)) throw std::runtime_error("CC test: the lid never touched the grains");
  // Seating: like a lab CC test, displacement counts from the point where the
  // force first exceeds a small fraction of its maximum (the lid first meets
  // the few highest grains).
  const double seat_force = c.seating_force_fraction * fmax;
  std::size_t first = 0;
  while (first < lid_f.size() && lid_f[first].z() < seat_force) ++first;
  CcCurves out;
  out.seating_m = lid_p.front().z() - lid_p[first].z();
  const double scale = c.edge_m / height_m;  // shortening of a cube cell of edge a at the same strain
  out.axial.source = lid.source;
  out.axial.x_name = "displacement_m";
  out.axial.y_name = "force_N";
  out.lateral.source = h5file.string() + " (walls x_minus, x_plus, y_minus, y_plus against the lid)";
  out.lateral.x_name = "axial_force_N";
  out.lateral.y_name = "lateral_force_N";
  std::vector<std::pair<double, double>> lateral;
  for (std::size_t i = first; i < lid_f.size(); ++i) {
    out.axial.x.push_back((lid_p[first].z() - lid_p[i].z()) * scale);
    out.axial.y.push_back(lid_f[i].z());
    double s = 0.0;
    // The bodies push each lateral wall outwards, against its inward normal.
    for (std::size_t w = 0; w < 4; ++w) s += -side[w][i].dot(kLateralWalls[w].normal);
    lateral.emplace_back(lid_f[i].z(), 0.25 * s);
  }
  // The lateral law is a proportionality: order the points by axial force so
  // that noise in the force does not read as unloading.
  std::sort(lateral.begin(), lateral.end());
  for (const auto& [fa, fl] : lateral) {
    if (!out.lateral.x.empty() && fa <= out.lateral.x.back()) continue;
    out.lateral.x.push_back(fa);
    out.lateral.y.push_back(fl);
  }
  return out;
}

// -------------------------------------------------------------- the run

bridge::RunOutcome runStages(const JsonDocument& doc, const bridge::RunContext& ctx) {
  const PipelineCase c = readPipeline(doc);
  const double a = c.edge_m;
  json results;

  // 1. Generate a loose packing tall enough to settle to about the cell height.
  micro::PackingSpec spec;
  const double solid_target = (1.0 - c.target_porosity) * a * a * a;
  spec.box_max_m = Eigen::Vector3d(a, a, solid_target / (c.loose_solid_fraction * a * a));
  spec.mean_radius_m = c.mean_radius_m;
  spec.radius_std_rel = c.radius_std_rel;
  spec.solid_fraction = c.loose_solid_fraction;
  spec.min_gap_m = 0.02 * c.mean_radius_m;
  spec.seed = c.seed;
  micro::Packing packing;
  try {
    packing = micro::randomPacking(spec);
  } catch (const std::runtime_error& e) {
    throw bridge::InputError(doc.file(), "/cell/grains/loose_solid_fraction", std::string(e.what()) + "; lower it");
  }
  const std::size_t n = packing.radii_m.size();
  double solid = 0.0;
  for (double r : packing.radii_m) solid += 4.0 / 3.0 * kPi * r * r * r;

  // 2. Settle under gravity inside the floor and the four lateral walls.
  const fs::path settle_dir = ctx.outdir / "1_settle";
  JsonDocument settle_doc =
      stageCase(settle_dir, microScene(c, packing.centers_m, packing.radii_m, cellWalls(a), c.settle_duration_s,
                                       c.settle_duration_s / 100.0, c.settle_friction));
  const auto settle =
      runStage("settle the grains under gravity (micro.scene)", "micro.scene", settle_doc, ctx, settle_dir);
  std::vector<Eigen::Vector3d> settled;
  {
    const bridge::H5Reader h5(settle_dir / "result.h5");
    const auto t = h5.dims("/bodies/position_m").at(0);
    settled = frame(h5, "/bodies/position_m", t - 1);
  }
  if (settled.size() != n) throw std::logic_error("pipeline: settle stage returned another number of bodies");
  double top = 0.0;
  for (std::size_t i = 0; i < n; ++i) top = std::max(top, settled[i].z() + packing.radii_m[i]);
  const double porosity = 1.0 - solid / (a * a * top);

  // 3. CC test: the lid comes down on the settled grains.
  const double duration = c.strain * top / c.lid_velocity_m_s;
  json walls = cellWalls(a);
  walls.push_back(wall(kLid, {0, 0, top}, {0, 0, -1}, {0, 0, -c.lid_velocity_m_s}));
  const fs::path cc_dir = ctx.outdir / "2_compression";
  JsonDocument cc_doc =
      stageCase(cc_dir, microScene(c, settled, packing.radii_m, walls, duration, duration / c.samples, c.friction));
  runStage("confined compression (micro.scene)", "micro.scene", cc_doc, ctx, cc_dir);
  const CcCurves curves = ccCurves(c, cc_dir / "result.h5", top);
  const fs::path curve_dir = ctx.outdir / "3_curves";
  fs::create_directories(curve_dir);
  bridge::writeCurveCsv(curve_dir / "axial.csv", curves.axial);
  bridge::writeCurveCsv(curve_dir / "lateral.csv", curves.lateral);

  // 4. Fit the axial law and the lateral reaction coefficient; the other laws
  //    come from the structure's base law file, and the provenance says so.
  JsonDocument structure = JsonDocument::load(c.structure_case);
  const fs::path base_law = c.structure_case.parent_path() / structure.root().string("law_file");
  const double fmax = *std::max_element(curves.axial.y.begin(), curves.axial.y.end());
  const double umax = curves.axial.x.back();
  const double secant = fmax / umax;
  const double cell_mass = (solid / (a * a * top)) * a * a * a * c.density_kg_m3;
  json fit_case = {{"format", "gabion.case/1"},
                   {"kind", "fit"},
                   {"description", "generated by the pipeline from its CC test"},
                   {"seed", c.seed},
                   {"material", {{"name", c.structure_material}, {"edge_m", a}, {"mass_kg", cell_mass}}},
                   {"base_law", {{"file", fs::absolute(base_law).string()}, {"material", c.structure_material}}},
                   // The lock-up from the settled fill (a fill already denser than 0.3 keeps the default).
                   {"lockup", porosity > 0.3 ? json{{"porosity", porosity}, {"densest_porosity", 0.25}}
                                             : json{{"strain", bridge::kDefaultLockupStrain}}},
                   {"axial",
                    {{"curves", {{{"file", fs::absolute(curve_dir / "axial.csv").string()}}}},
                     {"bounds",
                      {{"stiffness_N_m", {0.2 * secant, 50.0 * secant}},
                       {"yield_force_N", {0.05 * fmax, 1.5 * fmax}},
                       {"hardening_stiffness_N_m", {0.0, 2.0 * secant}}}}}},
                   {"lateral",
                    {{"curves", {{{"file", fs::absolute(curve_dir / "lateral.csv").string()}}}},
                     {"bounds", {{"reaction_coefficient", {0.0, 3.0}}}}}}};
  const fs::path fit_dir = ctx.outdir / "4_fit";
  JsonDocument fit_doc = stageCase(fit_dir, fit_case);
  const auto fit = runStage("fit the cell laws (fit)", "fit", fit_doc, ctx, fit_dir);

  // The structure's law file with the calibrated material replaced.
  bridge::LawFile laws = bridge::loadLawFile(base_law);
  const bridge::LawFile fitted = bridge::loadLawFile(fit_dir / "law.json");
  if (laws.materials.count(c.structure_material) == 0)
    throw bridge::InputError(doc.file(), "/structure/material",
                             "no material '" + c.structure_material + "' in " + base_law.string());
  laws.materials[c.structure_material] = fitted.materials.at(c.structure_material);
  json law_json = bridge::toJson(laws);
  law_json["description"] = "Structure laws: material '" + c.structure_material +
                            "' calibrated by the pipeline (see its provenance); the others as in " + base_law.string();
  bridge::writeJsonAtomic(ctx.outdir / "law.json", law_json);

  // 5. Structure impacts with the calibrated law, one per velocity.
  json impacts = json::array();
  bridge::PlotSpec force_plot;
  force_plot.title = "Boulder force against time (cf. paper Fig. 13)";
  force_plot.x_label = "time (s)";
  force_plot.y_label = "force on the boulder (N)";
  double plot_until = 0.0;
  for (double v : c.velocities_m_s) {
    JsonDocument impact = JsonDocument::load(c.structure_case);
    impact.applySet("boulder.velocity_m_s=" + fmt(v, 17));
    const fs::path dir = ctx.outdir / ("5_impact_" + fmt(v) + "_m_s");
    const auto out = runStage("structure impact at " + fmt(v) + " m/s (macro.impact)", "macro.impact", impact, ctx, dir,
                              ctx.outdir / "law.json");
    json row = {{"velocity_m_s", v}, {"folder", dir.filename().string()}};
    // macro.impact always reports these: a missing key is a broken contract, not a blank cell.
    for (const char* key : {"outcome", "input_energy_J", "peak_force_N", "max_penetration_m", "contact_duration_s",
                            "rebound_velocity_m_s", "balance_rel_error"})
      row[key] = out.results.at(key);
    impacts.push_back(row);
    const bridge::H5Reader h5(dir / "result.h5");
    force_plot.series.push_back({fmt(v) + " m/s", h5.read("/series/time_s"), h5.read("/series/boulder_force_N"),
                                 bridge::PlotSeries::Style::Line});
    plot_until = std::max(plot_until, 2.0 * out.results.at("contact_duration_s").get<double>());
  }
  // Show the contacts, not the long quiet tail after the boulder has left.
  if (plot_until > 0.0)
    for (auto& series : force_plot.series) {
      std::size_t keep = 0;
      while (keep < series.x.size() && series.x[keep] <= plot_until) ++keep;
      series.x.resize(keep);
      series.y.resize(keep);
    }
  bridge::writePlotPng(ctx.outdir / "impact_force_time.png", force_plot);

  results["cell"] = {{"edge_m", a},
                     {"grains", n},
                     {"settled_height_m", top},
                     {"settled_porosity", porosity},
                     {"mass_kg", cell_mass},
                     {"settle_energy_J", settle.results.at("energy")},
                     {"seating_m", curves.seating_m}};
  results["fit"] = fit.results;
  results["law_file"] = "law.json";
  results["impacts"] = impacts;
  results["plots"] = json::array({"4_fit/fit_axial.png", "4_fit/fit_lateral.png", "impact_force_time.png"});

  // 6. The report a person reads first.
  std::ostringstream r;
  r << "# Gabion calibration pipeline\n\nCase: `" << ctx.case_file.string() << "`\n\n"
    << "## 1. Virtual cell (micro)\n\n"
    << "- " << n << " grains (mean radius " << fmt(c.mean_radius_m) << " m, density " << fmt(c.density_kg_m3)
    << " kg/m3) settled under gravity in a " << fmt(a) << " m cell: height " << fmt(top) << " m, porosity "
    << fmt(porosity, 3) << " (paper: 0.436)\n"
    << "- Confined compression: lid at " << fmt(c.lid_velocity_m_s) << " m/s to " << fmt(100 * c.strain)
    << " % strain; seating " << fmt(1000 * curves.seating_m, 3) << " mm removed; curves in `3_curves/`\n\n"
    << "## 2. Fitted cell laws\n\n";
  const json& fj = fit.results.at("fit");
  for (const char* test : {"axial", "lateral"}) {
    // The chosen model, its error and its parameters with their intervals;
    // every candidate and evaluation count is in 4_fit/summary.json.
    const json& t = fj.at(test);
    const json brief = {{"model", t.at("model")}, {"nrms", t.at("nrms")}, {"parameters", t.at("parameters")}};
    r << "### " << test << "\n\n```json\n" << brief.dump(2) << "\n```\n\n";
  }
  r << "Law status: **" << fit.results.at("law_status").get<std::string>()
    << "**. `law.json` is the structure's law file with "
    << "material `" << c.structure_material << "` replaced by the calibrated one; laws the CC test cannot identify "
    << "(interface, impact) are carried from `" << base_law.string() << "`, as its provenance records.\n\n"
    << "![axial](4_fit/fit_axial.png)\n![lateral](4_fit/fit_lateral.png)\n\n"
    << "## 3. Structure impacts (macro)\n\n| velocity (m/s) | energy (kJ) | outcome | peak force (kN) | penetration "
       "(mm) | "
       "duration (ms) | energy balance error |\n|---|---|---|---|---|---|---|\n";
  for (const auto& row : impacts)
    r << "| " << fmt(row.at("velocity_m_s").get<double>()) << " | " << fmt(row.at("input_energy_J").get<double>() / 1e3)
      << " | " << row.at("outcome").get<std::string>() << " | " << fmt(row.at("peak_force_N").get<double>() / 1e3)
      << " | " << fmt(row.at("max_penetration_m").get<double>() * 1e3) << " | "
      << fmt(row.at("contact_duration_s").get<double>() * 1e3) << " | "
      << fmt(row.at("balance_rel_error").get<double>(), 2) << " |\n";
  r << "\n![force](impact_force_time.png)\n";
  bridge::writeTextAtomic(ctx.outdir / "report.md", r.str());
  results["report"] = "report.md";

  bridge::RunOutcome outcome;
  outcome.results = results;
  return outcome;
}

bridge::RunOutcome runPipeline(const JsonDocument& doc, const bridge::RunContext& ctx) {
  try {
    return runStages(doc, ctx);
  } catch (const StageFailure& e) {
    bridge::RunOutcome failed;
    failed.status = bridge::RunOutcome::Status::NumericalFailure;
    failed.message = e.what();
    return failed;
  }
}

void checkPipeline(const JsonDocument& doc) {
  const PipelineCase c = readPipeline(doc);
  // The structure case must be valid on its own and name a law file.
  JsonDocument structure = JsonDocument::load(c.structure_case);
  checkCase(structure, "macro.impact");
  if (!structure.root().has("law_file"))
    throw bridge::InputError(c.structure_case.string(), "/law_file",
                             "the pipeline needs a structure case with a law_file");
}

}  // namespace

bridge::CaseKind pipelineKind() {
  return {"pipeline", "calibrate a cell by virtual CC test, fit its laws, run structure impacts with them",
          checkPipeline, runPipeline};
}

}  // namespace gabion::app
