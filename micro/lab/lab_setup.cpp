#include "micro/lab/lab_setup.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <fstream>
#include <iterator>
#include <sstream>
#include <thread>

#include "bridge/cost.hpp"
#include "bridge/errors.hpp"
#include "bridge/interrupt.hpp"
#include "bridge/manifest.hpp"
#include "bridge/output.hpp"
#include "bridge/rows.hpp"
#include "micro/cell/cell_assembly.hpp"
#include "micro/cell/cell_file.hpp"
#include "micro/rigid_body.hpp"
#include "micro/scene_run.hpp"

namespace gabion::micro::lab {
namespace {

namespace fs = std::filesystem;
using bridge::Check;
using bridge::JsonReader;

}  // namespace

MaterialChange parseMaterialChange(const std::string& name, const JsonReader& r) {
  MaterialChange c;
  c.name = name;
  c.pointer = r.pointer();
  c.normal_stiffness_N_m = r.optionalNumber("normal_stiffness_N_m", Check::Positive);
  c.shear_stiffness_N_m = r.optionalNumber("shear_stiffness_N_m", Check::Positive);
  c.friction = r.optionalNumber("friction", Check::NonNegative);
  c.normal_force_limit_N = r.optionalNumber("normal_force_limit_N", Check::Positive);
  c.local_damping = r.optionalNumber("local_damping", Check::UnitOpen);
  c.viscous_damping_ratio = r.optionalNumber("viscous_damping_ratio", Check::UnitOpen);
  return c;
}

namespace {

CellSource parseSource(const JsonReader& root, const fs::path& dir) {
  CellSource s;
  const nlohmann::json& v = root.raw("cell");
  if (v.is_string()) {
    s.file = dir / root.string("cell");
    return s;
  }
  if (!v.is_object())
    root.fail("cell", "give a cell file (\"cell.h5\"), or {\"file\": ...}, or {\"case\": \"micro_cell.json\"}");
  const JsonReader c = root.object("cell");
  if (c.has("file") == c.has("case")) c.failHere("give either \"file\" (a cell file) or \"case\" (a micro.cell case)");
  if (c.has("file")) {
    s.file = dir / c.string("file");
    if (c.has("seed")) c.fail("seed", "only for a generated cell (\"case\")");
    return s;
  }
  s.generate = dir / c.string("case");
  if (!fs::is_regular_file(s.generate)) c.fail("case", "no such case file " + s.generate.string());
  if (c.has("seed")) s.seed = c.seed("seed", 0);
  return s;
}

// The micro.cell case of `source`, with its seed, checked as `gabion check` would.
bridge::JsonDocument loadCellCase(const CellSource& source, const std::string& file, const std::string& pointer) {
  bridge::JsonDocument doc = bridge::JsonDocument::load(source.generate);
  const JsonReader root = doc.root();
  if (root.string("format") != "gabion.case/1") root.fail("format", "expected 'gabion.case/1'");
  if (root.string("kind") != "micro.cell")
    throw bridge::InputError(file, pointer, source.generate.string() + " is not a micro.cell case");
  if (source.seed) doc.applySet("seed=" + std::to_string(*source.seed));
  cellKind().check(doc);
  if (root.has("description")) root.string("description");
  doc.finish();
  return doc;
}

}  // namespace

void MaterialChange::applyTo(Material& m) const {
  if (normal_stiffness_N_m) m.normal_stiffness_N_m = *normal_stiffness_N_m;
  if (shear_stiffness_N_m) m.shear_stiffness_N_m = *shear_stiffness_N_m;
  if (friction) m.friction = *friction;
  if (normal_force_limit_N) m.normal_force_limit_N = *normal_force_limit_N;
  if (local_damping) m.local_damping = *local_damping;
  if (viscous_damping_ratio) m.viscous_damping_ratio = *viscous_damping_ratio;
}

LabSetup parseLabSetup(const JsonReader& root, double default_mass_scale, double default_duration_s,
                       double default_series_s) {
  LabSetup s;
  s.file = root.file();
  const fs::path dir = fs::path(root.file()).parent_path();
  // The cell: one source, or a list of cell files (one per replicate).
  if (root.has("cell") && root.raw("cell").is_array()) {
    const nlohmann::json& list = root.raw("cell");
    if (list.empty()) root.fail("cell", "an empty list of cell files");
    for (std::size_t k = 0; k < list.size(); ++k) {
      if (!list[k].is_string())
        root.fail("cell", "a list of cells holds cell file names (entry " + std::to_string(k) + ")");
      s.cells.push_back({dir / list[k].get<std::string>(), {}, {}, 0.0});
    }
    if (root.has("replicates") && root.integer("replicates", 1) != static_cast<long long>(list.size()))
      root.fail("replicates", "a list of cell files makes one replicate per file");
  } else {
    const CellSource first = parseSource(root, dir);
    const auto n = root.integer("replicates", 1, 1);
    if (n > 64) root.fail("replicates", "at most 64");
    if (n > 1 && first.generate.empty())
      root.fail("replicates",
                "replicates need cells of different seeds: give \"cell\": {\"case\": \"micro_cell.json\"}, or a list "
                "of cell files");
    std::uint64_t seed0 = 0;
    if (!first.generate.empty() && !first.seed) {
      // the case's own seed, for the replicates' seeds after it
      const bridge::JsonDocument doc = bridge::JsonDocument::load(first.generate);
      const auto it = doc.json().find("seed");
      seed0 = it != doc.json().end() && it->is_number_unsigned() ? it->get<std::uint64_t>() : 1;
    }
    for (long long k = 0; k < n; ++k) {
      CellSource c = first;
      if (!c.generate.empty()) c.seed = (first.seed ? *first.seed : seed0) + static_cast<std::uint64_t>(k);
      s.cells.push_back(c);
    }
  }
  if (const auto m = root.optionalObject("materials"))
    for (const auto& [name, r] : m->members()) s.changes.push_back(parseMaterialChange(name, r));
  for (const JsonReader& r : root.objects("contact_pairs")) s.pairs.push_back(parseContactPair(r));
  if (const auto p = root.optionalObject("plates")) s.plates = parseMaterialChange("plates", *p);
  s.plates.name = "plates";
  s.netting_mass_scale = root.number("netting_mass_scale", default_mass_scale, Check::Positive);
  if (s.netting_mass_scale < 1.0) root.fail("netting_mass_scale", "must be >= 1 (1: no scaling)");
  s.gravity = root.vec3("gravity_m_s2", s.gravity);
  if (const auto r = root.optionalObject("run")) {
    s.run = parseRun(*r, default_duration_s);
    s.duration_given = r->has("duration_s");
    if (!r->has("series_interval_s")) s.run.series_interval_s = std::min(default_series_s, s.run.duration_s);
    if (!r->has("output_interval_s")) s.run.output_interval_s = s.run.duration_s / 50.0;
  } else {
    s.run.duration_s = default_duration_s;
    s.run.series_interval_s = std::min(default_series_s, default_duration_s);
    s.run.output_interval_s = default_duration_s / 50.0;
  }
  // The overlap check at 1 (the centre of one sphere at the other's surface)
  // unless given: a netting node pinched between a stone and a plate, the
  // boulder or the other cell is squeezed past half its radius under a
  // test's load at the cell's contact stiffness; the check stays one against
  // tunnelling (docs/lab.md).
  if (!root.has("run") || !root.object("run").has("max_overlap_ratio")) s.run.max_overlap_ratio = 1.0;
  return s;
}

Sample loadSample(const fs::path& cell_file, const LabSetup& setup) {
  Sample out;
  out.cell_file = cell_file;
  Scene& s = out.scene;
  if (!fs::exists(cell_file)) throw bridge::InputError(setup.file, "/cell", "no cell file " + cell_file.string());
  try {
    loadCellFile(cell_file, s);
  } catch (const bridge::InputError& e) {  // (named from the case's field that gave the file)
    throw bridge::InputError(setup.file, "/cell", cell_file.string() + ": " + e.message());
  }
  s.gravity_m_s2 = setup.gravity;
  s.run = setup.run;
  const auto find = [&](const std::string& name) {
    const auto it =
        std::find_if(s.materials.begin(), s.materials.end(), [&](const Material& m) { return m.name == name; });
    return it == s.materials.end() ? -1 : static_cast<int>(it - s.materials.begin());
  };
  std::string names;
  for (const Material& m : s.materials) names += (names.empty() ? "" : ", ") + m.name;
  for (const MaterialChange& c : setup.changes) {
    const int k = find(c.name);
    if (k < 0)
      throw bridge::InputError(
          setup.file, c.pointer,
          "the cell (" + cell_file.string() + ") has no material '" + c.name + "' (it has " + names + ")");
    c.applyTo(s.materials[static_cast<std::size_t>(k)]);
  }
  // The plates: the cell's formwork material (steel in a micro.cell), made
  // frictionless (their reactions are then normal forces only), with the
  // test's changes.
  Material plate = s.materials[static_cast<std::size_t>(std::max(0, find("formwork")))];
  plate.friction = 0.0;
  plate.name = "plates";
  setup.plates.applyTo(plate);
  out.plate_material = static_cast<int>(s.materials.size());
  s.materials.push_back(plate);
  for (const ContactPairInput& in : setup.pairs) s.contact_pairs.push_back(resolveContactPair(in, s.materials));
  out.rock_material = std::max(0, find("rock"));
  out.netting_material = find("netting");
  try {
    const std::string text = bridge::H5Reader(cell_file).attribute("/", "summary");
    out.cell_summary = nlohmann::json::parse(text);
  } catch (const std::exception&) {
    out.cell_summary = nlohmann::json::object();
  }
  // The netting's nodes (the spheres links join) take the test's mass scaling.
  std::vector<char> node(s.spheres.size(), 0);
  for (const LinkSpec& l : s.links) node[l.a] = node[l.b] = 1;
  for (std::size_t k = 0; k < s.spheres.size(); ++k)
    if (node[k]) s.spheres[k].mass_scale = setup.netting_mass_scale, ++out.netting_nodes;
  // Extent and mass.
  out.lo = Vec3::Constant(1e300), out.hi = Vec3::Constant(-1e300);
  const auto reach = [&](const Vec3& x, double r) {
    out.lo = out.lo.cwiseMin(x - Vec3::Constant(r));
    out.hi = out.hi.cwiseMax(x + Vec3::Constant(r));
  };
  for (const SphereSpec& sp : s.spheres) {
    reach(sp.center_m, sp.radius_m);
    if (!sp.fixed) out.mass_kg += sphereMass(s, sp);
  }
  for (const BlockSpec& b : s.blocks) {
    for (std::size_t k = 0; k < b.member_radii_m.size(); ++k)
      reach(b.position_m + b.orientation * b.member_centers_m[k], b.member_radii_m[k]);
    const double density = s.materials[static_cast<std::size_t>(b.material)].density_kg_m3;
    if (!b.fixed) out.mass_kg += clusterMassProperties(b.member_centers_m, b.member_radii_m, density, 1e-3).mass_kg;
  }
  if (s.spheres.empty() && s.blocks.empty())
    throw bridge::InputError(cell_file.string(), "", "the cell file holds no bodies");
  return out;
}

SphereSpec boulderSphere(Scene& scene, int rock_material, double diameter_m, double density_kg_m3,
                         const MaterialChange& change) {
  Material m = scene.materials[static_cast<std::size_t>(rock_material)];
  m.name = "boulder";
  m.density_kg_m3 = density_kg_m3;
  m.local_damping = 0.0;
  change.applyTo(m);
  scene.materials.push_back(m);
  const double r = 0.5 * diameter_m;
  SphereSpec b;
  b.radius_m = r;
  b.material = static_cast<int>(scene.materials.size() - 1);
  b.mass_kg = density_kg_m3 * 4.0 / 3.0 * 3.14159265358979323846 * r * r * r;
  return b;
}

bool limitStepToSpeed(Scene& scene, double speed_m_s, const std::string& file) {
  double rmin = 1e300;
  for (const SphereSpec& sp : scene.spheres) rmin = std::min(rmin, sp.radius_m);
  for (const BlockSpec& b : scene.blocks)
    for (const double r : b.member_radii_m) rmin = std::min(rmin, r);
  const double dt = chooseDt(scene, criticalTimeStep(scene), file);
  if (speed_m_s * dt <= 0.1 * rmin) return false;
  scene.run.dt_s = 0.1 * rmin / speed_m_s;
  return true;
}

double checkCells(const LabSetup& setup) {
  double edge = 0.0;
  for (std::size_t k = 0; k < setup.cells.size(); ++k) {
    const CellSource& c = setup.cells[k];
    double e = 0.0;
    if (c.generate.empty()) {
      const Sample sample = loadSample(c.file, setup);
      e = std::min(sample.hi.x() - sample.lo.x(), sample.hi.y() - sample.lo.y());
    } else {
      const bridge::JsonDocument doc = loadCellCase(c, setup.file, "/cell/case");
      const auto it = doc.json().find("edge_m");
      e = it != doc.json().end() && it->is_number() ? it->get<double>() : 0.5;
      if (k > 0) continue;  // (the same case for every replicate, with another seed)
    }
    if (k == 0) edge = e;
  }
  return edge;
}

fs::path generateCell(const CellSource& source, const fs::path& dir, const bridge::RunContext& ctx) {
  bridge::JsonDocument doc = loadCellCase(source, source.generate.string(), "");
  const std::string text = doc.json().dump(1);
  const fs::path cell = dir / "cell.h5", stamp = dir / "case.json";
  // The same case and seed made this cell already: take it.
  // (and its folder was committed whole: bridge/manifest.hpp)
  if (fs::exists(cell) && fs::exists(stamp)) {
    std::ifstream in(stamp);
    const std::string before((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (before == text && bridge::adoptManifest(dir)) return cell;
  }
  fs::create_directories(dir);
  bridge::beginManifest(dir);
  fs::remove(stamp);
  bridge::RunContext sub = ctx;
  sub.outdir = dir;
  sub.case_file = source.generate;
  sub.may_release_case = false;
  const bridge::RunOutcome out = cellKind().run(doc, sub);
  nlohmann::json summary = out.results;
  summary["format"] = "gabion.summary/1";
  summary["kind"] = "micro.cell";
  summary["status"] = bridge::statusName(out.status);
  summary["case_file"] = source.generate.string();
  summary["case"] = doc.json();
  bridge::writeJsonAtomic(dir / "summary.json", summary);
  if (out.status != bridge::RunOutcome::Status::Ok) {
    bridge::writeManifest(dir, bridge::statusName(out.status));
    throw bridge::NumericalError(0, 0.0, "generating the cell (" + dir.string() + "): " + out.message);
  }
  bridge::writeTextAtomic(stamp, text);
  bridge::writeManifest(dir, "ok");
  return cell;
}

double QuasiStatic::ratio() const {
  if (work_.empty()) return NAN;
  const double final_work = work_.back();
  double worst = 0.0;
  bool any = false;
  for (std::size_t k = 0; k < work_.size(); ++k)
    if (work_[k] > 0.1 * final_work && work_[k] > 0.0) worst = std::max(worst, kinetic_[k] / work_[k]), any = true;
  return any ? worst : NAN;
}

namespace {

// Runs job(k) for k = 0 .. n-1 on up to `threads` threads (the calling one
// included), each k claimed by whichever thread comes free first.
template <class Job>
void parallelFor(std::size_t n, int threads, const Job& job) {
  std::atomic<std::size_t> next{0};
  const auto worker = [&](bool first) {
    for (std::size_t k; (k = next++) < n;) job(k, first);
  };
  std::vector<std::thread> pool;
  const std::size_t workers = std::min<std::size_t>(n, static_cast<std::size_t>(std::max(1, threads)));
  for (std::size_t w = 1; w < workers; ++w) pool.emplace_back(worker, false);
  worker(true);
  for (std::thread& t : pool) t.join();
}

nlohmann::json scatterOf(const std::vector<double>& v) {
  double mean = 0.0, var = 0.0;
  for (const double x : v) mean += x / static_cast<double>(v.size());
  for (const double x : v) var += (x - mean) * (x - mean);
  const double sd = v.size() > 1 ? std::sqrt(var / static_cast<double>(v.size() - 1)) : 0.0;
  const auto [mn, mx] = std::minmax_element(v.begin(), v.end());
  return {{"mean", mean}, {"std", sd},         {"min", *mn},
          {"max", *mx},   {"count", v.size()}, {"cv", mean != 0.0 ? sd / std::fabs(mean) : 0.0}};
}

}  // namespace

std::optional<bridge::Estimate> estimateReplicates(const LabSetup& setup, std::size_t variants, const ScenePlan& plan,
                                                   bool stages_keep_ends) {
  const CellSource& first = setup.cells.front();
  if (!first.generate.empty()) return std::nullopt;
  const Sample sample = loadSample(first.file, setup);
  bridge::Estimate e;
  double kept = 0.0;  // (the stages' checkpoints, all on disk at the last stage's end)
  for (std::size_t v = 0; v < variants; ++v) {
    const Scene scene = plan(sample, v);
    const double dt = scene.run.dt_s > 0.0 ? scene.run.dt_s : chooseDt(scene, criticalTimeStep(scene), setup.file);
    const bridge::Estimate one = sceneEstimate(scene, dt);
    kept += one.checkpoint_bytes;
    bridge::addRun(e, one);
  }
  if (stages_keep_ends) e.checkpoint_bytes = kept;
  return bridge::times(e, static_cast<double>(setup.cells.size()));
}

namespace {

// An outcome as it crosses between processes (a row's result, a worker's answer).
nlohmann::json outcomeJson(const bridge::RunOutcome& out) {
  return {{"status", static_cast<int>(out.status)},
          {"message", out.message},
          {"results", out.results},
          {"answer", out.answer},
          {"report", out.report}};
}

bridge::RunOutcome outcomeOf(const nlohmann::json& j) {
  bridge::RunOutcome out;
  out.status = static_cast<bridge::RunOutcome::Status>(j.at("status").get<int>());
  out.message = j.at("message").get<std::string>();
  out.results = j.at("results");
  out.answer = j.value("answer", "");
  out.report = j.value("report", "");
  return out;
}

// The folder of run j (variant j % nv on replicate j / nv) when there are several.
std::string runFolder(const Replicates& r, std::size_t j) {
  const std::size_t nv = r.variants.size();
  std::string f = nv > 1 ? r.variants[j % nv] : "";
  if (r.setup.cells.size() > 1) f += (f.empty() ? "" : "_") + std::string("replicate_") + std::to_string(j / nv);
  return f;
}

// Generates replicate k's cell (on one thread when there are several).
fs::path generateReplicateCell(const Replicates& r, std::size_t k, const bridge::RunContext& ctx, bool first) {
  const std::size_t nr = r.setup.cells.size();
  const CellSource& c = r.setup.cells[k];
  bridge::RunContext rc = ctx;
  rc.threads = nr > 1 ? 1 : ctx.threads;
  rc.progress = first && ctx.progress;
  rc.workers = nullptr;
  const std::string name = nr > 1 ? "cell_seed" + std::to_string(*c.seed) : "cell";
  return generateCell(c, ctx.outdir / name, rc);
}

// Runs run j on `cell` into rc.outdir: its outcome, with the cell's file and seed.
bridge::RunOutcome runReplicate(const Replicates& r, std::size_t j, const fs::path& cell,
                                const bridge::RunContext& rc) {
  const std::size_t nv = r.variants.size(), k = j / nv;
  bridge::RunOutcome out;
  fs::create_directories(rc.outdir);
  const Sample sample = loadSample(cell, r.setup);
  try {
    out = r.test(sample, j % nv, rc);
  } catch (const bridge::NumericalError& e) {
    out.status = bridge::RunOutcome::Status::NumericalFailure;
    out.message = e.what();
  }
  out.results["cell_file"] = cell.string();
  if (r.setup.cells[k].seed) out.results["cell_seed"] = *r.setup.cells[k].seed;
  return out;
}

// One of several runs, in its own folder on one thread, with its summary.json.
bridge::RunOutcome runReplicateInFolder(const Replicates& r, std::size_t j, const fs::path& cell,
                                        const bridge::RunContext& ctx, bool first) {
  bridge::RunContext rc = ctx;
  rc.threads = 1;
  rc.progress = first && ctx.progress;
  rc.outdir = ctx.outdir / runFolder(r, j);
  rc.workers = nullptr;
  bridge::RunOutcome out = runReplicate(r, j, cell, rc);
  nlohmann::json summary = out.results;
  summary["format"] = "gabion.summary/1";
  summary["kind"] = r.label;
  summary["status"] = bridge::statusName(out.status);
  if (!out.message.empty()) summary["message"] = out.message;
  bridge::writeJsonAtomic(rc.outdir / "summary.json", summary);
  return out;
}

// A task's answer carries the files the worker wrote; rank 0 notes them
// for its manifest (bridge/manifest.hpp).
nlohmann::json writtenUnder(const fs::path& dir) {
  nlohmann::json files = nlohmann::json::array();
  for (const fs::path& f : bridge::writtenFiles(dir)) files.push_back((dir / f).string());
  return files;
}

void noteAll(const nlohmann::json& files) {
  for (const auto& f : files) bridge::noteWritten(f.get<std::string>());
}

// The case's summary from every run's outcome (or the error that kept it
// from ending): the runs, and the scatter of the headline values over each
// variant's replicates.
bridge::RunOutcome summarizeReplicates(const Replicates& reps, const std::vector<bridge::RunOutcome>& outs,
                                       const std::vector<std::string>& errors) {
  const std::string& label = reps.label;
  const std::vector<std::string>& variants = reps.variants;
  const std::vector<std::string>& scatter_keys = reps.scatter_keys;
  const std::size_t nr = reps.setup.cells.size(), nv = variants.size(), n = nr * nv;
  const auto folder = [&](std::size_t j) { return runFolder(reps, j); };
  bridge::RunOutcome out;
  nlohmann::json list = nlohmann::json::array();
  std::string failures;
  for (std::size_t j = 0; j < n; ++j) {
    nlohmann::json r = {{"folder", folder(j)}, {"variant", variants[j % nv]}, {"replicate", j / nv}};
    const std::string message = !errors[j].empty() ? errors[j] : outs[j].message;
    if (!errors[j].empty() || outs[j].status != bridge::RunOutcome::Status::Ok) {
      r["status"] = errors[j].empty() ? "numerical_failure" : "error";
      r["message"] = message;
      failures += folder(j) + ": " + message + "; ";
    } else {
      r["status"] = "ok";
      for (const std::string& key : scatter_keys)
        if (outs[j].results.contains(key)) r[key] = outs[j].results[key];
    }
    if (outs[j].results.contains("cell_seed")) r["cell_seed"] = outs[j].results["cell_seed"];
    list.push_back(r);
  }
  out.results["runs"] = list;
  // The scatter of each headline value over each variant's replicates.
  nlohmann::json scatter = nlohmann::json::object();
  std::ostringstream report;
  report.precision(4);
  report << label << ": " << nv << (nv == 1 ? " variant" : " variants") << " x " << nr
         << (nr == 1 ? " cell" : " replicate cells") << "\n";
  for (std::size_t v = 0; v < nv; ++v) {
    nlohmann::json per = nlohmann::json::object();
    for (const std::string& key : scatter_keys) {
      std::vector<double> x;
      for (std::size_t k = 0; k < nr; ++k) {
        const nlohmann::json& r = list[k * nv + v];
        if (r.contains(key) && r[key].is_number()) x.push_back(r[key].get<double>());
      }
      if (x.empty()) continue;
      per[key] = scatterOf(x);
      report << "  " << (nv > 1 ? variants[v] + " " : "") << key << ": " << per[key]["mean"].get<double>();
      if (nr > 1) report << " +- " << per[key]["std"].get<double>() << " (" << x.size() << " cells)";
      report << "\n";
    }
    scatter[variants[v]] = per;
  }
  out.results["scatter"] = scatter;
  out.answer = report.str();
  if (!failures.empty()) {
    out.status =
        bridge::interrupted() ? bridge::RunOutcome::Status::Interrupted : bridge::RunOutcome::Status::NumericalFailure;
    out.message = failures;
  }
  return out;
}

}  // namespace

std::function<nlohmann::json(const nlohmann::json&)> serveReplicates(std::shared_ptr<const Replicates> r) {
  return [r](const nlohmann::json& task) {
    bridge::RunContext ctx;
    ctx.outdir = task.at("outdir").get<std::string>();
    ctx.case_digest = task.at("case_digest").get<std::string>();
    ctx.threads = 1;
    if (task.contains("cell")) {
      const fs::path file = generateReplicateCell(*r, task.at("cell").get<std::size_t>(), ctx, false);
      return nlohmann::json{{"file", file.string()}, {"files", writtenUnder(file.parent_path())}};
    }
    const auto j = task.at("run").get<std::size_t>();
    nlohmann::json answer;
    try {
      const bridge::RunOutcome out = runReplicateInFolder(*r, j, task.at("cell_file").get<std::string>(), ctx, false);
      answer = outcomeJson(out);
    } catch (const bridge::WriteError&) {
      throw;
    } catch (const std::exception& e) {
      answer = {{"error", e.what()}};
    }
    answer["files"] = writtenUnder(ctx.outdir / runFolder(*r, j));
    return answer;
  };
}

bridge::RunOutcome runReplicates(const Replicates& reps, const bridge::RunContext& ctx) {
  const LabSetup& setup = reps.setup;
  const std::vector<std::string>& variants = reps.variants;
  const std::size_t nr = setup.cells.size(), nv = variants.size(), n = nr * nv;
  // Several runs go to the MPI workers, when there are some.
  bridge::RemoteWorkers* workers = n > 1 ? ctx.workers : nullptr;
  const auto task = [&](nlohmann::json t) {
    t["outdir"] = fs::absolute(ctx.outdir).string();
    t["case_digest"] = ctx.case_digest;
    nlohmann::json answer = workers->call(t);
    noteAll(answer.at("files"));
    return answer;
  };
  // The cells: generated first where they come from a case (in parallel),
  // each once whatever the number of variants.
  std::vector<fs::path> files(nr);
  std::vector<std::string> errors(n);
  std::vector<std::string> cell_errors(nr);
  const int cell_threads = nr > 1 ? (workers != nullptr ? workers->size() : ctx.threads) : 1;
  parallelFor(nr, cell_threads, [&](std::size_t k, bool first) {
    const CellSource& c = setup.cells[k];
    if (c.generate.empty()) {
      files[k] = c.file;
      return;
    }
    try {
      if (workers != nullptr && nr > 1)
        files[k] = task({{"cell", k}}).at("file").get<std::string>();
      else
        files[k] = generateReplicateCell(reps, k, ctx, first);
    } catch (const std::exception& e) {  // (a thread must not throw; the case was checked before)
      cell_errors[k] = e.what();
    }
  });
  std::vector<bridge::RunOutcome> outs(n);
  const auto cellFailed = [&](std::size_t j) {
    outs[j].status = bridge::RunOutcome::Status::NumericalFailure;
    outs[j].message = cell_errors[j / nv];
  };
  if (n == 1) {
    if (!cell_errors[0].empty()) {
      cellFailed(0);
      return outs[0];
    }
    return runReplicate(reps, 0, files[0], ctx);
  }
  // Several runs in parallel, one engine thread each (or one worker rank
  // each); every one writes its own folder.
  parallelFor(n, workers != nullptr ? workers->size() : ctx.threads, [&](std::size_t j, bool first) {
    if (!cell_errors[j / nv].empty()) {
      cellFailed(j);
      return;
    }
    try {
      if (workers != nullptr) {
        const nlohmann::json a = task({{"run", j}, {"cell_file", files[j / nv].string()}});
        if (a.contains("error")) {
          errors[j] = a.at("error").get<std::string>();
          return;
        }
        outs[j] = outcomeOf(a);
      } else {
        outs[j] = runReplicateInFolder(reps, j, files[j / nv], ctx, first);
      }
    } catch (const std::exception& e) {
      errors[j] = e.what();
    }
  });

  return summarizeReplicates(reps, outs, errors);
}

namespace {

// The replicates as rows: row k generates replicate k's cell and runs every
// variant on it, into the folders a local run uses; collected, the rows
// give the local run's summary.
class ReplicateRows final : public bridge::RowPlan {
 public:
  ReplicateRows(std::shared_ptr<const Replicates> reps, std::function<std::optional<bridge::Estimate>()> estimate)
      : reps_(std::move(reps)), cost_s_([this, estimate = std::move(estimate)] {
          const double n = static_cast<double>(std::max<std::size_t>(1, reps_->setup.cells.size()));
          std::optional<bridge::Estimate> e;
          try {
            e = estimate();
          } catch (const std::exception&) {
          }
          // (cells not generated yet cannot be costed: an hour each, one replicate a task)
          return e ? e->wall_time_s / n : 3600.0;
        }) {}
  std::size_t size() const override { return reps_->setup.cells.size(); }
  nlohmann::json describe(std::size_t k) const override {
    const CellSource& c = reps_->setup.cells[k];
    nlohmann::json p = {
        {"replicate", k}, {"cell", (c.generate.empty() ? c.file : c.generate).string()}, {"variants", reps_->variants}};
    return {{"parameters", p}, {"seed", c.seed ? nlohmann::json(*c.seed) : nlohmann::json()}};
  }
  nlohmann::json run(std::size_t k, const bridge::RunContext& ctx) const override {
    const Replicates& r = *reps_;
    const std::size_t nv = r.variants.size(), n = r.setup.cells.size() * nv;
    fs::path cell = r.setup.cells[k].file;
    if (!r.setup.cells[k].generate.empty()) cell = generateReplicateCell(r, k, ctx, false);  // (throws: a failed row)
    nlohmann::json runs = nlohmann::json::array();
    std::string failures;
    for (std::size_t v = 0; v < nv; ++v) {
      const std::size_t j = k * nv + v;
      try {
        const bridge::RunOutcome out =
            n == 1 ? runReplicate(r, j, cell, ctx) : runReplicateInFolder(r, j, cell, ctx, false);
        if (out.status != bridge::RunOutcome::Status::Ok) failures += runFolder(r, j) + ": " + out.message + "; ";
        runs.push_back(outcomeJson(out));
      } catch (const bridge::WriteError&) {
        throw;
      } catch (const std::exception& e) {
        failures += runFolder(r, j) + ": " + e.what() + "; ";
        runs.push_back({{"error", e.what()}});
      }
    }
    nlohmann::json result = {{"ok", failures.empty()}, {"runs", runs}};
    if (!failures.empty()) result["message"] = failures;
    return result;
  }
  double costS(std::size_t) const override { return cost_s_(); }
  bridge::RunOutcome assemble(const std::vector<std::optional<nlohmann::json>>& rows, const bridge::RowStats&,
                              const bridge::RunContext& ctx) const override {
    const Replicates& r = *reps_;
    const std::size_t nr = r.setup.cells.size(), nv = r.variants.size(), n = nr * nv;
    std::vector<bridge::RunOutcome> outs(n);
    std::vector<std::string> errors(n);
    for (std::size_t k = 0; k < nr; ++k) {
      // (the files its process wrote, listed in this folder's manifest)
      adoptFiles(ctx.outdir / (nr > 1 ? "cell_seed" + std::to_string(*r.setup.cells[k].seed) : "cell"));
      for (std::size_t v = 0; v < nv; ++v) {
        const std::size_t j = k * nv + v;
        if (n > 1) adoptFiles(ctx.outdir / runFolder(r, j));
        if (!rows[k]) {
          errors[j] = "missing: not run yet";
        } else if (!rows[k]->contains("runs")) {
          errors[j] = rows[k]->at("message").get<std::string>();
        } else if (rows[k]->at("runs").at(v).contains("error")) {
          errors[j] = rows[k]->at("runs").at(v).at("error").get<std::string>();
        } else {
          outs[j] = outcomeOf(rows[k]->at("runs").at(v));
        }
      }
    }
    if (n == 1) {
      if (!errors[0].empty()) {
        outs[0].status = bridge::RunOutcome::Status::NumericalFailure;
        outs[0].message = errors[0];
      }
      for (const auto& entry : fs::directory_iterator(ctx.outdir))
        if (entry.is_regular_file()) bridge::noteWritten(entry.path());
      return outs[0];
    }
    return summarizeReplicates(r, outs, errors);
  }

 private:
  // Notes every file under `dir` (written by another process) for this
  // process's manifest.
  static void adoptFiles(const fs::path& dir) {
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) return;
    for (const auto& entry : fs::recursive_directory_iterator(dir, ec))
      if (entry.is_regular_file() && entry.path().filename().string().find(".part") == std::string::npos)
        bridge::noteWritten(entry.path());
  }
  std::shared_ptr<const Replicates> reps_;
  bridge::Lazy<double> cost_s_;
};

}  // namespace

std::shared_ptr<const bridge::RowPlan> replicateRows(std::shared_ptr<const Replicates> reps,
                                                     std::function<std::optional<bridge::Estimate>()> estimate) {
  return std::make_shared<const ReplicateRows>(std::move(reps), std::move(estimate));
}

bridge::CaseKind replicateKind(std::string kind, std::string description,
                               std::function<void(const bridge::JsonDocument&)> check,
                               std::function<std::shared_ptr<const Replicates>(const bridge::JsonDocument&)> replicates,
                               std::function<std::optional<bridge::Estimate>(const bridge::JsonDocument&)> estimate) {
  return {std::move(kind),
          std::move(description),
          std::move(check),
          [replicates](const bridge::JsonDocument& doc, const bridge::RunContext& ctx) {
            return runReplicates(*replicates(doc), ctx);
          },
          estimate,
          [replicates, estimate](const bridge::JsonDocument& doc) {
            // (costed later, if at all: on a copy of the case)
            const auto copy = std::make_shared<bridge::JsonDocument>(doc.json(), doc.file());
            return replicateRows(replicates(doc), [estimate, copy] { return estimate(*copy); });
          },
          [replicates](const bridge::JsonDocument& doc) { return serveReplicates(replicates(doc)); }};
}

}  // namespace gabion::micro::lab
