#pragma once
/// \file
/// What every virtual lab test of a cell shares (docs/lab.md): where its
/// cell comes from (a cell file, or a micro.cell case generated first), the
/// changes it makes to the cell's materials, the rig's plates, the netting's
/// mass scaling, replicates on cells of different seeds run in parallel
/// with their scatter, and the measures every test reports (how quasi-static
/// it stayed).
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "bridge/json_reader.hpp"
#include "bridge/run.hpp"
#include "micro/scene.hpp"

namespace gabion::micro::lab {

/// Where one replicate's cell comes from.
struct CellSource {
  std::filesystem::path file;         ///< a cell file (gabion.cell/2) to start from, or
  std::filesystem::path generate;     ///< a micro.cell case, generated first into OUTDIR/cell[_<seed>]
  std::optional<std::uint64_t> seed;  ///< the generated cell's seed (absent: the case's own)
  double edge_m = 0.0;                ///< the cell's edge as its case gives it (generated cells; for checks)
};

/// A change to one of the cell's materials (`"materials": {"rock": {...}}`):
/// the keys given replace the file's values.
struct MaterialChange {
  std::string name, pointer;
  std::optional<double> normal_stiffness_N_m, shear_stiffness_N_m, friction, normal_force_limit_N, local_damping,
      viscous_damping_ratio;
  void applyTo(Material& m) const;
};

/// Reads a material change: any of normal_stiffness_N_m, shear_stiffness_N_m,
/// friction, normal_force_limit_N, local_damping, viscous_damping_ratio.
MaterialChange parseMaterialChange(const std::string& name, const bridge::JsonReader& r);

/// The keys every lab test shares (docs/lab.md, Common keys).
struct LabSetup {
  std::string file;                     ///< the case file, for messages
  std::vector<CellSource> cells;        ///< one per replicate
  std::vector<MaterialChange> changes;  ///< to the cell's materials
  std::vector<ContactPairInput> pairs;  ///< laws for pairs of materials (the cell's and "plates")
  MaterialChange plates;                ///< to the rig's plates (by default the cell's formwork material, frictionless)
  double netting_mass_scale = 1.0;      ///< inertia scaling of the netting's nodes (>= 1)
  Vec3 gravity = Vec3(0, 0, -9.81);
  RunSpec run;
  bool duration_given = false;  ///< run.duration_s given (else the test sets it from its loading)
};

/// Reads "cell", "replicates", "materials", "contact_pairs", "plates", "netting_mass_scale",
/// "gravity_m_s2" and "run" (duration default_duration_s, series every
/// default_series_s, overlap check at 1 unless given).
LabSetup parseLabSetup(const bridge::JsonReader& root, double default_mass_scale, double default_duration_s,
                       double default_series_s);

/// One cell, ready for a test: its bodies, links and materials (with the
/// test's changes), the rig's plate material, and where its bodies reach.
struct Sample {
  Scene scene;  ///< the cell's bodies and links, the setup's gravity and run; no walls
  int plate_material = 0, rock_material = 0, netting_material = -1;
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();  ///< extent of every body, radii included (m)
  double mass_kg = 0.0;                       ///< blocks and free spheres
  std::size_t netting_nodes = 0;              ///< spheres of the netting (those links join)
  nlohmann::json cell_summary;                ///< what the run that made the cell reported
  std::filesystem::path cell_file;
};

/// Loads a cell file for a test. Errors (a missing, foreign or damaged file,
/// a material change naming a material the cell does not have) are
/// InputErrors naming the case file and field, or the cell file.
Sample loadSample(const std::filesystem::path& cell_file, const LabSetup& setup);

/// Adds a boulder's contact material to `scene` (the rock's, material
/// `rock_material`, at `density_kg_m3`, with `change`; no local damping: a
/// body force on the boulder would take momentum that no contact gave) and
/// returns a sphere of it, `diameter_m` wide, at rest at the origin.
SphereSpec boulderSphere(Scene& scene, int rock_material, double diameter_m, double density_kg_m3,
                         const MaterialChange& change);

/// Holds the step of `scene` below a tenth of its smallest radius per step
/// of a body at `speed_m_s` (sets run.dt_s where the chosen step is longer:
/// a boulder must not pass a netting node within a step). Returns whether
/// it had to.
bool limitStepToSpeed(Scene& scene, double speed_m_s, const std::string& file);

/// Checks what can be checked before anything runs: every cell file loads,
/// every cell case passes its own check. Returns the first cell's edge (m).
double checkCells(const LabSetup& setup);

/// Generates the cell of `source` into `dir` (micro.cell), unless `dir`
/// already holds the cell of the same case and seed. Returns its cell file.
/// Throws NumericalError when the generation failed.
std::filesystem::path generateCell(const CellSource& source, const std::filesystem::path& dir,
                                   const bridge::RunContext& ctx);

/// How far a test stayed from quasi-static: the largest ratio of the kinetic
/// energy to the work done on the sample, once that work exceeds a tenth of
/// its final value (before, both are at the scale of the cell's own rest).
class QuasiStatic {
 public:
  void add(double kinetic_J, double work_J) { kinetic_.push_back(kinetic_J), work_.push_back(work_J); }
  double ratio() const;

