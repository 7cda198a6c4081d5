#include "fitting/calibration.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <fstream>
#include <iterator>
#include <limits>
#include <mutex>
#include <nlopt.hpp>
#include <random>
#include <set>
#include <thread>

#include "bridge/errors.hpp"
#include "bridge/manifest.hpp"

namespace gabion::fitting {

namespace fs = std::filesystem;
using nlohmann::json;

// ---------------------------------------------------------------- the log

EvaluationLog::EvaluationLog(fs::path file, std::string case_sha256, std::vector<std::string> parameter_names,
                             bool resume)
    : file_(std::move(file)) {
  const json header = {
      {"format", "gabion.evaluations/1"}, {"case_sha256", case_sha256}, {"parameters", parameter_names}};
  std::error_code ec;
  if (resume && fs::exists(file_, ec)) {
    std::string text;
    {
      std::ifstream in(file_, std::ios::binary);
      text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    std::size_t line_no = 0, at = 0, kept = 0;  // kept: bytes of whole, valid lines
    bool unterminated = false;
    while (at < text.size()) {
      const std::size_t end = text.find('\n', at);
      const bool last = end == std::string::npos;
      const std::string line = text.substr(at, last ? std::string::npos : end - at);
      ++line_no;
      json j;
      try {
        j = json::parse(line);
      } catch (const json::exception&) {
        // Only a last line cut short (the run was killed while writing it) is
        // tolerated: it is cut off below, so that the records appended next
        // start on a line of their own.
        if (last) break;
        throw bridge::InputError(file_.string(), "line " + std::to_string(line_no), "not valid JSON");
      }
      at = last ? text.size() : end + 1;
      kept = at;
      unterminated = last;
      if (line_no == 1) {
        if (j.value("format", "") != "gabion.evaluations/1")
          throw bridge::InputError(file_.string(), "line 1", "not a gabion.evaluations/1 log");
        if (j.value("case_sha256", "") != case_sha256 || j.value("parameters", json::array()) != header["parameters"])
          throw bridge::InputError(file_.string(), "line 1",
                                   "this log was written by another case or other parameters; remove it or use "
                                   "another output folder to start afresh");
        continue;
      }
      try {
        EvaluationRecord r;
        r.id = j.at("id").get<long long>();
        r.parameters = j.at("parameters").get<std::vector<double>>();
        r.ok = j.at("status").get<std::string>() == "ok";
        r.error = j.at("error").is_number() ? j.at("error").get<double>() : std::numeric_limits<double>::infinity();
        r.time_s = j.at("time_s").get<double>();
        r.message = j.value("message", "");
        if (r.parameters.size() != parameter_names.size()) throw std::runtime_error("wrong parameter count");
        next_id_ = std::max(next_id_, r.id + 1);
        records_[r.parameters] = r;
      } catch (const std::exception& e) {
        throw bridge::InputError(file_.string(), "line " + std::to_string(line_no),
                                 std::string("bad record: ") + e.what());
      }
    }
    if (kept < text.size()) fs::resize_file(file_, kept);  // (the torn line)
    if (unterminated) std::ofstream(file_, std::ios::app) << "\n";
    resumed_ = records_.size();
    if (kept > 0) {  // keep appending to the existing log
      bridge::noteWritten(file_);
      return;
    }
  }
  std::ofstream out(file_, std::ios::trunc);
  if (!out) throw bridge::InputError(file_.string(), "", "cannot write the evaluation log");
  out << header.dump() << "\n";
  out.close();
  if (!out) throw bridge::WriteError(file_.string(), "the evaluation log's header could not be written");
  bridge::noteWritten(file_);  // (a log, appended line by line: listed in the run's manifest)
}

bool EvaluationLog::find(const std::vector<double>& parameters, EvaluationRecord& out) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = records_.find(parameters);
  if (it == records_.end()) return false;
  out = it->second;
  return true;
}

void EvaluationLog::append(const EvaluationRecord& r) {
  json j = {{"id", r.id},
            {"parameters", r.parameters},
            {"error", std::isfinite(r.error) ? json(r.error) : json(nullptr)},
            {"time_s", r.time_s},
            {"status", r.ok ? "ok" : "failed"}};
  if (!r.message.empty()) j["message"] = r.message;
  std::lock_guard<std::mutex> lock(mutex_);
  records_[r.parameters] = r;
  // Append and close at once: a killed run loses at most the line being written.
  std::ofstream out(file_, std::ios::app);
  out << j.dump() << "\n";
  out.close();
  if (!out) throw bridge::WriteError(file_.string(), "evaluation " + std::to_string(r.id) + " could not be logged");
}

long long EvaluationLog::nextId() {
  std::lock_guard<std::mutex> lock(mutex_);
  return next_id_++;
}

std::vector<EvaluationRecord> EvaluationLog::records() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<EvaluationRecord> out;
  for (const auto& [p, r] : records_) out.push_back(r);
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
  return out;
}

