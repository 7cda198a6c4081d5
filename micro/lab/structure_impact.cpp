#include "micro/lab/structure_impact.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>

#include "bridge/errors.hpp"
#include "bridge/output.hpp"
#include "bridge/plot.hpp"
#include "micro/cell/cell_file.hpp"
#include "micro/lab/lab_setup.hpp"
#include "micro/netting/lacing.hpp"
#include "micro/scene_run.hpp"

namespace gabion::micro::lab {
namespace {

using bridge::Check;
using bridge::JsonReader;

constexpr int kBoulderGroup = 2;  // (rock 0, netting 1)
/// The anchors of the lacing tied to a part's plates (lacing.to_plates):
/// points that ride the plates and touch nothing.
constexpr int kPlateAnchorGroup = 3;
constexpr long long kMaxCells = kMaxResolvedCells;
/// A stack whose centre of mass still comes down faster than this (m/s) at
/// the end of its settling has not come to rest: 1.5 mm over an impact of
/// 0.15 s, against penetrations of tenths of a metre (settle.at_rest_m_s).
constexpr double kSettledDescentSpeed = 0.01;

/// How fast the centre of mass of a stack of weight `weight` came down over
/// the last fifth of the samples (t, gravity potential u) so far: the
/// potential's fall over the weight and that time (0 with under two samples).
double descentSpeed(const std::vector<double>& t, const std::vector<double>& u, double weight) {
  if (t.size() < 2 || t.size() != u.size() || weight <= 0.0) return 0.0;
  const std::size_t k = std::min(t.size() - 2, (4 * t.size()) / 5);
  return (u[k] - u.back()) / (weight * (t.back() - t[k]));
}

struct StructureCase {
  LabSetup setup;
  int nx = 1, ny = 1, nz = 1;
  bool fixed_back = true;
  double diameter_m = 0.5, density_kg_m3 = 2600.0, velocity_m_s = 20.0;
  MaterialChange boulder;                    // its contact material: the rock's, with these changes
  std::optional<std::array<double, 2>> aim;  // [y, z] on the front face (m); default: the middle front cell's centre
  std::optional<std::array<double, 2>> aim_fraction;  // or [y, z] as fractions of the face's width and height
  double gap_m = 0.002;                               // between the boulder and the front face at the start
  // The stack settling under its weight before the boulder comes: until its
  // centre of mass comes down slower than at_rest_m_s, for settle_s at least
  // and longest_s at most; or for settle_s exactly (until_at_rest false).
  double settle_s = 0.05;
  bool until_at_rest = true;
  double settle_longest_s = 1.0;
  double at_rest_m_s = kSettledDescentSpeed;
  // At rest also needs the bodies' mass-weighted rms speed below this; 0:
  // not checked (a stack may stop coming down and still sway).
  double at_rest_rms_m_s = 0.0;
  // The boulder aimed, once the stack has settled, at the laid-out aim point
  // (false) or at that point lowered by the struck cell's drop (true): the
  // same place on the cell as laid out, where the macro twin's boulder meets
  // its cell.
  bool aim_settled = false;
  // Cundall's local damping of every material while the stack settles (none:
  // each material's own); the impact runs with the materials' own. (A
  // higher value slows the stack's fall: it comes to rest later and looser.)
  std::optional<double> settle_local_damping;
  double rebound_restitution = 0.05;  // as macro.impact's run.rebound_restitution
  // Neighbouring cells laced along the edges where their faces meet
  // (micro/netting/lacing.hpp), `at_s` into the settling (0: as laid out).
  struct Lacing {
    LacingParams params;
    double at_s = 0.15;
    double edge_band_m = 0.0;  // 0: 1.5 node radii
    // A hybrid's resolved cells also laced to the plates that stand for
    // their macro neighbours (each edge node to a point riding the plate).
    bool to_plates = false;
    // Which edge nodes of a face on a plate get a wire: every one
    // (lacePlate), or those the lacing would pair with a neighbouring copy
    // of the cell (lacePlateAsNeighbour).
    bool plates_as_neighbour = false;
  };
  std::optional<Lacing> lacing;
};

/// `whole`: the structure is resolved whole (a part checks its own cell count).
StructureCase parseCase(const bridge::JsonDocument& doc, bool whole = true) {
  const JsonReader root = doc.root();
  StructureCase c;
  const JsonReader st = root.object("structure");
  const std::vector<double> cells = st.numbers("cells", Check::Positive, 3);
  if (cells.size() != 3 || std::any_of(cells.begin(), cells.end(), [](double n) { return n != std::floor(n); }))
    st.fail("cells", "expected [x (depth), y (width), z (height)] whole cell counts");
  if (whole && cells[0] * cells[1] * cells[2] > static_cast<double>(kMaxCells))
    st.fail("cells", "more than " + std::to_string(kMaxCells) +
                         " cells resolved at the fine scale: resolve a smaller structure, or the part of it the "
                         "boulder strikes");
  c.nx = static_cast<int>(cells[0]), c.ny = static_cast<int>(cells[1]), c.nz = static_cast<int>(cells[2]);
  if (const auto sup = st.optionalObject("support"))
    c.fixed_back = sup->choice("back", {"fixed", "none"}, "fixed") == "fixed";
  const JsonReader b = root.object("boulder");
  c.diameter_m = b.number("diameter_m", c.diameter_m, Check::Positive);
  c.density_kg_m3 = b.number("density_kg_m3", c.density_kg_m3, Check::Positive);
  c.velocity_m_s = b.number("velocity_m_s", c.velocity_m_s, Check::Positive);
  if (c.velocity_m_s > 100.0) b.fail("velocity_m_s", "an impact velocity above 100 m/s is no rockfall");
  if (b.has("aim_point_m")) {
    const std::vector<double> a = b.numbers("aim_point_m", Check::Finite, 2);
    if (a.size() != 2) b.fail("aim_point_m", "expected [y, z] on the front face (m)");
    c.aim = std::array<double, 2>{a[0], a[1]};
  }
  if (b.has("aim_face_fraction")) {
    if (c.aim) b.fail("aim_face_fraction", "give aim_point_m or aim_face_fraction, not both");
    const std::vector<double> a = b.numbers("aim_face_fraction", Check::Fraction, 2);
    if (a.size() != 2) b.fail("aim_face_fraction", "expected [y, z] fractions of the front face's width and height");
    c.aim_fraction = std::array<double, 2>{a[0], a[1]};
  }
  c.gap_m = b.number("initial_gap_m", c.gap_m, Check::NonNegative);
  if (const auto m = b.optionalObject("contact")) c.boulder = parseMaterialChange("boulder", *m);
  if (const auto s = root.optionalObject("settle")) {
    c.settle_s = s->number("duration_s", c.settle_s, Check::NonNegative);
    c.until_at_rest = s->boolean("until_at_rest", c.until_at_rest);
    c.settle_longest_s = s->number("longest_s", c.settle_longest_s, Check::Positive);
    c.at_rest_m_s = s->number("at_rest_m_s", c.at_rest_m_s, Check::Positive);
    c.at_rest_rms_m_s = s->number("at_rest_rms_speed_m_s", c.at_rest_rms_m_s, Check::NonNegative);
    c.aim_settled = s->choice("aim", {"laid_out", "settled_cell"}, "laid_out") == "settled_cell";
    c.settle_local_damping = s->optionalNumber("local_damping", Check::UnitOpen);
    if (c.until_at_rest && c.settle_longest_s < c.settle_s)
      s->fail("longest_s", "the longest settling is shorter than duration_s, the shortest");
  }
  c.rebound_restitution = root.number("rebound_restitution", c.rebound_restitution, Check::Fraction);
  if (const auto l = root.optionalObject("lacing")) {
    StructureCase::Lacing lc;
    lc.params.wire_diameter_m = l->number("wire_diameter_m", lc.params.wire_diameter_m, Check::Positive);
    if (lc.params.wire_diameter_m > 0.01) l->fail("wire_diameter_m", "a lacing wire over 10 mm thick is no wire");
    lc.params.max_gap_m = l->number("max_gap_m", lc.params.max_gap_m, Check::Positive);
    lc.at_s = l->number("at_s", lc.at_s, Check::NonNegative);
    lc.edge_band_m = l->number("edge_band_m", lc.edge_band_m, Check::NonNegative);
    lc.to_plates = l->boolean("to_plates", lc.to_plates);
    if (l->has("plate_partners")) {
      lc.plates_as_neighbour = l->choice("plate_partners", {"edge_nodes", "neighbour_face"}) == "neighbour_face";
      if (!lc.to_plates)
        l->fail("plate_partners", "says how the cells are laced to their plates: it needs to_plates true");
    }
    if (l->has("pull_N")) {
      lc.params.pull_N = l->number("pull_N", Check::Positive);
      // (the wires are pulled while the structure settles, and tied for the impact)
      if (!(c.settle_s > 0.0))
        l->fail("pull_N", "the lacing is pulled tight while the structure settles: give settle.duration_s > 0");
    }
    const double settling = c.settle_s > 0.0 ? (c.until_at_rest ? c.settle_longest_s : c.settle_s) : 0.0;
    if (lc.at_s > 0.0 && !(lc.at_s < settling))
      l->fail("at_s", "the cells would be laced after the settling ends (" + std::to_string(settling) +
                          " s): lace them earlier, or as laid out (0)");
    c.lacing = lc;
  }
  // An impact lasts tens of milliseconds; the series every 0.1 ms; no mass
  // scaling (the test is dynamic).
  c.setup = parseLabSetup(root, 1.0, 0.1, 1e-4);
  return c;
}

/// The structure as it stands: the cells, their base and back support, and
/// where each cell's blocks are.
struct Layout {
  Scene scene;
  Vec3 pitch = Vec3::Zero();  ///< centre-to-centre distance of neighbouring cells (the cell's outer extent)
  std::size_t blocks_per_cell = 0, spheres_per_cell = 0;
  /// Cells of the front (i = 0) and back (i = nx - 1) layers, by index (i + nx (j + ny k)).
  std::vector<std::size_t> front_cells, back_cells;
  std::vector<int> slot_of;             ///< grid index -> place among the cells laid out (-1: not laid out)
  std::vector<int> grid_of;             ///< place among the cells laid out -> grid index
  std::size_t first_plate = 0;          ///< the scene's wall of a part's first face (StructurePart::faces, in order)
  double plates_under_lowered_m = 0.0;  ///< the part's plates under its cells, below the extent (lid_plates)
};

/// The netting's node radius (m): the largest of the spheres its links join; 0 without a netting.
double nettingNodeRadius(const Scene& cell) {
  double r = 0.0;
  for (const LinkSpec& k : cell.links) r = std::max({r, cell.spheres[k.a].radius_m, cell.spheres[k.b].radius_m});
  return r;
}

}  // namespace

double lidClearance(const Sample& sample) {
  const Scene& cell = sample.scene;
  const double node_radius = nettingNodeRadius(cell);
  if (node_radius <= 0.0) return 0.0;  // (no netting: no lid)
  // (the lid's plane as the lacing finds it: the median of the nodes nearest the top)
  const double lid = cellEdges(cell, node_radius).plane[static_cast<std::size_t>(faceIndex(2, 1))] + node_radius;
  return std::max(0.0, sample.hi.z() - lid);
}

namespace {

/// The plate on a face of a resolved cell (StructurePart::Face), driven by
/// the coupled model: the cell's extent there, its normal into the cell, of
/// the netting's material (it stands for the next cell's netting).
WallSpec facePlate(const StructurePart::Face& f, const StructureCase& c, const Layout& l, const Sample& sample) {
  const int idx[3] = {f.cell % c.nx, (f.cell / c.nx) % c.ny, f.cell / (c.nx * c.ny)};
  const int a = f.axis, b = (a + 1) % 3, d = (a + 2) % 3;
  // (a tile's centre: its place (u, v) of tiles x tiles across the face)
  const double in_u = (f.tile % f.tiles + 0.5) / f.tiles, in_v = (f.tile / f.tiles + 0.5) / f.tiles;
  Vec3 centre;
  centre[a] = (idx[a] + (f.side > 0 ? 1.0 : 0.0)) * l.pitch[a];
  centre[b] = (idx[b] + in_u) * l.pitch[b];
  centre[d] = (idx[d] + in_v) * l.pitch[d];
  if (a == 2 && f.side < 0) centre[2] -= l.plates_under_lowered_m;  // (at the lid below, lid_plates)
  WallSpec w;
  w.name = "interface_" + std::to_string(f.cell) + "_" + "xyz"[a] + (f.side > 0 ? "_plus" : "_minus");
  if (f.tiles > 1) w.name += "_tile_" + std::to_string(f.tile % f.tiles) + "_" + std::to_string(f.tile / f.tiles);
  w.point_m = centre;
  w.normal = -static_cast<double>(f.side) * Vec3::Unit(a);
  w.material = sample.netting_material >= 0 ? sample.netting_material : sample.plate_material;
  w.program.kind = WallProgram::Kind::Driven;
  w.bounded = true;
  w.rounded_edges = true;  // (plates of neighbours that moved apart make a step; a node meets its edge)
  w.axis_u = Vec3::Unit(b);
  // (v = normal x u lies along the third axis, either way)
  w.half_u_m = 0.5 * l.pitch[b] / f.tiles;
  w.half_v_m = 0.5 * l.pitch[d] / f.tiles;
  return w;
}

Layout buildLayout(const StructureCase& c, const Sample& sample, const StructurePart* part = nullptr) {
  Layout out;
  const Scene& cell = sample.scene;
  out.pitch = sample.hi - sample.lo;
  out.blocks_per_cell = cell.blocks.size();
  out.spheres_per_cell = cell.spheres.size();
  Scene& s = out.scene;
  s.gravity_m_s2 = cell.gravity_m_s2;
  s.materials = cell.materials;
  s.contact_pairs = cell.contact_pairs;
  s.no_contact_groups = cell.no_contact_groups;
  s.run = cell.run;
  std::size_t index = 0;  // i + nx (j + ny k)
  std::size_t slot = 0;   // the cell's place among those laid out
  out.slot_of.assign(static_cast<std::size_t>(c.nx) * c.ny * c.nz, -1);
  for (int k = 0; k < c.nz; ++k)
    for (int j = 0; j < c.ny; ++j)
      for (int i = 0; i < c.nx; ++i, ++index) {
        if (part && std::find(part->cells.begin(), part->cells.end(), static_cast<int>(index)) == part->cells.end())
          continue;
        // Cell (i, j, k) spans [i, i+1] x [j, j+1] x [k, k+1] pitches from the origin.
        const Vec3 shift = Vec3(i * out.pitch.x(), j * out.pitch.y(), k * out.pitch.z()) - sample.lo;
        const std::size_t first_sphere = s.spheres.size();
        for (SphereSpec sp : cell.spheres) {
          sp.center_m += shift;
          s.spheres.push_back(sp);
        }
        for (BlockSpec b : cell.blocks) {
          b.position_m += shift;
          s.blocks.push_back(b);
        }
        for (LinkSpec l : cell.links) {
          l.a += first_sphere, l.b += first_sphere;
          s.links.push_back(l);
        }
        out.slot_of[index] = static_cast<int>(slot);
        out.grid_of.push_back(static_cast<int>(index));
        if (i == 0) out.front_cells.push_back(slot);
        if (i == c.nx - 1) out.back_cells.push_back(slot);
        ++slot;
      }
  s.walls.push_back(fixedWall("base", Vec3::Zero(), Vec3::UnitZ(), sample.plate_material));
  if (c.fixed_back)
    s.walls.push_back(fixedWall("back", Vec3(c.nx * out.pitch.x(), 0, 0), -Vec3::UnitX(), sample.plate_material));
  out.first_plate = s.walls.size();
  if (part) {
    if (part->lid_plates) out.plates_under_lowered_m = lidClearance(sample);
    for (const StructurePart::Face& f : part->faces) s.walls.push_back(facePlate(f, c, out, sample));
  }
  return out;
}

/// Laces every two neighbouring cells laid out (both resolved) along the
/// edges where their faces meet, with the bodies where `scene` has them (the
/// layout's, or a settling's state: the same spheres in the same order).
/// Returns what it did, for the summary.
nlohmann::json laceCells(const StructureCase& c, const Layout& l, const Sample& sample, Scene& scene,
                         const StructurePart* part) {
  const StructureCase::Lacing& lc = *c.lacing;
  const double node_radius = nettingNodeRadius(sample.scene);
  const double band = lc.edge_band_m > 0.0 ? lc.edge_band_m : 1.5 * node_radius;
  const CellEdges edges = cellEdges(sample.scene, band);
  LacingParams params = lc.params;
  params.min_length_m = 2.0 * node_radius;  // (a loop around both wires; nodes in touch are laced slack)
  std::size_t links = 0, unlaced = 0, faces = 0;
  for (std::size_t slot = 0; slot < l.grid_of.size(); ++slot) {
    const int g = l.grid_of[slot];
    const int idx[3] = {g % c.nx, (g / c.nx) % c.ny, g / (c.nx * c.ny)};
    const int n[3] = {c.nx, c.ny, c.nz}, stride[3] = {1, c.nx, c.nx * c.ny};
    for (int axis = 0; axis < 3; ++axis) {
      if (idx[axis] + 1 >= n[axis]) continue;
      const int other = l.slot_of[static_cast<std::size_t>(g + stride[axis])];
      if (other < 0) continue;
      const LacedFaces f = laceFaces(scene, edges, slot * l.spheres_per_cell,
                                     static_cast<std::size_t>(other) * l.spheres_per_cell, axis, params);
      scene.links.insert(scene.links.end(), f.links.begin(), f.links.end());
      links += f.links.size(), unlaced += f.unlaced, ++faces;
    }
  }
  nlohmann::json out = {{"at_s", lc.at_s},
                        {"wire_diameter_m", lc.params.wire_diameter_m},
                        {"max_gap_m", lc.params.max_gap_m},
                        {"edge_band_m", band},
                        {"faces_laced", faces},
                        {"links", links},
                        {"edge_nodes_unlaced", unlaced}};
  if (params.pull_N > 0.0) out["pull_N"] = params.pull_N, out["shortest_m"] = params.min_length_m;
  if (!part || !lc.to_plates) return out;
  // Each face a resolved cell shares with a macro cell is laced to its
  // plate (or its tiles), as the macro cell's netting would be: the plate
  // then pulls and drags its macro node as a laced neighbour would.
  for (int g = 0; g < 32; ++g) scene.no_contact_groups.emplace_back(kPlateAnchorGroup, g);
  std::map<std::pair<std::size_t, int>, std::vector<bool>> taken;  // (per cell and face: a node once, over tiles)
  std::map<std::pair<std::size_t, int>, std::vector<bool>> taken_across;  // (and the neighbour's stand-in's)
  std::size_t plate_links = 0, plate_unlaced = 0, plates = 0;
  for (std::size_t k = 0; k < part->faces.size(); ++k) {
    const StructurePart::Face& f = part->faces[k];
    const auto slot = static_cast<std::size_t>(l.slot_of[static_cast<std::size_t>(f.cell)]);
    const int face = faceIndex(f.axis, f.side > 0 ? 1 : 0);
    const std::size_t first = slot * l.spheres_per_cell, wall = l.first_plate + k;
    const LacedPlate p =
        lc.plates_as_neighbour
            ? lacePlateAsNeighbour(scene, edges, first, face, wall, kPlateAnchorGroup, params, l.pitch[f.axis],
                                   taken[{slot, face}], taken_across[{slot, face}])
            : lacePlate(scene, edges, first, face, wall, kPlateAnchorGroup, params, taken[{slot, face}]);
    plate_links += p.links, plate_unlaced += p.unlaced, ++plates;
  }
  out["to_plates"] = true;
  out["plate_partners"] = lc.plates_as_neighbour ? "neighbour_face" : "edge_nodes";
  out["plates_laced"] = plates;
  out["links_to_plates"] = plate_links;
  out["edge_nodes_unlaced_at_plates"] = plate_unlaced;
  return out;
}

/// Lacing needs a netting: a cell whose spheres no links join has no edges to lace.
void checkLacing(const StructureCase& c, const Sample& sample, const std::string& file,
                 const StructurePart* part = nullptr) {
  if (c.lacing && c.lacing->to_plates && !part)
    throw bridge::InputError(file, "/lacing/to_plates",
                             "a structure resolved whole has no plates to lace its cells to: to_plates is for a "
                             "hybrid's resolved cells (resolve.lacing)");
  if (c.lacing && sample.netting_nodes == 0)
    throw bridge::InputError(file, "/lacing",
                             "the cell (" + sample.cell_file.string() +
                                 ") has no netting to lace: no links join its spheres; leave lacing out");
}

/// A laced settling's parts (from_s to to_s of the settling, lacing.at_s
/// between them): the landing with one snapshot at its end, the rest with
/// four. The run and the estimate split it alike.
void settlingPart(RunSpec& run, double from_s, double to_s, bool landing) {
  run.duration_s = to_s - from_s;
  run.output_interval_s = landing ? run.duration_s : run.duration_s / 4.0;
}

/// The settling's scene (c.settle_s > 0): the laid-out structure for the
/// longest the settling may take, five snapshots, its series at least ten.
/// A part's plate under cells stacked above its resolved cell presses on it
/// with their weight: a servo along its normal, at most 0.5 m/s (the
/// stack's own descent is a few tenths of a metre a second at first), its
/// gain that speed at a force error of that weight.
Scene settleScene(const StructureCase& c, const Layout& l, const Sample& sample, const StructurePart* part) {
  const double longest = c.until_at_rest ? c.settle_longest_s : c.settle_s;
  Scene s = l.scene;
  if (part) {
    for (std::size_t k = 0; k < part->faces.size(); ++k) {
      const StructurePart::Face& f = part->faces[k];
      if (f.cells_above <= 0) continue;
      WallProgram& p = s.walls[l.first_plate + k].program;
      p.kind = WallProgram::Kind::Servo;
      p.target_force_N = f.cells_above * sample.mass_kg * s.gravity_m_s2.norm();
      p.max_speed_m_s = 0.5;
      p.gain_m_s_N = p.max_speed_m_s / p.target_force_N;
    }
  }
  if (c.settle_local_damping)
    for (Material& m : s.materials) m.local_damping = *c.settle_local_damping;
  s.run.duration_s = longest;
  s.run.output_interval_s = longest / 5.0;
  s.run.series_interval_s = std::min(s.run.series_interval_s, c.settle_s / 10.0);
  return s;
}

/// Where the boulder's path meets the front face (y, z), as the case gives
/// it or the middle front cell's centre (cell ny/2, nz/2: centred for odd counts).
Vec3 aimPoint(const StructureCase& c, const Layout& l) {
  if (c.aim) return Vec3(0.0, (*c.aim)[0], (*c.aim)[1]);
  if (c.aim_fraction)
    return Vec3(0.0, (*c.aim_fraction)[0] * c.ny * l.pitch.y(), (*c.aim_fraction)[1] * c.nz * l.pitch.z());
  return Vec3(0.0, (c.ny / 2 + 0.5) * l.pitch.y(), (c.nz / 2 + 0.5) * l.pitch.z());
}

/// The foremost point (least x) of the structure's bodies, radii included.
double foremostX(const Scene& s) {
  double x = std::numeric_limits<double>::infinity();
  for (const SphereSpec& p : s.spheres) x = std::min(x, p.center_m.x() - p.radius_m);
  for (const BlockSpec& b : s.blocks)
    for (std::size_t m = 0; m < b.member_centers_m.size(); ++m)
      x = std::min(x, (b.position_m + b.orientation * b.member_centers_m[m]).x() - b.member_radii_m[m]);
  return x;
}

/// The boulder, `gap` in front of the face, moving along +x.
SphereSpec structureBoulder(const StructureCase& c, Scene& s, const Sample& sample, const Vec3& aim) {
  SphereSpec b = boulderSphere(s, sample.rock_material, c.diameter_m, c.density_kg_m3, c.boulder);
  // initial_gap_m in front of the laid-out face (x = 0), or of the settled
  // one where the settling bulged it forward
  b.center_m = Vec3(std::min(0.0, foremostX(s)) - b.radius_m - c.gap_m, aim.y(), aim.z());
  b.velocity_m_s = Vec3(c.velocity_m_s, 0, 0);
  b.group = kBoulderGroup;
  return b;
}

void checkAim(const StructureCase& c, const Layout& l, const std::string& file) {
  const Vec3 a = aimPoint(c, l);
  if (a.y() < 0.0 || a.y() > c.ny * l.pitch.y() || a.z() < 0.0 || a.z() > c.nz * l.pitch.z()) {
    std::ostringstream m;
    m << "the aim point (" << a.y() << ", " << a.z() << ") m is off the front face, [0, " << c.ny * l.pitch.y()
      << "] x [0, " << c.nz * l.pitch.z() << "] m (" << c.ny << " x " << c.nz << " cells of " << l.pitch.y() << " x "
      << l.pitch.z() << " m)";
    throw bridge::InputError(file, "/boulder/aim_point_m", m.str());
  }
}

/// The impact scene: the settled structure (or the laid-out one) with the
/// boulder; the step kept below a tenth of the smallest radius per step of
/// the boulder's travel (as micro.uci).
Scene impactScene(const StructureCase& c, Scene structure, const Sample& sample, const Vec3& aim,
                  const std::string& file, std::size_t& boulder) {
  boulder = structure.spheres.size();
  structure.spheres.push_back(structureBoulder(c, structure, sample, aim));
  limitStepToSpeed(structure, c.velocity_m_s, file);
  return structure;
}

/// The mean position of blocks first .. first + count - 1 of a scene (a cell's, laid out or settled).
Vec3 meanBlockPosition(const Scene& sc, std::size_t first, std::size_t count) {
  Vec3 x = Vec3::Zero();
  for (std::size_t b = first; b < first + count; ++b) x += sc.blocks[b].position_m;
  return count > 0 ? Vec3(x / static_cast<double>(count)) : x;
}

/// Their mean height.
double meanBlockHeight(const Scene& sc, std::size_t first, std::size_t count) {
  return meanBlockPosition(sc, first, count).z();
}

Vec3 meanBlockPosition(const Engine& e, std::size_t spheres, std::size_t first, std::size_t count) {
  Vec3 x = Vec3::Zero();
  for (std::size_t b = first; b < first + count; ++b) x += e.body(spheres + b).position_m;
  return count > 0 ? Vec3(x / static_cast<double>(count)) : x;
}

bridge::RunOutcome runOne(const StructureCase& c, const Sample& sample, const bridge::RunContext& ctx,
                          const std::string& file, const StructurePart* part = nullptr) {
  checkLacing(c, sample, file, part);
  Layout layout = buildLayout(c, sample, part);
  checkAim(c, layout, file);
  // Laced as laid out, or once landed (in the settling, below).
  nlohmann::json lacing_results;
  // (the lacing's wires are the scene's links from here on, as laced)
  std::size_t first_lacing = std::numeric_limits<std::size_t>::max();
  if (c.lacing && c.lacing->at_s == 0.0) {
    first_lacing = layout.scene.links.size();
    lacing_results = laceCells(c, layout, sample, layout.scene, part);
  }
  Vec3 aim = aimPoint(c, layout);  // (laid out; lowered with the struck cell where settle.aim says)
  // (the cells laid out: the whole structure's, or a hybrid's resolved ones)
  const std::size_t laid_out = layout.blocks_per_cell > 0 ? layout.scene.blocks.size() / layout.blocks_per_cell : 0;
  nlohmann::json settle_results;
  double before_resume_s = 0.0;  // (the seconds the stopped runs of the landing and the settling stepped)
  // The landing's and settling's kept ends go once the run is over, ended,
  // failed or thrown out of (an input found wrong once landed); only a run
  // stopped by a signal keeps them, to take them back when resumed.
  struct KeptEnds {
    std::filesystem::path dir;
    bool stopped = false;
    KeptEnds(const KeptEnds&) = delete;
    KeptEnds& operator=(const KeptEnds&) = delete;
    ~KeptEnds() {
      if (!stopped)
        for (const char* stage : {"landing", "settle"}) removeKeptEnd(dir / stage);
    }
  } kept{ctx.outdir};
  const auto stoppedBy = [&kept](const bridge::RunOutcome& o) {
    if (o.status == bridge::RunOutcome::Status::Interrupted) kept.stopped = true;
  };
  // The struck cell (the front cell the aim point is on, laid out): the
  // boulder's penetration less that cell's own move is its indentation.
  const int struck = [&] {
    const auto at = [](double p, double pitch, int n) { return std::clamp(static_cast<int>(p / pitch), 0, n - 1); };
    const int j = at(aim.y(), layout.pitch.y(), c.ny), k = at(aim.z(), layout.pitch.z(), c.nz);
    return layout.slot_of[static_cast<std::size_t>(c.nx * (j + c.ny * k))];
  }();

  // 1. The stack settles under its weight (the cells were made standing
  // alone): until it is at rest (its centre of mass comes down slower than
  // at_rest_m_s over the settling's last fifth), or for a set time.
  Scene standing = layout.scene;
  if (c.settle_s > 0.0) {
    Scene s = settleScene(c, layout, sample, part);
    const double longest_settling = s.run.duration_s;
    bridge::RunContext sub = ctx;
    sub.outdir = ctx.outdir / "settle";
    std::filesystem::create_directories(sub.outdir);
    const double g = layout.scene.gravity_m_s2.norm(), weight = sample.mass_kg * static_cast<double>(laid_out) * g;
    std::vector<double> t, u;  // (the samples' times and gravity potentials)
    // The bodies' mass-weighted rms speed, from their kinetic energy (at the
    // last sample: the energies are measured at the samples).
    const auto rmsSpeed = [weight, g](double kinetic_J) {
      return std::sqrt(2.0 * std::max(0.0, kinetic_J) * g / weight);
    };
    SceneRunHooks hooks;
    hooks.label = "micro.structure settle";
    hooks.keep_end = true;  // (a run stopped in its impact takes the landing's and settling's ends back)
    // (a settling in two runs, the cells laced between them, counts its
    // time from the first's start)
    double t_offset = 0.0;
    hooks.record = [&](const Engine& e, double time) {
      t.push_back(t_offset + time);
      u.push_back(e.energy().gravity_potential_J);
    };
    if (c.until_at_rest)
      hooks.done = [&](const Engine& e) {
        return t_offset + e.time() >= c.settle_s && descentSpeed(t, u, weight) <= c.at_rest_m_s &&
               (c.at_rest_rms_m_s <= 0.0 || rmsSpeed(e.energy().kinetic_translational_J) <= c.at_rest_rms_m_s);
      };
    hooks.archive = [&](bridge::StateArchive& a) { a("time_s", t), a("gravity_potential_J", u); };
    // The plates beside the part's cells come down with them (each step the
    // plate's height offset is set to its cell's blocks' mean descent so
    // far), with in_plane Follow every plate moves in its plane with its
    // cell (its offset across its normal set to the blocks' mean move), with
    // Free it slides along x and y as the bodies push it, and
    // the plates that give come down as the top of the cell under them would
    // (Face::gives): none has a state of its own, so all go on the same
    // after a resume.
    std::vector<std::size_t> driven;           // the part's faces whose plates are driven here, in wall order
    std::vector<Vec3> wall0;                   // their plates' place, laid out
    std::vector<std::size_t> cell_of;          // each driven face's cell among those touched (several faces share one)
    std::vector<Vec3> cell0, cell_now;         // those cells' blocks' mean position laid out, and in the current step
    std::vector<char> cell_known;              // (whether cell_now holds this step's)
    std::size_t n_spheres = s.spheres.size();  // (the blocks' bodies come after the spheres)
    const bool any_gives =
        part && std::any_of(part->faces.begin(), part->faces.end(), [](const auto& f) { return f.gives; });
    if (part && (part->beside_follow || part->in_plane != StructurePart::InPlane::Still || any_gives)) {
      const std::size_t first = layout.first_plate;
      for (std::size_t k = 0; k < part->faces.size(); ++k)
        if (s.walls[first + k].program.kind == WallProgram::Kind::Driven) driven.push_back(k);
      const auto blocksOf = [&](int cell) {
        return static_cast<std::size_t>(layout.slot_of[static_cast<std::size_t>(cell)]) * layout.blocks_per_cell;
      };
      std::vector<int> touched;  // (the cells, each once)
      for (const std::size_t k : driven) {
        const int cell = part->faces[k].cell;
        const auto at = std::find(touched.begin(), touched.end(), cell);
        cell_of.push_back(static_cast<std::size_t>(at - touched.begin()));
        if (at == touched.end()) {
          touched.push_back(cell);
          cell0.push_back(meanBlockPosition(s, blocksOf(cell), layout.blocks_per_cell));
        }
        wall0.push_back(s.walls[first + k].point_m);
      }
      cell_now.resize(cell0.size()), cell_known.resize(cell0.size());
      // A giving plate's servo: as the plates that press with the weight
      // above (settleScene), at most 0.5 m/s, that speed at a force error of
      // one cell's weight.
      const double max_speed = 0.5, gain = max_speed / (sample.mass_kg * s.gravity_m_s2.norm());
      const bool follow = part->beside_follow, in_plane = part->in_plane == StructurePart::InPlane::Follow,
                 free = part->in_plane == StructurePart::InPlane::Free;
      hooks.start = [&, first, blocksOf, max_speed, gain, follow, in_plane, free](Engine& e) {
        e.setWallDriver([&, first, blocksOf, max_speed, gain, follow, in_plane, free](
                            double, double dt, const std::vector<Vec3>& forces, std::vector<Vec3>& moves) {
          std::fill(cell_known.begin(), cell_known.end(), 0);
          for (std::size_t q = 0; q < driven.size(); ++q) {
            const StructurePart::Face& f = part->faces[driven[q]];
            const std::size_t w = first + driven[q];
            const Vec3 wall_moved = e.wallPosition(w) - wall0[q];
            moves[q].setZero();
            if (f.gives) {
              // The load is what the bodies press down with; the cell's top
              // resists with its law at the plate's descent so far.
              const double descent = std::max(0.0, -wall_moved.z());
              const double excess = -forces[q].z() - bridge::axialResponse(f.law, descent, 0.0).force_N;
              moves[q].z() = -dt * std::clamp(gain * excess, 0.0, max_speed);
            }
            // (free: along x and y in its plane, with the bodies' push)
            if (free)
              for (int a = 0; a < 2; ++a)
                if (a != f.axis) moves[q][a] = dt * std::clamp(gain * forces[q][a], -max_speed, max_speed);
            // (a plate beside a cell follows it down; with in_plane every
            // plate follows it along both axes of its plane)
            if (!in_plane && (!follow || f.axis == 2)) continue;
            // (a cell's mean once a step, however many of its plates follow it)
            const std::size_t cq = cell_of[q];
            if (!cell_known[cq])
              cell_now[cq] = meanBlockPosition(e, n_spheres, blocksOf(f.cell), layout.blocks_per_cell),
              cell_known[cq] = 1;
            const Vec3 cell_moved = cell_now[cq] - cell0[cq];
            for (int a = 0; a < 3; ++a)
              if (a != f.axis && (in_plane || a == 2)) moves[q][a] = cell_moved[a] - wall_moved[a];
          }
        });
      };
    }
    double settled_at = NAN;
    // How tight the lacing got, where it is pulled tight: its wires' rest
    // lengths as the settling began and as it ended (mean, least, largest).
    nlohmann::json tightened;
    hooks.end = [&](const Engine& e, const Scene& in) {
      standing = stateScene(in, e), settled_at = t_offset + e.time();
      if (!(c.lacing && c.lacing->params.pull_N > 0.0 && first_lacing < in.links.size())) return;
      double before = 0.0, after = 0.0, least = INFINITY, most = 0.0;
      std::size_t n = 0, shortest = 0;
      for (std::size_t l = first_lacing; l < in.links.size(); ++l) {
        if (e.linkBroken(l)) continue;
        const double r = e.linkRestLength(l);
        before += in.links[l].wire.rest_length_m, after += r, ++n;
        least = std::min(least, r), most = std::max(most, r);
        if (r <= in.links[l].pull_min_m) ++shortest;
      }
      if (n == 0) return;
      tightened = {{"mean_laced_m", before / n},
                   {"mean_settled_m", after / n},
                   {"least_settled_m", least},
                   {"largest_settled_m", most},
                   {"at_shortest", shortest}};
    };
    if (c.lacing && c.lacing->at_s > 0.0) {
      // The cells land unlaced (for lacing.at_s, to the end: the test of rest
      // comes after), then are laced where they landed and settle on.
      Scene landing = s;
      settlingPart(landing.run, 0.0, c.lacing->at_s, true);
      SceneRunHooks first = hooks;
      first.label = "micro.structure landing";
      first.done = nullptr;
      bridge::RunContext land = ctx;
      land.outdir = ctx.outdir / "landing";
      std::filesystem::create_directories(land.outdir);
      bridge::RunOutcome landed = runScene(std::move(landing), file, land, first);
      stoppedBy(landed);
      if (landed.status != bridge::RunOutcome::Status::Ok) {
        landed.message = "landing the structure before its lacing: " + landed.message;
        return landed;
      }
      before_resume_s += bridge::wholeWallTime(0.0, landed.results);
      first_lacing = standing.links.size();
      lacing_results = laceCells(c, layout, sample, standing, part);
      n_spheres = standing.spheres.size();  // (the anchors of a lacing to the plates come after the cells')
      lacing_results["landed_in_s"] = settled_at;
      // (the settle keys are the second part's: its steps and energies)
      if (landed.results.contains("steps")) lacing_results["landing_steps"] = landed.results["steps"];
      if (ctx.progress)
        std::cerr << "micro.structure: landed in " << settled_at << " s; laced "
                  << lacing_results["faces_laced"].get<std::size_t>() << " pairs of faces with "
                  << lacing_results["links"].get<std::size_t>() << " wires ("
                  << lacing_results["edge_nodes_unlaced"].get<std::size_t>() << " edge nodes left unlaced)";
      if (ctx.progress && lacing_results.contains("links_to_plates"))
        std::cerr << "; " << lacing_results["links_to_plates"].get<std::size_t>() << " wires to "
                  << lacing_results["plates_laced"].get<std::size_t>() << " plates ("
                  << lacing_results["edge_nodes_unlaced_at_plates"].get<std::size_t>() << " edge nodes left unlaced)";
      if (ctx.progress) std::cerr << "\n";
      Scene rest = std::move(standing);  // (the settling's materials, runs and wall programs: stateScene keeps them)
      settlingPart(rest.run, settled_at, longest_settling, false);
      t_offset = settled_at;
      s = std::move(rest);
    }
    bridge::RunOutcome settled = runScene(std::move(s), file, sub, hooks);
    stoppedBy(settled);
    if (settled.status != bridge::RunOutcome::Status::Ok) {
      settled.message = "settling the structure: " + settled.message;
      if (before_resume_s > 0.0)
        settled.results[bridge::kWallTimeBeforeResume] = bridge::wholeWallTime(before_resume_s, settled.results);
      return settled;
    }
    settle_results = settled.results;
    before_resume_s += bridge::wholeWallTime(0.0, settled.results);
    if (!tightened.is_null()) lacing_results["pulled_tight"] = tightened;
    standing.run = layout.scene.run;              // (the state keeps the settling's run)
    standing.materials = layout.scene.materials;  // (and its local damping)
    // (the plates that pressed with the weight above are driven again, from
    // where the settling left them)
    for (std::size_t w = 0; w < standing.walls.size(); ++w) standing.walls[w].program = layout.scene.walls[w].program;
    // Was the stack at rest when the boulder came? How fast its centre of
    // mass came down over the settling's last fifth (the samples are whole
    // in a resumed settling: they are in its checkpoint).
    settle_results["descent_speed_m_s"] = descentSpeed(t, u, weight);
    // And how fast its bodies still moved, as a whole: a stack whose centre of
    // mass stands still may still sway, its rows sliding one way and back.
    // The root mean square of their speeds, weighted by mass.
    if (const auto& en = settle_results["energy"]; en.contains("kinetic_translational_J"))
      settle_results["rms_speed_m_s"] = rmsSpeed(en["kinetic_translational_J"].get<double>());
    if (c.at_rest_rms_m_s > 0.0) settle_results["at_rest_rms_speed_m_s"] = c.at_rest_rms_m_s;
    if (c.settle_local_damping) settle_results["local_damping"] = *c.settle_local_damping;
    settle_results["duration_s"] = settled_at;
    if (part && part->lid_plates) settle_results["plates_under_lowered_m"] = layout.plates_under_lowered_m;
    settle_results["until_at_rest"] = c.until_at_rest;
    // How far the stack came down, and the struck cell's blocks: the aim,
    // set on the laid-out wall, meets the settled cell this far above its
    // blocks' mean height.
    if (!u.empty()) settle_results["centre_of_mass_drop_m"] = (u.front() - u.back()) / weight;
    if (struck >= 0 && layout.blocks_per_cell > 0) {
      const std::size_t first = static_cast<std::size_t>(struck) * layout.blocks_per_cell;
      const double settled_z = meanBlockHeight(standing, first, layout.blocks_per_cell);
      const double drop = meanBlockHeight(layout.scene, first, layout.blocks_per_cell) - settled_z;
      settle_results["struck_cell_drop_m"] = drop;
      if (c.aim_settled) {
        aim.z() -= drop;
        settle_results["aim_lowered_m"] = drop;
      }
      settle_results["aim_above_struck_cell_m"] = aim.z() - settled_z;
    }
  }

  // 2. The impact.
  std::size_t boulder = 0;
  Scene scene = impactScene(c, standing, sample, aim, file, boulder);
  const std::size_t spheres = scene.spheres.size(), bpc = layout.blocks_per_cell;
  const double mass = scene.spheres[boulder].mass_kg, v0 = c.velocity_m_s;
  struct Series {
    std::vector<double> time, force, penetration, indentation, velocity, front, back;
    std::vector<double> front_fine, back_fine, front_macro, back_macro;  // (a hybrid's parts apart)
  } sr;
  double struck0 = NAN;
  double x_contact = NAN, t_contact = NAN, peak = 0.0, t_last_force = NAN;
  // (and the last time it stood above the boulder's weight: a boulder at
  // rest in its crater still presses the face, up to about its weight)
  double t_above_weight = NAN;
  const double weight = mass * scene.gravity_m_s2.norm();
  // Every cell's mean block position at the start and now, and the largest
  // moves of one along x and across it (the macro model's x-only assumption).
  std::vector<Vec3> cell0, now;
  double max_cell_x = 0.0, max_cell_across = 0.0;
  SceneRunHooks hooks;
  hooks.label = "micro.structure";
  hooks.record = [&](const Engine& e, double) {
    const Vec3 f = e.sphereForce(boulder);  // what the structure exerts on it
    const BodyState b = e.body(boulder);
    const double force = std::max(0.0, -f.x());
    if (std::isnan(x_contact) && f.squaredNorm() > 0.0) x_contact = b.position_m.x(), t_contact = e.time();
    now.resize(laid_out);
    for (std::size_t k = 0; k < laid_out; ++k) now[k] = meanBlockPosition(e, spheres, k * bpc, bpc);
    if (cell0.empty()) cell0 = now;
    for (std::size_t k = 0; k < laid_out; ++k) {
      const Vec3 d = now[k] - cell0[k];
      max_cell_x = std::max(max_cell_x, std::fabs(d.x()));
      max_cell_across = std::max(max_cell_across, std::hypot(d.y(), d.z()));
    }
    double front = 0.0, back = 0.0;
    for (const std::size_t k : layout.front_cells) front = std::max(front, now[k].x() - cell0[k].x());
    for (const std::size_t k : layout.back_cells) back = std::max(back, now[k].x() - cell0[k].x());
    if (part && part->faces_moved) {
      const auto [macro_front, macro_back] = part->faces_moved();
      sr.front_fine.push_back(front), sr.back_fine.push_back(back);
      sr.front_macro.push_back(macro_front), sr.back_macro.push_back(macro_back);
      front = std::max(front, macro_front), back = std::max(back, macro_back);
    }
    if (part && part->record) part->record(e);
    sr.time.push_back(e.time());
    sr.force.push_back(force);
    sr.penetration.push_back(std::isnan(x_contact) ? 0.0 : b.position_m.x() - x_contact);
    if (struck >= 0) {
      const double x = now[static_cast<std::size_t>(struck)].x();
      if (std::isnan(x_contact) || std::isnan(struck0)) struck0 = x;  // (its place at first contact)
      sr.indentation.push_back(sr.penetration.back() - (x - struck0));
    }
    sr.velocity.push_back(b.velocity_m_s.x());
    sr.front.push_back(front), sr.back.push_back(back);
    peak = std::max(peak, force);
    if (force > 0.01 * peak) t_last_force = e.time();
    if (force > weight) t_above_weight = e.time();
  };
  // Over: the boulder has left the face (no force for 5 ms, moving back),
  // come to rest in it (below 1 % of its speed), or passed the back face.
  std::string coupled_failure;
  hooks.done = [&](const Engine& e) {
    if (part && part->failure && coupled_failure.empty()) coupled_failure = part->failure();
    if (!coupled_failure.empty()) return true;
    if (std::isnan(t_contact)) return false;
    const double vx = sr.velocity.back();
    if (vx < 0.0 && e.time() - t_last_force > 0.005) return true;
    if (e.body(boulder).position_m.x() - 0.5 * c.diameter_m > c.nx * layout.pitch.x()) return true;
    // (at rest in the face: under gravity the face keeps holding it up, so
    // its speed, not the force, says it stopped)
    return e.time() - t_contact > 0.01 && e.body(boulder).velocity_m_s.norm() < 0.01 * v0;
  };
  hooks.archive = [&](bridge::StateArchive& a) {
    a("time_s", sr.time), a("force_N", sr.force), a("penetration_m", sr.penetration), a("velocity_m_s", sr.velocity);
    a("front_m", sr.front), a("back_m", sr.back);
    a("front_fine_m", sr.front_fine), a("back_fine_m", sr.back_fine);
    a("front_macro_m", sr.front_macro), a("back_macro_m", sr.back_macro);
    a("x_contact", x_contact), a("t_contact", t_contact), a("peak", peak), a("t_last_force", t_last_force);
    a("t_above_weight", t_above_weight);
    a("cell0", cell0), a("max_cell_x", max_cell_x), a("max_cell_across", max_cell_across);
    a("indentation_m", sr.indentation), a("struck0", struck0);
    if (part && part->archive) {
      bridge::StateArchive pa = a.group("coupled");
      part->archive(pa);
    }
  };
  if (part && part->drive) hooks.start = [part](Engine& e) { e.setWallDriver(part->drive); };
  hooks.write = [&](const Engine&, bridge::H5Writer& h5) {
    h5.write("/curves/impact/time_s", sr.time, "s");
    h5.write("/curves/impact/force_N", sr.force, "N");
    h5.write("/curves/impact/penetration_m", sr.penetration, "m");
    if (!sr.indentation.empty()) h5.write("/curves/impact/indentation_m", sr.indentation, "m");
    h5.write("/curves/impact/boulder_velocity_m_s", sr.velocity, "m/s");
    h5.write("/curves/impact/front_face_displacement_m", sr.front, "m");
    h5.write("/curves/impact/back_face_displacement_m", sr.back, "m");
    if (!sr.back_fine.empty()) {
      h5.write("/curves/impact/front_face_displacement_fine_m", sr.front_fine, "m");
      h5.write("/curves/impact/back_face_displacement_fine_m", sr.back_fine, "m");
      h5.write("/curves/impact/front_face_displacement_macro_m", sr.front_macro, "m");
      h5.write("/curves/impact/back_face_displacement_macro_m", sr.back_macro, "m");
    }
  };
  bridge::RunOutcome out = runScene(std::move(scene), file, ctx, hooks);
  stoppedBy(out);
  nlohmann::json& r = out.results;
  if (!settle_results.is_null()) r["settle"] = settle_results;
  // (a resumed run's time is its stages' whole: bridge/run.hpp)
  if (before_resume_s > 0.0 || r.contains(bridge::kWallTimeBeforeResume))
    r[bridge::kWallTimeBeforeResume] = bridge::wholeWallTime(before_resume_s, r);
  if (!lacing_results.is_null()) r["lacing"] = lacing_results;
  r["cells"] = {c.nx, c.ny, c.nz};
  r["cell_pitch_m"] = {layout.pitch.x(), layout.pitch.y(), layout.pitch.z()};
  r["aim_point_m"] = {aim.y(), aim.z()};
  r["velocity_m_s"] = v0;
  r["boulder_mass_kg"] = mass;
  r["impact_energy_J"] = 0.5 * mass * v0 * v0;
  r["cell_mass_kg"] = sample.mass_kg;
  // (the nominal edge the cell was made at, when its file says: the size its laws are for)
  if (sample.cell_summary.contains("edge_m")) r["cell_edge_m"] = sample.cell_summary["edge_m"];
  if (sr.time.empty()) return out;
  const bool touched = !std::isnan(t_contact);
  double max_pen = 0.0, t_peak = NAN, max_front = 0.0, max_back = 0.0, rebound = 0.0;
  for (std::size_t k = 0; k < sr.time.size(); ++k) {
    max_pen = std::max(max_pen, sr.penetration[k]);
    max_front = std::max(max_front, sr.front[k]), max_back = std::max(max_back, sr.back[k]);
    if (sr.force[k] == peak && std::isnan(t_peak)) t_peak = sr.time[k];
    if (touched && sr.time[k] >= t_last_force) rebound = std::max(rebound, -sr.velocity[k]);
  }
  const bool over = r["ended_by"] == "test";
  const bool through = sr.penetration.back() > 0.0 && touched &&
                       x_contact + sr.penetration.back() - 0.5 * c.diameter_m > c.nx * layout.pitch.x();
  r["peak_force_N"] = peak;
  r["time_of_peak_s"] = touched ? t_peak - t_contact : NAN;
  r["max_penetration_m"] = max_pen;
  r["final_penetration_m"] = sr.penetration.back();
  r["contact_duration_s"] = touched ? t_last_force - t_contact : 0.0;
  r["contact_duration_above_weight_s"] = touched && !std::isnan(t_above_weight) ? t_above_weight - t_contact : 0.0;
  r["rebound_velocity_m_s"] = rebound;
  r["max_front_face_displacement_m"] = max_front;
  r["max_back_face_displacement_m"] = max_back;
  if (!sr.back_fine.empty()) {  // which part moved the faces most: the resolved cells or the macro nodes
    const auto largest = [](const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); };
    r["max_face_displacement_by_part_m"] = {
        {"front", {{"fine", largest(sr.front_fine)}, {"macro", largest(sr.front_macro)}}},
        {"back", {{"fine", largest(sr.back_fine)}, {"macro", largest(sr.back_macro)}}}};
  }
  if (!sr.indentation.empty()) r["max_indentation_m"] = *std::max_element(sr.indentation.begin(), sr.indentation.end());
  r["max_cell_displacement_x_m"] = max_cell_x;
  r["max_cell_displacement_across_m"] = max_cell_across;
  r["touched"] = touched;
  r["outcome"] = through || !coupled_failure.empty()     ? "perforated"
                 : !over                                 ? "unfinished"
                 : rebound >= c.rebound_restitution * v0 ? "rebounded"
                                                         : "stopped";
  if (!coupled_failure.empty()) r["perforation"] = coupled_failure;
  nlohmann::json warnings = nlohmann::json::array();
  if (!touched)
    warnings.push_back("the boulder never touched the structure within run.duration_s");
  else if (!over)
    warnings.push_back("the impact was not over at the end of run.duration_s: lengthen it");
  if (!settle_results.is_null()) {
    const double descent = settle_results["descent_speed_m_s"].get<double>();
    const double rms = settle_results.value("rms_speed_m_s", 0.0);
    const bool coming_down = descent > c.at_rest_m_s;
    const bool swaying = c.at_rest_rms_m_s > 0.0 && rms > c.at_rest_rms_m_s;
    r["settled"] = !coming_down && !swaying;
    if (coming_down || swaying) {  // (coming down is said first: it is the larger motion)
      std::ostringstream m;
      m.precision(3);
      m << "the structure was still " << (coming_down ? "settling" : "moving")
        << " when the boulder came: at the end of its settling (" << settle_results["duration_s"].get<double>()
        << " s) ";
      if (coming_down)
        m << "its centre of mass was coming down at " << 1e3 * descent << " mm/s (at rest: below "
          << 1e3 * c.at_rest_m_s << " mm/s, settle.at_rest_m_s); the boulder struck a structure in motion: ";
      else
        m << "its bodies' rms speed was " << 1e3 * rms << " mm/s (at rest: below " << 1e3 * c.at_rest_rms_m_s
          << " mm/s, settle.at_rest_rms_speed_m_s); ";
      m << (c.until_at_rest ? "lengthen settle.longest_s" : "lengthen settle.duration_s, or set settle.until_at_rest");
      warnings.push_back(m.str());
    }
  }
  r["warnings"] = warnings;