 private:
  std::vector<double> kinetic_, work_;
};

/// One run's scene as its test runs it (rig, loading, duration, and a step
/// where the test sets one), for the test's cost estimate.
using ScenePlan = std::function<Scene(const Sample&, std::size_t variant)>;

/// What a test costs (bridge::Estimate), from the first replicate's cell:
/// every variant's scene planned, its step chosen as the run chooses it,
/// its steps those of its whole duration (a test may stop sooner). nullopt
/// where the cell is generated by the test itself (not made yet).
/// `stages_keep_ends`: the variants are the stages of one run, each keeping
/// its end (SceneRunHooks::keep_end) until the run is over, so that their
/// checkpoints add up.
std::optional<bridge::Estimate> estimateReplicates(const LabSetup& setup, std::size_t variants, const ScenePlan& plan,
                                                   bool stages_keep_ends = false);

/// One run of a test: builds its scene from the sample for `variant` (e.g.
/// one impact velocity of several) and runs it into ctx.outdir.
using TestRun = std::function<bridge::RunOutcome(const Sample&, std::size_t variant, const bridge::RunContext&)>;

/// A test's runs, made from its case once: every variant (names, e.g.
/// "v20") on every replicate's cell. `test` owns the parsed case.
struct Replicates {
  LabSetup setup;
  std::string label;  ///< the case kind, e.g. "micro.uci"
  std::vector<std::string> variants;
  TestRun test;
  std::vector<std::string> scatter_keys;  ///< summary values whose scatter over the replicates is reported
};

/// Runs a test for every variant on every replicate's cell (cells from a
/// case are generated first, in parallel). One run goes into ctx.outdir;
/// several into ctx.outdir/<variant>[_replicate_<k>], in parallel (a thread
/// each, up to ctx.threads, or on ctx.workers: MPI ranks), each with its
/// summary.json, and the summary lists them with the mean, standard
/// deviation and range of each of `scatter_keys` over the replicates of
/// each variant.
bridge::RunOutcome runReplicates(const Replicates& r, const bridge::RunContext& ctx);

/// The replicates as rows (bridge/rows.hpp; CaseKind::rows): row k generates
/// replicate k's cell and runs every variant on it, into the folders a local
/// run uses, so that the rows, run anywhere and collected, give the local
/// run's summary. `estimate` (the test's; nullopt, or throwing, where its
/// cells are not made yet) costs a row, when a row's cost is first asked for.
std::shared_ptr<const bridge::RowPlan> replicateRows(std::shared_ptr<const Replicates> reps,
                                                     std::function<std::optional<bridge::Estimate>()> estimate);

/// On an MPI worker rank: generates a replicate's cell, or runs one of the
/// runs, as runReplicates does on a thread of its own (CaseKind::serve).
std::function<nlohmann::json(const nlohmann::json&)> serveReplicates(std::shared_ptr<const Replicates> r);

/// A lab test's case kind from its parts: its runs, made from the case by
/// `replicates`, run here (runReplicates), on MPI ranks (serveReplicates)
/// or as rows (replicateRows).
bridge::CaseKind replicateKind(std::string kind, std::string description,
                               std::function<void(const bridge::JsonDocument&)> check,
                               std::function<std::shared_ptr<const Replicates>(const bridge::JsonDocument&)> replicates,
                               std::function<std::optional<bridge::Estimate>(const bridge::JsonDocument&)> estimate);

}  // namespace gabion::micro::lab
