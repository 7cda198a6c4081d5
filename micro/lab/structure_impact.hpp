#pragma once
/// \file
/// `micro.structure`, a structure resolved at the fine scale (docs/resolved.md):
/// nx x ny x nz copies of one cell (a cell file, or a micro.cell case
/// generated first), side by side at the pitch of the cell's outer extent so
/// that neighbouring cells meet through their nettings, on a rigid base and
/// (by default) against a rigid back support, as a macro.impact structure
/// is laid out: x the depth from the front face, y the width, z the height.
/// The stack first settles under its weight; then a spherical boulder
/// strikes the front face along +x. Its force, penetration and contact
/// time, the front and back cells' displacements and the outcome are
/// those of macro.impact, measured on the resolved cells.
#include <array>
#include <functional>
#include <nlohmann/json.hpp>
#include <utility>
#include <vector>

#include "bridge/json_reader.hpp"
#include "bridge/laws/cell_axial_law.hpp"
#include "bridge/run.hpp"
#include "bridge/state_archive.hpp"
#include "micro/engine.hpp"
#include "micro/lab/lab_setup.hpp"

namespace gabion::micro::lab {

bridge::CaseKind structureImpactKind();

/// The most cells resolved at the fine scale in one run (each a few thousand bodies).
constexpr long long kMaxResolvedCells = 1000;

/// A part of a micro.structure resolved at the fine scale, the rest modelled
/// by someone else (the hybrid structure, app/hybrid.cpp): only `cells` are
/// laid out, and every face they share with a cell that is not resolved is
/// a plate (a bounded wall, program Driven) that `drive` moves.
struct StructurePart {
  std::vector<int> cells;  ///< resolved cells, by grid index i + nx (j + ny k); the struck cell among them
  /// A face of a resolved cell that meets a cell not resolved.
  struct Face {
    int cell = 0;   ///< the resolved cell's grid index
    int axis = 0;   ///< 0: x, 1: y, 2: z
    int side = 1;   ///< +1: its face at the upper end along the axis; -1: the lower
    int other = 0;  ///< the grid index of the cell across the face
    /// Cells stacked on this face (an upper face, axis 2 and side +1): while
    /// the part settles its plate presses on the resolved cell with their
    /// weight (the cell file's mass each), a servo along z; 0: it stands
    /// still. In the impact it is driven as every plate.
    int cells_above = 0;
    /// A lower face (axis 2, side -1) whose plate gives: while the part
    /// settles the plate comes down as the top of the cell under it would
    /// under the load on it, along the loading curve of `law` (that cell's
    /// axial law, the confined compression's): a servo that lowers it, at
    /// most 0.5 m/s, while the bodies press on it with more than the law's
    /// force at its descent so far, and never raises it. false: it stands
    /// still. In the impact it is driven as every plate.
    bool gives = false;
    bridge::AxialLawParams law;
    /// The face cut into tiles x tiles plates (each its own Face, the same
    /// cell, axis, side and other), this one tile number `tile` = u + tiles v,
    /// u along the axis after `axis` (cyclically), v along the one after
    /// that; 1: the whole face is one plate.
    int tiles = 1;
    int tile = 0;
  };
  std::vector<Face> faces;
  /// The plates under the resolved cells (lower faces, on macro cells)
  /// stand at the height of a cell's lid, lidClearance under the cell's
  /// extent, where a cell above comes to rest on a real cell; false: at
  /// the extent, which one upright block under the lid sets.
  bool lid_plates = false;
  /// While the part settles, the plates beside its cells (x and y faces)
  /// come down with the cell they touch (its blocks' mean height), as the
  /// macro cell they stand for would sink beside it; false: they stand still.
  bool beside_follow = false;
  /// While the part settles, how the plates it drives (all but those
  /// pressing with the weight above, a servo along z: Face::cells_above)
  /// move in their own planes. Along its normal a plate stands still,
  /// follows or gives as set apart from this.
  enum class InPlane {
    Still,   ///< they stand still in their planes
    Follow,  ///< each moves in its plane with the cell it touches (its blocks' mean move across its normal)
    /// each is free along x and y in its plane, as the macro cell it stands
    /// for would be on the wall's frictionless base: a servo that moves it
    /// with the bodies' tangential push on it, at most 0.5 m/s (that speed
    /// at a push of one cell's weight), so that its friction holds no
    /// horizontal force on the cell; along z (a plate beside) as
    /// beside_follow says
    Free,
  };
  InPlane in_plane = InPlane::Still;
  /// The faces' plates in this order are the engine's Driven walls: each
  /// step, the forces the bodies exert on them (N) in, their displacements
  /// over the step (m) out (Engine::WallDriver). Called in the impact only
  /// (while the part settles the plates stand still, but for those that
  /// carry the weight of cells above, Face::cells_above, those that give,
  /// Face::gives, with beside_follow those beside the cells, and with
  /// in_plane Follow or Free all of them).
  Engine::WallDriver drive;
  /// The largest front and back face displacements (m) of the cells not
  /// resolved, read at each series sample (the summary's face keys take the
  /// larger of both parts).
  std::function<std::pair<double, double>()> faces_moved;
  /// The coupled model's state, into or out of the impact's checkpoints.
  std::function<void(bridge::StateArchive&)> archive;
  /// At each series sample of the impact, with the fine engine after its step.
  std::function<void(const Engine&)> record;
  /// Read at each series sample: not empty when the coupled model has
  /// failed past its range (a cell crushed beyond its lock-up); the impact
  /// then ends `perforated`, with this message.
  std::function<std::string()> failure;
};

/// How far a cell's lid lies under its extent (m): the extent's top less
/// the lid's top, the plane of its netting's top face (the median height of
/// the nodes nearest it, as the lacing finds its faces: cellEdges) plus a
/// node's radius; 0 for a cell without a netting. The clearance a cell
/// stacked on it falls through before it rests on the lid, one upright
/// block under the lid setting the extent (docs/resolved.md, Why a stacked
/// cell sinks).
double lidClearance(const Sample& sample);

/// Checks a micro.structure document run as `part` (the cell file, the
/// scene with the part's plates), as `gabion check` would.
void checkStructurePart(const bridge::JsonDocument& doc, const StructurePart& part);
/// Runs a micro.structure document (a cell file, not a cell case) as
/// `part`: the resolved cells settle between their plates, then the boulder
/// strikes with `part.drive` moving the plates.
bridge::RunOutcome runStructurePart(const bridge::JsonDocument& doc, const StructurePart& part,
                                    const bridge::RunContext& ctx);
/// What running it costs (bridge/cost.hpp).
std::optional<bridge::Estimate> estimateStructurePart(const bridge::JsonDocument& doc, const StructurePart& part);

}  // namespace gabion::micro::lab