// ---------------------------------------------------------------- the loop

namespace {

struct Interrupted : std::runtime_error {
  Interrupted() : std::runtime_error("evaluation budget of this session reached") {}
};

// Everything the evaluations of one calibration share.
struct Loop {
  Loop(const std::vector<Parameter>& p, const Evaluator& e, const CalibrationSettings& s, EvaluationLog& l,
       fs::path root, bridge::Progress* pr)
      : params(p), evaluate(e), settings(s), log(l), scratch_root(std::move(root)), progress(pr) {}
  const std::vector<Parameter>& params;
  const Evaluator& evaluate;
  const CalibrationSettings& settings;
  EvaluationLog& log;
  fs::path scratch_root;
  bridge::Progress* progress = nullptr;
  std::mutex mutex;
  std::condition_variable finished;         // an in-flight evaluation ended
  std::set<std::vector<double>> in_flight;  // points being evaluated now
  long long fresh = 0, reused = 0, failed = 0, done = 0, planned = 0;
  bool interrupted = false;

  // Evaluates at unit-box point u: from the log if it is there, else runs it.
  double operator()(const std::vector<double>& u) {
    std::vector<double> x;
    for (std::size_t i = 0; i < u.size(); ++i) x.push_back(fromUnit(params[i], u[i]));
    EvaluationRecord r;
    {
      // Two searches may ask for the same point at once (a shared start, a
      // converged pair): the second waits for the first and reuses its
      // result, so that a point is never run twice.
      std::unique_lock<std::mutex> lock(mutex);
      for (;;) {
        if (log.find(x, r)) {
          ++reused;
          return r.ok ? r.error : settings.penalty;
        }
        if (in_flight.count(x) == 0) break;
        finished.wait(lock);
      }
      if (settings.max_new_evaluations >= 0 && fresh >= settings.max_new_evaluations) {
        interrupted = true;
        throw Interrupted();
      }
      ++fresh;
      in_flight.insert(x);
    }
    // However this evaluation ends (a log that cannot be written throws),
    // the point leaves in_flight and the searches waiting for it wake up.
    struct InFlight {
      Loop& loop;
      const std::vector<double>& x;
      ~InFlight() {
        {
          std::lock_guard<std::mutex> lock(loop.mutex);
          loop.in_flight.erase(x);
        }
        loop.finished.notify_all();
      }
    } in_flight_guard{*this, x};
    r.id = log.nextId();
    r.parameters = x;
    const fs::path scratch = scratch_root / ("eval_" + std::to_string(r.id));
    const auto t0 = std::chrono::steady_clock::now();
    try {
      fs::remove_all(scratch);
      fs::create_directories(scratch);
      r.error = evaluate(x, scratch);
      if (!std::isfinite(r.error)) r.ok = false, r.message = "objective is not finite";
    } catch (const std::exception& e) {
      r.ok = false;
      r.message = e.what();
    } catch (...) {
      r.ok = false;
      r.message = "unknown exception";
    }
    r.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!r.ok) r.error = settings.penalty;
    if (!settings.keep_evaluation_folders) {
      std::error_code ec;
      fs::remove_all(scratch, ec);
    }
    log.append(r);
    std::lock_guard<std::mutex> lock(mutex);
    if (!r.ok) ++failed;
    ++done;
    if (progress) progress->update(static_cast<double>(done), static_cast<double>(planned), done);
    return r.error;
  }
};

// Runs task(i) for i in [0, n) on up to `threads` threads.
template <class Task>
void parallelFor(std::size_t n, int threads, Task task) {
  std::atomic<std::size_t> next{0};
  const auto worker = [&] {
    for (std::size_t i = next++; i < n; i = next++) task(i);
  };
  const std::size_t workers = std::min<std::size_t>(n, static_cast<std::size_t>(std::max(1, threads)));
  std::vector<std::thread> pool;
  for (std::size_t w = 1; w < workers; ++w) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
}

