// The macro.design case kind: the smallest structure (thickness and height in
// cells, front-layer material) that meets the acceptance criteria under the
// design impact, or a table of impacts with their probabilities, each taken
// `impacts` times in a row; its margins, its residual capacity (how many
// design impacts it takes before a criterion fails) and its capacity against
// thickness (docs/macro.md, Design).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include "bridge/cost.hpp"
#include "bridge/curve.hpp"
#include "bridge/errors.hpp"
#include "bridge/output.hpp"
#include "bridge/parallel.hpp"
#include "bridge/plot.hpp"
#include "bridge/rows.hpp"
#include "macro/case_reader.hpp"
#include "macro/criteria.hpp"
#include "macro/runs.hpp"

namespace gabion::macro {

using bridge::Check;
using bridge::InputError;
using bridge::JsonDocument;
using bridge::JsonReader;
using nlohmann::json;

namespace {

/// One impact of the design table.
struct DesignImpact {
  BoulderSpec boulder;
  double probability = 1.0;
};

struct DesignSpec {
  int t_lo = 2, t_hi = 10;  // thickness (cells along x)
  int h_lo = 2, h_hi = 8;   // height (cells along z)
  std::vector<std::string> materials;
  Criteria criteria;
  int repeats = 1;  // design impacts each section must take in a row
  double acceptance_probability = 1.0;
  bool exhaustive = false;
  int residual_max = 10;
  bool capacity_chart = true;
  double capacity_tolerance = 0.02;
};

struct Plan {
  ImpactCase c;
  DesignSpec spec;
  std::vector<DesignImpact> impacts;
  double edge_m = 0.5;
  std::size_t design_impact = 0;  // the most probable (first of equals): residual capacity, capacity chart
};

/// A section: thickness, height, front material (index into spec.materials).
struct Section {
  int t = 0, h = 0, m = 0;
};

/// What the design impacts did to a section.
struct SectionResult {
  Section section;
  bool met = false;
  double probability_met = 0.0;  // sum of the probabilities of the impacts it holds within the criteria
  std::string failed;            // the criterion the most probable failing impact failed ("height", ...)
  double back_face_ratio = 0.0;  // worst over the impacts it holds (met), over all of them (not met)
  double penetration_ratio = 0.0;
  int impacts_run = 0;
  double balance_rel_error = 0.0;
};

int cellsOf(const Plan& p, const Section& s) {
  return s.t * s.h * p.c.structure.ny;
}

// Order of preference: fewer cells, then the front material listed first, then lower.
bool cheaper(const Plan& p, const Section& a, const Section& b) {
  const int ca = cellsOf(p, a), cb = cellsOf(p, b);
  if (ca != cb) return ca < cb;
  if (a.m != b.m) return a.m < b.m;
  return a.h < b.h;
}

std::pair<int, int> readRange(const JsonReader& r, const std::string& key, int fallback_lo, int fallback_hi) {
  if (!r.has(key)) return {fallback_lo, fallback_hi};
  const auto v = r.numbers(key, Check::Finite, 2);
  if (v.size() != 2) r.fail(key, "expected [smallest, largest] in cells");
  for (double x : v)
    if (x != std::floor(x) || x < 1.0 || x > 200.0) r.fail(key, "cell counts must be whole numbers in [1, 200]");
  if (v[0] > v[1])
    r.fail(key, "inverted: the smallest (" + std::to_string(static_cast<int>(v[0])) + ") is above the largest (" +
                    std::to_string(static_cast<int>(v[1])) + ")");
  return {static_cast<int>(v[0]), static_cast<int>(v[1])};
}

// The impacts_csv table: velocity_m_s (required), mass_kg, aim_y_m, aim_z_m, probability.
std::vector<DesignImpact> readImpactTable(const JsonDocument& doc, const BoulderSpec& base) {
  const JsonReader root = doc.root();
  const std::filesystem::path file = std::filesystem::path(doc.file()).parent_path() / root.string("impacts_csv");
  const bridge::CsvTable t =
      bridge::readCsvTable(file, {"velocity_m_s"}, {"mass_kg", "aim_y_m", "aim_z_m", "probability"});
  std::vector<DesignImpact> out;
  const auto has = [&](const char* c) { return t.columns.count(c) != 0; };
  if (has("aim_y_m") != has("aim_z_m"))
    throw InputError(t.source, "line " + std::to_string(t.header_line), "give both aim_y_m and aim_z_m, or neither");
  for (std::size_t i = 0; i < t.rows(); ++i) {
    DesignImpact d{base, 1.0 / static_cast<double>(t.rows())};
    const double v = t.columns.at("velocity_m_s")[i];
    if (!(v > 0.0)) throw InputError(t.source, t.where(i, "velocity_m_s"), "must be > 0");
    d.boulder.velocity_m_s = base.velocity_m_s.normalized() * v;
    if (has("mass_kg")) {
      const double m = t.columns.at("mass_kg")[i];
      if (!(m > 0.0)) throw InputError(t.source, t.where(i, "mass_kg"), "must be > 0");
      d.boulder.setMass(m, false);
    }
    if (has("aim_y_m")) {
      d.boulder.aim_y_m = t.columns.at("aim_y_m")[i];
      d.boulder.aim_z_m = t.columns.at("aim_z_m")[i];
    }
    if (has("probability")) {
      d.probability = t.columns.at("probability")[i];
      if (!(d.probability > 0.0 && d.probability <= 1.0))
        throw InputError(t.source, t.where(i, "probability"), "must be in (0, 1]");
    }
    out.push_back(d);
  }
  return out;
}

Plan plan(const JsonDocument& doc) {
  Plan p;
  const JsonReader root = doc.root();
  if (root.has("impacts") && root.has("impacts_csv"))
    root.fail("impacts_csv", "give either 'impacts' or 'impacts_csv'");
  p.c = readImpactCase(doc, false);
  const StructureSpec& base = p.c.structure;
  if (!base.front_offset_cells.empty())
    root.object("structure").fail("front_offset_cells", "not with macro.design: the design varies the height");
  if (!base.material.cells.empty())
    root.object("structure").object("material").fail("cells", "not with macro.design: give front and core");

  // Cell edge and default aim: from the case's structure.
  try {
    p.edge_m = buildStructure(base, p.c.laws).edge_m;
  } catch (const std::invalid_argument& e) {
    throw InputError(doc.file(), "/structure", e.what());
  }
  const auto [aim_y, aim_z] = defaultAim(base, p.edge_m);

  const JsonReader d = root.object("design");
  DesignSpec& s = p.spec;
  std::tie(s.t_lo, s.t_hi) = readRange(d, "thickness_cells", base.nx, base.nx);
  std::tie(s.h_lo, s.h_hi) = readRange(d, "height_cells", base.nz, base.nz);
  if (d.has("front_materials")) {
    const json& v = d.raw("front_materials");
    if (!v.is_array() || v.empty()) d.fail("front_materials", "expected a non-empty array of material names");
    for (std::size_t i = 0; i < v.size(); ++i) {
      if (!v[i].is_string()) d.fail("front_materials", "entries must be material names");
      const std::string name = v[i].get<std::string>();
      if (p.c.laws.materials.count(name) == 0)
        throw InputError(doc.file(), d.pointer() + "/front_materials/" + std::to_string(i),
                         "material '" + name + "' is not in the law file (" + p.c.law_source + ")");
      s.materials.push_back(name);
    }
  } else {
    s.materials.push_back(base.material.front);
  }
  const JsonReader crit = d.object("criteria");
  s.criteria.max_back_face_m = crit.number("max_back_face_displacement_m", s.criteria.max_back_face_m, Check::Positive);
  s.criteria.max_penetration_m = crit.number("max_penetration_m", s.criteria.max_penetration_m, Check::Positive);
  s.repeats = static_cast<int>(crit.integer("impacts", s.repeats, 1));
  if (s.repeats > 100) crit.fail("impacts", "at most 100 impacts in a row");
  s.acceptance_probability = d.number("acceptance_probability", s.acceptance_probability, Check::Positive);
  if (s.acceptance_probability > 1.0) d.fail("acceptance_probability", "must be in (0, 1]");
  s.exhaustive = d.choice("search", {"bisection", "exhaustive"}, "bisection") == "exhaustive";
  s.residual_max = static_cast<int>(d.integer("residual_capacity_max_impacts", s.residual_max, 1));
  if (s.residual_max > 1000) d.fail("residual_capacity_max_impacts", "at most 1000");
  s.capacity_chart = d.boolean("capacity_chart", s.capacity_chart);
  s.capacity_tolerance = d.number("capacity_tolerance", s.capacity_tolerance, Check::Positive);
  if (s.capacity_tolerance >= 0.5) d.fail("capacity_tolerance", "must be < 0.5");

  // The design impacts: the table of the CSV file, the `impacts` list (with
  // probabilities, equal shares by default) or the boulder alone.
  const BoulderSpec& b0 = p.c.impacts.front();
  if (root.has("impacts_csv")) {
    p.impacts = readImpactTable(doc, b0);
    for (auto& i : p.impacts) i.boulder.gravity_m_s2 = p.c.run.gravity_m_s2;
  } else {
    const auto list = root.has("impacts") ? root.objects("impacts", true) : std::vector<JsonReader>{};
    for (std::size_t i = 0; i < p.c.impacts.size(); ++i) {
      DesignImpact di{p.c.impacts[i], 1.0 / static_cast<double>(p.c.impacts.size())};
      if (i < list.size() && list[i].has("probability")) {
        di.probability = list[i].number("probability", Check::Positive);
        if (di.probability > 1.0) list[i].fail("probability", "must be in (0, 1]");
      }
      if (!p.c.aim_given[i]) di.boulder.aim_y_m = aim_y, di.boulder.aim_z_m = aim_z;
      p.impacts.push_back(di);
    }
  }
  double total = 0.0;
  for (std::size_t i = 0; i < p.impacts.size(); ++i) {
    total += p.impacts[i].probability;
    if (p.impacts[i].probability > p.impacts[p.design_impact].probability) p.design_impact = i;
    const BoulderSpec& b = p.impacts[i].boulder;
    const double width = base.ny * p.edge_m, height = s.h_hi * p.edge_m;
    if (b.aim_y_m < 0.0 || b.aim_y_m > width || b.aim_z_m < 0.0 || b.aim_z_m > height) {
      const std::string where = root.has("impacts_csv") ? "/impacts_csv"
                                : root.has("impacts")   ? "/impacts/" + std::to_string(i) + "/aim_point_m"
                                                        : "/boulder/aim_point_m";
      throw InputError(doc.file(), where,
                       "impact " + std::to_string(i) + " aims outside the largest front face [0, " +
                           std::to_string(width) + "] x [0, " + std::to_string(height) + "] m");
    }
  }
  if (std::abs(total - 1.0) > 1e-6)
    throw InputError(doc.file(), root.has("impacts_csv") ? "/impacts_csv" : "/impacts",
                     "the impacts' probabilities sum to " + std::to_string(total) + ", expected 1");
  const long long sections =
      static_cast<long long>(s.t_hi - s.t_lo + 1) * (s.h_hi - s.h_lo + 1) * static_cast<long long>(s.materials.size());
  if (sections > 20000)
    d.fail("thickness_cells", "the bounds hold " + std::to_string(sections) + " sections: at most 20,000");
  return p;
}

StructureSpec sectionSpec(const Plan& p, const Section& s) {
  StructureSpec spec = p.c.structure;
  spec.nx = s.t;
  spec.nz = s.h;
  spec.material.front = p.spec.materials[static_cast<std::size_t>(s.m)];
  return spec;
}

// Runs every design impact `repeats` times in a row on a fresh section.
SectionResult evaluate(const Plan& p, const Section& sec) {
  SectionResult out;
  out.section = sec;
  const Structure structure = buildStructure(sectionSpec(p, sec), p.c.laws);
  double failed_p = -1.0;
  double all_back = 0.0, all_pen = 0.0;  // worst over every impact run
  for (const DesignImpact& di : p.impacts) {
    std::string failed;
    double back = 0.0, pen = 0.0;
    if (di.boulder.aim_z_m >= sec.h * p.edge_m) {
      failed = "height";  // its centre passes over the top
    } else {
      Model model(structure, p.c.run.kinematics);
      RunSettings run = p.c.run;
      for (int k = 0; k < p.spec.repeats && failed.empty(); ++k) {
        run.relax = p.c.run.relax && k + 1 < p.spec.repeats;  // (at rest for the next impact only)
        const ImpactResult r = runImpact(model, di.boulder, run, k, nullptr);
        ++out.impacts_run;
        if (!r.ok)
          throw bridge::NumericalError(0, 0.0,
                                       "section " + std::to_string(sec.t) + " x " + std::to_string(sec.h) + " (" +
                                           p.spec.materials[static_cast<std::size_t>(sec.m)] + "): " + r.message);
        const Verdict v = judge(r, p.spec.criteria);
        back = std::max(back, v.back_face_ratio);
        pen = std::max(pen, v.penetration_ratio);
        out.balance_rel_error = std::max(out.balance_rel_error, r.balance_rel_error);
        failed = v.failed;
      }
    }
    all_back = std::max(all_back, back);
    all_pen = std::max(all_pen, pen);
    if (failed.empty()) {
      out.probability_met += di.probability;
      out.back_face_ratio = std::max(out.back_face_ratio, back);
      out.penetration_ratio = std::max(out.penetration_ratio, pen);
    } else if (di.probability > failed_p) {
      failed_p = di.probability, out.failed = failed;
    }
  }
  out.met = out.probability_met >= p.spec.acceptance_probability - 1e-12;
  if (out.met) {
    out.failed.clear();
  } else {
    out.back_face_ratio = all_back;
    out.penetration_ratio = all_pen;
  }
  return out;
}

// How many design impacts in a row the section takes with the criteria met
// (up to `max`), and what fails after them.
std::pair<int, std::string> residualCapacity(const Plan& p, const Section& sec, int max) {
  const Structure structure = buildStructure(sectionSpec(p, sec), p.c.laws);
  Model model(structure, p.c.run.kinematics);
  const BoulderSpec& b = p.impacts[p.design_impact].boulder;
  if (b.aim_z_m >= sec.h * p.edge_m) return {0, "height"};
  for (int k = 0; k < max; ++k) {
    const ImpactResult r = runImpact(model, b, p.c.run, k, nullptr);
    if (!r.ok)
      throw bridge::NumericalError(0, 0.0, "residual capacity, impact " + std::to_string(k + 1) + ": " + r.message);
    const Verdict v = judge(r, p.spec.criteria);
    if (!v.met) return {k, v.failed};
  }
  return {max, ""};
}

json margins(const Plan& p, const SectionResult& r) {
  json m = json::object();
  if (std::isfinite(p.spec.criteria.max_back_face_m)) m["back_face"] = 1.0 - r.back_face_ratio;
  if (std::isfinite(p.spec.criteria.max_penetration_m)) m["penetration"] = 1.0 - r.penetration_ratio;
  return m;
}

json toJson(const Plan& p, const SectionResult& r) {
  json j = {{"thickness_cells", r.section.t},
            {"height_cells", r.section.h},
            {"front_material", p.spec.materials[static_cast<std::size_t>(r.section.m)]},
            {"cells", cellsOf(p, r.section)},
            {"met", r.met},
            {"probability_met", r.probability_met},
            {"impacts_run", r.impacts_run},
            {"margins", margins(p, r)}};
  if (!r.failed.empty()) j["failed"] = r.failed;
  return j;
}

}  // namespace

// At most: every section searched (exhaustive: all; bisection: about
// log2 of the thicknesses per material and height) takes every design
// impact `repeats` times, on the largest section; then the residual
// capacity and the capacity chart (a bisection per thickness and material).
std::optional<bridge::Estimate> estimateDesignCase(const JsonDocument& doc) {
  const Plan p = plan(doc);
  const DesignSpec& s = p.spec;
  const Structure largest = buildStructure(sectionSpec(p, {s.t_hi, s.h_hi, 0}), p.c.laws);
  Model probe(largest, p.c.run.kinematics);
  probe.placeBoulder(p.impacts[p.design_impact].boulder);
  const bridge::Estimate one = impactEstimate(p.c.run, largest, probe.criticalTimeStep());
  const double nm = static_cast<double>(s.materials.size()), nh = s.h_hi - s.h_lo + 1.0, nt = s.t_hi - s.t_lo + 1.0;
  const double sections = nm * nh * (s.exhaustive ? nt : std::ceil(std::log2(nt)) + 2.0);
  double impacts = sections * static_cast<double>(p.impacts.size()) * s.repeats + s.residual_max;
  if (s.capacity_chart) impacts += nm * nt * std::ceil(std::log2(1.0 / s.capacity_tolerance) + 4.0);
  bridge::Estimate e = bridge::times(one, impacts);
  e.output_bytes = 1e4 * sections + 1e6;  // (tables and charts; no series)
  return e;
}

void checkDesignCase(const JsonDocument& doc) {
  plan(doc);
}

namespace {

// The search's independent pieces: every section (exhaustive), or per front
// material and height the thinnest section that holds, by bisection over
// the thickness (a thicker section of the same height and material holding
// at least as well).
struct Piece {
  int m = 0, h = 0, t = 0;  // t: the section's thickness (exhaustive only)
};

std::vector<Piece> pieces(const Plan& p) {
  const DesignSpec& s = p.spec;
  std::vector<Piece> out;
  for (int m = 0; m < static_cast<int>(s.materials.size()); ++m)
    for (int h = s.h_lo; h <= s.h_hi; ++h) {
      if (!s.exhaustive) {
        out.push_back({m, h, 0});
        continue;
      }
      for (int t = s.t_lo; t <= s.t_hi; ++t) out.push_back({m, h, t});
    }
  return out;
}

// The sections a piece evaluates, in the order it evaluates them.
std::vector<SectionResult> searchPiece(const Plan& p, const Piece& piece) {
  const DesignSpec& s = p.spec;
  if (s.exhaustive) return {evaluate(p, {piece.t, piece.h, piece.m})};
  std::vector<SectionResult> out;
  out.push_back(evaluate(p, {s.t_hi, piece.h, piece.m}));
  if (!out.back().met || s.t_lo == s.t_hi) return out;
  out.push_back(evaluate(p, {s.t_lo, piece.h, piece.m}));
  if (out.back().met) return out;
  int bad = s.t_lo, good = s.t_hi;
  while (good - bad > 1) {
    const int mid = (bad + good) / 2;
    out.push_back(evaluate(p, {mid, piece.h, piece.m}));
    (out.back().met ? good : bad) = mid;
  }
  return out;
}

json sectionJson(const SectionResult& r) {
  return {{"t", r.section.t},
          {"h", r.section.h},
          {"m", r.section.m},
          {"met", r.met},
          {"probability_met", r.probability_met},
          {"failed", r.failed},
          {"back_face_ratio", r.back_face_ratio},
          {"penetration_ratio", r.penetration_ratio},
          {"impacts_run", r.impacts_run},
          {"balance_rel_error", r.balance_rel_error}};
}

SectionResult sectionOf(const json& j) {
  SectionResult r;
  r.section = {j.at("t").get<int>(), j.at("h").get<int>(), j.at("m").get<int>()};
  r.met = j.at("met").get<bool>();
  r.probability_met = j.at("probability_met").get<double>();
  r.failed = j.at("failed").get<std::string>();
  r.back_face_ratio = j.at("back_face_ratio").get<double>();
  r.penetration_ratio = j.at("penetration_ratio").get<double>();
  r.impacts_run = j.at("impacts_run").get<int>();
  r.balance_rel_error = j.at("balance_rel_error").get<double>();
  return r;
}

bridge::RunOutcome finishDesign(const Plan& p, const std::vector<SectionResult>& evaluated, double search_s,
                                const bridge::RunContext& ctx);

// The search's pieces as rows (bridge/rows.hpp): run anywhere, collected,
// the rest of the case (the choice, margins, residual capacity, the
// capacity chart and report) is made from them as a local run makes it.
class DesignRows final : public bridge::RowPlan {
 public:
  explicit DesignRows(const JsonDocument& doc)
      : p_(plan(doc)),
        pieces_(pieces(p_)),
        cost_s_([this, copy = std::make_shared<JsonDocument>(doc.json(), doc.file())] {
          const auto e = estimateDesignCase(*copy);
          return e ? e->wall_time_s / static_cast<double>(std::max<std::size_t>(1, pieces_.size())) : 1.0;
        }) {}
  std::size_t size() const override { return pieces_.size(); }
  json describe(std::size_t i) const override {
    const Piece& c = pieces_[i];
    json par = {{"front_material", p_.spec.materials[static_cast<std::size_t>(c.m)]}, {"height_cells", c.h}};
    if (p_.spec.exhaustive) par["thickness_cells"] = c.t;
    return {{"parameters", par}, {"seed", nullptr}};
  }
  json run(std::size_t i, const bridge::RunContext&) const override {
    json sections = json::array();
    for (const auto& r : searchPiece(p_, pieces_[i])) sections.push_back(sectionJson(r));
    return {{"ok", true}, {"sections", sections}};
  }
  double costS(std::size_t) const override { return cost_s_(); }
  bridge::RunOutcome assemble(const std::vector<std::optional<json>>& rows, const bridge::RowStats& stats,
                              const bridge::RunContext& ctx) const override {
    std::vector<SectionResult> evaluated;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      if (!rows[i]) continue;
      if (!rows[i]->at("ok").get<bool>())  // (as the local search, which stops there)
        throw bridge::NumericalError(0, 0.0, rows[i]->at("message").get<std::string>());
      for (const auto& j : rows[i]->at("sections")) evaluated.push_back(sectionOf(j));
    }
    if (stats.missing > 0) {  // (no design is chosen from part of the search)
      bridge::RunOutcome out;
      out.results["design"] = nullptr;
      out.results["sections_evaluated"] = evaluated.size();
      out.answer = "macro.design: the search is not complete (" + std::to_string(stats.missing) + " of " +
                   std::to_string(rows.size()) + " rows missing): no section chosen\n";
      return out;
    }
    return finishDesign(p_, evaluated, stats.wall_time_s, ctx);
  }

