#include "app/pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>

#include "app/registry.hpp"
#include "app/sub_case.hpp"
#include "bridge/cost.hpp"
#include "bridge/errors.hpp"
#include "bridge/interrupt.hpp"
#include "bridge/law_file.hpp"
#include "bridge/manifest.hpp"
#include "bridge/output.hpp"
#include "bridge/plot.hpp"
#include "bridge/units.hpp"
#include "fitting/joint_fit.hpp"
#include "fitting/law_fit.hpp"
#include "fitting/sha256.hpp"
#include "gabion_version.hpp"

namespace gabion::app {

namespace {

namespace fs = std::filesystem;
using bridge::Check;
using bridge::JsonDocument;
using bridge::JsonReader;
using nlohmann::json;

/// The four virtual lab tests, in the order they run.
const std::vector<std::string> kTests = {"cc", "uc", "uci", "shear"};
const std::map<std::string, std::string> kTestKind = {
    {"cc", "micro.cc"}, {"uc", "micro.uc"}, {"uci", "micro.uci"}, {"shear", "micro.shear"}};

/// Everything a pipeline case says (docs/pipeline.md).
struct PipelineCase {
  fs::path cell;  ///< a micro.cell case, or a cell file (.h5) used as it is
  bool cell_is_file = false;
  double cell_edge_m = 0.5;  ///< the edge of a given cell file's cell
  unsigned long seed = 1;
  int replicates = 1;
  std::map<std::string, fs::path> tests;  ///< lab case per test name
  std::vector<double> uci_velocities_m_s;
  /// Plate speeds of the confined compressions the axial law's momentum
  /// flux is fitted on (empty: none, the law has no flux).
  std::vector<double> cc_rate_velocities_m_s;
  /// Cells in the row whose confined compression along x, beside one
  /// cell's, gives the joint law (0: none); and those compressions' strain.
  int joint_cells_in_series = 0;
  double joint_strain = 0.15;
  fs::path structure_case;
  std::string material = "front";
  std::vector<double> velocities_m_s;
  std::optional<fs::path> sweep_case, capacity_case, design_case;
  std::map<std::string, std::vector<std::string>> settings;  ///< per stage: --set lines
};

fs::path relative(const JsonDocument& doc, const std::string& p) {
  return fs::path(doc.file()).parent_path() / p;
}

PipelineCase readPipeline(const JsonDocument& doc) {
  const JsonReader root = doc.root();
  PipelineCase c;
  c.seed = static_cast<unsigned long>(root.seed("seed", 1));
  c.cell = relative(doc, root.string("cell"));
  c.cell_is_file = c.cell.extension() == ".h5";
  if (root.has("cell_edge_m")) {
    if (!c.cell_is_file) root.fail("cell_edge_m", "only with a cell file as 'cell' (a micro.cell case gives its edge)");
    c.cell_edge_m = root.number("cell_edge_m", Check::Positive);
  }
  c.replicates = static_cast<int>(root.integer("replicates", 1, 1));
  if (c.replicates > 16) root.fail("replicates", "at most 16 cells");
  if (c.cell_is_file && c.replicates > 1)
    root.fail("replicates", "replicates need a micro.cell case as 'cell' (cells of consecutive seeds)");
  const JsonReader lab = root.object("lab");
  for (const auto& t : kTests) c.tests[t] = relative(doc, lab.string(t));
  c.uci_velocities_m_s = root.numbers("uci_velocities_m_s", Check::Positive, 1);
  if (root.has("cc_rate_velocities_m_s"))
    c.cc_rate_velocities_m_s = root.numbers("cc_rate_velocities_m_s", Check::Positive, 1);
  if (const auto j = root.optionalObject("joint")) {
    c.joint_cells_in_series = static_cast<int>(j->integer("cells_in_series", 2, 2));
    if (c.joint_cells_in_series > 4) j->fail("cells_in_series", "must be <= 4 (cells in a row along the load)");
    c.joint_strain = j->number("strain", c.joint_strain, Check::Positive);
    if (c.joint_strain > 0.6) j->fail("strain", "must be <= 0.6 (the lid's travel over the row's length)");
  }
  const JsonReader st = root.object("structure");
  c.structure_case = relative(doc, st.string("case"));
  c.material = st.string("material", c.material);
  c.velocities_m_s = st.numbers("velocities_m_s", Check::Positive, 1);
  if (root.has("sweep")) c.sweep_case = relative(doc, root.string("sweep"));
  if (root.has("capacity")) c.capacity_case = relative(doc, root.string("capacity"));
  if (root.has("design")) c.design_case = relative(doc, root.string("design"));
  if (root.has("stage_settings")) {
    const json& all = root.raw("stage_settings");
    const std::vector<std::string> stages = {"cell", "cc",     "uc",    "uci",      "shear",
                                             "fit",  "impact", "sweep", "capacity", "design"};
    if (!all.is_object()) root.fail("stage_settings", "expected an object: stage name -> list of settings");
    for (const auto& [name, v] : all.items()) {
      if (std::find(stages.begin(), stages.end(), name) == stages.end())
        throw bridge::InputError(doc.file(), "/stage_settings/" + name,
                                 "unknown stage (cell, cc, uc, uci, shear, fit, impact, sweep, capacity, design)");
      bool ok = v.is_array();
      for (const auto& line : v) ok = ok && line.is_string() && line.get<std::string>().find('=') != std::string::npos;
      if (!ok)
        throw bridge::InputError(doc.file(), "/stage_settings/" + name,
                                 "expected a list of \"path.to.key=value\" settings");
      for (const auto& line : v) c.settings[name].push_back(line.get<std::string>());
    }
  }
  return c;
}

/// A stage that stopped on numerical trouble: the pipeline stops and reports it.
struct StageFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// What a stage left: its summary, whether it was reused, its wall time.
struct StageResult {
  std::string name;
  fs::path dir;
  json summary;
  bool reused = false;
  double wall_time_s = 0.0;
  json dropped_runs = json::array();  ///< failed runs the stage went on without ({folder, message})
};

std::string fmt(double x, int digits = 4) {
  std::ostringstream s;
  s << std::setprecision(digits) << x;
  return s.str();
}

// The stage's content key: the program's version, its case and the bytes of
// the files it reads.
std::string stageKey(const json& case_value, const std::vector<fs::path>& inputs) {
  std::string text = std::string("gabion ") + gabion::kVersion + "\n" + case_value.dump();
  for (const auto& f : inputs) text += "\n" + f.string() + " " + fitting::sha256File(f);
  return fitting::sha256Hex(text);
}

/// Where the pipeline is: stages done of all, since when, and how long the
/// rest should take (for the progress lines on a terminal). The ETA counts
/// the stages whose kind estimates its cost (the micro lab tests, known once
/// the cell exists) in body-steps, at the seconds per body-step measured on
/// those already run (at first the rate of the default cell's tests); the
/// fit and macro stages take about a second together.
struct StageClock {
  int done = 0, total = 0;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  std::map<std::string, double> estimated;  ///< body-steps, by stage name, where its kind estimates them
  std::map<std::string, double> pending;    ///< those of the stages still to run
  std::string current;                      ///< the stage running
  std::chrono::steady_clock::time_point current_start = start;
  double measured_s = 0.0, measured_body_steps = 0.0;
  // (the default pipeline's four tests as the README's command runs them:
  // 272 s for 7.75e9 estimated body-steps, 2.4e-8 to 4.9e-8 s each;
  // summary.json, stages)
  static constexpr double kInitialSecondsPerBodyStep = bridge::kMicroSecondsPerBodyStep;

