#include "bridge/law_file.hpp"

#include <cmath>

#include "bridge/errors.hpp"

namespace gabion::bridge {

using nlohmann::json;

namespace {
const char* modelName(AxialModel m) {
  switch (m) {
    case AxialModel::Bilinear:
      return "bilinear";
    case AxialModel::Densifying:
      return "densifying";
    case AxialModel::Softening:
      return "softening";
    case AxialModel::ElasticPerfectlyPlastic:
      break;
  }
  return "elastic_perfectly_plastic";
}
}  // namespace

void setDefaultLockup(AxialLawParams& p, double edge_m) {
  p.lockup_shortening_m = kDefaultLockupStrain * edge_m;
  p.lockup_stiffness_N_m = kDefaultLockupStiffnessRatio * looseStiffness(p);
}

AxialLawParams readAxialLaw(const JsonReader& r, double edge_m, int version, bool impact) {
  AxialLawParams p;
  const std::string model =
      version >= 2
          ? r.choice("model", impact ? std::vector<std::string>{"elastic_perfectly_plastic", "bilinear", "densifying",
                                                                "softening"}
                                     : std::vector<std::string>{"elastic_perfectly_plastic", "bilinear", "densifying"})
          : r.choice("model", {"elastic_perfectly_plastic", "bilinear"});
  p.model = model == "bilinear"     ? AxialModel::Bilinear
            : model == "densifying" ? AxialModel::Densifying
            : model == "softening"  ? AxialModel::Softening
                                    : AxialModel::ElasticPerfectlyPlastic;
  p.stiffness_N_m = r.number("stiffness_N_m", Check::Positive);
  p.yield_force_N = r.number("yield_force_N", Check::Positive);
  if (p.model == AxialModel::Softening) {
    p.softening_stiffness_N_m = r.number("softening_stiffness_N_m", Check::Positive);
    p.residual_force_N = r.number("residual_force_N", Check::NonNegative);
    p.softening_onset_m = r.optionalNumber("softening_onset_m", Check::NonNegative).value_or(0.0);
    if (p.residual_force_N > p.yield_force_N)
      r.fail("residual_force_N",
             "must not exceed yield_force_N (the peak) (" + std::to_string(p.yield_force_N) + " N)");
  } else {
    for (const char* key : {"softening_stiffness_N_m", "residual_force_N", "softening_onset_m"})
      if (r.has(key)) r.fail(key, "only for the model 'softening'");
  }
  if (impact) {
    p.rate_coefficient_N_s2_m2 = r.optionalNumber("rate_coefficient_N_s2_m2", Check::NonNegative).value_or(0.0);
    p.rate_growth_m = r.optionalNumber("rate_growth_m", Check::NonNegative).value_or(0.0);
    for (const char* key : {"viscosity_N_s_m", "momentum_flux_kg_m", "momentum_flux_growth_m"})
      if (r.has(key))
        r.fail(key, "only for an axial law (a cell pushed by its neighbour); the impact law has its rate term");
  } else {
    p.viscosity_N_s_m = r.optionalNumber("viscosity_N_s_m", Check::NonNegative).value_or(0.0);
    p.momentum_flux_kg_m = r.optionalNumber("momentum_flux_kg_m", Check::NonNegative).value_or(0.0);
    p.momentum_flux_growth_m = r.optionalNumber("momentum_flux_growth_m", Check::NonNegative).value_or(0.0);
    if (r.has("momentum_flux_growth_m") && !(p.momentum_flux_kg_m > 0.0))
      r.fail("momentum_flux_growth_m", "needs momentum_flux_kg_m > 0 (the growth of the flux it sets)");
    for (const char* key : {"rate_coefficient_N_s2_m2", "rate_growth_m"})
      if (r.has(key)) r.fail(key, "only for an impact law (the overstress of the indentation rate)");
  }
  if (hardens(p.model)) {
    p.hardening_stiffness_N_m = r.number("hardening_stiffness_N_m", Check::NonNegative);
    if (p.hardening_stiffness_N_m >= p.stiffness_N_m)
      r.fail("hardening_stiffness_N_m", "must be smaller than stiffness_N_m");
  } else if (r.has("hardening_stiffness_N_m")) {
    r.fail("hardening_stiffness_N_m", "only for the models 'bilinear' and 'densifying'");
  }
  if (version < 2) {
    setDefaultLockup(p, edge_m);
    for (const char* key : {"lockup_shortening_m", "lockup_stiffness_N_m"})
      if (r.has(key)) r.fail(key, "a gabion.law/2 key: set \"format\": \"gabion.law/2\" to give a lock-up");
    return p;
  }
  if (p.model == AxialModel::Densifying) {
    p.densification_onset_m = r.number("densification_onset_m", Check::NonNegative);
    p.densification_stiffness_N_m = r.number("densification_stiffness_N_m", Check::Positive);
  } else {
    for (const char* key : {"densification_onset_m", "densification_stiffness_N_m"})
      if (r.has(key)) r.fail(key, "only for the model 'densifying'");
  }
  setDefaultLockup(p, edge_m);
  p.lockup_shortening_m = r.optionalNumber("lockup_shortening_m", Check::Positive).value_or(p.lockup_shortening_m);
  p.lockup_stiffness_N_m = r.optionalNumber("lockup_stiffness_N_m", Check::Positive).value_or(p.lockup_stiffness_N_m);
  if (p.lockup_shortening_m >= edge_m)
    r.fail("lockup_shortening_m", "must be smaller than the cell edge (" + std::to_string(edge_m) + " m)");
  if (p.model == AxialModel::Densifying && p.densification_onset_m >= p.lockup_shortening_m)
    r.fail("densification_onset_m",
           "must be below lockup_shortening_m (" + std::to_string(p.lockup_shortening_m) + " m)");
  if (r.has("densification")) {
    if (impact) r.fail("densification", "only for an axial law (the compaction of a cell pushed by its neighbour)");
    if (p.model != AxialModel::Densifying) r.fail("densification", "only for the model 'densifying'");
    p.plastic_densification = r.choice("densification", {"elastic", "plastic"}) == "plastic";
    // The compaction is read from the plastic shortening (cell_axial_law.hpp):
    // the densification must start past first yield.
    const double first_yield = p.yield_force_N / p.stiffness_N_m;
    if (p.plastic_densification && p.densification_onset_m < first_yield)
      r.fail("densification",
             "'plastic' needs densification_onset_m at or past first yield, yield_force_N / "
             "stiffness_N_m = " +
                 std::to_string(first_yield) + " m");
  }
  if (r.has("densification_unloading_stiffness_N_m")) {
    if (!p.plastic_densification)
      r.fail("densification_unloading_stiffness_N_m",
             "only with \"densification\": \"plastic\" (the dense part's unloading of a compacted cell)");
    p.densification_unloading_stiffness_N_m = r.number("densification_unloading_stiffness_N_m", Check::Positive);
    if (p.densification_unloading_stiffness_N_m < p.densification_stiffness_N_m)
      r.fail("densification_unloading_stiffness_N_m",
             "must be at least densification_stiffness_N_m (" + std::to_string(p.densification_stiffness_N_m) +
                 " N/m): a softer unloading than loading would give back more than the compaction took");
  }
  return p;
}

json toJson(const AxialLawParams& p) {
  json j;
  j["model"] = modelName(p.model);
  j["stiffness_N_m"] = p.stiffness_N_m;
  j["yield_force_N"] = p.yield_force_N;
  if (hardens(p.model)) j["hardening_stiffness_N_m"] = p.hardening_stiffness_N_m;
  if (p.model == AxialModel::Densifying) {
    j["densification_onset_m"] = p.densification_onset_m;
    j["densification_stiffness_N_m"] = p.densification_stiffness_N_m;
  }
  if (p.model == AxialModel::Softening) {
    j["softening_stiffness_N_m"] = p.softening_stiffness_N_m;
    j["residual_force_N"] = p.residual_force_N;
    j["softening_onset_m"] = p.softening_onset_m;
  }
  if (p.rate_coefficient_N_s2_m2 > 0.0) j["rate_coefficient_N_s2_m2"] = p.rate_coefficient_N_s2_m2;
  if (p.rate_growth_m > 0.0) j["rate_growth_m"] = p.rate_growth_m;
  if (p.plastic_densification) j["densification"] = "plastic";
  if (p.densification_unloading_stiffness_N_m > 0.0)
    j["densification_unloading_stiffness_N_m"] = p.densification_unloading_stiffness_N_m;
  if (p.viscosity_N_s_m > 0.0) j["viscosity_N_s_m"] = p.viscosity_N_s_m;
  if (p.momentum_flux_kg_m > 0.0) j["momentum_flux_kg_m"] = p.momentum_flux_kg_m;
  if (p.momentum_flux_growth_m > 0.0) j["momentum_flux_growth_m"] = p.momentum_flux_growth_m;
  if (std::isfinite(p.lockup_shortening_m)) {  // (a law built without one reads back with the default)
    j["lockup_shortening_m"] = p.lockup_shortening_m;
    j["lockup_stiffness_N_m"] = p.lockup_stiffness_N_m;
  }
  return j;
}

LawFile readLawMaterials(const JsonReader& materials, int version) {
  LawFile out;
  const auto members = materials.members();
  if (members.empty()) materials.failHere("at least one material is required");
  for (const auto& [name, m] : members) {
    CellMaterial c;
    c.edge_m = m.number("edge_m", Check::Positive);
    c.mass_kg = m.number("mass_kg", Check::Positive);
    c.axial = readAxialLaw(m.object("axial"), c.edge_m, version);
    c.lateral.reaction_coefficient = m.object("lateral").number("reaction_coefficient", Check::NonNegative);
    const JsonReader itf = m.object("interface");
    c.interface.friction = itf.number("friction", Check::NonNegative);
    c.interface.tangential_stiffness_N_m = itf.number("tangential_stiffness_N_m", Check::Positive);
    c.impact = readAxialLaw(m.object("impact"), c.edge_m, version, /*impact=*/true);
    if (const auto jl = m.optionalObject("joint")) {
      jl->choice("model", {"power"});
      JointLawParams j;
      j.closure_at_1kN_m = jl->number("closure_at_1kN_m", Check::Positive);
      j.exponent = jl->number("exponent", Check::Positive);
      c.joint = j;
      c.joint_info = json::object();
      if (jl->has("force_range_N")) c.joint_info["force_range_N"] = jl->numbers("force_range_N", Check::NonNegative, 2);
      if (jl->has("provenance")) c.joint_info["provenance"] = jl->raw("provenance");
    }
    const JsonReader prov = m.object("provenance");
    prov.choice("status", {"illustrative", "fitted", "measured"});
    c.provenance = m.raw("provenance");
    out.materials.emplace(name, std::move(c));
  }
  out.version = version;
  return out;
}

LawFile loadLawFile(const std::filesystem::path& path) {
  JsonDocument doc = JsonDocument::load(path);
  const JsonReader root = doc.root();
  const std::string format = root.string("format");
  if (format != "gabion.law/2" && format != "gabion.law/1")
    root.fail("format", "expected 'gabion.law/2' (or the earlier 'gabion.law/1'), got '" + format + "'");
  root.choice("kind", {"cell_laws"});
  LawFile laws = readLawMaterials(root.object("materials"), format == "gabion.law/1" ? 1 : 2);
  if (root.has("description")) root.string("description");
  doc.finish();
  return laws;
}

json toJson(const LawFile& laws) {
  json j;
  j["format"] = "gabion.law/2";
  j["kind"] = "cell_laws";
  json mats = json::object();
  for (const auto& [name, c] : laws.materials) {
    json m;
    m["edge_m"] = c.edge_m;
    m["mass_kg"] = c.mass_kg;
    m["axial"] = toJson(c.axial);
    m["lateral"] = {{"reaction_coefficient", c.lateral.reaction_coefficient}};
    m["interface"] = {{"friction", c.interface.friction},
                      {"tangential_stiffness_N_m", c.interface.tangential_stiffness_N_m}};
    m["impact"] = toJson(c.impact);
    if (c.joint) {
      json jl = c.joint_info.is_object() ? c.joint_info : json::object();
      jl["model"] = "power";
      jl["closure_at_1kN_m"] = c.joint->closure_at_1kN_m;
      jl["exponent"] = c.joint->exponent;
      m["joint"] = jl;
    }
    m["provenance"] = c.provenance;
    mats[name] = m;
  }
  j["materials"] = mats;
  return j;
}

}  // namespace gabion::bridge