 private:
  Plan p_;
  std::vector<Piece> pieces_;
  bridge::Lazy<double> cost_s_;
};

}  // namespace

std::shared_ptr<const bridge::RowPlan> designRows(const JsonDocument& doc) {
  return std::make_shared<const DesignRows>(doc);
}

bridge::RunOutcome runDesignCase(const JsonDocument& doc, const bridge::RunContext& ctx) {
  const Plan p = plan(doc);
  const auto t0 = std::chrono::steady_clock::now();
  // The search: its pieces in parallel, each writing only its own slot.
  const std::vector<Piece> all = pieces(p);
  std::vector<std::vector<SectionResult>> per(all.size());
  bridge::Progress progress(ctx, p.spec.exhaustive ? "macro.design (exhaustive)" : "macro.design (bisection)");
  // (under mpirun each piece runs on whichever rank is free, as a row)
  const int workers = ctx.workers != nullptr ? ctx.workers->size() : ctx.threads;
  bridge::runParallel(all.size(), workers, progress, [&](std::size_t i) {
    if (ctx.workers == nullptr) {
      per[i] = searchPiece(p, all[i]);
      return;
    }
    const json a = ctx.workers->call({{"rows", json::array({i})},
                                      {"outdir", std::filesystem::absolute(ctx.outdir).string()},
                                      {"case_digest", ctx.case_digest}});
    const json& row = a.at("results").at(0);
    if (!row.at("ok").get<bool>()) throw bridge::NumericalError(0, 0.0, row.at("message").get<std::string>());
    for (const auto& j : row.at("sections")) per[i].push_back(sectionOf(j));
  });
  std::vector<SectionResult> evaluated;
  for (auto& v : per) evaluated.insert(evaluated.end(), v.begin(), v.end());
  const double search_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return finishDesign(p, evaluated, search_s, ctx);
}