  {
    bridge::PlotSpec plot;
    plot.title = "Resolved structure: " + std::to_string(c.nx) + " x " + std::to_string(c.ny) + " x " +
                 std::to_string(c.nz) + " cells, boulder at " + std::to_string(v0).substr(0, 4) + " m/s";
    plot.x_label = "time from first contact (ms)";
    plot.y_label = "force on the boulder (kN)";
    bridge::PlotSeries s{"resolved", {}, {}, bridge::PlotSeries::Style::Line};
    const double t0 = touched ? t_contact : 0.0;
    for (std::size_t k = 0; k < sr.time.size(); ++k)
      if (sr.time[k] >= t0 - 0.002) s.x.push_back(1000.0 * (sr.time[k] - t0)), s.y.push_back(1e-3 * sr.force[k]);
    plot.series = {s};
    bridge::writePlotPng(ctx.outdir / "structure_force_time.png", plot);
  }
  std::ostringstream rep;
  rep.precision(4);
  rep << hooks.label << ": " << r["outcome"].get<std::string>() << "; peak force " << peak << " N, penetration "
      << 1000.0 * max_pen << " mm, contact " << 1000.0 * r["contact_duration_s"].get<double>() << " ms, back face "
      << 1000.0 * max_back << " mm\n";
  out.answer = rep.str() + out.answer;
  return out;
}

/// The cell file of a part's document (a part runs one given cell).
Sample partSample(const StructureCase& c, const bridge::JsonDocument& doc) {
  checkCells(c.setup);
  if (!c.setup.cells.front().generate.empty() || c.setup.cells.size() != 1)
    throw bridge::InputError(doc.file(), "/cell", "a resolved part runs one cell file, not a cell case or replicates");
  return loadSample(c.setup.cells.front().file, c.setup);
}

void checkPart(const StructureCase& c, const StructurePart& part, const std::string& file) {
  const int n = c.nx * c.ny * c.nz;
  if (static_cast<long long>(part.cells.size()) > kMaxCells)
    throw bridge::InputError(file, "/structure/cells",
                             "more than " + std::to_string(kMaxCells) + " cells resolved at the fine scale");
  for (const int cell : part.cells)
    if (cell < 0 || cell >= n) throw bridge::InputError(file, "/structure/cells", "a resolved cell is off the grid");
  for (const StructurePart::Face& f : part.faces)
    if (f.cell < 0 || f.cell >= n || f.axis < 0 || f.axis > 2 || (f.side != 1 && f.side != -1) || f.tiles < 1 ||
        f.tile < 0 || f.tile >= f.tiles * f.tiles)
      throw bridge::InputError(file, "/structure/cells", "an interface face is off the grid");
}

void check(const bridge::JsonDocument& doc) {
  const StructureCase c = parseCase(doc);
  checkCells(c.setup);
  if (!c.setup.cells.front().generate.empty()) return;
  const Sample sample = loadSample(c.setup.cells.front().file, c.setup);
  checkLacing(c, sample, doc.file());
  const Layout l = buildLayout(c, sample);
  checkAim(c, l, doc.file());
  std::size_t boulder = 0;
  const Scene s = impactScene(c, l.scene, sample, aimPoint(c, l), doc.file(), boulder);
  validateScene(s, doc.file());
  chooseDt(s, criticalTimeStep(s), doc.file());
}

/// What the structure (or a part of it) costs: its settling, at most
/// settle.longest_s, then the impact, each with its own step and outputs.
std::optional<bridge::Estimate> estimateRuns(const StructureCase& c, const std::string& file,
                                             const StructurePart* part = nullptr) {
  // (a settling laced once landed is two runs: the landing, to lacing.at_s, then the rest)
  const bool landing = c.settle_s > 0.0 && c.lacing && c.lacing->at_s > 0.0;
  const std::size_t runs = c.settle_s > 0.0 ? (landing ? 3 : 2) : 1;
  return estimateReplicates(
      c.setup, runs,
      [&](const Sample& s, std::size_t run) {
        const Layout l = buildLayout(c, s, part);
        std::size_t boulder = 0;
        if (run == 0) return impactScene(c, l.scene, s, aimPoint(c, l), file, boulder);
        Scene settle = settleScene(c, l, s, part);
        if (landing) {
          const double longest = settle.run.duration_s, at = c.lacing->at_s;
          if (run == 2)
            settlingPart(settle.run, 0.0, at, true);
          else
            settlingPart(settle.run, at, longest, false);
        }
        return settle;
      },
      /*stages_keep_ends=*/true);
}

std::optional<bridge::Estimate> estimate(const bridge::JsonDocument& doc) {
  return estimateRuns(parseCase(doc), doc.file());
}

std::shared_ptr<const Replicates> replicates(const bridge::JsonDocument& doc) {
  const auto c = std::make_shared<const StructureCase>(parseCase(doc));
  const std::string file = doc.file();
  return std::make_shared<const Replicates>(Replicates{
      c->setup,
      "micro.structure",
      {"impact"},
      [c, file](const Sample& s, std::size_t, const bridge::RunContext& rc) { return runOne(*c, s, rc, file); },
      {"peak_force_N", "max_penetration_m", "contact_duration_s", "max_back_face_displacement_m",
       "rebound_velocity_m_s"}});
}

}  // namespace

