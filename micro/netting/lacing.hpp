#pragma once
/// \file
/// Lacing between neighbouring cells (docs/resolved.md, Lacing): in a built
/// wall every cell is laced to the cells beside, behind and above it along
/// the edges where their faces meet, a wire through the meshes of both
/// nettings. Here a lacing wire joins each edge node of a cell's face to the
/// nearest free edge node of the facing face of its neighbour, at their
/// distance when laced (stress free, tension only, breaking as the
/// netting's wires: bridge/laws/wire.hpp).
///
/// The faces of a cell's netting are found from its nodes alone (a cell file
/// keeps nodes and wires, not faces): each face is the plane at the median
/// coordinate of the nodes nearest to it, found by a few rounds of
/// assigning nodes to the nearest plane, starting from the nodes' extent
/// (the median, not the extent: the lid of a filled cell is far from flat,
/// one upright block lifting it by tens of millimetres). An edge node of a
/// face lies within a band of that face's plane and of a plane across it.
#include <array>
#include <cstdint>
#include <vector>

#include "bridge/laws/wire.hpp"
#include "micro/scene.hpp"

namespace gabion::micro {

/// Face numbers: axis + 3 side, side 0 at the lower end along the axis (x-,
/// y-, z-), 1 at the upper (x+, y+, z+).
constexpr int faceIndex(int axis, int upper) {
  return axis + 3 * upper;
}

/// Where a cell's netting nodes lie, found from the cell's spheres alone.
struct CellEdges {
  /// Per sphere of the cell: bit f set when the sphere is a netting node (an
  /// end of a link) within `band` of face f's plane; 0 for every other sphere.
  std::vector<std::uint8_t> faces;
  std::array<double, 6> plane{};  ///< each face's plane: its coordinate along its axis (m)
  double band_m = 0.0;

  /// Whether sphere k is an edge node of face f: near f's plane and near a
  /// plane across it.
  bool onEdgeOf(std::size_t k, int f) const {
    const std::uint8_t m = faces[k], across = static_cast<std::uint8_t>(0x3F & ~((1u << (f % 3)) | (8u << (f % 3))));
    return (m >> f & 1u) != 0 && (m & across) != 0;
  }
};

/// The edges of `cell`'s netting (its spheres joined by links), each face's
/// plane and the nodes within `band_m` of each (> 0).
CellEdges cellEdges(const Scene& cell, double band_m);

struct LacingParams {
  double wire_diameter_m = 0.0022;  ///< the netting's default lacing wire (micro/netting/mesh.hpp)
  bridge::WireStressStrain table = bridge::defaultWireTable();
  /// Nodes further apart than this when laced are not joined (m).
  double max_gap_m = 0.05;
  /// A lacing wire's rest length is at least this (m): nodes laced closer
  /// are slack until they are this far apart.
  double min_length_m = 0.0;
  /// > 0: each wire is pulled tight with this tension (N) from where it was
  /// laced, down to min_length_m (LinkSpec::pull_force_N).
  double pull_N = 0.0;
};

/// What lacing two faces made: its links, and the edge nodes left without
/// one (no free node of the other face within max_gap_m).
struct LacedFaces {
  std::vector<LinkSpec> links;
  std::size_t unlaced = 0;
};

/// What lacing a face to a plate made: the anchors (spheres that ride the
/// plate) and their wires are in the scene; `unlaced`, the edge nodes over
/// the plate further than max_gap_m from their anchor.
struct LacedPlate {
  std::size_t links = 0, unlaced = 0;
};

/// Laces the edge nodes of face `face` of a cell (its spheres those of
/// `edges`' cell, from `first` in `scene`, where they are now) to the plate
/// `wall` of `scene` (a bounded wall, standing for the neighbouring cell's
/// netting): each edge node over the plate's rectangle, and not yet
/// `taken` (a face cut in tiles: one plate each), is joined to an anchor,
/// a fixed sphere of the node's radius in contact group `anchor_group`
/// (which should touch nothing) that rides the plate
/// (SphereSpec::rides_wall), where the neighbour's node would stand: at the
/// node's projection on the plate, one node radius behind it. Anchors are
/// appended to scene.spheres, their wires to scene.links.
LacedPlate lacePlate(Scene& scene, const CellEdges& edges, std::size_t first, int face, std::size_t wall,
                     int anchor_group, const LacingParams& params, std::vector<bool>& taken);

/// Laces the edge nodes of face `face` of a cell to the plate `wall`, as
/// lacePlate, but as the wall's lacing would join them to a neighbouring
/// copy of the cell: the neighbour's facing edge nodes are this cell's own
/// edge nodes of the opposite face, where they are now, one `pitch_m` (the
/// layout's cell pitch along the face's axis) over, and the two faces are
/// paired as laceFaces pairs two cells' (nearest first, each node once,
/// within max_gap_m). Each pair's anchor stands at the neighbour's node and
/// rides the plate. So a face on a plate gets the wires a face between two
/// resolved cells gets, not one per edge node. `taken` and `taken_across`
/// (this face's nodes and the stand-in's) carry over the tiles of one face.
LacedPlate lacePlateAsNeighbour(Scene& scene, const CellEdges& edges, std::size_t first, int face, std::size_t wall,
                                int anchor_group, const LacingParams& params, double pitch_m, std::vector<bool>& taken,
                                std::vector<bool>& taken_across);

/// Laces the face of cell a at the upper end along `axis` to the facing face
/// of cell b (its neighbour along +axis): the cells' spheres are those of
/// `edges`' cell, starting at `first_a` and `first_b` in `scene`, where they
/// are now. Pairs are taken nearest first, each node in one lacing link at
/// most, ties in index order: the same links for the same scene.
LacedFaces laceFaces(const Scene& scene, const CellEdges& edges, std::size_t first_a, std::size_t first_b, int axis,
                     const LacingParams& params);

}  // namespace gabion::micro
