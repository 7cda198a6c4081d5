#pragma once
/// \file
/// Double-twisted hexagonal wire netting (docs/netting.md): one particle per
/// node (each end of a double twist), one wire link per wire segment, the
/// wire law of bridge/laws/wire.hpp. Flat sheets of any size and closed
/// boxes; the links become micro::LinkSpec through linkSpec().
///
/// Geometry of a sheet, in its own frame: twists along y, rows of twists at
/// y = r (a + b) (a: twist length, b: rise of the single wires between rows),
/// even rows with twists at x = 0, D, 2D, ..., odd rows at x = D/2, 3D/2, ...
/// (D: the mesh opening, the distance between the twists of one row). The
/// top node of each twist joins the bottom nodes of the two twists of the
/// next row at x -/+ D/2 by single wires, so each mesh is a hexagon D wide and
/// a + 2b high. The side edges x = 0 and x = W carry a selvedge wire through
/// their nodes. A sheet holds whole meshes: its real size is reported.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "bridge/laws/wire.hpp"
#include "micro/scene.hpp"

namespace gabion::micro {

/// Mesh and wire parameters (defaults: 8x10 gabion mesh of 2.7 mm wire).
struct MeshSpec {
  double opening_m = 0.08;       ///< D, distance between the twists of one row
  double twist_length_m = 0.04;  ///< a, length of a double twist
  double wire_rise_m = 0.03;     ///< b; the mesh height is a + 2b (100 mm for 8x10)
  double wire_diameter_m = 0.0027;
  double selvedge_diameter_m = 0.0034;
  double lacing_diameter_m = 0.0022;
  bridge::WireStressStrain table = bridge::defaultWireTable();
  bridge::DoubleTwistParams twist;
  double steel_density_kg_m3 = 7850.0;
  /// Contact radius of a node (m); 0: 4 x the wire diameter (10.8 mm for 2.7 mm wire).
  double node_radius_m = 0.0;
  /// Mass of every node (kg); 0: the wire it carries (half of each of its links).
  double node_mass_kg = 0.0;
  /// Extra nodes evenly along every single wire (0: nodes at the twists'
  /// ends only), so that the rock meets the wire between the twists.
  int wire_beads = 0;
  /// The wires bend as beams clamped in their nodes (single wires, twists,
  /// selvedges; lacing stays a pin-jointed tie): bridge/laws/wire_beam.hpp,
  /// E and the yield stress from the table's first point. false: the
  /// paper's pin-jointed netting.
  bool bending = false;
  /// Mass scaling of the nodes (>= 1, SphereSpec::mass_scale): their inertia
  /// times this, their weight unchanged; a larger stable time step for a
  /// small error in the dynamics (docs/netting.md, Time step).
  double node_mass_scale = 1.0;

  double nodeRadius() const { return node_radius_m > 0.0 ? node_radius_m : 4.0 * wire_diameter_m; }
};

enum class WireKind : std::uint8_t { Single, DoubleTwist, Selvedge, Lacing };
const char* wireKindName(WireKind kind);

struct NettingLink {
  std::uint32_t a = 0, b = 0;  ///< node indices
  WireKind kind = WireKind::Single;
  double rest_length_m = 0.0;
};

/// A generated netting: nodes, links, masses.
struct Netting {
  std::vector<Vec3> node_m;
  std::vector<double> node_mass_kg;
  /// Moment of inertia of every node (kg m^2): the wire pieces it carries,
  /// each half of a link turning about the node as a rod about its end.
  std::vector<double> node_inertia_kg_m2;
  double node_radius_m = 0.0;
  std::vector<NettingLink> links;
  /// A flat sheet: the nodes of its first row's bottom (y = 0) and of its last
  /// row's top (y = length), each in increasing x; its real size.
  std::vector<std::uint32_t> bottom_edge, top_edge;
  double width_m = 0.0, length_m = 0.0;
  /// A box: the nodes of each face (bottom z = 0, top z = edge, front y = 0,
  /// back y = edge, left x = 0, right x = edge); nodes on an edge are in two.
  std::vector<std::vector<std::uint32_t>> faces;
};

/// A flat sheet of whole meshes within width_m (x) by length_m (y, along the
/// twists), in the z = 0 plane with its corner at the origin. Throws
/// std::invalid_argument when not even one mesh fits.
Netting flatSheet(const MeshSpec& mesh, double width_m, double length_m);

/// A closed box of netting, the cube [0, edge]^3: six faces of whole meshes
/// (the nearest numbers of meshes, each face's sheet stretched or shrunk to
/// the edge, a few per cent), twists along y on the bottom and top and along
/// z on the sides. Where two faces meet, nodes closer than two node radii
/// become one (a shared node) and every other edge node is laced (a lacing
/// wire) to the nearest edge node of the other face. Rest lengths are the
/// generated distances: the box is stress free. `open_top`: no top face (a
/// basket, to be filled; faces[1] is then empty). Throws
/// std::invalid_argument when not even one mesh fits.
Netting closedBox(const MeshSpec& mesh, double edge_m, bool open_top = false);

/// Fills in node masses (given, or the wire each node carries, times the
/// mass scale), their moments of inertia (the wire pieces they carry, turning
/// with them; a given node mass spreads over them in proportion) and the
/// radius.
void assignNodeMasses(const MeshSpec& mesh, Netting& net);

/// The engine link of a netting link: a wire of its kind's diameter, a double
/// twist by the twist rule, node indices offset by `first_sphere`.
LinkSpec linkSpec(const MeshSpec& mesh, const NettingLink& link, std::size_t first_sphere);

}  // namespace gabion::micro
