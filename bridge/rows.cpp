#include "bridge/rows.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <fstream>
#include <iterator>
#include <set>

#include "bridge/errors.hpp"
#include "bridge/interrupt.hpp"
#include "bridge/manifest.hpp"
#include "bridge/output.hpp"
#include "bridge/parallel.hpp"
#include "bridge/state_archive.hpp"

namespace gabion::bridge {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kLogFormat = "gabion.rows/1";
constexpr const char* kRowFormat = "gabion.row/1";

std::string readText(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// A result as the runner keeps it: an object with a boolean "ok", and a
// "message" when it failed.
json checkedResult(json r) {
  if (!r.is_object() || !r.contains("ok") || !r.at("ok").is_boolean())
    return {{"ok", false}, {"message", "the row gave no result"}};
  if (!r.at("ok").get<bool>() && !r.contains("message")) r["message"] = "failed";
  return r;
}

bool failedResult(const std::optional<json>& r) {
  return r && !r->at("ok").get<bool>();
}

// rows.jsonl, opened for the case of `digest`: the rows finished by earlier
// runs, and appended to as rows end. A log of another case (or another
// number of rows) is started afresh; a torn last line is cut off.
class RowLog {
 public:
  RowLog(fs::path file, const std::string& digest, std::size_t rows)
      : file_(std::move(file)), header_({{"format", kLogFormat}, {"case_digest", digest}, {"rows", rows}}) {}

  // The results the log holds (nullopt where none); truncates a torn tail.
  std::vector<std::optional<json>> read(bool repair) {
    std::vector<std::optional<json>> out(header_.at("rows").get<std::size_t>());
    std::error_code ec;
    if (!fs::exists(file_, ec)) return out;
    const std::string text = readText(file_);
    std::size_t pos = 0, kept = 0;
    bool same = false;
    for (std::size_t line = 0; pos < text.size(); ++line) {
      const std::size_t end = text.find('\n', pos);
      if (end == std::string::npos) break;
      try {
        const json j = json::parse(text.substr(pos, end - pos));
        if (line == 0) {
          same = j == header_;
          if (!same) break;
        } else {
          const auto index = j.at("index").get<std::size_t>();
          if (index < out.size()) out[index] = checkedResult(j.at("result"));
        }
      } catch (const std::exception&) {
        break;  // (a damaged line: the rows after it are run again)
      }
      pos = end + 1;
      kept = pos;
    }
    if (!same) return std::vector<std::optional<json>>(out.size());
    same_ = true;
    if (repair && kept < text.size()) fs::resize_file(file_, kept);
    noteWritten(file_);
    return out;
  }

  // Starts the log unless read() found it to be this case's.
  void open() {
    if (same_) return;
    std::ofstream out(file_, std::ios::trunc);
    out << header_.dump() << "\n";
    out.close();
    if (!out) throw WriteError(file_.string(), "the row log could not be started");
    noteWritten(file_);
    same_ = true;
  }

  // Appends rows (index, wall time, result) at once.
  template <class Rows>
  void append(const Rows& rows) {
    std::string lines;
    for (const auto& r : rows)
      lines += json{{"index", r.index}, {"wall_time_s", r.wall_time_s}, {"result", r.result}}.dump() + "\n";
    const std::lock_guard<std::mutex> lock(mutex_);
    // Appended and closed at once: a killed run loses at most the rows being written.
    std::ofstream out(file_, std::ios::app);
    out << lines;
    out.close();
    if (!out) throw WriteError(file_.string(), "rows could not be logged");
  }

 private:
  fs::path file_;
  json header_;
  bool same_ = false;
  std::mutex mutex_;
};

fs::path rowFolder(const fs::path& outdir, std::size_t i) {
  return outdir / "rows" / std::to_string(i);
}

std::string hostName() {
  char name[256] = {0};
  if (gethostname(name, sizeof name - 1) != 0) return "";
  return name;
}

json interruptedResult() {
  return {{"ok", false}, {"message", std::string("not run: interrupted by ") + signalName(interruptSignal())}};
}

// What a row runs with: the case's folder, one thread.
RunContext rowContext(const RunContext& ctx) {
  RunContext rc;
  rc.outdir = ctx.outdir;
  rc.case_file = ctx.case_file;
  rc.case_digest = ctx.case_digest;
  rc.threads = 1;
  return rc;
}

// A row left out after SIGINT or SIGTERM (interruptedResult).
bool notRun(const json& result) {
  return result.value("message", "").rfind("not run:", 0) == 0;
}

// How rows are about to run here: on MPI ranks, or on up to ctx.threads threads.
RowStats runningStats(const RunContext& ctx, std::size_t rows) {
  RowStats stats;
  stats.where = ctx.workers != nullptr ? "mpi" : "threads";
  stats.workers = ctx.workers != nullptr
                      ? ctx.workers->size()
                      : std::max(1, std::min<int>(ctx.threads, static_cast<int>(std::max<std::size_t>(1, rows))));
  return stats;
}

// Runs row i here; a row that throws is a failed row.
json runOne(const RowPlan& plan, std::size_t i, const RunContext& ctx) {
  try {
    return checkedResult(plan.run(i, rowContext(ctx)));
  } catch (const WriteError&) {
    throw;
  } catch (const std::exception& e) {
    return {{"ok", false}, {"message", e.what()}};
  }
}

// A finished row: its index, wall time and result.
struct Done {
  std::size_t index;
  double wall_time_s;
  json result;
};

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Runs the rows `todo` on ctx.threads threads, or in bundles on ctx.workers,
// and gives each batch of finished rows to `done` (from several threads at
// once). A bundle is sized from the rows' measured time, about 0.1 s of work,
// and small enough that every worker gets several: a message per row would
// make rank 0 the bottleneck of rows of milliseconds. After SIGINT or SIGTERM
// the rows not started are given as not run.
template <class OnDone>
void runAll(const RowPlan& plan, const std::vector<std::size_t>& todo, const RunContext& ctx, int workers,
            Progress& progress, const OnDone& done) {
  if (ctx.workers == nullptr) {
    runParallel(todo.size(), workers, progress, [&](std::size_t k) {
      const std::size_t i = todo[k];
      if (interrupted()) return done(std::vector<Done>{{i, 0.0, interruptedResult()}});
      const auto r0 = std::chrono::steady_clock::now();
      json r = runOne(plan, i, ctx);
      done(std::vector<Done>{{i, secondsSince(r0), std::move(r)}});
    });
    return;
  }
  std::mutex mutex;
  std::size_t next = 0, measured = 0;
  double measured_s = 0.0;
  const auto take = [&](std::size_t& first) -> std::size_t {
    const std::lock_guard<std::mutex> lock(mutex);
    const std::size_t left = todo.size() - next;
    std::size_t k = 1;
    if (measured > 0) {
      const double per_row = std::max(measured_s / static_cast<double>(measured), 1e-6);
      const auto share = std::max<std::size_t>(1, left / (4 * static_cast<std::size_t>(workers)));
      k = std::min<std::size_t>(share, static_cast<std::size_t>(std::max(1.0, 0.1 / per_row)));
    }
    k = std::min(k, left);
    first = next;
    next += k;
    return k;
  };
  runParallel(static_cast<std::size_t>(workers), workers, progress, [&](std::size_t) {
    for (std::size_t first = 0, k = take(first); k > 0; k = take(first)) {
      std::vector<Done> batch;
      if (interrupted()) {
        for (std::size_t j = first; j < first + k; ++j) batch.push_back({todo[j], 0.0, interruptedResult()});
        done(batch);
        continue;
      }
      json rows = json::array();
      for (std::size_t j = first; j < first + k; ++j) rows.push_back(todo[j]);
      json answer;
      try {
        answer = ctx.workers->call(
            {{"rows", rows}, {"outdir", fs::absolute(ctx.outdir).string()}, {"case_digest", ctx.case_digest}});
      } catch (const WriteError&) {
        throw;
      } catch (const std::exception& e) {  // (the rank could not run them: each is failed with why)
        for (std::size_t j = first; j < first + k; ++j)
          batch.push_back({todo[j], 0.0, {{"ok", false}, {"message", e.what()}}});
        done(batch);
        continue;
      }
      double wall = 0.0;
      for (std::size_t j = 0; j < k; ++j) {
        const double w = answer.at("wall_time_s").at(j).get<double>();
        wall += w;
        batch.push_back({todo[first + j], w, checkedResult(answer.at("results").at(j))});
      }
      {
        const std::lock_guard<std::mutex> lock(mutex);
        measured += k;
        measured_s += wall;
      }
      done(batch);
    }
  });
}

// Adds the rows' account to an assembled outcome.
RunOutcome finish(RunOutcome out, const RowStats& stats, std::size_t size) {
  out.results["rows"] = {{"total", size},
                         {"run", stats.run},
                         {"reused", stats.reused},
                         {"failed", stats.failed},
                         {"missing", stats.missing},
                         {"workers", stats.workers},
                         {"where", stats.where},
                         {"wall_time_s", stats.wall_time_s}};
  return out;
}

std::size_t countFailed(const std::vector<std::optional<json>>& results) {
  return static_cast<std::size_t>(std::count_if(results.begin(), results.end(), failedResult));
}

}  // namespace

std::string rowsDigest(const json& case_value) {
  json c = case_value;
  c.erase("description");
  return hexDigest(fnv1a(c.dump()));
}

namespace {

// Takes the results of the per-row folders in `outdir` into `out` (over the
// log's: a folder's comes from an explicit rerun).
void addRowFolders(const fs::path& outdir, const std::string& digest, std::vector<std::optional<json>>& out) {
  const std::size_t rows = out.size();
  std::error_code ec;
  if (!fs::is_directory(outdir / "rows", ec)) return;
  for (const auto& entry : fs::directory_iterator(outdir / "rows", ec)) {
    const fs::path file = entry.path() / "row.json";
    if (!fs::is_regular_file(file, ec)) continue;  // (a task that has not ended)
    json j;
    try {
      j = json::parse(readText(file));
    } catch (const std::exception&) {
      continue;  // (written atomically: cannot be torn; a user's edit is not a result)
    }
    if (j.value("format", "") != kRowFormat) continue;
    if (j.value("case_digest", "") != digest)
      throw InputError(file.string(), "/case_digest",
                       "this row was run for another case than the folder's run.json; rows of two cases do not mix "
                       "in one folder (remove " +
                           (outdir / "rows").string() + ", or collect into another folder)");
    const auto index = j.at("index").get<std::size_t>();
    if (index >= rows) continue;
    out[index] = checkedResult(j.at("result"));
    noteWritten(file);
  }
}

}  // namespace

std::vector<std::optional<json>> findRowResults(const fs::path& outdir, const std::string& digest, std::size_t rows) {
  std::vector<std::optional<json>> out = RowLog(outdir / "rows.jsonl", digest, rows).read(false);
  addRowFolders(outdir, digest, out);
  return out;
}

std::vector<std::size_t> selectRows(const std::string& spec, const std::vector<std::optional<json>>& known,
                                    const std::string& source) {
  std::set<std::size_t> out;
  const std::size_t n = known.size();
  auto number = [&](const std::string& s) -> std::size_t {
    if (s.empty() || s.find_first_not_of("0123456789") != std::string::npos || s.size() > 12)
      throw InputError(source, "",
                       "'" + spec +
                           "': expected rows as A:B (A to B-1), i, lists of them (0:10,12), 'missing' or "
                           "'failed'");
    return static_cast<std::size_t>(std::stoull(s));
  };
  std::size_t pos = 0;
  while (pos <= spec.size()) {
    const std::size_t comma = std::min(spec.find(',', pos), spec.size());
    const std::string part = spec.substr(pos, comma - pos);
    if (part == "missing" || part == "failed") {
      for (std::size_t i = 0; i < n; ++i)
        if (part == "missing" ? !known[i].has_value() : failedResult(known[i])) out.insert(i);
    } else if (const auto colon = part.find(':'); colon != std::string::npos) {
      const std::size_t a = number(part.substr(0, colon)), b = number(part.substr(colon + 1));
      if (a >= b || b > n)
        throw InputError(source, "",
                         "'" + part + "': rows A:B need A < B <= " + std::to_string(n) + " (the case has " +
                             std::to_string(n) + " rows, 0 to " + std::to_string(n - 1) + ")");
      for (std::size_t i = a; i < b; ++i) out.insert(i);
    } else {
      const std::size_t i = number(part);
      if (i >= n)
        throw InputError(source, "",
                         "row " + part + " does not exist: the case has " + std::to_string(n) + " rows, 0 to " +
                             std::to_string(n - 1));
      out.insert(i);
    }
    pos = comma + 1;
  }
  return {out.begin(), out.end()};
}

std::string rowSpec(const std::vector<std::size_t>& rows) {
  std::string out;
  for (std::size_t k = 0; k < rows.size();) {
    std::size_t e = k;
    while (e + 1 < rows.size() && rows[e + 1] == rows[e] + 1) ++e;
    if (!out.empty()) out += ",";
    out += e == k ? std::to_string(rows[k]) : std::to_string(rows[k]) + ":" + std::to_string(rows[e] + 1);
    k = e + 1;
  }
  return out;
}

RunOutcome runRows(const RowPlan& plan, const JsonDocument& doc, const RunContext& ctx) {
  const std::size_t n = plan.size();
  const std::string digest = rowsDigest(doc.json());
  RowLog log(ctx.outdir / "rows.jsonl", digest, n);
  std::vector<std::optional<json>> results = log.read(true);  // (a torn tail cut off)
  addRowFolders(ctx.outdir, digest, results);
  log.open();
  std::vector<std::size_t> todo;
  for (std::size_t i = 0; i < n; ++i)
    if (!results[i]) todo.push_back(i);

  RowStats stats = runningStats(ctx, todo.size());
  stats.reused = n - todo.size();
  Progress progress(ctx, "rows");
  const auto t0 = std::chrono::steady_clock::now();
  runAll(plan, todo, ctx, stats.workers, progress, [&](std::vector<Done> batch) {
    std::vector<Done> ran;  // (a row not run is not logged: a rerun runs it)
    for (Done& d : batch) {
      if (!notRun(d.result)) ran.push_back(d);
      results[d.index] = std::move(d.result);
    }
    if (!ran.empty()) log.append(ran);
  });
  stats.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::size_t not_run = 0;
  for (std::size_t i : todo) not_run += notRun(*results[i]) ? 1 : 0;
  stats.run = todo.size() - not_run;
  stats.failed = countFailed(results) - not_run;
  RunOutcome out = finish(plan.assemble(results, stats, ctx), stats, n);
  if (interrupted()) {
    out.status = RunOutcome::Status::Interrupted;
    out.message = std::string("interrupted by ") + signalName(interruptSignal()) + " after " +
                  std::to_string(n - not_run) + " of " + std::to_string(n) +
                  " rows; the table lists every row, and a rerun into the folder runs the rest";
  }
  return out;
}

RunOutcome runRowSlice(const RowPlan& plan, const JsonDocument& doc, const std::vector<std::size_t>& which,
                       const RunContext& ctx) {
  const std::string digest = rowsDigest(doc.json());
  const std::string host = hostName();
  RowStats stats = runningStats(ctx, which.size());
  Progress progress(ctx, "rows");
  const auto t0 = std::chrono::steady_clock::now();
  std::atomic<std::size_t> failed{0}, skipped{0};
  runAll(plan, which, ctx, stats.workers, progress, [&](const std::vector<Done>& batch) {
    for (const Done& d : batch) {
      if (notRun(d.result)) {
        ++skipped;
        continue;
      }
      if (!d.result.at("ok").get<bool>()) ++failed;
      const fs::path folder = rowFolder(ctx.outdir, d.index);
      std::error_code ec;
      fs::create_directories(folder, ec);
      if (ec) throw WriteError(folder.string(), "cannot make the row's folder: " + ec.message());
      writeJsonAtomic(folder / "row.json", {{"format", kRowFormat},
                                            {"case_digest", digest},
                                            {"index", d.index},
                                            {"row", plan.describe(d.index)},
                                            {"wall_time_s", d.wall_time_s},
                                            {"host", host},
                                            {"result", d.result}});
    }
  });
  stats.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  stats.run = which.size() - skipped;
  stats.failed = failed;
  RunOutcome out;
  out.answer = "rows " + rowSpec(which) + ": " + std::to_string(stats.run) + " run, " + std::to_string(stats.failed) +
               " failed, into " + (ctx.outdir / "rows").string() + "/<row>/row.json\n";
  out = finish(out, stats, plan.size());
  if (interrupted()) {
    out.status = RunOutcome::Status::Interrupted;
    out.message = std::string("interrupted by ") + signalName(interruptSignal()) + " after " +
                  std::to_string(stats.run) + " of " + std::to_string(which.size()) + " rows";
  }
  return out;
}

RunOutcome collectRows(const RowPlan& plan, const JsonDocument& doc, const RunContext& ctx) {
  const std::size_t n = plan.size();
  const std::vector<std::optional<json>> results = findRowResults(ctx.outdir, rowsDigest(doc.json()), n);
  RowStats stats;
  stats.where = "collected";
  stats.reused = static_cast<std::size_t>(
      std::count_if(results.begin(), results.end(), [](const auto& r) { return r.has_value(); }));
  stats.missing = n - stats.reused;
  stats.failed = countFailed(results);
  return finish(plan.assemble(results, stats, ctx), stats, n);
}

json runRowBundle(const RowPlan& plan, const json& task) {
  RunContext ctx;
  ctx.outdir = task.at("outdir").get<std::string>();
  ctx.case_digest = task.at("case_digest").get<std::string>();
  json results = json::array(), walls = json::array();
  for (const auto& i : task.at("rows")) {
    const auto r0 = std::chrono::steady_clock::now();
    results.push_back(runOne(plan, i.get<std::size_t>(), ctx));
    walls.push_back(secondsSince(r0));
  }
  return {{"results", results}, {"wall_time_s", walls}};
}

std::string rowTable(const RowPlan& plan, const JsonDocument& doc) {
  const std::string digest = rowsDigest(doc.json());
  std::string out;
  for (std::size_t i = 0; i < plan.size(); ++i) {
    json row = plan.describe(i);
    json line = {{"index", i}};
    line["parameters"] = row.value("parameters", json::object());
    line["seed"] = row.value("seed", json());
    line["case_digest"] = digest;
    out += line.dump() + "\n";
  }
  return out;
}

}  // namespace gabion::bridge
