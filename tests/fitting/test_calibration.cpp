// The calibration loop with a cheap objective standing in for a DEM run:
// parallel population + local searches, failures logged not fatal, and an
// interrupted calibration that resumes from its log without re-running anything.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <fstream>
#include <iterator>

#include "bridge/errors.hpp"
#include "fitting/calibration.hpp"
#include "tests/support/run_gabion.hpp"

namespace gabion::fitting {
namespace {

const std::vector<Parameter> kParams = {makeParameter("k_n", 1e4, 1e7), makeParameter("friction", 0.1, 1.0)};

// A smooth bowl with its minimum at k_n = 3e5, friction = 0.45.
double bowl(const std::vector<double>& x) {
  const double a = std::log(x[0] / 3e5), b = (x[1] - 0.45) / 0.2;
  return a * a + b * b;
}

CalibrationSettings settings(int threads) {
  CalibrationSettings s;
  s.initial_samples = 10;
  s.starts = 2;
  s.local_max_evaluations = 60;
  s.xtol_rel = 1e-6;
  s.threads = threads;
  s.seed = 5;
  return s;
}

TEST(Calibration, FindsTheMinimumWithParallelEvaluations) {
  const auto dir = testing::scratchDir("calib_min");
  std::atomic<int> calls{0};
  const Evaluator f = [&](const std::vector<double>& x, const std::filesystem::path& scratch) {
    EXPECT_TRUE(std::filesystem::is_directory(scratch));
    ++calls;
    return bowl(x);
  };
  EvaluationLog log(dir / "evaluations.jsonl", "case", {"k_n", "friction"}, false);
  const auto r = calibrate(kParams, f, settings(2), log, dir);
  EXPECT_NEAR(r.best[0], 3e5, 3e5 * 1e-3);
  EXPECT_NEAR(r.best[1], 0.45, 1e-3);
  EXPECT_EQ(r.new_evaluations, calls.load());
  EXPECT_EQ(static_cast<long long>(log.records().size()), r.new_evaluations);
  EXPECT_FALSE(r.interrupted);
  EXPECT_FALSE(std::filesystem::exists(dir / "eval_0")) << "scratch folders are removed";
}

TEST(Calibration, FailedEvaluationsAreLoggedNotFatal) {
  const auto dir = testing::scratchDir("calib_fail");
  const Evaluator f = [&](const std::vector<double>& x, const std::filesystem::path&) {
    if (x[1] > 0.8) throw std::runtime_error("numerical failure: overlap beyond bound");
    if (x[0] > 3e6) return std::nan("");
    return bowl(x);
  };
  EvaluationLog log(dir / "evaluations.jsonl", "case", {"k_n", "friction"}, false);
  const auto r = calibrate(kParams, f, settings(2), log, dir);
  EXPECT_GT(r.failed_evaluations, 0);
  EXPECT_NEAR(r.best[1], 0.45, 1e-3);
  int failed_lines = 0;
  std::ifstream in(dir / "evaluations.jsonl");
  for (std::string line; std::getline(in, line);)
    if (line.find("\"status\":\"failed\"") != std::string::npos) {
      ++failed_lines;
      EXPECT_TRUE(line.find("overlap beyond bound") != std::string::npos ||
                  line.find("not finite") != std::string::npos)
          << line;
    }
  EXPECT_EQ(failed_lines, r.failed_evaluations);
}

TEST(Calibration, InterruptedRunResumesFromItsLog) {
  const auto full_dir = testing::scratchDir("calib_full"), dir = testing::scratchDir("calib_resume");
  std::atomic<int> calls{0};
  const Evaluator f = [&](const std::vector<double>& x, const std::filesystem::path&) {
    ++calls;
    return bowl(x);
  };
  // Reference: one uninterrupted run.
  EvaluationLog full_log(full_dir / "evaluations.jsonl", "case", {"k_n", "friction"}, false);
  const auto full = calibrate(kParams, f, settings(1), full_log, full_dir);
  const int full_calls = calls.exchange(0);

  // Session 1 stops after 7 evaluations (as if killed); session 2 resumes.
  auto s = settings(1);
  s.max_new_evaluations = 7;
  {
    EvaluationLog log(dir / "evaluations.jsonl", "case", {"k_n", "friction"}, true);
    const auto r1 = calibrate(kParams, f, s, log, dir);
    EXPECT_TRUE(r1.interrupted);
    EXPECT_EQ(calls.load(), 7);
  }
  // A half-written line at the end (killed while writing) is ignored.
  { std::ofstream(dir / "evaluations.jsonl", std::ios::app) << "{\"id\": 99, \"param"; }
  s.max_new_evaluations = -1;
  EvaluationLog log(dir / "evaluations.jsonl", "case", {"k_n", "friction"}, true);
  EXPECT_EQ(log.resumed(), 7u);
  const auto r2 = calibrate(kParams, f, s, log, dir);
  EXPECT_FALSE(r2.interrupted);
  EXPECT_EQ(r2.reused_evaluations >= 7, true);
  EXPECT_EQ(calls.load(), full_calls) << "no evaluation is run twice across the two sessions";
  EXPECT_EQ(r2.best, full.best);
  EXPECT_EQ(r2.best_error, full.best_error);
  // The torn line was cut off before session 2 appended to the log: a third
  // session reads every record (the records glued onto it broke the next
  // resume), and a last record that lost only its newline is kept.
  const std::size_t records = static_cast<std::size_t>(full_calls);
  EXPECT_EQ(EvaluationLog(dir / "evaluations.jsonl", "case", {"k_n", "friction"}, true).resumed(), records);
  {
    std::ifstream in(dir / "evaluations.jsonl");
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_EQ(text.back(), '\n');
    text.pop_back();
    std::ofstream(dir / "evaluations.jsonl", std::ios::trunc) << text;
  }
  EXPECT_EQ(EvaluationLog(dir / "evaluations.jsonl", "case", {"k_n", "friction"}, true).resumed(), records);
  EXPECT_EQ(EvaluationLog(dir / "evaluations.jsonl", "case", {"k_n", "friction"}, true).resumed(), records);
}

TEST(Calibration, LogOfAnotherCaseIsRefused) {
  const auto dir = testing::scratchDir("calib_other");
  { EvaluationLog log(dir / "evaluations.jsonl", "case-A", {"k_n", "friction"}, false); }
  EXPECT_THROW(EvaluationLog(dir / "evaluations.jsonl", "case-B", {"k_n", "friction"}, true), bridge::InputError);
  EXPECT_THROW(EvaluationLog(dir / "evaluations.jsonl", "case-A", {"k_n"}, true), bridge::InputError);
  EXPECT_NO_THROW(EvaluationLog(dir / "evaluations.jsonl", "case-A", {"k_n", "friction"}, true));
}

TEST(Calibration, OneParameterLocalSearch) {
  const auto dir = testing::scratchDir("calib_1d");
  const std::vector<Parameter> p = {makeParameter("k_n", 1e4, 1e7)};
  const Evaluator f = [](const std::vector<double>& x, const std::filesystem::path&) {
    const double a = std::log(x[0] / 2e5);
    return a * a;
  };
  for (const char* algo : {"LN_BOBYQA", "LN_SBPLX"}) {
    EvaluationLog log(dir / (std::string(algo) + ".jsonl"), "case", {"k_n"}, false);
    auto s = settings(2);
    s.local_algorithm = algo;
    const auto r = calibrate(p, f, s, log, dir);
    EXPECT_NEAR(r.best[0], 2e5, 2e5 * 1e-3) << algo;
  }
}

}  // namespace
}  // namespace gabion::fitting
