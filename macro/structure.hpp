#pragma once
/// \file
/// The structure of the macro scale: a grid of cells, one node per cell at the
/// cell centre (Bertrand et al. 2006, Scale 2 and Fig. 12), the materials of
/// the cells, the supports, and every interaction between nodes built once
/// from the layout and the law file. Grid axes: x = depth from the front face
/// (the impact direction), y = width, z = height. A cell (i, j, k) spans
/// [i, i+1] x [j, j+1] x [k, k+1] edges; its node sits at the centre.
#include <string>
#include <vector>

#include "bridge/law_file.hpp"
#include "bridge/laws/cell_axial_law.hpp"
#include "bridge/laws/interface_friction_law.hpp"

namespace gabion::macro {

/// Kinematics of the nodes: translations along x only (the paper's assumption:
/// confinement makes lateral motion negligible) or full 3-D translations.
enum class Kinematics { XOnly, ThreeD };

/// How the cells get their material: by rule (the first `front_depth_cells`
/// cells of every row from the front face are `front`, the others `core`) or
/// by an explicit list, one name per cell in node order (x fastest, then y,
/// then z; only cells that exist).
struct MaterialRule {
  std::string front;               ///< rule: material of the front layer
  std::string core;                ///< rule: material of the other cells
  int front_depth_cells = 1;       ///< rule: depth of the front layer (cells)
  std::vector<std::string> cells;  ///< explicit list (used when not empty)
};

/// Supports of the structure.
struct SupportSpec {
  bool fixed_back = true;                         ///< a rigid wall behind the back face
  bool ground_friction = false;                   ///< Coulomb friction of the base cells on the ground
  double ground_friction_coefficient = -1.0;      ///< mu on the ground; < 0: the cell's interface friction
  double ground_tangential_stiffness_N_m = -1.0;  ///< k_t on the ground (N/m); < 0: the cell's interface value
  double gravity_m_s2 = 9.81;                     ///< sets the ground normal force (weight of the column), m/s^2
};

/// The layout of a structure.
struct StructureSpec {
  int nx = 1, ny = 1, nz = 1;           ///< cell counts: depth, width, height
  std::vector<int> front_offset_cells;  ///< per z layer: cells removed at the front (stepped face); empty = 0
  MaterialRule material;                ///< material per cell (empty names: the law file's only material)
  SupportSpec support;
  /// Cells resolved at the fine scale instead (the hybrid structure), by grid
  /// index i + nx (j + ny k): they get no node. A node whose front neighbour
  /// is one meets it at its own front face, so its rear link spans its whole
  /// cell (wholeFrontCellLaw). They must not be in front of a node (the
  /// resolved part is closed towards the front).
  std::vector<int> resolved_cells;
};

/// A node's axial (x) interaction partner that is not a node.
constexpr int kWall = -1;

/// Everything fixed about a structure: nodes, materials and interactions with
/// their laws, built from a layout and a law file. Structure-of-arrays; all
/// handles are indices. The mutable state lives in Model.
struct Structure {
  double edge_m = 0.5;  ///< cell edge (m), common to all materials
  int nx = 0, ny = 0, nz = 0;
  std::vector<int> front_offset_cells;  ///< per z layer

  // Nodes (cells), x fastest then y then z.
  std::vector<int> gi, gj, gk;     ///< grid indices
  std::vector<double> x0, y0, z0;  ///< undeformed node position (m)
  std::vector<double> mass_kg, inv_mass;
  std::vector<int> material;  ///< index into material_names / materials
  std::vector<std::string> material_names;
  std::vector<bridge::CellMaterial> materials;
  std::vector<double> reaction_coefficient;  ///< per node: lateral reaction coefficient of its material

