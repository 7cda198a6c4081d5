#include "app/resolved.hpp"

#include <cmath>
#include <filesystem>
#include <sstream>

#include "app/hybrid.hpp"
#include "app/registry.hpp"
#include "app/sub_case.hpp"
#include "bridge/cost.hpp"
#include "bridge/errors.hpp"
#include "bridge/law_file.hpp"
#include "bridge/manifest.hpp"
#include "bridge/output.hpp"
#include "bridge/plot.hpp"

namespace gabion::app {
namespace {

namespace fs = std::filesystem;
using bridge::Check;
using bridge::JsonDocument;
using bridge::JsonReader;
using nlohmann::json;

/// The keys both runs report, compared.
const std::vector<std::string>& comparedKeys() {
  static const std::vector<std::string> keys = {"peak_force_N", "max_penetration_m", "contact_duration_s",
                                                "max_back_face_displacement_m"};
  return keys;
}

/// The keys the resolved run and its hybrids report beyond those, compared
/// between them alone: the contact's end above the boulder's weight (the
/// macro twin's boulder has no weight along x).
const std::vector<std::string>& fineKeys() {
  static const std::vector<std::string> keys = {"contact_duration_above_weight_s"};
  return keys;
}

/// The keys a hybrid is compared on with the resolved run: both lists.
const std::vector<std::string>& hybridKeys() {
  static const std::vector<std::string> keys = [] {
    std::vector<std::string> k = comparedKeys();
    k.insert(k.end(), fineKeys().begin(), fineKeys().end());
    return k;
  }();
  return keys;
}

/// (m - a) / |a|: m's error relative to a, NaN where either is not a number or a is 0.
double relativeError(double a, double m) {
  return std::isfinite(a) && std::isfinite(m) && a != 0.0 ? (m - a) / std::fabs(a) : NAN;
}

/// The two sub-cases of a macro.resolved case, as JSON.
struct Plan {
  json twin, resolved;
  std::vector<json> hybrids;  ///< macro.impact cases with "resolve", one per `hybrid/within_m`
  std::vector<double> within_m;
  std::string depth = "reach";     ///< `hybrid/depth`: "whole" resolves every cell behind a front one within reach
  std::string below = "plates";    ///< `hybrid/below`: as a hybrid's `resolve/below` ("plates", "cells", "gives")
  std::string above = "fixed";     ///< `hybrid/above`: "weight" presses the cells above onto the resolved ones
  std::string beside = "fixed";    ///< `hybrid/beside`: "follow" brings the plates beside down with their cells
  std::string in_plane = "still";  ///< `hybrid/in_plane`: "follow" or "free", as a hybrid's `resolve/in_plane`
  std::string across = "fixed";    ///< `hybrid/across`: "gives" lets the plates across x give as their cells would
  double law_edge_m = 0.0;         ///< the laws' cell edge (0: not known)
};

/// The hybrids' settings other than their reach, in words (" through the depth and below", ...).
std::string hybridSettings(const Plan& p) {
  std::string w = p.depth == "whole" ? " through the depth" : "";
  if (p.below == "cells") w += " and below";
  if (p.below == "gives") w += ", plates below giving";
  if (p.above == "weight") w += ", weight above";
  if (p.beside == "follow") w += ", plates beside following";
  if (p.in_plane == "follow") w += ", plates following in plane";
  if (p.in_plane == "free") w += ", plates free along x and y";
  if (p.across == "gives") w += ", plates across x giving";
  return w;
}

fs::path absoluteFrom(const JsonDocument& doc, const std::string& path) {
  const fs::path p(path);
  return p.is_absolute() ? p : fs::absolute(fs::path(doc.file()).parent_path() / p);
}

Plan plan(const JsonDocument& doc) {
  const JsonReader root = doc.root();
  Plan p;
  const fs::path law = absoluteFrom(doc, root.string("law_file"));
  const fs::path cell = absoluteFrom(doc, root.string("cell"));
  const JsonReader st = root.object("structure");
  const JsonReader b = root.object("boulder");
  // The twin: a macro.impact of the same structure and boulder with the laws.
  json boulder = {{"diameter_m", b.number("diameter_m", 0.5, Check::Positive)},
                  {"density_kg_m3", b.number("density_kg_m3", 2600.0, Check::Positive)},
                  {"velocity_m_s", b.number("velocity_m_s", Check::Positive)}};
  p.twin = {{"format", "gabion.case/1"},
            {"kind", "macro.impact"},
            {"law_file", law.string()},
            {"structure", root.raw("structure")},
            {"boulder", boulder},
            {"run", root.has("macro_run") ? root.raw("macro_run") : json{{"kinematics", "x-only"}}}};
  // The resolved structure: its cells and back support; the aim as a
  // fraction of the front face (the resolved cells are as wide as the cell
  // file's extent, the macro's as the laws' edge).
  const std::vector<double> cells = st.numbers("cells", Check::Positive, 3);
  if (cells.size() != 3) st.fail("cells", "expected [x (depth), y (width), z (height)] cell counts");
  json rs = {{"cells", cells}};
  if (const auto sup = st.optionalObject("support")) rs["support"] = {{"back", sup->string("back", "fixed")}};
  json rb = boulder;
  try {
    const bridge::LawFile lf = bridge::loadLawFile(law);
    if (!lf.materials.empty()) p.law_edge_m = lf.materials.begin()->second.edge_m;
  } catch (const bridge::InputError&) {
    // (the twin's check names the law file's fault)
  }
  if (b.has("aim_point_m")) {
    const std::vector<double> aim = b.numbers("aim_point_m", Check::Finite, 2);
    p.twin["boulder"]["aim_point_m"] = aim;
    const double edge = p.law_edge_m;
    if (edge > 0.0 && aim.size() == 2)
      rb["aim_face_fraction"] = {aim[0] / (cells[1] * edge), aim[1] / (cells[2] * edge)};
  }
  p.resolved = {{"format", "gabion.case/1"},
                {"kind", "micro.structure"},
                {"cell", cell.string()},
                {"structure", rs},
                {"boulder", rb}};
  // (the resolved run's own keys, checked by micro.structure: settle, run, materials, ...)
  if (root.has("resolved")) {
    const json& extra = root.raw("resolved");
    if (!extra.is_object()) root.fail("resolved", "expected an object of micro.structure keys");
    for (const auto& [key, value] : extra.items()) p.resolved[key] = value;
  }
  // The hybrids: the twin with the cells near the aim resolved as the
  // resolved structure's are (the same cell, the same micro keys).
  if (const auto h = root.optionalObject("hybrid")) {
    p.within_m = h->numbers("within_m", Check::NonNegative, 1);
    p.depth = h->choice("depth", {"reach", "whole"}, "reach");
    p.below = h->choice("below", {"plates", "cells", "gives"}, "plates");
    p.above = h->choice("above", {"fixed", "weight"}, "fixed");
    p.beside = h->choice("beside", {"fixed", "follow"}, "fixed");
    p.in_plane = h->choice("in_plane", {"still", "follow", "free"}, "still");
    p.across = h->choice("across", {"fixed", "gives"}, "fixed");
    for (const double w : p.within_m) {
      json c = p.twin;
      json resolve = {{"cell", cell.string()}, {"within_m", w},      {"depth", p.depth},       {"below", p.below},
                      {"above", p.above},      {"beside", p.beside}, {"in_plane", p.in_plane}, {"across", p.across}};
      for (const auto& [key, value] : p.resolved.items())
        if (key != "format" && key != "kind" && key != "cell" && key != "structure" && key != "boulder")
          resolve[key] = value;
      c["resolve"] = resolve;
      p.hybrids.push_back(c);
    }
  }
  // (a lacing to the plates is the hybrids': the wall resolved whole has no plates)
  if (json* l = p.resolved.contains("lacing") ? &p.resolved["lacing"] : nullptr; l && l->is_object())
    l->erase("to_plates"), l->erase("plate_partners");
  return p;
}

/// A sub-case as a document named after the user's file and the part
/// (errors then name both), checked by its kind.
JsonDocument subDocument(const JsonDocument& doc, const json& value, const std::string& part) {
  return JsonDocument(value, doc.file() + " (" + part + ")");
}

/// Every part of the case with its name: the twin, the resolved structure, the hybrids.
std::vector<std::pair<const json*, std::string>> parts(const Plan& p) {
  std::vector<std::pair<const json*, std::string>> out = {{&p.twin, "macro_twin"}, {&p.resolved, "resolved"}};
  for (std::size_t k = 0; k < p.hybrids.size(); ++k) out.emplace_back(&p.hybrids[k], "hybrid_" + std::to_string(k));
  return out;
}

void check(const JsonDocument& doc) {
  const Plan p = plan(doc);
  for (const auto& [value, part] : parts(p)) {
    const JsonDocument sub = subDocument(doc, *value, part);
    checkCase(sub).check(sub);
    sub.finish();
  }
}

std::optional<bridge::Estimate> estimate(const JsonDocument& doc) {
  const Plan p = plan(doc);
  bridge::Estimate total;
  for (const auto& [value, part] : parts(p)) {
    const JsonDocument sub = subDocument(doc, *value, part);
    const bridge::CaseKind& k = checkCase(sub);
    if (!k.estimate) continue;
    const auto e = k.estimate(sub);
    if (!e) return std::nullopt;
    bridge::addRun(total, *e);
  }
  return total;
}

/// A part's run: its summary, wall time, and how it ended.
/// Runs a sub-case into `dir` (its case.json, summary.json and manifest).
SubCase runPart(const std::string& name, const json& value, const bridge::RunContext& parent, const fs::path& dir) {
  fs::create_directories(dir);
  bridge::beginManifest(dir);
  // (its progress lines say which part they are of: a run of an hour has three)
  const auto& outer = parent.progress_context;
  SubCase part = runSubCase(value, "", parent, dir, [name, outer](double eta_s) {
    return (outer ? outer(eta_s) + " " : std::string()) + "macro.resolved, " + name + ":";
  });
  bridge::writeManifest(dir, bridge::statusName(part.status));
  if (part.status != bridge::RunOutcome::Status::Ok) part.message = name + " (" + dir.string() + "): " + part.message;
  return part;
}

/// A force history from first contact (ms, kN).
bridge::PlotSeries history(const std::string& label, const std::vector<double>& t, const std::vector<double>& f) {
  bridge::PlotSeries s{label, {}, {}, bridge::PlotSeries::Style::Line};
  std::size_t first = 0;
  while (first < f.size() && !(f[first] > 0.0)) ++first;
  if (first == f.size()) return s;
  for (std::size_t k = first > 0 ? first - 1 : 0; k < t.size(); ++k)
    s.x.push_back(1000.0 * (t[k] - t[first])), s.y.push_back(1e-3 * f[k]);
  return s;
}

bridge::RunOutcome run(const JsonDocument& doc, const bridge::RunContext& ctx) {
  const Plan p = plan(doc);
  const SubCase tp = runPart("the macro twin", p.twin, ctx, ctx.outdir / "macro_twin");
  if (tp.status != bridge::RunOutcome::Status::Ok) return {tp.status, tp.message, "", "", {{"macro_twin", tp.summary}}};
  const SubCase rp = runPart("the resolved structure", p.resolved, ctx, ctx.outdir / "resolved");
  if (rp.status != bridge::RunOutcome::Status::Ok) return {rp.status, rp.message, "", "", {{"resolved", rp.summary}}};
  const json &twin = tp.summary, &res = rp.summary;
  const double twin_wall = tp.wall_time_s, res_wall = rp.wall_time_s;
  std::vector<SubCase> hp;  // (a failed hybrid is reported, and the others still run)
  for (std::size_t k = 0; k < p.hybrids.size(); ++k)
    hp.push_back(
        runPart("hybrid " + std::to_string(k), p.hybrids[k], ctx, ctx.outdir / ("hybrid_" + std::to_string(k))));

  bridge::RunOutcome out;
  json& r = out.results;
  json macro = json::object(), error = json::object();
  std::vector<double> resolved_value, macro_value, rel;
  const auto number = [](const json& j, const std::string& key) {
    const auto it = j.find(key);
    return it != j.end() && it->is_number() ? it->get<double>() : NAN;
  };
  for (const std::string& key : comparedKeys()) {
    const double a = number(res, key), m = number(twin, key);
    resolved_value.push_back(a), macro_value.push_back(m);
    rel.push_back(relativeError(a, m));
    r[key] = a;
    macro[key] = m;
    error[key] = rel.back();
  }
  for (const std::string& key : fineKeys()) r[key] = number(res, key);
  r["outcome"] = res.value("outcome", "unknown");
  r["wall_time_s_resolved"] = res_wall;
  // (parts resumed from checkpoints: the time their stopped runs stepped, bridge/run.hpp)
  double before_resume_s = bridge::wholeWallTime(0.0, twin) + bridge::wholeWallTime(0.0, res);
  for (const SubCase& h : hp) before_resume_s += bridge::wholeWallTime(0.0, h.summary);
  if (before_resume_s > 0.0) r[bridge::kWallTimeBeforeResume] = before_resume_s;
  macro["outcome"] = twin.value("outcome", "unknown");
  macro["wall_time_s"] = twin_wall;
  r["macro_twin"] = macro;
  r["relative_error"] = error;
  r["same_outcome"] = r["outcome"] == macro["outcome"];
  r["wall_time_s_macro"] = twin_wall;
  r["speed_up"] = twin_wall > 0.0 ? res_wall / twin_wall : NAN;
  json hybrids = json::array();
  for (std::size_t k = 0; k < hp.size(); ++k) {
    const json& h = hp[k].summary;
    json row = {{"within_m", p.within_m[k]}, {"depth", p.depth},
                {"below", p.below},          {"above", p.above},
                {"beside", p.beside},        {"in_plane", p.in_plane},
                {"across", p.across},        {"folder", "hybrid_" + std::to_string(k)}};
    if (hp[k].status != bridge::RunOutcome::Status::Ok) {
      row["status"] = "failed";
      row["message"] = hp[k].message;
      hybrids.push_back(row);
      continue;
    }
    json herr = json::object();
    for (const std::string& key : hybridKeys()) {
      const double a = number(res, key), m = number(h, key);
      row[key] = m;
      herr[key] = relativeError(a, m);
    }
    const json info = h.value("hybrid", json::object());
    row["status"] = "ok";
    row["outcome"] = h.value("outcome", "unknown");
    row["relative_error"] = herr;
    row["resolved_cells"] = info.value("resolved_cells", json::array()).size();
    row["interfaces"] = info.value("interfaces", json::array()).size();
    row["balance_rel_error"] = info.value("balance_rel_error", NAN);
    row["interface_mismatch_J"] = info.value("interface_mismatch_J", NAN);
    row["wall_time_s"] = hp[k].wall_time_s;
    row["speed_up"] = hp[k].wall_time_s > 0.0 ? res_wall / hp[k].wall_time_s : NAN;
    hybrids.push_back(row);
  }
  if (!hp.empty()) r["hybrids"] = hybrids;
  json warnings = json::array();
  if (const auto w = cellSizeMismatch(p.law_edge_m, res, "the macro twin")) warnings.push_back(*w);
  // (the twin stands at rest: a resolved wall still coming down is not the structure it stands for)
  if (!res.value("settled", true)) {
    const json settle = res.value("settle", json::object());
    std::ostringstream w;
    w.precision(3);
    w << "the resolved wall was struck before it came to rest (its centre of mass coming down at "
      << 1e3 * settle.value("descent_speed_m_s", NAN)
      << " mm/s, resolved/summary.json): the comparison includes its slump; lengthen resolved.settle."
      << (settle.value("until_at_rest", false) ? "longest_s" : "duration_s");
    warnings.push_back(w.str());
  }
  r["warnings"] = warnings;
  r["resolved"] = {
      {"cells", res.value("cells", json())},
      {"cell_pitch_m", res.value("cell_pitch_m", json())},
      {"bodies", res.value("bodies", json())},
      {"steps", res.value("steps", json())},
      {"dt_s", res.value("dt_s", json())},
      {"energy_balance_rel_error", res.contains("energy") ? res["energy"].value("balance_rel_error", NAN) : NAN}};

  // Both force histories from first contact.
  {
    const bridge::H5Reader a(ctx.outdir / "resolved" / "result.h5"), m(ctx.outdir / "macro_twin" / "result.h5");
    bridge::PlotSpec plot;
    plot.title = "Force on the boulder: resolved cells against the macro twin";
    plot.x_label = "time from first contact (ms)";
    plot.y_label = "force (kN)";
    plot.series = {
        history("resolved (micro.structure)", a.read("/curves/impact/time_s"), a.read("/curves/impact/force_N")),
        history("macro twin (macro.impact)", m.read("/series/time_s"), m.read("/series/boulder_force_N"))};
    for (std::size_t k = 0; k < hp.size(); ++k) {
      if (hp[k].status != bridge::RunOutcome::Status::Ok) continue;
      const bridge::H5Reader h(ctx.outdir / ("hybrid_" + std::to_string(k)) / "result.h5");
      std::ostringstream label;
      const std::size_t n = hybrids[k]["resolved_cells"].get<std::size_t>();
      label << "hybrid, within " << p.within_m[k] << " m" << hybridSettings(p) << " (" << n
            << (n == 1 ? " cell" : " cells") << " resolved)";
      plot.series.push_back(history(label.str(), h.read("/curves/impact/time_s"), h.read("/curves/impact/force_N")));
    }
    bridge::writePlotPng(ctx.outdir / "resolved_vs_macro.png", plot);
  }
  std::ostringstream a;
  a.precision(3);
  a << "resolved against its macro twin (relative error of the twin):\n";
  for (std::size_t k = 0; k < comparedKeys().size(); ++k) {
    a << "  " << comparedKeys()[k] << ": " << resolved_value[k] << " resolved, " << macro_value[k] << " macro (";
    if (std::isfinite(rel[k]))
      a << 100.0 * rel[k] << " %)\n";
    else
      a << "n/a)\n";
  }
  a << "  outcome: " << r["outcome"].get<std::string>() << " resolved, " << macro["outcome"].get<std::string>()
    << " macro\n  wall time: " << res_wall << " s resolved, " << twin_wall << " s macro (the macro twin "
    << res_wall / twin_wall << " times faster)\n";
  for (const json& h : hybrids) {
    a << "  hybrid within " << h["within_m"].get<double>() << " m" << hybridSettings(p) << ": ";
    if (h["status"] != "ok") {
      a << "failed: " << h["message"].get<std::string>() << "\n";
      continue;
    }
    const std::size_t n = h["resolved_cells"].get<std::size_t>();
    a << n << (n == 1 ? " cell" : " cells") << " resolved, " << h["wall_time_s"].get<double>() << " s ("
      << h["speed_up"].get<double>() << " times faster than resolved); error";
    for (const std::string& key : hybridKeys()) {
      const json& e = h["relative_error"][key];
      a << " " << key << " ";
      if (e.is_number())
        a << 100.0 * e.get<double>() << " %";
      else
        a << "n/a";
    }
    a << "; outcome " << h["outcome"].get<std::string>() << "\n";
  }
  out.answer = a.str();
  return out;
}

}  // namespace

bridge::CaseKind resolvedKind() {
  return {"macro.resolved",
          "a structure run resolved at the fine scale and as its one-node-per-cell macro twin, compared "
          "(docs/resolved.md)",
          check, run, estimate};
}

}  // namespace gabion::app
