#include "app/sub_case.hpp"

#include <chrono>

#include "app/registry.hpp"
#include "bridge/output.hpp"

namespace gabion::app {

SubCase runSubCase(const nlohmann::json& case_value, const std::string& expected_kind, const bridge::RunContext& parent,
                   const std::filesystem::path& dir, std::function<std::string(double)> progress_context) {
  std::filesystem::create_directories(dir);
  bridge::writeJsonAtomic(dir / "case.json", case_value);
  const bridge::JsonDocument doc = bridge::JsonDocument::load(dir / "case.json");
  const bridge::CaseKind& k = checkCase(doc, expected_kind);
  bridge::RunContext ctx = parent;
  ctx.outdir = dir;
  ctx.case_file = doc.file();
  if (progress_context) ctx.progress_context = std::move(progress_context);
  const auto t0 = std::chrono::steady_clock::now();
  const bridge::RunOutcome ran = k.run(doc, ctx);
  SubCase out;
  const double process_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  out.wall_time_s = bridge::wholeWallTime(process_s, ran.results);
  out.status = ran.status;
  out.message = ran.message;
  out.summary = ran.results;
  out.summary["format"] = "gabion.summary/1";
  out.summary["kind"] = k.kind;
  out.summary["status"] = bridge::statusName(ran.status);
  if (!ran.message.empty()) out.summary["message"] = ran.message;
  out.summary["wall_time_s"] = out.wall_time_s;
  if (ran.results.contains(bridge::kWallTimeBeforeResume)) out.summary["wall_time_this_process_s"] = process_s;
  out.summary["case"] = doc.json();
  bridge::writeJsonAtomic(dir / "summary.json", out.summary);
  return out;
}

}  // namespace gabion::app