  double secondsPerBodyStep() const {
    return measured_body_steps > 0.0 ? measured_s / measured_body_steps : kInitialSecondsPerBodyStep;
  }
  /// Seconds left, given the running stage's own estimate of its remaining
  /// time (`run_eta_s`, < 0 when it has none); NaN while nothing is estimated.
  double eta(double run_eta_s) const {
    if (pending.empty()) return NAN;
    double left = 0.0;
    for (const auto& [name, body_steps] : pending) {
      double t = body_steps * secondsPerBodyStep();
      if (name == current) {
        t -= std::chrono::duration<double>(std::chrono::steady_clock::now() - current_start).count();
        t = std::max(t, run_eta_s);
      }
      left += std::max(t, 0.0);
    }
    return left;
  }
  std::string prefix(double run_eta_s = -1.0) const {
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::ostringstream o;
    o << "pipeline [" << done + 1 << "/" << total << ", " << std::fixed << std::setprecision(0) << s << " s";
    const double left = eta(run_eta_s);
    if (std::isfinite(left)) o << ", ETA " << left << " s";
    o << "]";
    return o.str();
  }
  void begin(const std::string& name) {
    current = name;
    current_start = std::chrono::steady_clock::now();
  }
  /// The stage is over: its time calibrates the rate when it ran (not reused).
  void end(const std::string& name, bool ran, double wall_s) {
    const auto it = pending.find(name);
    if (it != pending.end()) {
      if (ran) measured_s += wall_s, measured_body_steps += it->second;
      pending.erase(it);
    }
    current.clear();
    ++done;
  }
};

/// A stage's case as it will run (its --set lines applied, the calibrated
/// laws in place of its own for the macro stages) and its content key: the
/// program's version, that case and the bytes of every file it reads.
struct StagedCase {
  json value;
  std::string key;
};

StagedCase stageCase(json case_value, const std::vector<fs::path>& inputs, const std::vector<std::string>& settings,
                     const fs::path& dir, const std::optional<fs::path>& law) {
  // The settings go through the case document (as --set does).
  {
    JsonDocument staged(case_value, (dir / "case.json").string());
    for (const auto& s : settings) staged.applySet(s);
    case_value = staged.json();
  }
  std::vector<fs::path> all = inputs;
  if (law) {
    case_value.erase("laws");
    case_value["law_file"] = law->string();
    all.push_back(*law);
  }
  const std::string key = stageKey(case_value, all);
  return {std::move(case_value), key};
}

/// A stage's record from an earlier run.
struct Reused {
  json summary;
  double wall_time_s = 0.0;
  json dropped_runs;
};

/// The summary, wall time and left-out runs of the stage in `dir` when it
/// ran with `key` and was accepted; nullopt when it must run (again).
std::optional<Reused> reusable(const fs::path& dir, const std::string& key) {
  if (!fs::exists(dir / "stage.json") || !fs::exists(dir / "summary.json")) return std::nullopt;
  try {
    std::ifstream in(dir / "stage.json");
    const json st = json::parse(in);
    std::ifstream sin(dir / "summary.json");
    json summary = json::parse(sin);
    // (and the stage's folder was committed whole: its manifest lists its
    // files as they are; adopting them lists them in the pipeline's)
    // (a lab stage that went on without its failed runs says so in its record)
    const bool accepted = summary.value("status", "") == "ok" || st.contains("dropped_runs");
    if (st.value("key", "") == key && accepted && bridge::adoptManifest(dir))
      return Reused{std::move(summary), st.value("wall_time_s", 0.0), st.value("dropped_runs", json::array())};
  } catch (const std::exception&) {
    // A damaged record: run the stage again.
  }
  return std::nullopt;
}

/// The failed runs of a lab stage on several cells that the pipeline can go
/// on without: every failure numerical (not an input or write error, not an
/// interruption), and every variant (UCI velocity) keeping a run that ended
/// ok on some cell. Each as {folder, message}; null when the stage cannot go
/// on.
json droppableRuns(const json& summary) {
  if (summary.value("status", "") != "numerical_failure" || !summary.contains("runs")) return nullptr;
  json dropped = json::array();
  std::map<std::string, int> ok_per_variant;
  for (const auto& r : summary.at("runs")) {
    const std::string status = r.value("status", "");
    const std::string variant = r.value("variant", "");
    ok_per_variant[variant] += status == "ok" ? 1 : 0;
    if (status == "ok") continue;
    if (status != "numerical_failure") return nullptr;
    dropped.push_back({{"folder", r.value("folder", "")}, {"message", r.value("message", "")}});
  }
  for (const auto& [variant, n] : ok_per_variant)
    if (n == 0) return nullptr;
  return dropped.empty() ? json(nullptr) : dropped;
}

/// Whether a stage that failed in some of its runs stops the pipeline, or
/// goes on without them where droppableRuns allows (lab stages on several
/// cells: the fit uses the other cells' runs, and the report says so).
enum class FailedRuns { Stop, LeaveOut };

/// Runs one stage through its kind's public CaseKind, in its own folder:
/// the case written to `dir/case.json`, the summary beside it, and
/// `stage.json` written last with the stage's content key. A stage whose key
/// is unchanged and whose summary says ok is not run again.
StageResult runStage(const std::string& name, const std::string& kind, json case_value,
                     const std::vector<fs::path>& inputs, const std::vector<std::string>& settings,
                     const bridge::RunContext& parent, const fs::path& dir, StageClock& clock,
                     const std::optional<fs::path>& law = std::nullopt, FailedRuns failed_runs = FailedRuns::Stop) {
  if (bridge::interrupted())
    throw StageFailure(std::string("interrupted by ") + bridge::signalName(bridge::interruptSignal()) +
                       " before stage '" + name + "'");
  StageResult out;
  out.name = name;
  out.dir = dir;
  fs::create_directories(dir);
  StagedCase staged = stageCase(std::move(case_value), inputs, settings, dir, law);
  case_value = std::move(staged.value);
  const std::string& key = staged.key;
  clock.begin(name);
  if (auto done = reusable(dir, key)) {
    out.summary = std::move(done->summary);
    out.reused = true;
    out.wall_time_s = done->wall_time_s;
    out.dropped_runs = std::move(done->dropped_runs);
    if (parent.progress)
      std::printf("%s %s: unchanged, reused (%s)\n", clock.prefix().c_str(), name.c_str(), dir.c_str());
    clock.end(name, false, out.wall_time_s);
    return out;
  }
  bridge::beginManifest(dir);
  fs::remove(dir / "stage.json");
  if (parent.progress) std::printf("%s %s (%s) ...\n", clock.prefix().c_str(), name.c_str(), kind.c_str());
  std::fflush(stdout);
  SubCase ran =
      runSubCase(case_value, kind, parent, dir, [&clock](double run_eta_s) { return clock.prefix(run_eta_s); });
  out.wall_time_s = ran.wall_time_s;
  json record = {{"key", key}, {"wall_time_s", out.wall_time_s}};
  if (ran.status != bridge::RunOutcome::Status::Ok) {
    const json dropped =
        failed_runs == FailedRuns::LeaveOut && !bridge::interrupted() ? droppableRuns(ran.summary) : json(nullptr);
    if (dropped.is_null()) {
      bridge::writeManifest(dir, bridge::statusName(ran.status));
      throw StageFailure("pipeline stage '" + name + "' (" + dir.string() + "): " + ran.message);
    }
    // Loud, at once: the stage goes on without these runs.
    for (const auto& d : dropped)
      std::fprintf(stderr, "pipeline: warning: stage '%s': run %s failed and is left out of the fit: %s\n",
                   name.c_str(), d.at("folder").get<std::string>().c_str(), d.at("message").get<std::string>().c_str());
    record["dropped_runs"] = dropped;
    out.dropped_runs = dropped;
  }
  bridge::writeJsonAtomic(dir / "stage.json", record);
  bridge::writeManifest(dir, "ok");
  out.summary = std::move(ran.summary);
  if (parent.progress) std::printf("%s %s done in %.1f s\n", clock.prefix().c_str(), name.c_str(), out.wall_time_s);
  clock.end(name, true, out.wall_time_s);
  return out;
}

json loadJson(const fs::path& p) {
  return JsonDocument::load(p).json();
}

// The result files of a lab stage, one per run (replicate and variant), with
// the run's replicate label.
std::vector<std::pair<fs::path, std::string>> labResults(const StageResult& s) {
  std::vector<std::pair<fs::path, std::string>> out;
  if (!s.summary.contains("runs")) {
    out.emplace_back(s.dir / "result.h5", "0");
    return out;
  }
  for (const auto& r : s.summary.at("runs"))
    if (r.value("status", "ok") == "ok")  // (failed runs the stage went on without are left out)
      out.emplace_back(s.dir / r.at("folder").get<std::string>() / "result.h5",
                       std::to_string(r.at("replicate").get<int>()));
  return out;
}

// Largest value of a key over a lab stage's runs (or its own summary).
double labMax(const StageResult& s, const std::string& key) {
  double m = 0.0;
  if (s.summary.contains(key) && s.summary.at(key).is_number()) m = s.summary.at(key).get<double>();
  if (s.summary.contains("runs"))
    for (const auto& r : labResults(s)) {
      const fs::path sum = r.first.parent_path() / "summary.json";
      if (!fs::exists(sum)) continue;
      const json j = loadJson(sum);
      if (j.contains(key) && j.at(key).is_number()) m = std::max(m, j.at(key).get<double>());
    }
  return m;
}

// A bound pair [f_lo x, f_hi x] around a scale x read from the data.
json around(double x, double lo, double hi) {
  return json::array({lo * x, hi * x});
}

// The fit case from the four tests' result files: every law fitted, bounds
// spanning decades around the scales the tests measured, the lock-up from the
// cell's porosity.
json fitCase(const PipelineCase& c, const std::map<std::string, StageResult>& lab, const std::vector<StageResult>& rate,
             const std::vector<StageResult>& joint, double edge_m, double mass_kg, double porosity) {
  auto curves = [&](const std::string& test, bool cyclic) {
    json list = json::array();
    for (const auto& [file, label] : labResults(lab.at(test))) {
      json e = {{"file", fs::absolute(file).string()}, {"replicate", label}};
      if (cyclic) e["path"] = "cyclic";
      list.push_back(e);
    }
    return list;
  };
  const StageResult& cc = lab.at("cc");
  const double f_cc = std::max(labMax(cc, "peak_force_N"), 1.0);
  const double k_cc = std::max(f_cc / (0.15 * edge_m), 1.0);  // a secant over the test's strain
  const StageResult& uci = lab.at("uci");
  const double f_imp = std::max(labMax(uci, "peak_force_N"), 1.0);
  const double pen = std::max(labMax(uci, "max_penetration_m"), 1e-3);
  const double k_imp = f_imp / pen;
  const StageResult& sh = lab.at("shear");
  const double kt = std::max(labMax(sh, "tangential_stiffness_N_m"), 1.0);
  json lockup = porosity > 0.3 ? json{{"porosity", porosity}, {"densest_porosity", 0.25}}
                               : json{{"strain", bridge::kDefaultLockupStrain}};
  json out = {{"format", "gabion.case/1"},
              {"kind", "fit"},
              {"description", "generated by the pipeline from its virtual lab tests"},
              {"seed", c.seed},
              {"material", {{"name", c.material}, {"edge_m", edge_m}, {"mass_kg", mass_kg}}},
              {"lockup", lockup},
              {"axial",
               {{"curves", curves("cc", true)},
                {"bounds",
                 {{"stiffness_N_m", around(k_cc, 0.01, 100.0)},
                  {"yield_force_N", around(f_cc, 0.001, 2.0)},
                  {"hardening_stiffness_N_m", around(k_cc, 0.0, 20.0)}}}}},
              {"lateral", {{"curves", curves("cc", true)}, {"bounds", {{"reaction_coefficient", {0.0, 3.0}}}}}},
              {"interface",
               {{"curves", curves("shear", false)},
                {"bounds", {{"friction", {0.01, 2.0}}, {"tangential_stiffness_N_m", around(kt, 0.01, 100.0)}}}}},
              {"impact",
               {{"curves", curves("uci", true)},
                {"bounds",
                 {{"stiffness_N_m", around(k_imp, 0.1, 100.0)},
                  {"yield_force_N", around(f_imp, 0.001, 2.0)},
                  {"hardening_stiffness_N_m", around(k_imp, 0.0, 50.0)}}}}}};
  // The compressions at other plate speeds: the axial law's momentum flux
  // (docs/fitting.md), each run's curve with its time axis.
  if (!rate.empty()) {
    json list = json::array();
    for (const StageResult& r : rate)
      for (const auto& [file, label] : labResults(r)) list.push_back({{"file", fs::absolute(file).string()}});
    out["axial"]["rate_curves"] = list;
  }
  // The compressions along x of one cell and of a row: the joint law
  // (docs/fitting.md), from the first replicate's pair.
  if (joint.size() == 2) {
    const auto first = [](const StageResult& st) {
      const auto files = labResults(st);
      return files.empty() ? json() : json{{"file", fs::absolute(files.front().first).string()}, {"path", "cyclic"}};
    };
    out["joint"] = {{"cell", first(joint[0])}, {"row", first(joint[1])}, {"cells_in_series", c.joint_cells_in_series}};
  }
  return out;
}

std::string base64(const std::string& bytes) {
  static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) | (static_cast<unsigned char>(bytes[i + 1]) << 8) |
                       static_cast<unsigned char>(bytes[i + 2]);
    out += {t[(v >> 18) & 63], t[(v >> 12) & 63], t[(v >> 6) & 63], t[v & 63]};
  }
  if (i + 1 == bytes.size()) {
    const unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
    out += {t[(v >> 18) & 63], t[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == bytes.size()) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) | (static_cast<unsigned char>(bytes[i + 1]) << 8);
    out += {t[(v >> 18) & 63], t[(v >> 12) & 63], t[(v >> 6) & 63], '='};
  }
  return out;
}

