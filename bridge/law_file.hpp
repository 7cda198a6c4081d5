#pragma once
/// \file
/// The law file `gabion.law/1`: the macro cell laws of named materials, written
/// by the fitting and read by the macro model. See docs/formats.md.
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "bridge/json_reader.hpp"
#include "bridge/laws/cell_axial_law.hpp"

namespace gabion::bridge {

/// Lateral reaction: the normal force on a lateral face of a cell is this
/// coefficient times the cell's axial force (CC test, paper Sec. 4).
struct LateralLaw {
  double reaction_coefficient = 0.0;  ///< dimensionless, >= 0
};

/// Inter-cell interface: Coulomb friction with a tangential spring.
struct InterfaceLaw {
  double friction = 0.5;                  ///< Coulomb coefficient (dimensionless)
  double tangential_stiffness_N_m = 0.0;  ///< (N/m)
};

/// The laws of one cell material.
struct CellMaterial {
  double edge_m = 0.5;   ///< cell edge (m)
  double mass_kg = 0.0;  ///< cell mass (kg)
  AxialLawParams axial;  ///< confined compression between x-neighbours
  LateralLaw lateral;
  InterfaceLaw interface;
  AxialLawParams impact;                                 ///< boulder against the front face
  nlohmann::json provenance = nlohmann::json::object();  ///< what it was fitted from, how, error; "status" is required
};

/// A law file: materials by name.
struct LawFile {
  std::map<std::string, CellMaterial> materials;
};

/// Reads an axial/impact law object ({"model", "stiffness_N_m", "yield_force_N",
/// "hardening_stiffness_N_m" for bilinear}).
AxialLawParams readAxialLaw(const JsonReader& r);
nlohmann::json toJson(const AxialLawParams& p);

/// Reads the "materials" object of a law file (or of a case that embeds laws).
LawFile readLawMaterials(const JsonReader& materials);
/// Loads and validates a whole `gabion.law/1` file (throws InputError).
LawFile loadLawFile(const std::filesystem::path& path);
nlohmann::json toJson(const LawFile& laws);

}  // namespace gabion::bridge