  /// Law tables, indexed by the links below.
  std::vector<bridge::AxialLawParams> axial_laws;
  /// Each axial law as the spring its links evaluate (bridge::cellSpring,
  /// hardening precomputed for the step loop).
  std::vector<bridge::CellSpring> axial_springs;
  /// Each axial law's crushing shortening (m): past it the cell is crushed
  /// beyond its lock-up (crushShortening).
  std::vector<double> axial_crush_m;
  std::vector<bridge::FrictionParams> friction_laws;
  std::vector<double> friction_half_inv_k;  ///< per friction law: 1 / (2 k_t) (m/N)

  /// x-neighbours (a in front of b) and back supports (b == kWall): axial law
  /// in compression; in 3-D also friction on the face (normal = axial force).
  struct AxialLinks {
    std::vector<int> a, b, law, friction;
  } axial;
  /// Lateral neighbours (a at the lower index along `dir`: 1 = y, 2 = z):
  /// friction along x (and, in 3-D, along the other lateral axis) with the
  /// normal force = reaction coefficient x axial force; in 3-D also the
  /// normal spring `law` (the cell law across the face, compression only).
  struct LateralLinks {
    std::vector<int> a, b, dir, law, friction;
  } lateral;
  /// Base cells on the ground (ground friction support).
  struct GroundLinks {
    std::vector<int> node, law, friction;
    std::vector<double> weight_N;  ///< normal force from the column's weight (N)
  } ground;
  /// Front-face elements: the front cell of each (y, z) row, a cube the
  /// boulder can strike through its material's impact law.
  struct FrontElements {
    std::vector<int> node, law;               ///< law: the impact law of the node's material
    std::vector<double> x_min, y_min, z_min;  ///< undeformed cube corner (m); the cube is edge_m wide
    /// Which of the cube's side faces no cell of the structure covers (a
    /// boulder can sink into the cube through them): kOpen* bits.
    std::vector<unsigned char> open_sides;
    static constexpr unsigned char kOpenYMinus = 1, kOpenYPlus = 2, kOpenZMinus = 4, kOpenZPlus = 8;
  } front;
  std::vector<int> back_nodes;  ///< the back cell of each row

  std::size_t nodeCount() const { return mass_kg.size(); }
  /// Node index of grid cell (i, j, k), or -1 where there is no cell.
  int nodeAt(int i, int j, int k) const;
  std::vector<int> node_of;  ///< grid index -> node (-1: none)
};

/// Builds the structure; throws std::invalid_argument with a message naming
/// the offending item (the caller turns it into an InputError on its key).
Structure buildStructure(const StructureSpec& spec, const bridge::LawFile& laws);

/// The axial law of two half cells in series (an x-neighbour pair of two
/// materials): stiffness 2 k_a k_b / (k_a + k_b), the smaller yield force, the
/// same series rule for the hardening and lock-up stiffnesses, the mean of the
/// lock-up shortenings; hardening only if both harden.
/// Equal materials give the material's law unchanged.
bridge::AxialLawParams seriesAxialLaw(const bridge::AxialLawParams& a, const bridge::AxialLawParams& b);
/// Half a cell against a rigid wall: stiffnesses doubled, lock-up shortening
/// halved, the same yield force.
bridge::AxialLawParams halfCellLaw(const bridge::AxialLawParams& a);
/// A cell `factor` times as long as the law's (stiffnesses divided by it,
/// shortenings multiplied): halfCellLaw is factor 0.5. A node whose front
/// face meets a resolved cell takes seriesAxialLaw(cellLengthLaw(a, 2), b)
/// behind it: the whole of its cell and half of the next in series.
bridge::AxialLawParams cellLengthLaw(const bridge::AxialLawParams& a, double factor);

/// A cell is crushed once shortened past its lock-up by this fraction of what
/// remains of it at lock-up: the dense fill itself then gives way, and the
/// one-node-per-cell model no longer describes the structure (an impact's
/// outcome is then `perforated`; docs/macro.md).
constexpr double kCrushFraction = 0.1;
/// Shortening at which a link of law `p` spanning `length_m` crushes:
/// u_L + kCrushFraction (length - u_L); infinity without a lock-up.
double crushShortening(const bridge::AxialLawParams& p, double length_m);

}  // namespace gabion::macro