std::string html(const std::string& s) {
  std::string o;
  for (char ch : s) o += ch == '<' ? "&lt;" : ch == '>' ? "&gt;" : ch == '&' ? "&amp;" : std::string(1, ch);
  return o;
}

// Once the page has loaded, the body records how many figures it has, how
// many did not load and how many are blank (under 0.5 % of their pixels
// other than white): what a person would see, for the headless-browser test
// and for anyone who opens the page's source.
constexpr const char* kImageCheck = R"(<script>
window.addEventListener('load', () => {
  let broken = 0, blank = 0;
  for (const img of document.images) {
    if (!img.complete || img.naturalWidth === 0) { ++broken; continue; }
    const c = document.createElement('canvas');
    c.width = 200; c.height = Math.max(1, Math.round(200 * img.naturalHeight / img.naturalWidth));
    const g = c.getContext('2d');
    g.drawImage(img, 0, 0, c.width, c.height);
    const d = g.getImageData(0, 0, c.width, c.height).data;
    let ink = 0;
    for (let i = 0; i < d.length; i += 4) if (d[i] < 240 || d[i + 1] < 240 || d[i + 2] < 240) ++ink;
    if (ink < 0.005 * c.width * c.height) ++blank;
  }
  document.body.dataset.images = document.images.length;
  document.body.dataset.brokenImages = broken;
  document.body.dataset.blankImages = blank;
});
</script>
)";

