// The `gabion` command line: run or check a case, draw a result's figure,
// print the version.
// Exit codes: 0 ok, 1 internal error, 2 bad input, 3 numerical failure,
// 128 + the signal when SIGINT or SIGTERM stopped the run.
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

#include "app/registry.hpp"
#include "app/standard_figure.hpp"
#include "bridge/cost.hpp"
#include "bridge/errors.hpp"
#include "bridge/interrupt.hpp"
#include "bridge/manifest.hpp"
#include "bridge/output.hpp"
#include "bridge/state_archive.hpp"
#include "gabion_version.hpp"

namespace fs = std::filesystem;
using gabion::bridge::InputError;
using gabion::bridge::JsonDocument;

namespace {

constexpr int kExitOk = 0;
constexpr int kExitInternal = 1;
constexpr int kExitBadInput = 2;
constexpr int kExitNumerical = 3;
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
    if (!value.contains("law_file") && !value.contains("laws"))
      throw InputError(o.case_file, "",
                       "--law " + o.law_file + ": this " + value.value("kind", std::string("")) +
                           " case reads no laws (only the macro cases do)");
    if (!fs::is_regular_file(o.law_file)) throw InputError(o.law_file, "", "--law: no such file");
    value.erase("laws");
    value["law_file"] = fs::absolute(o.law_file).string();
    doc = JsonDocument(value, o.case_file);
  }
  const auto* kind = &gabion::app::checkCase(doc);
  return {std::move(doc), kind};
}

// What the case will cost (bridge/cost.hpp), from a copy of the checked
// document; nullopt where its kind cannot say. Bad input throws InputError
// as check does.
std::optional<gabion::bridge::Estimate> estimateOf(const gabion::bridge::CaseKind& kind, const JsonDocument& doc) {
  if (!kind.estimate) return std::nullopt;
  try {
    return kind.estimate(JsonDocument(doc.json(), doc.file()));
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

int commandRun(Options& o) {
  auto [doc, kind] = loadAndCheck(o);
  const fs::path outdir = o.outdir.empty() ? fs::path("results") / fs::path(o.case_file).stem() : fs::path(o.outdir);
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
        estimate->output_bytes > gabion::bridge::kAnnounceBytes)
      std::cerr << "gabion: this run: " << gabion::bridge::describe(*estimate) << "\n";
  }
  std::error_code ec;
  fs::create_directories(outdir, ec);
  if (ec || !fs::is_directory(outdir))
    throw InputError(outdir.string(), "", "cannot make the output folder (-o): " + ec.message());
  if (access(outdir.c_str(), W_OK) != 0)
    throw InputError(outdir.string(), "", "the output folder (-o) is not writable");

  gabion::bridge::RunContext ctx;
  ctx.outdir = outdir;
  ctx.threads = o.threads;
  ctx.case_file = o.case_file;
  ctx.progress = !o.quiet && isatty(STDOUT_FILENO) != 0;
  // The effective case for summary.json, kept as text so that the kind may
  // free the document while it runs.
  const std::string case_text = doc.json().dump();
  ctx.case_digest = gabion::bridge::hexDigest(gabion::bridge::fnv1a(case_text));
  ctx.may_release_case = true;

  const auto t0 = std::chrono::steady_clock::now();
  // The folder's earlier set of files is no longer trusted from here; its
  // new manifest is written last (bridge/manifest.hpp).
  gabion::bridge::beginManifest(outdir);
  // What `gabion run --resume OUTDIR` continues: the effective case as it
  // starts (kinds that keep their finished work take it: a sweep's rows, a
  // calibration's evaluations, a pipeline's stages).
  gabion::bridge::writeJsonAtomic(outdir / "run.json", {{"format", "gabion.run/1"},
                                                        {"case_file", fs::absolute(o.case_file).string()},
                                                        {"threads", o.threads},
                                                        {"case", doc.json()}});
  gabion::bridge::RunOutcome outcome;
  try {
    outcome = kind->run(doc, ctx);
  } catch (const gabion::bridge::NumericalError& e) {
    outcome.status = gabion::bridge::RunOutcome::Status::NumericalFailure;
    outcome.message = e.what();
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
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
  summary["kind"] = kind->kind;
  const bool ok = outcome.status == gabion::bridge::RunOutcome::Status::Ok;
  summary["status"] = gabion::bridge::statusName(outcome.status);
  if (!outcome.message.empty()) summary["message"] = outcome.message;
  summary["version"] = gabion::kVersion;
  summary["wall_time_s"] = wall;
  summary["threads"] = o.threads;
  summary["case_file"] = o.case_file;
  if (estimate)
    summary["estimate"] = {{"bodies", estimate->bodies},
                           {"steps", estimate->steps},
                           {"runs", estimate->runs},
                           {"wall_time_s", estimate->wall_time_s},
                           {"memory_bytes", estimate->memory_bytes},
                           {"output_bytes", estimate->output_bytes},
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

}  // namespace

namespace {
int runCommandLine(int argc, char** argv);
}

// A result file that failed to write (a full disk) leaves an HDF5 handle
// that the library's clean-up at exit would crash on: the process then ends
// without it, its streams flushed (bridge/output.hpp).
int main(int argc, char** argv) {
  const int code = runCommandLine(argc, argv);
  if (gabion::bridge::hdf5HandlesAbandoned()) {
    std::cout.flush();
    std::cerr.flush();
    std::_Exit(code);
  }
  return code;
}

namespace {
int runCommandLine(int argc, char** argv) {
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
  run->add_flag("-q,--quiet", o.quiet, "no progress line and no timing report");
  run->add_flag("--force", o.force,
                "run a case past the cost limits (more than a day on one thread, 80 % of the memory, the disk's free "
                "space)");

  auto* check = app.add_subcommand("check", "Validate a case without running it");
  check->add_option("case", o.case_file, "case file (JSON)")->required();
  check->add_option("--law", o.law_file, "law file (gabion.law/2, or /1) replacing the case's laws");
  check->add_option("--set", o.sets, "override a case value: path.to.key=value (repeatable)");

  auto* kinds = app.add_subcommand("kinds", "List the case kinds this build runs");

  auto* plot = app.add_subcommand("plot", "Draw the standard figure of a result file (result.h5)");
  plot->add_option("result", o.result_file, "a run's result.h5")->required();
  plot->add_option("-o,--output", o.figure, "figure file, .png or .svg (default: beside the result, .png)");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {  // (--help and --version too: exit 0)
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitBadInput;
  }
  o.threads_given = run->count("--threads") > 0;
  try {
    if (kinds->parsed()) {
      for (const auto& k : gabion::app::allKinds()) std::cout << k.kind << "\t" << k.description << "\n";
      return kExitOk;
    }
    if (check->parsed()) return commandCheck(o);
    if (plot->parsed()) {
      const fs::path figure = o.figure.empty() ? fs::path(o.result_file).replace_extension(".png") : fs::path(o.figure);
      gabion::app::writeStandardFigure(o.result_file, figure);
      std::cout << figure.string() << "\n";
      return kExitOk;
    }
    return commandRun(o);
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
