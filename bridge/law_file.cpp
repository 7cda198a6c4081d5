#include "bridge/law_file.hpp"

#include "bridge/errors.hpp"

namespace gabion::bridge {

using nlohmann::json;

AxialLawParams readAxialLaw(const JsonReader& r) {
  AxialLawParams p;
  const std::string model = r.choice("model", {"elastic_perfectly_plastic", "bilinear"});
  p.model = model == "bilinear" ? AxialModel::Bilinear : AxialModel::ElasticPerfectlyPlastic;
  p.stiffness_N_m = r.number("stiffness_N_m", Check::Positive);
  p.yield_force_N = r.number("yield_force_N", Check::Positive);
  if (p.model == AxialModel::Bilinear) {
    p.hardening_stiffness_N_m = r.number("hardening_stiffness_N_m", Check::NonNegative);
    if (p.hardening_stiffness_N_m >= p.stiffness_N_m)
      r.fail("hardening_stiffness_N_m", "must be smaller than stiffness_N_m");
  } else if (r.has("hardening_stiffness_N_m")) {
    r.fail("hardening_stiffness_N_m", "only for model 'bilinear'");
  }
  return p;
}

json toJson(const AxialLawParams& p) {
  json j;
  j["model"] = p.model == AxialModel::Bilinear ? "bilinear" : "elastic_perfectly_plastic";
  j["stiffness_N_m"] = p.stiffness_N_m;
  j["yield_force_N"] = p.yield_force_N;
  if (p.model == AxialModel::Bilinear) j["hardening_stiffness_N_m"] = p.hardening_stiffness_N_m;
  return j;
}

LawFile readLawMaterials(const JsonReader& materials) {
  LawFile out;
  const auto members = materials.members();
  if (members.empty()) materials.failHere("at least one material is required");
  for (const auto& [name, m] : members) {
    CellMaterial c;
    c.edge_m = m.number("edge_m", Check::Positive);
    c.mass_kg = m.number("mass_kg", Check::Positive);
    c.axial = readAxialLaw(m.object("axial"));
    c.lateral.reaction_coefficient = m.object("lateral").number("reaction_coefficient", Check::NonNegative);
    const JsonReader itf = m.object("interface");
    c.interface.friction = itf.number("friction", Check::NonNegative);
    c.interface.tangential_stiffness_N_m = itf.number("tangential_stiffness_N_m", Check::Positive);
    c.impact = readAxialLaw(m.object("impact"));
    const JsonReader prov = m.object("provenance");
    prov.choice("status", {"illustrative", "fitted", "measured"});
    c.provenance = m.raw("provenance");
    out.materials.emplace(name, std::move(c));
  }
  return out;
}

LawFile loadLawFile(const std::filesystem::path& path) {
  JsonDocument doc = JsonDocument::load(path);
  const JsonReader root = doc.root();
  const std::string format = root.string("format");
  if (format != "gabion.law/1") root.fail("format", "expected 'gabion.law/1', got '" + format + "'");
  root.choice("kind", {"cell_laws"});
  LawFile laws = readLawMaterials(root.object("materials"));
  if (root.has("description")) root.string("description");
  doc.finish();
  return laws;
}

json toJson(const LawFile& laws) {
  json j;
  j["format"] = "gabion.law/1";
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
    m["provenance"] = c.provenance;
    mats[name] = m;
  }
  j["materials"] = mats;
  return j;
}

}  // namespace gabion::bridge