/// The report: one self-contained HTML file (figures embedded), the figures
/// also copied into OUT/figures/.
class Report {
 public:
  explicit Report(fs::path out) : out_(std::move(out)) { fs::create_directories(out_ / "figures"); }
  void heading(const std::string& h) { body_ << "<h2>" << html(h) << "</h2>\n"; }
  void text(const std::string& t) { body_ << "<p>" << t << "</p>\n"; }
  void warning(const std::string& w) {
    warnings_.push_back(w);
    body_ << "<p class=\"warn\">&#9888; " << html(w) << "</p>\n";
  }
  void table(const std::vector<std::string>& head, const std::vector<std::vector<std::string>>& rows) {
    body_ << "<table><tr>";
    for (const auto& h : head) body_ << "<th>" << html(h) << "</th>";
    body_ << "</tr>\n";
    for (const auto& r : rows) {
      body_ << "<tr>";
      for (const auto& c : r) body_ << "<td>" << html(c) << "</td>";
      body_ << "</tr>\n";
    }
    body_ << "</table>\n";
  }
  /// Embeds a PNG (and copies it to figures/ under `name`); a missing file is a warning.
  void figure(const fs::path& png, const std::string& name, const std::string& caption) {
    if (!fs::exists(png)) {
      warning("figure missing: " + png.string());
      return;
    }
    fs::copy_file(png, out_ / "figures" / name, fs::copy_options::overwrite_existing);
    std::ifstream in(png, std::ios::binary);
    std::ostringstream bytes;
    bytes << in.rdbuf();
    body_ << "<figure><img alt=\"" << html(caption) << "\" src=\"data:image/png;base64," << base64(bytes.str())
          << "\"><figcaption>" << html(caption) << " (<code>figures/" << html(name)
          << "</code>)</figcaption></figure>\n";
    figures_.push_back("figures/" + name);
  }
  const std::vector<std::string>& figures() const { return figures_; }
  const std::vector<std::string>& warnings() const { return warnings_; }
  void write(const std::string& title) const {
    std::ostringstream doc;
    doc << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" << html(title)
        << "</title>\n<style>body{font-family:sans-serif;max-width:60em;margin:2em auto;line-height:1.4}"
           "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:0.2em 0.6em;"
           "text-align:right}th{background:#eee}img{max-width:100%}figure{margin:1.5em 0}"
           ".warn{color:#a40;font-weight:bold}code{background:#f4f4f4}</style></head>\n<body>\n<h1>"
        << html(title) << "</h1>\n"
        << body_.str() << kImageCheck << "</body></html>\n";
    bridge::writeTextAtomic(out_ / "report.html", doc.str());
  }

 private:
  fs::path out_;
  std::ostringstream body_;
  std::vector<std::string> figures_, warnings_;
};

// A parameter's unit and value as the report and the console show them.
std::string unitOf(const std::string& name) {
  return bridge::displayUnit(name).unit;
}
double inUnit(const std::string& name, double v) {
  return bridge::displayUnit(name).scale * v;
}

// A sub-case's file references made absolute (its copy runs in another folder).
json absolutePaths(json v, const fs::path& from) {
  for (const char* key : {"law_file", "impacts_csv"})
    if (v.contains(key) && v[key].is_string())
      v[key] = fs::absolute(from.parent_path() / v[key].get<std::string>()).string();
  return v;
}

// A number of a summary, or NaN.
double num(const json& j, const std::string& key) {
  return j.contains(key) && j.at(key).is_number() ? j.at(key).get<double>() : std::nan("");
}