namespace {

bridge::RunOutcome finishDesign(const Plan& p, const std::vector<SectionResult>& evaluated, double search_s,
                                const bridge::RunContext& ctx) {
  const DesignSpec& s = p.spec;
  const int nm = static_cast<int>(s.materials.size());
  const SectionResult* best = nullptr;
  for (const auto& r : evaluated)
    if (r.met && (best == nullptr || cheaper(p, r.section, best->section))) best = &r;
  int impacts_run = 0;
  double worst_balance = 0.0;
  for (const auto& r : evaluated)
    impacts_run += r.impacts_run, worst_balance = std::max(worst_balance, r.balance_rel_error);

  bridge::RunOutcome out;
  json& res = out.results;
  std::ostringstream answer;
  answer.precision(3);
  // The section reported when none holds: the largest of the first material.
  const SectionResult* largest = nullptr;
  for (const auto& r : evaluated)
    if (r.section.t == s.t_hi && r.section.h == s.h_hi && (largest == nullptr || r.section.m < largest->section.m))
      largest = &r;
  Section chart_section{s.t_hi, s.h_hi, 0};
  if (best != nullptr) {
    const Section& b = best->section;
    chart_section = b;
    res["design"] = toJson(p, *best);
    json m = margins(p, *best);
    std::string governing;
    double smallest = INFINITY;
    for (auto it = m.begin(); it != m.end(); ++it)
      if (it.value().get<double>() < smallest) smallest = it.value().get<double>(), governing = it.key();
    res["governing_criterion"] = governing.empty() ? json(nullptr) : json(governing);
    const auto [residual, after] = residualCapacity(p, b, s.residual_max);
    res["residual_capacity_impacts"] = residual;
    res["residual_capacity_is_at_least"] = residual >= s.residual_max;
    if (!after.empty()) res["residual_capacity_governing_criterion"] = after;
    answer << "smallest section: " << b.t << " cells thick x " << b.h << " high (" << cellsOf(p, b) << " cells, front '"
           << s.materials[static_cast<std::size_t>(b.m)] << "')";
    if (!governing.empty())
      answer << "; governing: " << criterionText(governing) << ", margin " << 100.0 * smallest << " %";
    answer << "; it takes " << (residual >= s.residual_max ? "at least " : "") << residual << " design impact"
           << (residual == 1 ? "" : "s") << " in a row";
  } else {
    res["design"] = nullptr;
    const std::string failed = largest != nullptr ? largest->failed : "";
    res["governing_criterion"] = failed.empty() ? json(nullptr) : json(failed);
    answer << "no section within the bounds meets the criteria: the largest, " << s.t_hi << " x " << s.h_hi
           << " cells with front '" << s.materials.front() << "', fails on "
           << (failed.empty() ? std::string("the criteria") : std::string(criterionText(failed)));
  }
  res["answer"] = answer.str();
  res["search"] = s.exhaustive ? "exhaustive" : "bisection";
  res["search_wall_time_s"] = search_s;
  res["sections_evaluated"] = evaluated.size();
  res["impacts_run"] = impacts_run;
  res["balance_rel_error"] = worst_balance;
  res["criteria"] = {{"held", true},
                     {"max_back_face_displacement_m",
                      std::isfinite(s.criteria.max_back_face_m) ? json(s.criteria.max_back_face_m) : json(nullptr)},
                     {"max_penetration_m",
                      std::isfinite(s.criteria.max_penetration_m) ? json(s.criteria.max_penetration_m) : json(nullptr)},
                     {"impacts", s.repeats},
                     {"acceptance_probability", s.acceptance_probability}};
  json impacts = json::array();
  for (const auto& di : p.impacts)
    impacts.push_back({{"velocity_m_s", di.boulder.velocity_m_s.norm()},
                       {"mass_kg", di.boulder.mass_kg},
                       {"energy_J", 0.5 * di.boulder.mass_kg * di.boulder.velocity_m_s.squaredNorm()},
                       {"aim_point_m", {di.boulder.aim_y_m, di.boulder.aim_z_m}},
                       {"probability", di.probability}});
  res["impacts"] = impacts;
  json list = json::array();
  for (const auto& r : evaluated) list.push_back(toJson(p, r));
  res["sections"] = list;

  // Capacity against thickness, at the chosen height, for every front
  // material: the capacity bisection over the design impact's velocity.
  if (s.capacity_chart) {
    const DesignImpact& di = p.impacts[p.design_impact];
    const double v = di.boulder.velocity_m_s.norm(), energy = 0.5 * di.boulder.mass_kg * v * v;
    std::vector<Section> secs;
    for (int m = 0; m < nm; ++m)
      for (int t = s.t_lo; t <= s.t_hi; ++t) secs.push_back({t, chart_section.h, m});
    std::vector<CapacitySearch> caps(secs.size());
    bridge::Progress progress(ctx, "macro.design: capacity against thickness");
    bridge::runParallel(secs.size(), ctx.threads, progress, [&](std::size_t i) {
      const Structure structure = buildStructure(sectionSpec(p, secs[i]), p.c.laws);
      const auto run = [&](double x) {
        CapacityEvaluation ev;
        ev.x = x;
        BoulderSpec b = di.boulder;
        b.velocity_m_s = b.velocity_m_s.normalized() * x;
        ev.energy_J = 0.5 * b.mass_kg * x * x;
        Model model(structure, p.c.run.kinematics);
        RunSettings once = p.c.run;
        once.relax = false;
        ev.result = runImpact(model, b, once, 0, nullptr);
        if (!ev.result.ok) throw bridge::NumericalError(0, 0.0, "capacity chart: " + ev.result.message);
        ev.verdict = judge(ev.result, s.criteria);
        if (b.aim_z_m >= secs[i].h * p.edge_m) ev.verdict = {false, "height", 0.0, 0.0};
        return ev;
      };
      caps[i] = searchCapacity(run, 0.1 * v, 4.0 * v, false, s.capacity_tolerance, 40);
    });
    bridge::PlotSpec plot;
    plot.title = "Capacity against thickness: one impact, " + std::to_string(chart_section.h) + " cells high";
    plot.x_label = "thickness (cells)";
    plot.y_label = "capacity (kJ)";
    json table = json::array();
    double t_first = s.t_lo, t_last = s.t_hi;
    for (int m = 0; m < nm; ++m) {
      bridge::PlotSeries series{
          "front '" + s.materials[static_cast<std::size_t>(m)] + "'", {}, {}, bridge::PlotSeries::Style::LineMarkers};
      for (std::size_t i = 0; i < secs.size(); ++i) {
        if (secs[i].m != m) continue;
        const CapacitySearch& c = caps[i];
        const double cap = c.kind == CapacitySearch::Kind::NoneMet ? 0.0 : c.evaluations[c.good].energy_J;
        series.x.push_back(secs[i].t);
        series.y.push_back(cap / 1e3);
        table.push_back({{"thickness_cells", secs[i].t},
                         {"height_cells", secs[i].h},
                         {"front_material", s.materials[static_cast<std::size_t>(m)]},
                         {"capacity_energy_J", c.kind == CapacitySearch::Kind::NoneMet ? json(nullptr) : json(cap)},
                         {"capacity_is_at_least", c.kind == CapacitySearch::Kind::AllMet}});
      }
      plot.series.push_back(series);
    }
    plot.series.push_back(
        {"design impact energy", {t_first, t_last}, {energy / 1e3, energy / 1e3}, bridge::PlotSeries::Style::Line});
    bridge::writePlotPng(ctx.outdir / "capacity_vs_thickness.png", plot);
    res["capacity_vs_thickness"] = table;
    res["plots"] = {"capacity_vs_thickness.png"};
  }

  // A short report.
  std::ostringstream md;
  md << "# macro.design\n\nCase: `" << ctx.case_file.string() << "`\n\n**" << answer.str() << ".**\n\n";
  md << "Search: " << (s.exhaustive ? "exhaustive" : "bisection over the thickness per material and height") << ", "
     << evaluated.size() << " sections, " << impacts_run << " impacts, " << search_s << " s.\n\n";
  md << "| thickness | height | front | cells | held | P(met) | back face / limit | penetration / limit |\n"
        "|---|---|---|---|---|---|---|---|\n";
  std::vector<SectionResult> sorted = evaluated;
  std::sort(sorted.begin(), sorted.end(),
            [&](const SectionResult& a, const SectionResult& b) { return cheaper(p, a.section, b.section); });
  for (const auto& r : sorted)
    md << "| " << r.section.t << " | " << r.section.h << " | " << s.materials[static_cast<std::size_t>(r.section.m)]
       << " | " << cellsOf(p, r.section) << " | " << (r.met ? "yes" : "no (" + r.failed + ")") << " | "
       << r.probability_met << " | " << r.back_face_ratio << " | " << r.penetration_ratio << " |\n";
  if (s.capacity_chart) md << "\n![capacity against thickness](capacity_vs_thickness.png)\n";
  bridge::writeTextAtomic(ctx.outdir / "report.md", md.str());
  out.answer = "macro.design: " + answer.str() + "\n";
  return out;
}

}  // namespace

}  // namespace gabion::macro
