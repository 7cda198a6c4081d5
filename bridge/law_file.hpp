#pragma once
/// \file
/// The law file `gabion.law/2`: the macro cell laws of named materials, written
/// by the fitting and read by the macro model. Files of version 1 (no lock-up,
/// no densifying model) are still read: their laws get the default lock-up.
/// See docs/formats.md.
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "bridge/json_reader.hpp"
#include "bridge/laws/cell_axial_law.hpp"
#include "bridge/laws/cell_joint_law.hpp"

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
  AxialLawParams impact;                ///< boulder against the front face
  std::optional<JointLawParams> joint;  ///< two cells pressed together (optional)
  nlohmann::json joint_info;            ///< the joint's force_range_N and provenance, as read or fitted (written back)
  nlohmann::json provenance = nlohmann::json::object();  ///< what it was fitted from, how, error; "status" is required
};

/// A law file: materials by name.
struct LawFile {
  std::map<std::string, CellMaterial> materials;
  int version = 2;  ///< format version it was read from (1 or 2)
};

/// The lock-up a law gets when its file does not give one: the fill's densest
/// state is reached at kDefaultLockupStrain of the cell edge, and the dense
/// fill is kDefaultLockupStiffnessRatio times stiffer than the loose one
/// (its stiffest loading tangent, bridge::looseStiffness).
/// 0.25 is the strain that takes the paper's fill porosity 0.436 to 0.25, a
/// dense crushed-rock packing (lockupStrain); docs/formats.md.
constexpr double kDefaultLockupStrain = 0.25;
constexpr double kDefaultLockupStiffnessRatio = 10.0;
/// Axial strain that takes a fill of porosity `porosity` to `densest_porosity`
/// at constant solid volume and cross-section: (n - n_d) / (1 - n_d).
inline double lockupStrain(double porosity, double densest_porosity) {
  return (porosity - densest_porosity) / (1.0 - densest_porosity);
}

/// Reads an axial/impact law object ({"model", "stiffness_N_m", "yield_force_N",
/// "hardening_stiffness_N_m" for bilinear and densifying, "lockup_shortening_m"
/// and "lockup_stiffness_N_m"}; "softening_stiffness_N_m" and
/// "residual_force_N", optionally "softening_onset_m", for softening). `edge_m` sets the default lock-up;
/// version 1 accepts neither the lock-up keys nor the densifying model;
/// only an impact law (`impact`) may soften.
AxialLawParams readAxialLaw(const JsonReader& r, double edge_m, int version = 2, bool impact = false);
nlohmann::json toJson(const AxialLawParams& p);
/// The default lock-up of a law for cells of edge `edge_m` (see above).
void setDefaultLockup(AxialLawParams& p, double edge_m);

/// Reads the "materials" object of a law file (or of a case that embeds laws).
LawFile readLawMaterials(const JsonReader& materials, int version = 2);
/// Loads and validates a whole law file, version 1 or 2 (throws InputError).
LawFile loadLawFile(const std::filesystem::path& path);
nlohmann::json toJson(const LawFile& laws);

}  // namespace gabion::bridge