void checkStructurePart(const bridge::JsonDocument& doc, const StructurePart& part) {
  const StructureCase c = parseCase(doc, false);
  checkPart(c, part, doc.file());
  const Sample sample = partSample(c, doc);
  checkLacing(c, sample, doc.file(), &part);
  const Layout l = buildLayout(c, sample, &part);
  checkAim(c, l, doc.file());
  std::size_t boulder = 0;
  const Scene s = impactScene(c, l.scene, sample, aimPoint(c, l), doc.file(), boulder);
  validateScene(s, doc.file());
  chooseDt(s, criticalTimeStep(s), doc.file());
}

bridge::RunOutcome runStructurePart(const bridge::JsonDocument& doc, const StructurePart& part,
                                    const bridge::RunContext& ctx) {
  const StructureCase c = parseCase(doc, false);
  checkPart(c, part, doc.file());
  return runOne(c, partSample(c, doc), ctx, doc.file(), &part);
}

std::optional<bridge::Estimate> estimateStructurePart(const bridge::JsonDocument& doc, const StructurePart& part) {
  return estimateRuns(parseCase(doc, false), doc.file(), &part);
}

bridge::CaseKind structureImpactKind() {
  return replicateKind("micro.structure",
                       "a structure of generated cells resolved at the fine scale, struck by a boulder on its front "
                       "face (docs/resolved.md)",
                       check, replicates, estimate);
}

}  // namespace gabion::micro::lab