bridge::RunOutcome runStages(const JsonDocument& doc, const bridge::RunContext& ctx) {
  const PipelineCase c = readPipeline(doc);
  const auto t_start = std::chrono::steady_clock::now();
  std::vector<StageResult> stages;
  const auto settingsOf = [&](const std::string& stage) {
    const auto it = c.settings.find(stage);
    return it == c.settings.end() ? std::vector<std::string>{} : it->second;
  };
  const fs::path out = ctx.outdir;
  StageClock clock;
  clock.total = (c.cell_is_file ? 0 : c.replicates) + static_cast<int>(kTests.size()) +
                static_cast<int>(c.cc_rate_velocities_m_s.size()) + (c.joint_cells_in_series > 0 ? 2 : 0) + 1 +
                static_cast<int>(c.velocities_m_s.size()) + (c.sweep_case ? 1 : 0) + (c.capacity_case ? 1 : 0) +
                (c.design_case ? 1 : 0);

  // 1. The cell(s): generated from the micro.cell case (consecutive seeds for
  //    replicates), or the cell file given.
  std::vector<fs::path> cells;
  std::vector<StageResult> cell_stages;  // (one per replicate; none for a cell file)
  double edge_m = 0.0, porosity = 0.0;
  json cell_summary;
  if (c.cell_is_file) {
    cells.push_back(fs::absolute(c.cell));
    edge_m = c.cell_edge_m;
    const bridge::H5Reader h5(c.cell);  // the micro.cell run's summary, kept in the cell file
    cell_summary = json::parse(h5.attribute("/", "summary"));
    porosity = num(cell_summary, "porosity");
  } else {
    const json cell_case = absolutePaths(loadJson(c.cell), c.cell);
    edge_m = cell_case.value("edge_m", 0.5);
    for (int k = 0; k < c.replicates; ++k) {
      json one = cell_case;
      one["seed"] = c.seed + static_cast<unsigned long>(k);
      const std::string name = c.replicates > 1 ? "1_cell_seed" + std::to_string(c.seed + k) : "1_cell";
      stages.push_back(runStage("cell" + (c.replicates > 1 ? " (seed " + std::to_string(c.seed + k) + ")" : ""),
                                "micro.cell", one, {}, settingsOf("cell"), ctx, out / name, clock));
      cell_stages.push_back(stages.back());
      cells.push_back(fs::absolute(out / name / "cell.h5"));
      if (k == 0) cell_summary = stages.back().summary;
    }
    porosity = num(cell_summary, "porosity");
  }

  // 2. The virtual lab tests on the cell(s).
  std::map<std::string, StageResult> lab;
  std::map<std::string, json> test_cases;
  json cc_loading = json::object();  // the CC stage's loading, as it will run
  for (const auto& t : kTests) {
    json tc = absolutePaths(loadJson(c.tests.at(t)), c.tests.at(t));
    if (cells.size() == 1) {
      tc["cell"] = cells.front().string();
    } else {
      tc["cell"] = json::array();
      for (const auto& f : cells) tc["cell"].push_back(f.string());
    }
    tc.erase("replicates");
    if (t == "uci") {
      tc.erase("velocity_m_s");
      tc["velocities_m_s"] = c.uci_velocities_m_s;
    }
    test_cases[t] = tc;
    // What it will cost, for the ETA: nothing when it will be reused.
    const fs::path dir = out / ("2_" + t);
    const StagedCase staged = stageCase(tc, cells, settingsOf(t), dir, std::nullopt);
    if (t == "cc") cc_loading = staged.value.value("loading", json::object());
    if (reusable(dir, staged.key)) continue;
    if (const auto e = findKind(kTestKind.at(t))->estimate(JsonDocument(staged.value, (dir / "case.json").string())))
      clock.estimated[t] = clock.pending[t] = e->body_steps;
  }
  // A CC stage beyond the quasi-static one (at another plate speed, or
  // along x for the joint): its name, its case and its folder.
  struct ExtraCc {
    std::string name;
    json value;
    fs::path dir;
  };
  // The confined compression again at faster plate speeds, where asked
  // (the axial law's momentum flux): to the CC stage's strain, without
  // unloading, the netting's real mass (the fill's inertia is what they
  // measure).
  std::vector<ExtraCc> rate_cases;
  for (double v : c.cc_rate_velocities_m_s) {
    json tc = test_cases.at("cc");
    tc["loading"] = cc_loading;  // (its strain, or the default where it gives none)
    tc["loading"]["velocity_m_s"] = v;
    tc["loading"]["unload_at_strain"] = json::array();
    tc["netting_mass_scale"] = 1;
    tc["description"] = "The CC test at " + fmt(v) + " m/s: the axial law's momentum flux (pipeline)";
    const std::string name = "cc at " + fmt(v) + " m/s";
    const fs::path dir = out / ("2_cc_rate_" + fmt(v) + "_m_s");
    rate_cases.push_back({name, tc, dir});
    const StagedCase staged = stageCase(tc, cells, {}, dir, std::nullopt);
    if (reusable(dir, staged.key)) continue;
    if (const auto e = findKind("micro.cc")->estimate(JsonDocument(staged.value, (dir / "case.json").string())))
      clock.estimated[name] = clock.pending[name] = e->body_steps;
  }
  // Where a joint is asked for: the confined compression along x of one
  // cell and of a row of them, to the joint's strain, without unloading.
  std::vector<ExtraCc> joint_cases;
  if (c.joint_cells_in_series > 0)
    for (const int n : {1, c.joint_cells_in_series}) {
      json tc = test_cases.at("cc");
      tc["loading"] = cc_loading;
      tc["loading"]["axis"] = "x";
      tc["loading"]["cells_in_series"] = n;
      tc["loading"]["strain"] = c.joint_strain;
      tc["loading"]["unload_at_strain"] = json::array();
      tc["description"] =
          n == 1 ? std::string("The CC test along x of one cell: the joint law (pipeline)")
                 : "The CC test along x of a row of " + std::to_string(n) + " cells: the joint law (pipeline)";
      const std::string name = n == 1 ? "cc along x" : "cc along x, " + std::to_string(n) + " cells";
      const fs::path dir = out / (n == 1 ? "2_cc_x" : "2_cc_x_row");
      joint_cases.push_back({name, tc, dir});
      const StagedCase staged = stageCase(tc, cells, {}, dir, std::nullopt);
      if (reusable(dir, staged.key)) continue;
      if (const auto e = findKind("micro.cc")->estimate(JsonDocument(staged.value, (dir / "case.json").string())))
        clock.estimated[name] = clock.pending[name] = e->body_steps;
    }
  for (const auto& t : kTests) {
    stages.push_back(runStage(t, kTestKind.at(t), test_cases.at(t), cells, settingsOf(t), ctx, out / ("2_" + t), clock,
                              std::nullopt, cells.size() > 1 ? FailedRuns::LeaveOut : FailedRuns::Stop));
    lab[t] = stages.back();
  }
  std::vector<StageResult> rate, joint;
  for (const ExtraCc& r : rate_cases) {
    stages.push_back(runStage(r.name, "micro.cc", r.value, cells, {}, ctx, r.dir, clock, std::nullopt,
                              cells.size() > 1 ? FailedRuns::LeaveOut : FailedRuns::Stop));
    rate.push_back(stages.back());
  }
  for (const ExtraCc& r : joint_cases) {
    stages.push_back(runStage(r.name, "micro.cc", r.value, cells, {}, ctx, r.dir, clock, std::nullopt,
                              cells.size() > 1 ? FailedRuns::LeaveOut : FailedRuns::Stop));
    joint.push_back(stages.back());
  }
  double mass_kg = num(cell_summary, "mass_kg");
  if (!(mass_kg > 0.0)) mass_kg = num(lab.at("cc").summary, "mass_kg");

  // 3. Every law fitted from the tests' curves.
  std::vector<fs::path> curve_files;
  for (const auto& [t, st] : lab)
    for (const auto& r : labResults(st)) curve_files.push_back(r.first);
  for (const StageResult& st : rate)
    for (const auto& r : labResults(st)) curve_files.push_back(r.first);
  for (const StageResult& st : joint)
    for (const auto& r : labResults(st)) curve_files.push_back(r.first);
  stages.push_back(runStage("fit", "fit", fitCase(c, lab, rate, joint, edge_m, mass_kg, porosity), curve_files,
                            settingsOf("fit"), ctx, out / "3_fit", clock));
  const StageResult fit = stages.back();

  // The structure's law file with the calibrated material replaced.
  const fs::path structure_law =
      relative(JsonDocument::load(c.structure_case), loadJson(c.structure_case).at("law_file"));
  bridge::LawFile laws = bridge::loadLawFile(structure_law);
  const bridge::LawFile fitted = bridge::loadLawFile(out / "3_fit" / "law.json");
  if (laws.materials.count(c.material) == 0)
    throw bridge::InputError(doc.file(), "/structure/material",
                             "no material '" + c.material + "' in " + structure_law.string());
  laws.materials[c.material] = fitted.materials.at(c.material);
  json law_json = bridge::toJson(laws);
  law_json["description"] = "Structure laws: material '" + c.material +
                            "' calibrated by the pipeline (see its provenance); the others as in " +
                            structure_law.string();
  bridge::writeJsonAtomic(out / "law.json", law_json);
  const fs::path law = fs::absolute(out / "law.json");

  // 4. The structure at several energies, its capacity and its design.
  std::vector<StageResult> impacts;
  const json structure_case = absolutePaths(loadJson(c.structure_case), c.structure_case);
  for (double v : c.velocities_m_s) {
    json sc = structure_case;
    sc["boulder"]["velocity_m_s"] = v;
    sc.erase("impacts");
    const std::string name = "4_impact_" + fmt(v) + "_m_s";
    stages.push_back(runStage("impact at " + fmt(v) + " m/s", "macro.impact", sc, {}, settingsOf("impact"), ctx,
                              out / name, clock, law));
    impacts.push_back(stages.back());
  }
  std::optional<StageResult> sweep, capacity, design;
  if (c.sweep_case) {
    stages.push_back(runStage("sweep", "macro.sweep", absolutePaths(loadJson(*c.sweep_case), *c.sweep_case), {},
                              settingsOf("sweep"), ctx, out / "4_sweep", clock, law));
    sweep = stages.back();
  }
  if (c.capacity_case) {
    stages.push_back(runStage("capacity", "macro.capacity", absolutePaths(loadJson(*c.capacity_case), *c.capacity_case),
                              {}, settingsOf("capacity"), ctx, out / "5_capacity", clock, law));
    capacity = stages.back();
  }
  if (c.design_case) {
    stages.push_back(runStage("design", "macro.design", absolutePaths(loadJson(*c.design_case), *c.design_case), {},
                              settingsOf("design"), ctx, out / "6_design", clock, law));
    design = stages.back();
  }

  // 5. The report.
  Report rep(out);
  const json& fj = fit.summary.at("fit");
  rep.heading("Answer");
  std::ostringstream headline;
  if (capacity) headline << "Capacity of the wall: " << html(capacity->summary.at("answer").get<std::string>()) << ". ";
  if (design) headline << "Design: " << html(design->summary.at("answer").get<std::string>()) << ".";
  if (!headline.str().empty()) rep.text(headline.str());
  rep.text("Law file: <code>law.json</code> (material <code>" + html(c.material) + "</code> calibrated; status <b>" +
           html(fit.summary.at("law_status").get<std::string>()) + "</b>).");

  rep.heading("1. The virtual cell");
  {
    rep.text((cell_stages.size() > 1 ? "The first of " + std::to_string(cell_stages.size()) + " cells (seed " +
                                           std::to_string(c.seed) + "; each below): "
                                     : std::string()) +
             fmt(num(cell_summary, "blocks")) + " blocks, mass " + fmt(num(cell_summary, "mass_kg")) +
             " kg, porosity " + fmt(porosity, 3) + " (target " + fmt(num(cell_summary, "target_porosity"), 3) + "), " +
             fmt(edge_m) + " m cell.");
    if (c.cell_is_file) {
      rep.text("Cell file: <code>" + html(c.cell.string()) + "</code>.");
    } else if (cell_stages.size() == 1) {
      const fs::path& d = cell_stages.front().dir;
      rep.figure(d / "cell_view.png", "cell_view.png", "The generated cell: its blocks and netting");
      rep.figure(d / "grading_0.png", "grading.png", "Grading of the blocks against its target");
      rep.figure(d / "vibration.png", "vibration.png", "Porosity during filling and vibration");
    } else {
      // Replicates: a row and a view per cell (how far they are apart is
      // what the laws' scatter between cells comes from), then the first
      // cell's grading and vibration.
      std::vector<std::vector<std::string>> cell_rows;
      for (std::size_t k = 0; k < cell_stages.size(); ++k) {
        const json& cs = cell_stages[k].summary;
        const std::string seed = std::to_string(c.seed + k);
        cell_rows.push_back({seed, fmt(num(cs, "blocks")), fmt(num(cs, "mass_kg")), fmt(num(cs, "porosity"), 3),
                             cs.contains("closing") ? fmt(num(cs.at("closing"), "levelled_blocks")) : "-"});
      }
      rep.table({"seed", "blocks", "mass (kg)", "porosity", "blocks taken off at closing"}, cell_rows);
      for (std::size_t k = 0; k < cell_stages.size(); ++k) {
        const std::string seed = std::to_string(c.seed + k);
        rep.figure(cell_stages[k].dir / "cell_view.png", "cell_view_seed" + seed + ".png",
                   "The cell of seed " + seed + ": its blocks and netting");
      }
      const fs::path& d = cell_stages.front().dir;
      rep.figure(d / "grading_0.png", "grading.png", "Grading of the blocks against its target (first cell)");
      rep.figure(d / "vibration.png", "vibration.png", "Porosity during filling and vibration (first cell)");
    }
  }

  rep.heading("2. Virtual lab tests");
  std::vector<std::vector<std::string>> rows;
  for (const auto& t : kTests) {
    const StageResult& st = lab.at(t);
    // (the shear test's peak is that of the push, across the interface)
    const char* peak = t == "shear" ? "peak_tangential_force_N" : "peak_force_N";
    rows.push_back({t, kTestKind.at(t), fmt(labMax(st, peak) / 1e3), fmt(labMax(st, "kinetic_to_work_ratio"), 3),
                    st.reused ? "reused" : "run", fmt(st.wall_time_s, 3)});
    const json& s = st.summary;
    if (s.contains("quasi_static") && s.at("quasi_static").is_boolean() && !s.at("quasi_static").get<bool>())
      rep.warning(t + ": the test left its quasi-static range (kinetic energy over work above the limit)");
  }
  // (the compressions at other plate speeds are dynamic on purpose: no warning)
  // Runs a stage went on without (replicate cells: the fit has the others').
  json dropped_runs = json::array();
  const auto noteDropped = [&](const std::string& stage, const StageResult& st) {
    const std::size_t n = st.summary.contains("runs") ? st.summary.at("runs").size() : 0;
    for (const auto& d : st.dropped_runs) {
      dropped_runs.push_back({{"stage", stage},
                              {"folder", (st.dir / d.at("folder").get<std::string>()).string()},
                              {"message", d.at("message")}});
      rep.warning(stage + ": run " + d.at("folder").get<std::string>() + " failed (" +
                  d.at("message").get<std::string>() + "); the fit has the other " +
                  std::to_string(n - st.dropped_runs.size()) + " of its " + std::to_string(n) + " runs");
    }
  };
  for (const auto& t : kTests) noteDropped(t, lab.at(t));
  for (const StageResult& st : rate) noteDropped(st.name, st);
  for (const StageResult& st : rate)
    rows.push_back({st.name, "micro.cc", fmt(labMax(st, "peak_force_N") / 1e3),
                    fmt(labMax(st, "kinetic_to_work_ratio"), 3), st.reused ? "reused" : "run", fmt(st.wall_time_s, 3)});
  rep.table({"test", "kind", "peak force (kN; shear: tangential)", "kinetic / work", "stage", "wall time (s)"}, rows);
  // Each run's figure from its own folder (labResults: the test's runs, one
  // per cell); with replicates, named by its cell's seed.
  const auto labFigure = [&](const std::string& test, const std::string& png, const std::string& caption) {
    for (const auto& [result, replicate] : labResults(lab.at(test))) {
      if (cells.size() == 1) {
        rep.figure(result.parent_path() / png, png, caption);
        continue;
      }
      const std::string seed = std::to_string(c.seed + std::stoul(replicate));
      rep.figure(result.parent_path() / png, png.substr(0, png.size() - 4) + "_seed" + seed + ".png",
                 caption + " (cell of seed " + seed + ")");
    }
  };
  labFigure("cc", "cc_curve.png", "CC: axial force against shortening");
  labFigure("uc", "uc_curve.png", "UC: axial force against shortening");
  labFigure("shear", "shear_curve.png", "Interface shear");

  rep.heading("3. Fitted cell laws");
  rows.clear();
  for (const char* law_name : {"axial", "momentum_flux", "lateral", "interface", "impact"}) {
    if (!fj.contains(law_name)) continue;  // (the momentum flux only where its compressions ran)
    const json& l = fj.at(law_name);
    for (const auto& [pname, p] : l.at("parameters").items()) {
      const double v = p.at("value").get<double>();
      const json& iv = fitting::reportedInterval(p);
      const std::string interval =
          iv.is_null() ? "-"
                       : fmt(inUnit(pname, iv[0].get<double>())) + " to " + fmt(inUnit(pname, iv[1].get<double>()));
      std::vector<std::string> row = {
          law_name, l.at("model").get<std::string>(), pname, unitOf(pname), fmt(inUnit(pname, v)), interval};
      if (c.replicates > 1) {  // the scatter between the cells: the replicate mean's interval
        const json& rv = p.contains("replicate_mean_95") ? p.at("replicate_mean_95") : json();
        row.push_back(rv.is_null()
                          ? "-"
                          : fmt(inUnit(pname, rv[0].get<double>())) + " to " + fmt(inUnit(pname, rv[1].get<double>())));
      }
      rows.push_back(row);
    }
    const double nrms = l.at("nrms").get<double>();
    if (nrms > fitting::kPoorFitNrms)
      rep.warning(std::string(law_name) + " law: a poor fit (normalised RMS error " + fmt(nrms, 3) + " > " +
                  fmt(fitting::kPoorFitNrms) + ")");
  }
  std::vector<std::string> columns = {"law", "model", "parameter", "unit", "value", "95 % interval"};
  if (c.replicates > 1) columns.push_back("95 % interval of the mean over " + std::to_string(c.replicates) + " cells");
  rep.table(columns, rows);
  for (const char* law_name : {"axial", "lateral", "interface", "impact"})
    rep.figure(out / "3_fit" / ("fit_" + std::string(law_name) + ".png"), "fit_" + std::string(law_name) + ".png",
               std::string("Data and fitted ") + law_name + " law");
  if (fj.contains("momentum_flux"))
    rep.figure(out / "3_fit" / "fit_momentum_flux.png", "fit_momentum_flux.png",
               "The axial law's momentum flux: CC at other plate speeds");
  if (fj.contains("joint")) {
    rep.text("The joint between two cells (CC along x of one cell and of a row of " +
             std::to_string(c.joint_cells_in_series) +
             "; docs/fitting.md): " + html(fitting::describeJointFit(fj.at("joint"))) +
             ". A hybrid's resolve.joint \"law\" carries it at its interface plates (docs/resolved.md).");
    rep.figure(out / "3_fit" / "fit_joint.png", "fit_joint.png", "The joint between two cells: closure against force");
  }

  rep.heading("4. The structure");
  rows.clear();
  bridge::PlotSpec force_plot;
  force_plot.title = "Boulder force against time (cf. the paper's Fig. 13)";
  force_plot.x_label = "time (ms)";
  force_plot.y_label = "force on the boulder (kN)";
  json impact_rows = json::array();
  for (std::size_t i = 0; i < impacts.size(); ++i) {
    const json& s = impacts[i].summary;
    rows.push_back({fmt(c.velocities_m_s[i]), fmt(num(s, "input_energy_J") / 1e3), s.at("outcome").get<std::string>(),
                    fmt(num(s, "peak_force_N") / 1e3), fmt(num(s, "max_penetration_m") * 1e3),
                    fmt(num(s, "max_back_face_displacement_m") * 1e3), fmt(num(s, "contact_duration_s") * 1e3),
                    fmt(num(s, "balance_rel_error"), 2)});
    json row = {{"velocity_m_s", c.velocities_m_s[i]}, {"folder", impacts[i].dir.filename().string()}};
    for (const char* key : {"outcome", "input_energy_J", "peak_force_N", "max_penetration_m",
                            "max_back_face_displacement_m", "contact_duration_s", "balance_rel_error"})
      row[key] = s.at(key);
    impact_rows.push_back(row);
    const bridge::H5Reader h5(impacts[i].dir / "result.h5");
    const double until = 2.0 * num(s, "contact_duration_s");
    std::vector<double> t = h5.read("/series/time_s"), f = h5.read("/series/boulder_force_N");
    std::size_t keep = 0;
    while (keep < t.size() && t[keep] <= until) ++keep;
    t.resize(keep), f.resize(keep);
    for (auto& x : t) x *= 1e3;
    for (auto& x : f) x /= 1e3;
    force_plot.series.push_back({fmt(c.velocities_m_s[i]) + " m/s", t, f, bridge::PlotSeries::Style::Line});
  }
  rep.table({"velocity (m/s)", "energy (kJ)", "outcome", "peak force (kN)", "penetration (mm)", "back face (mm)",
             "contact (ms)", "balance error"},
            rows);
  bridge::writePlotPng(out / "impact_force_time.png", force_plot);
  rep.figure(out / "impact_force_time.png", "impact_force_time.png", "Boulder force against time");
  if (sweep) {
    const json& o = sweep->summary.at("outcomes");
    std::ostringstream t;
    t << "<b>Design charts.</b> A sweep of " << sweep->summary.at("points").get<long long>() << " impacts (";
    bool first = true;
    for (const auto& [outcome, count] : o.items()) {
      t << (first ? "" : ", ") << count.get<long long>() << " " << html(outcome);
      first = false;
    }
    t << "), <code>4_sweep/sweep.csv</code>; perforated impacts are marked, and the sweep's limits drawn.";
    rep.text(t.str());
    for (const char* chart : {"chart_peak_force.png", "chart_penetration.png", "chart_back_face.png"})
      if (fs::exists(out / "4_sweep" / chart))
        rep.figure(out / "4_sweep" / chart, std::string("sweep_") + chart,
                   std::string(chart) == "chart_peak_force.png"    ? "Peak force against impact energy"
                   : std::string(chart) == "chart_penetration.png" ? "Penetration against impact energy"
                                                                   : "Back-face displacement against impact energy");
  }
  if (capacity) {
    rep.text("<b>Capacity.</b> " + html(capacity->summary.at("answer").get<std::string>()) + ".");
    rep.figure(out / "5_capacity" / "capacity.png", "capacity.png", "Capacity search: the impacts run");
  }
  if (design) {
    rep.text("<b>Design.</b> " + html(design->summary.at("answer").get<std::string>()) + ".");
    rep.figure(out / "6_design" / "capacity_vs_thickness.png", "capacity_vs_thickness.png",
               "Capacity against thickness");
  }

  rep.heading("5. Stages");
  rows.clear();
  for (const auto& st : stages)
    rows.push_back({st.name, st.dir.filename().string(), st.reused ? "reused" : "run", fmt(st.wall_time_s, 3)});
  rep.table({"stage", "folder", "", "wall time (s)"}, rows);
  rep.write("Gabion calibration pipeline: " + doc.file());

  // Summary and console.
  bridge::RunOutcome result;
  json& res = result.results;
  json stage_list = json::array();
  int reused = 0;
  for (const auto& st : stages) {
    stage_list.push_back({{"name", st.name},
                          {"folder", st.dir.filename().string()},
                          {"reused", st.reused},
                          {"wall_time_s", st.wall_time_s}});
    if (clock.estimated.count(st.name)) stage_list.back()["estimated_body_steps"] = clock.estimated.at(st.name);
    reused += st.reused ? 1 : 0;
  }
  res["stages"] = stage_list;
  res["stages_reused"] = reused;
  res["cell"] = {{"edge_m", edge_m},
                 {"mass_kg", mass_kg},
                 {"porosity", porosity > 0.0 ? json(porosity) : json(nullptr)},
                 {"files", json::array()}};
  for (const auto& f : cells) res["cell"]["files"].push_back(f.string());
  res["fit"] = fj;
  res["law_status"] = fit.summary.at("law_status");
  res["law_file"] = "law.json";
  res["impacts"] = impact_rows;
  if (capacity)
    res["capacity"] = {{"answer", capacity->summary.at("answer")},
                       {"capacity_energy_J", capacity->summary.at("capacity_energy_J")}};
  if (design) res["design"] = {{"answer", design->summary.at("answer")}, {"design", design->summary.at("design")}};
  res["report"] = "report.html";
  res["figures"] = rep.figures();
  res["warnings"] = rep.warnings();
  res["dropped_runs"] = dropped_runs;
  res["pipeline_wall_time_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();

  std::ostringstream console;
  console << "pipeline: fitted laws of '" << c.material << "' (95 % intervals):\n";
  for (const char* law_name : {"axial", "momentum_flux", "lateral", "interface", "impact"})
    if (fj.contains(law_name)) console << "  " << fitting::describeFit(law_name, fj.at(law_name)) << "\n";
  if (fj.contains("joint")) console << "  " << fitting::describeJointFit(fj.at("joint")) << "\n";
  if (capacity) console << "pipeline: capacity: " << capacity->summary.at("answer").get<std::string>() << "\n";
  if (design) console << "pipeline: design: " << design->summary.at("answer").get<std::string>() << "\n";
  for (const auto& w : rep.warnings()) console << "pipeline: warning: " << w << "\n";
  if (!c.cell_is_file && c.replicates == 1)
    console << "pipeline: note: the laws are those of one cell, one draw of its packing; another can give others "
               "(docs/pipeline.md, One cell is one draw): replicates > 1 fits them on several\n";
  console << "pipeline: report: " << (out / "report.html").string() << " (" << stages.size() << " stages, " << reused
          << " reused)\n";
  result.answer = console.str();
  return result;
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

// Every referenced case must be valid on its own (as its stage will read it,
// the cell given), before anything runs.
void checkPipeline(const JsonDocument& doc) {
  const PipelineCase c = readPipeline(doc);
  const auto check = [&](const fs::path& file, const std::string& kind, const std::string& pointer) {
    if (!fs::exists(file)) throw bridge::InputError(doc.file(), pointer, file.string() + ": file does not exist");
    JsonDocument sub = JsonDocument::load(file);
    checkCase(sub, kind);
  };
  if (c.cell_is_file) {
    if (!fs::exists(c.cell)) throw bridge::InputError(doc.file(), "/cell", c.cell.string() + ": file does not exist");
  } else {
    check(c.cell, "micro.cell", "/cell");
  }
  for (const auto& t : kTests) {
    // (the test's own cell is replaced by the pipeline's: check it with that cell when it is a file)
    const fs::path file = c.tests.at(t);
    if (!fs::exists(file)) throw bridge::InputError(doc.file(), "/lab/" + t, file.string() + ": file does not exist");
    JsonDocument sub = JsonDocument::load(file);
    const json cell = c.cell_is_file ? json(fs::absolute(c.cell).string())
                                     : json{{"case", fs::absolute(c.cell).string()}, {"seed", c.seed}};
    sub.applySet("cell=" + cell.dump());
    sub.applySet("replicates=1");
    checkCase(sub, kTestKind.at(t));
  }
  check(c.structure_case, "macro.impact", "/structure/case");
  const json sc = loadJson(c.structure_case);
  if (!sc.contains("law_file"))
    throw bridge::InputError(c.structure_case.string(), "/law_file",
                             "the pipeline needs a structure case with a law_file");
  const auto laws = bridge::loadLawFile(relative(JsonDocument::load(c.structure_case), sc.at("law_file")));
  if (laws.materials.count(c.material) == 0)
    throw bridge::InputError(doc.file(), "/structure/material",
                             "no material '" + c.material + "' in the structure's law file");
  if (c.sweep_case) check(*c.sweep_case, "macro.sweep", "/sweep");
  if (c.capacity_case) check(*c.capacity_case, "macro.capacity", "/capacity");
  if (c.design_case) check(*c.design_case, "macro.design", "/design");
}

// The cell stages, and the lab tests when the cell is a file; the lab
// tests on a cell yet to be generated, and the structure stages (seconds
// beside the micro ones), are not costed before the run: partial. While it
// runs, the pipeline's ETA costs each test as soon as its cell exists.
std::optional<bridge::Estimate> estimatePipeline(const JsonDocument& doc) {
  const PipelineCase c = readPipeline(doc);
  bridge::Estimate e;
  e.partial = true;
  if (c.cell_is_file) {
    for (const auto& t : kTests) {
      JsonDocument sub = JsonDocument::load(c.tests.at(t));
      sub.applySet("cell=" + json(fs::absolute(c.cell).string()).dump());
      sub.applySet("replicates=1");
      if (const auto one = findKind(kTestKind.at(t))->estimate(sub)) bridge::addRun(e, *one);
    }
    return e;
  }
  json cell_case = absolutePaths(loadJson(c.cell), c.cell);
  cell_case["seed"] = c.seed;
  if (const auto one = findKind("micro.cell")->estimate(JsonDocument(cell_case, c.cell.string())))
    bridge::addRun(e, bridge::times(*one, c.replicates));
  return e;
}

}  // namespace

bridge::CaseKind pipelineKind() {
  return {"pipeline",
          "the calibration chain: generate the cell, run CC, UC, UCI and shear on it, fit every law, run the wall "
          "with them (impacts, capacity, design), write report.html",
          checkPipeline, runPipeline, estimatePipeline};
}

}  // namespace gabion::app
