// The `gabion` command line: run or check a case, run its rows here, on MPI
// ranks or as a Slurm job array and collect them, draw a result's figure,
// print the version.
// Exit codes: 0 ok, 1 internal error, 2 bad input, 3 numerical failure,
// 4 collected with rows missing, 128 + the signal when SIGINT or SIGTERM
// stopped the run.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <iterator>
#include <optional>
#include <set>

#include "app/mpi_workers.hpp"
#include "app/registry.hpp"
#include "app/slurm.hpp"
#include "app/standard_figure.hpp"
#include "bridge/cost.hpp"
#include "bridge/errors.hpp"
#include "bridge/interrupt.hpp"
#include "bridge/manifest.hpp"
#include "bridge/output.hpp"
#include "bridge/rows.hpp"
#include "bridge/state_archive.hpp"
#include "bridge/units.hpp"
#include "gabion_version.hpp"

namespace fs = std::filesystem;
using gabion::bridge::InputError;
using gabion::bridge::JsonDocument;

namespace {

constexpr int kExitOk = 0;
constexpr int kExitInternal = 1;
constexpr int kExitBadInput = 2;
constexpr int kExitNumerical = 3;
constexpr int kExitIncomplete = 4;     // collect: some rows have no result yet
constexpr int kExitInterrupted = 128;  // + the signal: 130 for SIGINT, 143 for SIGTERM (the shell's convention)

struct Options {
  std::string case_file;
  std::string outdir;
  std::string law_file;
  std::vector<std::string> sets;
  int threads = 1;
  bool quiet = false;
  bool force = false;  // run past the cost limits (bridge/cost.hpp)
  std::string resume;  // run: OUTDIR of the run to continue (its run.json)
  bool threads_given = false;
  std::string result_file;  // plot
  std::string figure;       // plot: -o
  std::string rows;         // run, submit: the rows to run (bridge::selectRows)
  bool dry_run = false;     // submit: write the batch script only
  gabion::app::SlurmOptions slurm;
};

// The run to continue: the effective case OUTDIR/run.json recorded when it
// started (after --set and --law), with its case file and threads.
JsonDocument resumedCase(Options& o) {
  if (!o.case_file.empty() || !o.sets.empty() || !o.law_file.empty() || !o.outdir.empty())
    throw InputError(o.resume, "",
                     "--resume continues a run as it was started: give no case file, --set, --law or -o with it");
  const fs::path record = fs::path(o.resume) / "run.json";
  if (!fs::is_regular_file(record))
    throw InputError(record.string(), "", "--resume: no such file: the folder holds no run that `gabion run` started");
  const JsonDocument r = JsonDocument::load(record);
  const auto root = r.root();
  if (root.string("format") != "gabion.run/1") root.fail("format", "expected \"gabion.run/1\"");
  o.case_file = root.string("case_file");
  if (!o.threads_given) o.threads = static_cast<int>(root.integer("threads", 1, 1));
  o.outdir = o.resume;
  return JsonDocument(r.json().at("case"), o.case_file);
}

// Loads the case (or the one --resume continues), applies --set, finds its
// kind and validates every key. Throws InputError; writes nothing.
// --law sets the case's "law_file" (in place of embedded "laws"): the case
// is checked with the laws it will run with.
std::pair<JsonDocument, const gabion::bridge::CaseKind*> loadAndCheck(Options& o) {
  if (!o.resume.empty()) {
    JsonDocument doc = resumedCase(o);
    const auto* kind = &gabion::app::checkCase(doc);
    return {std::move(doc), kind};
  }
  if (o.case_file.empty()) throw InputError("gabion run", "", "give a case file, or --resume OUTDIR");
  JsonDocument doc = JsonDocument::load(o.case_file);
  for (const auto& s : o.sets) doc.applySet(s);
  if (!o.law_file.empty()) {
    nlohmann::json value = doc.json();
    // The macro kinds read laws (a case of theirs that names none yet gets
    // them here); the other kinds read none.
    const std::string kind = value.is_object() ? value.value("kind", std::string("")) : std::string();
    if (!value.contains("law_file") && !value.contains("laws") && kind.rfind("macro.", 0) != 0)
      throw InputError(o.case_file, "",
                       "--law " + o.law_file + ": this " + kind + " case reads no laws (only the macro.* cases do)");
    if (!fs::is_regular_file(o.law_file)) throw InputError(o.law_file, "", "--law: no such file");
    value.erase("laws");
    value["law_file"] = fs::absolute(o.law_file).string();
    doc = JsonDocument(value, o.case_file);
  }
  const auto* kind = &gabion::app::checkCase(doc);
  return {std::move(doc), kind};
}

// What the case will cost (bridge/cost.hpp), from the checked document
// (check has already refused its unknown keys; no copy of a large case);
// nullopt where its kind cannot say. Bad input throws InputError as check
// does.
std::optional<gabion::bridge::Estimate> estimateOf(const gabion::bridge::CaseKind& kind, const JsonDocument& doc) {
  if (!kind.estimate) return std::nullopt;
  try {
    return kind.estimate(doc);
  } catch (const InputError&) {
    throw;
  } catch (const std::exception&) {
    return std::nullopt;  // (what check passed but the estimate could not cost)
  }
}

int commandCheck(Options& o) {
  const auto [doc, kind] = loadAndCheck(o);
  std::cout << o.case_file << ": ok\n";
  if (const auto e = estimateOf(*kind, doc)) std::cout << "  cost: " << gabion::bridge::describe(*e) << "\n";
  return kExitOk;
}

// The output folder (-o), made and checked writable. Throws InputError.
fs::path makeOutdir(const std::string& given) {
  const fs::path outdir(given);
  std::error_code ec;
  fs::create_directories(outdir, ec);
  if (ec || !fs::is_directory(outdir))
    throw InputError(outdir.string(), "", "cannot make the output folder (-o): " + ec.message());
  if (access(outdir.c_str(), W_OK) != 0)
    throw InputError(outdir.string(), "", "the output folder (-o) is not writable");
  return outdir;
}

// What `gabion run --resume OUTDIR` continues, and `gabion collect` reads:
// the effective case as it starts (kinds that keep their finished work take
// it: a sweep's rows, a calibration's evaluations, a pipeline's stages).
void writeRunRecord(const Options& o, const fs::path& outdir, const JsonDocument& doc) {
  nlohmann::json record = {
      {"format", "gabion.run/1"}, {"case_file", fs::absolute(o.case_file).string()}, {"threads", o.threads}};
  // (the case lent, not copied: a large case's document is the run's largest)
  doc.lendValue(record, "case",
                [&](const nlohmann::json& r) { gabion::bridge::writeJsonAtomic(outdir / "run.json", r); });
}

// The rows a case has, or an InputError naming the option that needs them.
std::shared_ptr<const gabion::bridge::RowPlan> rowsOf(const gabion::bridge::CaseKind& kind, const JsonDocument& doc,
                                                      const std::string& option) {
  if (!kind.rows) {
    std::string with;
    for (const auto& k : gabion::app::allKinds())
      if (k.rows) with += (with.empty() ? "" : ", ") + k.kind;
    throw InputError(doc.file(), "/kind",
                     option + ": a " + kind.kind + " case is one run, not a set of rows (cases of rows: " + with + ")");
  }
  return kind.rows(doc);
}

// The rows --rows selects; "missing" and "failed" are read from outdir.
std::vector<std::size_t> selectedRows(const Options& o, const gabion::bridge::RowPlan& plan, const JsonDocument& doc,
                                      const fs::path& outdir) {
  std::vector<std::optional<nlohmann::json>> known(plan.size());
  if (o.rows.find("missing") != std::string::npos || o.rows.find("failed") != std::string::npos)
    known = gabion::bridge::findRowResults(outdir, gabion::bridge::rowsDigest(doc.json()), plan.size());
  return gabion::bridge::selectRows(o.rows, known, "--rows");
}

// A folder's rows belong to one case: refuses to add rows of another.
void requireSameRows(const fs::path& outdir, const JsonDocument& doc) {
  const fs::path record = outdir / "run.json";
  if (!fs::is_regular_file(record)) return;
  const JsonDocument r = JsonDocument::load(record);
  if (!r.json().contains("case") || !fs::is_directory(outdir / "rows")) return;
  if (gabion::bridge::rowsDigest(r.json().at("case")) != gabion::bridge::rowsDigest(doc.json()))
    throw InputError(record.string(), "/case",
                     "this folder holds the rows of another case; give another -o, or remove " + outdir.string());
}

// Writes summary.json and the manifest of a run that ended, prints its files
// and answer; its exit code.
int finishRun(const Options& o, const gabion::bridge::CaseKind& kind, gabion::bridge::RunOutcome outcome, double wall,
              const std::optional<gabion::bridge::Estimate>& estimate, const std::string& case_text,
              const fs::path& outdir) {
  // A signal that came during the run (bridge/interrupt.hpp) is what ended
  // it, whatever a part of it made of being stopped (a calibration records
  // its stopped evaluations as failed ones and goes on): its summary never
  // says ok.
  if (gabion::bridge::interrupted()) {
    outcome.status = gabion::bridge::RunOutcome::Status::Interrupted;
    if (outcome.message.find("interrupted") == std::string::npos)
      outcome.message = std::string("interrupted by ") + gabion::bridge::signalName(gabion::bridge::interruptSignal()) +
                        (outcome.message.empty() ? "" : ": " + outcome.message);
  }

  nlohmann::json summary;
  summary["format"] = "gabion.summary/1";
  summary["kind"] = kind.kind;
  const bool ok = outcome.status == gabion::bridge::RunOutcome::Status::Ok;
  summary["status"] = gabion::bridge::statusName(outcome.status);
  if (!outcome.message.empty()) summary["message"] = outcome.message;
  summary["version"] = gabion::kVersion;
  summary["wall_time_s"] = gabion::bridge::wholeWallTime(wall, outcome.results);
  if (outcome.results.contains(gabion::bridge::kWallTimeBeforeResume)) summary["wall_time_this_process_s"] = wall;
  summary["threads"] = o.threads;
  summary["case_file"] = o.case_file;
  if (estimate)
    summary["estimate"] = {{"bodies", estimate->bodies},
                           {"steps", estimate->steps},
                           {"runs", estimate->runs},
                           {"wall_time_s", estimate->wall_time_s},
                           {"memory_bytes", estimate->memory_bytes},
                           {"output_bytes", estimate->output_bytes},
                           {"checkpoint_bytes", estimate->checkpoint_bytes},
                           {"partial", estimate->partial}};
  summary["case"] = nlohmann::json::parse(case_text);
  for (auto it = outcome.results.begin(); it != outcome.results.end(); ++it) summary[it.key()] = it.value();
  gabion::bridge::writeJsonAtomic(outdir / "summary.json", summary);
  gabion::bridge::writeManifest(outdir, summary["status"].get<std::string>());

  if (outcome.status == gabion::bridge::RunOutcome::Status::Interrupted) {
    std::cerr << "gabion: " << outcome.message << "\n"
              << "gabion: what was written so far is in " << outdir.string() << "\n";
    return kExitInterrupted + gabion::bridge::interruptSignal();
  }
  if (!ok) {
    std::cerr << "gabion: numerical failure: " << outcome.message << "\n"
              << "gabion: what was written so far is in " << outdir.string() << "\n";
    return kExitNumerical;
  }
  // The files this run wrote (its manifest's, top level); a reused folder's
  // older files are counted, not listed as results.
  std::cout << "results: " << fs::absolute(outdir).string() << "\n";
  std::set<fs::path> ours;
  for (const fs::path& f : gabion::bridge::writtenFiles(outdir))
    if (std::distance(f.begin(), f.end()) == 1) ours.insert(f);
  ours.insert("manifest.json");
  for (const fs::path& f : ours) std::cout << "  " << f.string() << "\n";
  std::size_t older = 0;
  for (const auto& entry : fs::directory_iterator(outdir))
    if (entry.is_regular_file() && ours.count(entry.path().filename()) == 0) ++older;
  if (older > 0) std::cout << "  (and " << older << " older file" << (older > 1 ? "s" : "") << ", not from this run)\n";
  std::cout << outcome.answer;
  if (!o.quiet) std::cout << outcome.report;
  return kExitOk;
}

// What a rank runs of a case's tasks: its rows, or what its kind serves
// (fit.micro's evaluations, a lab test's replicates); empty for a case of
// one run.
gabion::app::TaskHandler taskHandler(const gabion::bridge::CaseKind& kind, const JsonDocument& doc) {
  std::shared_ptr<const gabion::bridge::RowPlan> plan;
  gabion::app::TaskHandler served;
  if (kind.rows) plan = kind.rows(doc);
  if (kind.serve) served = kind.serve(doc);
  if (!plan && !served) return {};
  return [plan, served](const nlohmann::json& task) {
    if (task.contains("rows") && plan) return gabion::bridge::runRowBundle(*plan, task);  // (a slice's, a sweep's)
    if (!served) throw std::runtime_error("this case's kind takes no such task: " + task.dump());
    return served(task);  // (the kind's own: a calibration's evaluations, a replicate)
  };
}

// The run's context as the options give it: where, on how many threads, from
// which case file, and how its progress shows (a plain line every minute
// when stdout is a log, not a terminal).
gabion::bridge::RunContext runContext(const Options& o, const fs::path& outdir) {
  gabion::bridge::RunContext ctx;
  ctx.outdir = outdir;
  ctx.threads = o.threads;
  ctx.case_file = o.case_file;
  ctx.progress = !o.quiet;
  ctx.progress_log = isatty(STDOUT_FILENO) == 0;
  return ctx;
}

// --rows: runs a slice of the case's rows into their per-row folders; no
// table, summary or manifest (other processes may be writing rows beside).
int runSlice(const Options& o, const gabion::bridge::CaseKind& kind, const JsonDocument& doc, const fs::path& outdir,
             gabion::bridge::RemoteWorkers* workers) {
  const auto plan = rowsOf(kind, doc, "--rows");
  const std::vector<std::size_t> which = selectedRows(o, *plan, doc, outdir);
  makeOutdir(outdir.string());
  requireSameRows(outdir, doc);
  if (o.resume.empty()) writeRunRecord(o, outdir, doc);
  gabion::bridge::RunContext ctx = runContext(o, outdir);
  ctx.workers = workers;
  ctx.case_digest = gabion::bridge::hexDigest(gabion::bridge::fnv1a(doc.json().dump()));
  const auto outcome = gabion::bridge::runRowSlice(*plan, doc, which, ctx);
  if (outcome.status == gabion::bridge::RunOutcome::Status::Interrupted) {
    std::cerr << "gabion: " << outcome.message << "\n";
    return kExitInterrupted + gabion::bridge::interruptSignal();
  }
  std::cout << outcome.answer;
  return kExitOk;
}

int commandRun(Options& o, gabion::app::RankPool* workers) {
  auto [doc, kind] = loadAndCheck(o);
  const fs::path outdir = o.outdir.empty() ? fs::path("results") / fs::path(o.case_file).stem() : fs::path(o.outdir);
  if (!o.rows.empty()) {
    if (workers != nullptr) workers->workHere(taskHandler(*kind, doc));
    return runSlice(o, *kind, doc, outdir, workers);
  }
  // Costed before anything is written: past the limits it is refused unless
  // --force; a long or large run says so before it starts.
  const auto estimate = estimateOf(*kind, doc);
  if (estimate) {
    const std::string why = gabion::bridge::overLimits(*estimate, outdir);
    if (!why.empty() && !o.force)
      throw InputError(o.case_file, "",
                       "refused before it starts: " + why + " (estimate: " + gabion::bridge::describe(*estimate) +
                           "); reduce the case, or run it anyway with --force");
    if (!why.empty() || estimate->wall_time_s > gabion::bridge::kAnnounceWallTimeS ||
        estimate->memory_bytes > gabion::bridge::kAnnounceBytes ||
        estimate->output_bytes + estimate->checkpoint_bytes > gabion::bridge::kAnnounceBytes)
      std::cerr << "gabion: this run: " << gabion::bridge::describe(*estimate) << "\n";
  }
  makeOutdir(outdir.string());

  gabion::bridge::RunContext ctx = runContext(o, outdir);
  if (workers != nullptr && (kind->rows || kind->serve)) {
    workers->workHere(taskHandler(*kind, doc));  // (rank 0 takes tasks too)
    ctx.workers = workers;
  }
  if (workers != nullptr && ctx.workers == nullptr)
    std::cerr << "gabion: a " << kind->kind << " case is one run, not a set of tasks: it runs on rank 0 alone\n";
  // The effective case for summary.json, kept as text so that the kind may
  // free the document while it runs.
  const std::string case_text = doc.json().dump();
  ctx.case_digest = gabion::bridge::hexDigest(gabion::bridge::fnv1a(case_text));
  ctx.may_release_case = true;

  const auto t0 = std::chrono::steady_clock::now();
  // The folder's earlier set of files is no longer trusted from here; its
  // new manifest is written last (bridge/manifest.hpp).
  gabion::bridge::beginManifest(outdir);
  writeRunRecord(o, outdir, doc);
  gabion::bridge::RunOutcome outcome;
  try {
    outcome = kind->run(doc, ctx);
  } catch (const gabion::bridge::NumericalError& e) {
    outcome.status = gabion::bridge::RunOutcome::Status::NumericalFailure;
    outcome.message = e.what();
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return finishRun(o, *kind, std::move(outcome), wall, estimate, case_text, outdir);
}

// gabion collect OUTDIR: the table of the rows found in OUTDIR (run there
// by --rows slices, Slurm tasks or an interrupted run); rows not found are
// marked missing, and the command that runs exactly those is named.
int commandCollect(Options& o) {
  auto [doc, kind] = loadAndCheck(o);
  const fs::path outdir = o.outdir;
  const auto plan = rowsOf(*kind, doc, "collect");
  gabion::bridge::RunContext ctx;
  ctx.outdir = outdir;
  ctx.threads = o.threads;
  ctx.case_file = o.case_file;
  const std::string case_text = doc.json().dump();
  const auto t0 = std::chrono::steady_clock::now();
  gabion::bridge::beginManifest(outdir);
  gabion::bridge::RunOutcome outcome;
  try {
    outcome = gabion::bridge::collectRows(*plan, doc, ctx);
  } catch (const gabion::bridge::NumericalError& e) {  // (a failed row the kind cannot go on from)
    outcome.status = gabion::bridge::RunOutcome::Status::NumericalFailure;
    outcome.message = e.what();
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const int code = finishRun(o, *kind, outcome, wall, std::nullopt, case_text, outdir);
  if (code != kExitOk) return code;
  // What is left to run, and the one command that runs it.
  const auto results = gabion::bridge::findRowResults(outdir, gabion::bridge::rowsDigest(doc.json()), plan->size());
  std::vector<std::size_t> missing, failed;
  for (std::size_t i = 0; i < results.size(); ++i) {
    if (!results[i])
      missing.push_back(i);
    else if (!results[i]->at("ok").get<bool>())
      failed.push_back(i);
  }
  const std::string dir = fs::absolute(outdir).string();
  std::cout << "rows: " << plan->size() - missing.size() << " of " << plan->size() << " done";
  if (!failed.empty()) std::cout << ", " << failed.size() << " failed (rows " << gabion::bridge::rowSpec(failed) << ")";
  std::cout << "\n";
  const std::string failed_spec = gabion::bridge::rowSpec(failed);
  if (missing.empty()) {
    if (!failed.empty())
      std::cout << "to run the failed rows again: gabion run --resume " << dir << " --rows " << failed_spec
                << "; then gabion collect " << dir << "\n";
    return kExitOk;
  }
  const std::string spec = gabion::bridge::rowSpec(missing);
  std::cerr << "gabion: " << missing.size() << " row" << (missing.size() > 1 ? "s" : "") << " missing: " << spec << "\n"
            << "gabion: run exactly those here:  gabion run --resume " << dir << " --rows " << spec << "\n"
            << "gabion: or as a Slurm array:     gabion submit slurm --resume " << dir << " --rows " << spec << "\n"
            << "gabion: then collect again:      gabion collect " << dir << "\n";
  if (!failed.empty())
    std::cerr << "gabion: (the failed rows too:      --rows " << spec << "," << failed_spec << " in either command)\n";
  return kExitIncomplete;
}

// gabion rows CASE: the case's rows, a JSON line each.
int commandRows(Options& o) {
  auto [doc, kind] = loadAndCheck(o);
  std::cout << gabion::bridge::rowTable(*rowsOf(*kind, doc, "rows"), doc);
  return kExitOk;
}

// gabion submit slurm CASE -o OUTDIR: the rows as a Slurm job array.
int commandSubmitSlurm(Options& o) {
  auto [doc, kind] = loadAndCheck(o);
  const auto plan = rowsOf(*kind, doc, "submit slurm");
  if (o.outdir.empty()) throw InputError(o.case_file, "", "submit slurm: give the output folder (-o) the tasks share");
  const fs::path outdir = makeOutdir(o.outdir);
  requireSameRows(outdir, doc);
  std::vector<std::size_t> which;
  if (o.rows.empty()) {
    // (rows already done in the folder are not submitted again)
    const auto known = gabion::bridge::findRowResults(outdir, gabion::bridge::rowsDigest(doc.json()), plan->size());
    for (std::size_t i = 0; i < plan->size(); ++i)
      if (!known[i]) which.push_back(i);
  } else {
    which = selectedRows(o, *plan, doc, outdir);
  }
  if (o.resume.empty()) writeRunRecord(o, outdir, doc);
  o.slurm.cpus_per_task = o.threads;
  o.slurm.submit = !o.dry_run;
  const auto s = gabion::app::submitSlurm(*plan, which, outdir, fs::read_symlink("/proc/self/exe"), o.slurm);
  std::cout << "batch script: " << s.script.string() << "\n"
            << "  " << s.rows << " rows in " << s.tasks << (s.tasks == 1 ? " array task" : " array tasks")
            << " of up to " << s.rows_per_task << " rows (estimated " << gabion::bridge::showNumber(s.estimated_task_s)
            << " s a task at most)\n";
  const std::string dir = fs::absolute(outdir).string();
  if (s.job_id.empty()) {
    std::cout << "not submitted (--dry-run): sbatch " << s.script.string() << "\n";
    return kExitOk;
  }
  std::cout << "submitted: job " << s.job_id << " (squeue -j " << s.job_id << ")\n"
            << "when it ends: gabion collect " << dir << "\n";
  return kExitOk;
}

// On an MPI worker rank: answers rank 0's tasks until it says stop. A worker
// whose case cannot be read answers every task with why.
int serveAsWorker(Options& o, bool run_command, const gabion::app::MpiSession& mpi) {
  gabion::app::TaskHandler handler;
  std::string why = "this command gives MPI workers no tasks";
  if (run_command) {
    try {
      auto [doc, kind] = loadAndCheck(o);
      handler = taskHandler(*kind, doc);
    } catch (const std::exception& e) {
      why = e.what();
    }
  }
  gabion::app::serveTasks(mpi, [&](const nlohmann::json& task) {
    if (!handler) throw std::runtime_error(why);
    return handler(task);
  });
  return kExitOk;
}

}  // namespace

namespace {
int runCommandLine(int argc, char** argv, const gabion::app::MpiSession& mpi);
}

// A result file that failed to write (a full disk) leaves an HDF5 handle
// that the library's clean-up at exit would crash on: the process then ends
// without it, its streams flushed (bridge/output.hpp).
int main(int argc, char** argv) {
  if (!gabion::app::MpiSession::available() && gabion::app::MpiSession::launcherSize() > 1) {
    std::cerr << "gabion: started on several MPI ranks, but this gabion was built without MPI (install "
                 "libopenmpi-dev and build again): each rank would run the whole case\n";
    return kExitBadInput;
  }
  int code = kExitInternal;
  {
    gabion::app::MpiSession mpi(argc, argv);
    code = runCommandLine(argc, argv, mpi);
    if (gabion::bridge::hdf5HandlesAbandoned()) {
      std::cout.flush();
      std::cerr.flush();
      std::_Exit(code);
    }
  }
  return code;
}

namespace {
int runCommandLine(int argc, char** argv, const gabion::app::MpiSession& mpi) {
  gabion::bridge::installInterruptHandlers();
  CLI::App app{"gabion: two-scale DEM for cellular rockfall protection structures"};
  app.set_version_flag("--version", std::string("gabion ") + gabion::kVersion);
  app.require_subcommand(1);
  Options o;

  auto* run = app.add_subcommand("run", "Run a case and write results into OUTDIR");
  run->add_option("case", o.case_file, "case file (JSON)");
  run->add_option("--resume", o.resume,
                  "continue the run in OUTDIR as it was started (its run.json): a sweep runs only the points it had "
                  "not finished, a calibration the evaluations it had not logged, a pipeline the stages not done");
  run->add_option("-o,--output", o.outdir, "output folder (default: results/<case name>)");
  run->add_option("--law", o.law_file, "law file (gabion.law/2, or /1) replacing the case's laws (macro cases)");
  run->add_option("--set", o.sets, "override a case value: path.to.key=value (repeatable)");
  run->add_option("--threads", o.threads, "worker threads")->check(CLI::Range(1, 256));
  run->add_option("--rows", o.rows,
                  "run only these rows of a case of rows (A:B is A to B-1; lists 0:10,12; 'missing', 'failed'), each "
                  "into OUTDIR/rows/<row>/; `gabion collect OUTDIR` makes the table");
  run->add_flag("-q,--quiet", o.quiet, "no progress line and no timing report");
  run->add_flag("--force", o.force,
                "run a case past the cost limits (more than a day on one thread, 80 % of the memory, the disk's free "
                "space)");

  auto* check = app.add_subcommand("check", "Validate a case without running it");
  check->add_option("case", o.case_file, "case file (JSON)")->required();
  check->add_option("--law", o.law_file, "law file (gabion.law/2, or /1) replacing the case's laws");
  check->add_option("--set", o.sets, "override a case value: path.to.key=value (repeatable)");

  auto* rows = app.add_subcommand("rows", "Print the rows of a case of rows (a sweep's points), a JSON line each");
  rows->add_option("case", o.case_file, "case file (JSON)")->required();
  rows->add_option("--law", o.law_file, "law file replacing the case's laws");
  rows->add_option("--set", o.sets, "override a case value: path.to.key=value (repeatable)");

  auto* collect = app.add_subcommand(
      "collect", "Make the table of the rows run into OUTDIR (--rows slices, Slurm tasks); names the rows missing");
  collect->add_option("outdir", o.resume, "the output folder the rows were run into")->required();
  collect->add_flag("-q,--quiet", o.quiet, "no timing report");

  auto* submit = app.add_subcommand("submit", "Submit the rows of a case to a cluster's scheduler");
  submit->require_subcommand(1);
  auto* slurm = submit->add_subcommand("slurm", "as a Slurm job array (sbatch), bundles of rows per task");
  slurm->add_option("case", o.case_file, "case file (JSON)");
  slurm->add_option("--resume", o.resume, "submit rows of the run in OUTDIR (with --rows missing, failed)");
  slurm->add_option("-o,--output", o.outdir, "output folder, shared by the tasks (required without --resume)");
  slurm->add_option("--law", o.law_file, "law file replacing the case's laws");
  slurm->add_option("--set", o.sets, "override a case value: path.to.key=value (repeatable)");
  slurm->add_option("--rows", o.rows, "the rows to submit (default: every row not done in OUTDIR)");
  slurm->add_option("--rows-per-task", o.slurm.rows_per_task,
                    "rows bundled into one array task (default: from their estimated cost, about --task-seconds)");
  slurm->add_option("--task-seconds", o.slurm.task_target_s, "wall time aimed at per task when bundling (600)")
      ->check(CLI::PositiveNumber);
  slurm->add_option("--max-parallel", o.slurm.max_parallel, "array tasks running at once (--array=...%K)")
      ->check(CLI::Range(1, 1000000));
  slurm->add_option("--threads", o.threads, "threads of each task (--cpus-per-task)")->check(CLI::Range(1, 256));
  slurm->add_option("--partition", o.slurm.partition, "sbatch --partition");
  slurm->add_option("--time", o.slurm.time, "sbatch --time, per task (e.g. 00:30:00)");
  slurm->add_option("--mem", o.slurm.mem, "sbatch --mem, per task (e.g. 2G)");
  slurm->add_option("--account", o.slurm.account, "sbatch --account");
  slurm->add_option("--sbatch", o.slurm.extra, "a further #SBATCH option, e.g. --sbatch=--qos=short (repeatable)");
  slurm->add_flag("--dry-run", o.dry_run, "write the batch script, do not submit it");

  auto* kinds = app.add_subcommand("kinds", "List the case kinds this build runs");

  auto* plot = app.add_subcommand("plot", "Draw the standard figure of a result file (result.h5)");
  plot->add_option("result", o.result_file, "a run's result.h5")->required();
  plot->add_option("-o,--output", o.figure, "figure file, .png or .svg (default: beside the result, .png)");

  // Under mpirun, ranks other than 0 serve rank 0's tasks and write nothing;
  // rank 0's pool of ranks stops them when it goes, however this ends.
  std::unique_ptr<gabion::app::RankPool> workers;
  if (mpi.size() > 1 && !mpi.worker()) workers = gabion::app::workerRanks(mpi);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {  // (--help and --version too: exit 0)
    if (mpi.worker()) return serveAsWorker(o, false, mpi);
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitBadInput;
  }
  o.threads_given = run->count("--threads") > 0 || slurm->count("--threads") > 0;
  if (mpi.worker()) return serveAsWorker(o, run->parsed(), mpi);
  try {
    if (kinds->parsed()) {
      for (const auto& k : gabion::app::allKinds())
        std::cout << k.kind << "\t" << k.description << (k.rows ? " [rows]" : "") << "\n";
      return kExitOk;
    }
    if (check->parsed()) return commandCheck(o);
    if (rows->parsed()) return commandRows(o);
    if (collect->parsed()) return commandCollect(o);
    if (slurm->parsed()) {
      if (o.resume.empty() && o.case_file.empty())
        throw InputError("gabion submit slurm", "", "give a case file and -o OUTDIR, or --resume OUTDIR");
      if (!o.resume.empty() && !o.case_file.empty())
        throw InputError(o.resume, "", "--resume submits rows of the run in OUTDIR: give no case file with it");
      return commandSubmitSlurm(o);
    }
    if (plot->parsed()) {
      const fs::path figure = o.figure.empty() ? fs::path(o.result_file).replace_extension(".png") : fs::path(o.figure);
      gabion::app::writeStandardFigure(o.result_file, figure);
      std::cout << figure.string() << "\n";
      return kExitOk;
    }
    return commandRun(o, workers.get());
  } catch (const InputError& e) {
    std::cerr << e.what() << "\n";
    return kExitBadInput;
  } catch (const gabion::bridge::WriteError& e) {
    std::cerr << "gabion: " << e.what() << "\n";
    return kExitInternal;
  } catch (const std::exception& e) {
    std::cerr << "gabion: internal error: " << e.what() << "\n";
    return kExitInternal;
  }
}
}  // namespace