// Seeded Latin hypercube in the unit box (the same points on every platform:
// our own mapping of the 64-bit engine, no std distributions).
std::vector<std::vector<double>> latinHypercube(std::size_t n, std::size_t dims, unsigned long seed) {
  std::mt19937_64 rng(seed);
  const auto uniform = [&] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
  std::vector<std::vector<double>> pts(n, std::vector<double>(dims));
  for (std::size_t d = 0; d < dims; ++d) {
    std::vector<std::size_t> perm(n);
    for (std::size_t i = 0; i < n; ++i) perm[i] = i;
    for (std::size_t i = n; i > 1; --i) std::swap(perm[i - 1], perm[static_cast<std::size_t>(rng() % i)]);
    for (std::size_t i = 0; i < n; ++i) pts[i][d] = (static_cast<double>(perm[i]) + uniform()) / static_cast<double>(n);
  }
  return pts;
}

double nloptCallback(unsigned n, const double* u, double* /*grad*/, void* data) {
  auto& loop = *static_cast<Loop*>(data);
  try {
    return loop(std::vector<double>(u, u + n));
  } catch (const Interrupted&) {
    throw nlopt::forced_stop();  // NLopt's C++ wrapper turns this into a clean stop
  }
}

}  // namespace

std::vector<std::vector<double>> initialPopulation(const std::vector<Parameter>& params,
                                                   const CalibrationSettings& settings) {
  std::vector<std::vector<double>> out;
  for (const auto& u : latinHypercube(settings.initial_samples, params.size(), settings.seed)) {
    std::vector<double> x;
    for (std::size_t i = 0; i < u.size(); ++i) x.push_back(fromUnit(params[i], u[i]));  // (as Loop converts it)
    out.push_back(std::move(x));
  }
  return out;
}

CalibrationResult calibrate(const std::vector<Parameter>& params, const Evaluator& evaluate,
                            const CalibrationSettings& settings, EvaluationLog& log, const fs::path& scratch_root,
                            bridge::Progress* progress) {
  const auto t0 = std::chrono::steady_clock::now();
  Loop loop{params, evaluate, settings, log, scratch_root, progress};
  loop.planned = static_cast<long long>(settings.initial_samples + settings.starts * settings.local_max_evaluations);
  const std::size_t dims = params.size();
  CalibrationResult result;

  // Stage 1: the population, in parallel.
  const auto samples = latinHypercube(settings.initial_samples, dims, settings.seed);
  std::vector<double> errors(samples.size(), std::numeric_limits<double>::infinity());
  parallelFor(samples.size(), settings.threads, [&](std::size_t i) {
    try {
      errors[i] = loop(samples[i]);
    } catch (const Interrupted&) {
    }
  });

  // Stage 2: local searches from the best distinct samples, in parallel.
  std::vector<std::size_t> order(samples.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return errors[a] < errors[b]; });
  std::vector<std::vector<double>> starts;
  for (std::size_t i : order)
    if (starts.size() < settings.starts && errors[i] < settings.penalty) starts.push_back(samples[i]);
  result.local_status.assign(starts.size(), "");
  if (!loop.interrupted) {
    parallelFor(starts.size(), settings.threads, [&](std::size_t s) {
      nlopt::opt opt(static_cast<nlopt::algorithm>(nlopt_algorithm_from_string(settings.local_algorithm.c_str())),
                     static_cast<unsigned>(dims));
      opt.set_lower_bounds(std::vector<double>(dims, 0.0));
      opt.set_upper_bounds(std::vector<double>(dims, 1.0));
      opt.set_min_objective(nloptCallback, &loop);
      opt.set_xtol_rel(settings.xtol_rel);
      opt.set_maxeval(settings.local_max_evaluations);
      // A step of about one Latin-hypercube stratum: the sample is that close to its optimum.
      opt.set_initial_step(
          std::vector<double>(dims, 0.5 / static_cast<double>(std::max<std::size_t>(2, samples.size()))));
      std::vector<double> u = starts[s];
      double value = 0.0;
      try {
        const auto r = opt.optimize(u, value);
        result.local_status[s] = r == nlopt::XTOL_REACHED      ? "xtol_reached"
                                 : r == nlopt::MAXEVAL_REACHED ? "maxeval_reached"
                                                               : "converged";
      } catch (const nlopt::forced_stop&) {
        result.local_status[s] = "interrupted";
      } catch (const std::exception& e) {
        result.local_status[s] = std::string("failure: ") + e.what();
      }
    });
  }

  // The best point of everything evaluated, this session or before.
  result.best_error = std::numeric_limits<double>::infinity();
  long long failed_logged = 0;
  for (const auto& r : log.records()) {
    if (!r.ok) ++failed_logged;
    if (r.ok && r.error < result.best_error) result.best_error = r.error, result.best = r.parameters;
  }
  result.new_evaluations = loop.fresh;
  result.reused_evaluations = loop.reused;
  result.failed_evaluations = failed_logged;
  result.interrupted = loop.interrupted;
  result.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace gabion::fitting
