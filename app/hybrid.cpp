#include "app/hybrid.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <memory>
#include <sstream>

#include "bridge/errors.hpp"
#include "bridge/output.hpp"
#include "macro/case_reader.hpp"
#include "macro/model.hpp"
#include "micro/lab/structure_impact.hpp"

namespace gabion::app {
namespace {

namespace fs = std::filesystem;
using bridge::Check;
using bridge::InputError;
using bridge::JsonDocument;
using bridge::JsonReader;
using micro::lab::StructurePart;
using nlohmann::json;
using Vec3 = Eigen::Vector3d;

/// The most tiles along an edge of a plate cut for the joint law (a tile of
/// a 0.5 m face at 5 is 0.1 m, a block or two).
constexpr int kMaxJointTiles = 5;

/// A hybrid case, read: the macro case, the cells resolved, their faces on
/// macro cells, and the fine part as a micro.structure document.
struct Plan {
  macro::ImpactCase c;
  macro::Structure structure;  ///< the macro part: no node for a resolved cell
  double within_m = 0.0;
  /// `resolve.behind_within_m`: the reach of the layers behind the front one (depth "whole"); further than
  /// within_m, macro cells of the front layer stand in front of resolved cells
  double behind_within_m = 0.0;
  bool whole_depth = false;    ///< `resolve.depth` "whole": every cell behind a resolved front cell too
  bool cells_below = false;    ///< `resolve.below` "cells": every cell under a resolved one too, down to the base
  bool below_gives = false;    ///< `resolve.below` "gives": a plate over a macro cell gives as its top would, settling
  bool lid_below = false;      ///< `resolve.below` "lid": a plate over a macro cell at the height of a cell's lid
  bool weight_above = false;   ///< `resolve.above` "weight": an upper plate presses with the cells above, settling
  bool beside_follow = false;  ///< `resolve.beside` "follow": the plates beside come down with their cell, settling
  /// `resolve.in_plane`: "follow", every plate moves in its plane with its cell, "free", slides along x and y as
  /// the bodies push it, settling
  StructurePart::InPlane in_plane = StructurePart::InPlane::Still;
  bool across_gives = false;  ///< `resolve.across` "gives": the plates across x give as their macro cells would, struck
  bool joints = false;        ///< `resolve.joint` "law": the plates on x faces give as the joint law closes, struck
  int joint_tiles = 1;        ///< `resolve.joint_tiles`: with joints, each x face's plate cut in n x n tiles
  int macro_axes = 1;         ///< `resolve.macro_motion`: the macro nodes move along x (1), x and y (2), or x, y, z (3)
  std::vector<int> resolved;
  std::vector<StructurePart::Face> faces;
  std::vector<std::size_t> across;  ///< with across "gives": the faces whose plates give (side faces and those under)
  /// with joint "law": the x faces, and the joint law of the macro cell across each
  std::vector<std::pair<std::size_t, bridge::JointLawParams>> joint_faces;
  json micro_case;
  std::string micro_file;  ///< names the fine part in messages
};

fs::path absoluteFrom(const JsonDocument& doc, const std::string& path) {
  const fs::path p(path);
  return p.is_absolute() ? p : fs::absolute(fs::path(doc.file()).parent_path() / p);
}

/// Distance (m) from the aim point (0, y, z) on the front plane to the box of cell (i, j, k).
double distanceToCell(int i, int j, int k, double edge, double y, double z) {
  const auto gap = [edge](double p, int n) { return std::max({0.0, n * edge - p, p - (n + 1) * edge}); };
  const double dx = gap(0.0, i), dy = gap(y, j), dz = gap(z, k);
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

/// The laws of the macro cell across a face of a resolved cell.
const bridge::CellMaterial& cellAcross(const macro::Structure& s, const StructurePart::Face& f) {
  const int node = s.node_of[static_cast<std::size_t>(f.other)];
  return s.materials[static_cast<std::size_t>(s.material[static_cast<std::size_t>(node)])];
}

Plan plan(const JsonDocument& doc) {
  const JsonReader root = doc.root();
  Plan p;
  p.c = macro::readImpactCase(doc, false);
  const JsonReader rs = root.object("resolve");
  p.within_m = rs.number("within_m", 0.0, Check::NonNegative);
  p.whole_depth = rs.choice("depth", {"reach", "whole"}, "reach") == "whole";
  p.behind_within_m = p.within_m;
  if (rs.has("behind_within_m")) {
    if (!p.whole_depth)
      rs.fail("behind_within_m", "a reach of its own for the layers behind the front one needs depth \"whole\"");
    p.behind_within_m = rs.number("behind_within_m", p.within_m, Check::NonNegative);
  }
  const std::string below = rs.choice("below", {"plates", "cells", "gives", "lid"}, "plates");
  p.cells_below = below == "cells";
  p.lid_below = below == "lid";
  p.below_gives = below == "gives";
  p.weight_above = rs.choice("above", {"fixed", "weight"}, "fixed") == "weight";
  p.beside_follow = rs.choice("beside", {"fixed", "follow"}, "fixed") == "follow";
  const std::string in_plane = rs.choice("in_plane", {"still", "follow", "free"}, "still");
  p.in_plane = in_plane == "follow" ? StructurePart::InPlane::Follow
               : in_plane == "free" ? StructurePart::InPlane::Free
                                    : StructurePart::InPlane::Still;
  p.across_gives = rs.choice("across", {"fixed", "gives"}, "fixed") == "gives";
  p.joints = rs.choice("joint", {"none", "law"}, "none") == "law";
  p.joint_tiles = static_cast<int>(rs.integer("joint_tiles", 1, 1));
  if (p.joint_tiles > kMaxJointTiles)
    rs.fail("joint_tiles", "at most " + std::to_string(kMaxJointTiles) + " tiles along an edge");
  if (p.joint_tiles > 1 && !p.joints)
    rs.fail("joint_tiles", "tiles carry the joint law: give resolve.joint \"law\" too");
  const std::string motion = rs.choice("macro_motion", {"x", "xy", "xyz"}, "x");
  p.macro_axes = static_cast<int>(motion.size());
  const fs::path cell_file = absoluteFrom(doc, rs.string("cell"));
  if (p.c.impacts.size() != 1)
    root.fail("impacts", "a hybrid run takes one impact (the fine part is struck once): give `boulder`");
  macro::BoulderSpec& b = p.c.impacts.front();
  if (b.velocity_m_s.y() != 0.0 || b.velocity_m_s.z() != 0.0)
    root.fail("boulder", "a hybrid run's boulder moves along +x (velocity_m_s a number, or [v, 0, 0])");
  if (p.c.run.kinematics != macro::Kinematics::XOnly)
    root.fail("run",
              "a hybrid run couples x-only macro nodes (run.kinematics \"x-only\"): in 3-D the resolved "
              "cells' weight on their macro neighbours has no counterpart in the macro model");
  for (const int off : p.c.structure.front_offset_cells)
    if (off != 0) root.fail("structure", "a hybrid structure has a plane front face (no front_offset_cells)");

  // The aim, on the whole structure; then which cells are within reach
  // (with depth "whole": which columns, by their front cell; the layers
  // behind the front one within their own reach, behind_within_m).
  const macro::Structure whole = macro::buildCaseStructure(doc, p.c);
  macro::resolveAims(doc, p.c, whole);
  const int nx = whole.nx, ny = whole.ny, nz = whole.nz;
  const double e = whole.edge_m;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        if (distanceToCell(p.whole_depth ? 0 : i, j, k, e, b.aim_y_m, b.aim_z_m) <=
            (i > 0 ? p.behind_within_m : p.within_m))
          p.resolved.push_back(i + nx * (j + ny * k));
  // With below "cells", a resolved cell stands on resolved cells down to
  // the base, as in the wall, not on the plate of a macro cell that does
  // not come down under its weight.
  if (p.cells_below) {
    std::vector<char> in(static_cast<std::size_t>(nx) * ny * nz, 0);
    for (const int cell : p.resolved) in[static_cast<std::size_t>(cell)] = 1;
    for (int k = nz - 1; k > 0; --k)
      for (int q = 0; q < nx * ny; ++q)
        if (in[static_cast<std::size_t>(q + nx * ny * k)]) in[static_cast<std::size_t>(q + nx * ny * (k - 1))] = 1;
    p.resolved.clear();
    for (int cell = 0; cell < nx * ny * nz; ++cell)
      if (in[static_cast<std::size_t>(cell)]) p.resolved.push_back(cell);
  }
  if (p.resolved.empty()) {  // (an aim on the face's edge is within 0 of a cell: never empty)
    rs.fail("within_m", "no cell is within reach of the aim point");
  }
  if (static_cast<long long>(p.resolved.size()) > micro::lab::kMaxResolvedCells)
    rs.fail("within_m", std::to_string(p.resolved.size()) + " cells within reach: more than " +
                            std::to_string(micro::lab::kMaxResolvedCells) + " resolved at the fine scale");
  if (static_cast<int>(p.resolved.size()) == nx * ny * nz) {
    std::ostringstream m;
    m << "within " << p.within_m << " m of the aim point lies the whole structure (" << nx << " x " << ny << " x " << nz
      << " cells): the resolved region is larger than the structure; run it resolved (macro.resolved, "
         "micro.structure), or resolve less";
    rs.fail("within_m", m.str());
  }
  const auto isResolved = [&](int i, int j, int k) {
    return std::find(p.resolved.begin(), p.resolved.end(), i + nx * (j + ny * k)) != p.resolved.end();
  };
  for (const int cell : p.resolved) {
    const int ijk[3] = {cell % nx, (cell / nx) % ny, cell / (nx * ny)}, n[3] = {nx, ny, nz};
    for (int axis = 0; axis < 3; ++axis)
      for (const int side : {-1, 1}) {
        int o[3] = {ijk[0], ijk[1], ijk[2]};
        o[axis] += side;
        if (o[axis] < 0 || o[axis] >= n[axis] || isResolved(o[0], o[1], o[2])) continue;
        // (an upper face: the cells stacked on it, their weight on the
        // resolved cell while it settles, with above "weight")
        const int above = axis == 2 && side > 0 && p.weight_above ? nz - 1 - ijk[2] : 0;
        // (with joint tiles, an x face is tiles x tiles plates, each a face)
        const int tiles = axis == 0 ? p.joint_tiles : 1;
        for (int t = 0; t < tiles * tiles; ++t)
          p.faces.push_back({cell, axis, side, o[0] + nx * (o[1] + ny * o[2]), above, false, {}, tiles, t});
      }
  }
  p.c.structure.resolved_cells = p.resolved;
  // In 3-D the macro part stands on the ground as the resolved cells stand
  // on their base: the half-cell law against sinking, friction under the
  // column's weight (support "ground" "friction", whatever the case says).
  if (p.macro_axes > 1) p.c.structure.support.ground_friction = true;
  p.structure = macro::buildCaseStructure(doc, p.c);
  // With below "gives", the plate under a resolved cell, the top of the
  // macro cell below, gives along that cell's axial law while the part settles.
  if (p.below_gives)
    for (StructurePart::Face& f : p.faces)
      if (f.axis == 2 && f.side < 0) f.gives = true, f.law = cellAcross(p.structure, f).axial;
  // With across "gives", in the impact, the plates beside and under the
  // resolved cells give as the macro cells across them would be shortened
  // (Coupler::give).
  if (p.across_gives)
    for (std::size_t k = 0; k < p.faces.size(); ++k) {
      StructurePart::Face& f = p.faces[k];
      if (f.axis == 1 || (f.axis == 2 && f.side < 0)) f.law = cellAcross(p.structure, f).axial, p.across.push_back(k);
    }

  // With joint "law", in the impact, the plates on the x faces give as the
  // joint between the resolved cell and the macro cell across closes
  // (Coupler::give), by that cell's joint law.
  if (p.joints)
    for (std::size_t k = 0; k < p.faces.size(); ++k) {
      const StructurePart::Face& f = p.faces[k];
      if (f.axis != 0) continue;
      const bridge::CellMaterial& m = cellAcross(p.structure, f);
      if (!m.joint)
        rs.fail("joint",
                "\"law\" needs a joint law in the macro cells' material (law.json: materials/<name>/joint; fit it "
                "with a fit case's \"joint\" from two confined compressions, docs/fitting.md)");
      p.joint_faces.emplace_back(k, *m.joint);
    }

  // The fine part: micro.structure's keys, the structure's size, back
  // support and boulder, and the aim as the same fraction of the face.
  json boulder = {{"diameter_m", b.diameter_m},
                  {"density_kg_m3", b.density_kg_m3},
                  {"velocity_m_s", b.velocity_m_s.x()},
                  {"aim_face_fraction", {b.aim_y_m / (ny * e), b.aim_z_m / (nz * e)}}};
  p.micro_case = {
      {"cell", cell_file.string()},
      {"structure",
       {{"cells", {nx, ny, nz}}, {"support", {{"back", p.c.structure.support.fixed_back ? "fixed" : "none"}}}}},
      {"boulder", boulder},
      {"rebound_restitution", p.c.run.rebound_restitution}};
  for (const auto& [key, value] : root.raw("resolve").items()) {
    if (key == "cell" || key == "within_m" || key == "behind_within_m" || key == "depth" || key == "below" ||
        key == "above" || key == "beside" || key == "in_plane" || key == "across" || key == "joint" ||
        key == "joint_tiles" || key == "macro_motion")
      continue;
    if (key == "structure" || key == "boulder")
      rs.fail(key, "the hybrid's structure and boulder are the macro case's: give them there");
    p.micro_case[key] = value;
  }
  p.micro_file = doc.file() + " (resolve)";
  return p;
}

/// The macro part in motion, stepped by the fine engine's wall driver.
class Coupler {
  /// A plate that gives (give()): its face, its law's loading curve (force,
  /// N, at a move, m) and that curve's inverse, its servo's gain (m/s per N) and top speed, where
  /// the curve stood at the impact's start and how far the plate has moved
  /// since (m).
  struct GivingPlate {
    std::size_t face = 0;
    std::function<double(double)> force_at;
    std::function<double(double)> carrying;  ///< its inverse: the move (m) at which it first carries a force (N)
    double gain_m_s_N = 0.0, top_m_s = 0.0, start_m = 0.0, moved_m = 0.0;
  };
  /// One kind of giving plates, with the work into their laws (J).
  struct Giving {
    std::vector<GivingPlate> plates;
    bool started = false;
    double work_J = 0.0;  // the plates' work into the laws, sum F . d
    std::vector<double> movedByFace(std::size_t n) const {
      std::vector<double> out(n, NAN);
      for (const GivingPlate& q : plates) out[q.face] = q.moved_m;
      return out;
    }
    void archive(bridge::StateArchive& a, const std::string& name) {
      std::vector<double> start, moved;
      for (const GivingPlate& q : plates) start.push_back(q.start_m), moved.push_back(q.moved_m);
      a(name + "_J", work_J), a(name + "_started", started), a(name + "_start_m", start);
      a(name + "_moved_m", moved);
      for (std::size_t k = 0; k < plates.size() && k < start.size() && k < moved.size(); ++k)
        plates[k].start_m = start[k], plates[k].moved_m = moved[k];
    }
  };
  static constexpr double kAcrossSpeed_m_s = 0.5;  // (as the plates that give while the part settles)
  /// (the joints of a struck wall close at up to about 1.3 m/s, bench_struck_cell)
  static constexpr double kJointSpeed_m_s = 2.0;

 public:
  /// With macro_motion "xy" or "xyz" the macro part runs in 3-D kinematics
  /// (the lateral links' cell law across the y and z faces, the ground's
  /// under the base, friction on every face), with "xy" its z forces held
  /// at zero: its nodes do not move along z (the friction along z is
  /// driven by z slides only).
  explicit Coupler(const Plan& p)
      : model_(p.structure, p.macro_axes > 1 ? macro::Kinematics::ThreeD : p.c.run.kinematics),
        axes_(p.macro_axes),
        faces_(p.faces),
        critical_s_(model_.criticalTimeStep()) {
    for (const StructurePart::Face& f : p.faces) {
      const int node = p.structure.node_of[static_cast<std::size_t>(f.other)];
      face_node_.push_back(static_cast<std::size_t>(node));
    }
    for (std::size_t q = 0; q < p.structure.nodeCount(); ++q) {
      if (p.structure.gi[q] == 0) front_.push_back(q);
      if (p.structure.gi[q] == p.structure.nx - 1) back_.push_back(q);
    }
    // A back node behind a resolved cell stands for its cell's front face
    // (its rear link spans the whole cell, macro/structure.cpp); against a
    // fixed back support its cell's centre, what the back face measures in
    // the resolved cells and at every other node, moves half as far.
    for (const std::size_t q : back_) {
      const int i = p.structure.gi[q], j = p.structure.gj[q], k = p.structure.gk[q];
      const bool whole = i > 0 && p.structure.nodeAt(i - 1, j, k) < 0;  // (no node there: a resolved cell)
      back_centre_.push_back(whole && p.c.structure.support.fixed_back ? 0.5 : 1.0);
    }
    node_force_.assign(p.structure.nodeCount(), Vec3::Zero());
    const auto weightAcross = [&](std::size_t k) {
      return cellAcross(p.structure, p.faces[k]).mass_kg * p.c.structure.support.gravity_m_s2;
    };
    for (const std::size_t k : p.across) {
      const bridge::AxialLawParams law = p.faces[k].law;
      const auto at = [law](double u) { return bridge::axialResponse(law, u, 0.0).force_N; };
      across_.plates.push_back(
          {k, at, [at](double f) { return carrying(at, f); }, kAcrossSpeed_m_s / weightAcross(k), kAcrossSpeed_m_s});
    }
    // A tile carries its share of the face's joint law: the closure at a
    // pressure is the law's at that pressure over the whole face (the joint
    // a bed of independent springs), so a tile of 1/n of the face closes
    // as the whole face would under n times the tile's force.
    for (const auto& [k, law] : p.joint_faces) {
      const double n = static_cast<double>(p.faces[k].tiles) * p.faces[k].tiles;
      joints_.plates.push_back({k, [law = law, n](double c) { return bridge::jointForce(law, c) / n; },
                                [law = law, n](double f) { return bridge::jointClosure(law, n * f); },
                                n * kJointSpeed_m_s / weightAcross(k), kJointSpeed_m_s});
    }
  }

  /// Engine::WallDriver: the plates' forces onto their nodes, one macro
  /// step, the nodes' displacements back to the plates.
  ///
  /// The macro part starts at rest with no force in its laws, while the
  /// plates carry the settled part's forces (the resolved cells' weight on
  /// the plates under them, their fill's push on the others), which in the
  /// wall the cells across hold with forces of their own. In x-only that
  /// push is small and the nodes take the plates' whole forces. In 3-D
  /// (macro_motion "xy", "xyz") the nodes take the forces' change since
  /// the impact's first step: the settled forces are the macro part's
  /// pre-stress, and their work on the nodes' moves (prestress_work_J_)
  /// is energy the cells across bring in.
  void drive(double, double dt, const std::vector<Vec3>& forces, std::vector<Vec3>& moves) {
    if (dt > critical_s_) {
      std::ostringstream m;
      m << "the fine step " << dt << " s is above the macro part's critical step " << critical_s_ << " s";
      throw bridge::NumericalError(model_.steps(), model_.time_s(), m.str());
    }
    if (prestress_.empty()) prestress_ = axes_ > 1 ? forces : std::vector<Vec3>(forces.size(), Vec3::Zero());
    for (const std::size_t n : face_node_) node_force_[n].setZero();
    for (std::size_t k = 0; k < forces.size(); ++k) node_force_[face_node_[k]] += forces[k] - prestress_[k];
    for (const std::size_t n : face_node_)
      model_.setExternalForce(n, {node_force_[n].x(), node_force_[n].y(), axes_ > 2 ? node_force_[n].z() : 0.0});
    const macro::StepStatus st = model_.step(dt);
    if (st == macro::StepStatus::NonFinite)
      throw bridge::NumericalError(model_.steps(), model_.time_s(), "the macro part: " + model_.failure());
    if (st == macro::StepStatus::Perforation && failure_.empty()) failure_ = "the macro part: " + model_.failure();
    last_force_ = forces;
    const std::vector<double>&vx = model_.vx(), &vy = model_.vy(), &vz = model_.vz();
    // (the node moves along x, y with "xy", z with "xyz"; the plate with it)
    for (std::size_t k = 0; k < forces.size(); ++k) {
      const std::size_t n = face_node_[k];
      moves[k] = Vec3(dt * vx[n], axes_ > 1 ? dt * vy[n] : 0.0, axes_ > 2 ? dt * vz[n] : 0.0);
      prestress_work_J_ += prestress_[k].dot(moves[k]);
    }
    if (axes_ > 1) {  // (x-only nodes do not move across x)
      for (const double u : model_.uy()) max_move_m_[0] = std::max(max_move_m_[0], std::fabs(u));
      for (const double u : model_.uz()) max_move_m_[1] = std::max(max_move_m_[1], std::fabs(u));
    }
    give(across_, dt, forces, moves);
    give(joints_, dt, forces, moves);
    for (std::size_t k = 0; k < forces.size(); ++k) work_on_fine_J_ -= forces[k].dot(moves[k]);
  }

  /// Plates that give (across "gives": those beside and under a resolved
  /// cell, by the macro cell across's axial law; joint "law": those on its
  /// x faces, by the joint law, the joint between the two cells closing):
  /// each moves along its normal, away from the resolved cell, as the
  /// law's loading curve allows: a servo, at most its top speed (that speed
  /// at a push in excess of the macro cell's weight), while the bodies push
  /// the plate with more than the curve carries at its move so far, and
  /// never back. The curve starts where it carries the push at the impact's
  /// start (the weight on the plates under, next to nothing on the others).
  /// The macro node does not move with it: the work into the law
  /// (g.work_J) is dissipated.
  void give(Giving& g, double dt, const std::vector<Vec3>& forces, std::vector<Vec3>& moves) {
    for (GivingPlate& q : g.plates) {
      const StructurePart::Face& f = faces_[q.face];
      const double push = f.side * forces[q.face][f.axis];  // (towards the macro cell)
      if (!g.started) q.start_m = q.carrying(push);
      const double carried = q.force_at(q.start_m + q.moved_m);
      const double d = dt * std::clamp(q.gain_m_s_N * (push - carried), 0.0, q.top_m_s);
      q.moved_m += d;
      moves[q.face][f.axis] += f.side * d;
      g.work_J += push * d;
    }
    g.started = true;
  }

  /// Where a loading curve first carries `force` (bisection: the curve does
  /// not fall), 0 for none: the inverse of a law that has none in closed form.
  static double carrying(const std::function<double(double)>& at, double force) {
    if (!(force > at(0.0))) return 0.0;
    double lo = 0.0, hi = 1e-3;
    while (at(hi) < force && hi < 1.0) lo = hi, hi *= 2.0;
    for (int k = 0; k < 60; ++k) (at(0.5 * (lo + hi)) < force ? lo : hi) = 0.5 * (lo + hi);
    return hi;
  }

  std::pair<double, double> facesMoved() const {
    double front = 0.0, back = 0.0;
    for (const std::size_t q : front_) front = std::max(front, model_.ux()[q]);
    for (std::size_t k = 0; k < back_.size(); ++k) back = std::max(back, back_centre_[k] * model_.ux()[back_[k]]);
    return {front, back};
  }

  /// At each series sample: the balance of both parts together, from the
  /// impact's start (the fine part's terms as its ledger has them).
  void record(const micro::Engine& e) {
    const double fine = e.energy().total_J + work_on_fine_J_;  // (its interface work taken back out)
    if (!started_) fine0_ = fine, settled_ = last_force_, started_ = true;
    // The plates' forces when the x faces carry most (from the settled state).
    if (last_force_.size() == settled_.size()) {
      double axial = 0.0;
      for (std::size_t k = 0; k < faces_.size(); ++k)
        if (faces_[k].axis == 0 && faces_[k].side > 0) axial += last_force_[k].x() - settled_[k].x();
      if (axial > peak_axial_N_) peak_axial_N_ = axial, at_peak_ = last_force_;
    }
    const macro::Energy& m = model_.energy();
    residual_J_ = (fine - fine0_) + m.total() + across_.work_J + joints_.work_J + prestress_work_J_;
  }

  void archive(bridge::StateArchive& a) {
    model_.archive(a);
    a("work_on_fine_J", work_on_fine_J_), a("fine0", fine0_), a("started", started_), a("residual_J", residual_J_);
    a("last_force", last_force_), a("settled", settled_), a("at_peak", at_peak_), a("peak_axial_N", peak_axial_N_);
    a("failure", failure_), a("max_y_move_m", max_move_m_[0]), a("max_z_move_m", max_move_m_[1]);
    a("prestress", prestress_), a("prestress_work_J", prestress_work_J_);
    across_.archive(a, "across");
    joints_.archive(a, "joint");
  }

  const std::string& failure() const { return failure_; }

  /// How far each plate that gives across x has moved (m), by face; NAN for the others.
  std::vector<double> movedAcross() const { return across_.movedByFace(faces_.size()); }
  /// How far each x face's joint closed in the impact (m), by face; NAN for the others.
  std::vector<double> jointClosed() const { return joints_.movedByFace(faces_.size()); }

  /// Each plate's force settled and when the x faces carried most, and
  /// for a lateral face of a cell with an x face behind it, its normal
  /// force over that x face's (both from the settled state): the lateral
  /// reaction the macro laws take as reaction_coefficient x axial force.
  json interfaceForces() const {
    json out = json::array();
    for (std::size_t k = 0; k < faces_.size(); ++k) {
      const Vec3 settled = k < settled_.size() ? settled_[k] : Vec3::Zero();
      const Vec3 peak = k < at_peak_.size() ? at_peak_[k] : Vec3::Zero();
      json f = {{"force_settled_N", {settled.x(), settled.y(), settled.z()}},
                {"force_at_peak_axial_N", {peak.x(), peak.y(), peak.z()}}};
      const int a = faces_[k].axis;
      double axial = 0.0;  // (the x face behind, all its tiles)
      bool behind = false;
      for (std::size_t q = 0; q < faces_.size() && a != 0; ++q) {
        if (faces_[q].axis != 0 || faces_[q].side != 1 || faces_[q].cell != faces_[k].cell) continue;
        behind = true;
        axial += (q < at_peak_.size() ? at_peak_[q].x() : 0.0) - (q < settled_.size() ? settled_[q].x() : 0.0);
      }
      if (behind && axial > 0.0) f["reaction_to_axial_at_peak"] = std::fabs(peak[a] - settled[a]) / axial;
      out.push_back(f);
    }
    return out;
  }

  json report(double impact_energy_J) const {
    const macro::Energy& m = model_.energy();
    const double mismatch = work_on_fine_J_ + m.external_work_J + across_.work_J + joints_.work_J + prestress_work_J_;
    return {
        {"work_on_fine_part_J", work_on_fine_J_},
        {"work_on_macro_part_J", m.external_work_J},
        {"work_into_cells_across_J", across_.work_J},
        {"work_into_joints_J", joints_.work_J},
        {"interface_mismatch_J", mismatch},
        {"macro_energy_J",
         {{"kinetic", m.kinetic_J}, {"elastic", m.elastic_J}, {"plastic", m.plastic_J}, {"friction", m.friction_J}}},
        {"macro_balance_rel_error", impact_energy_J > 0.0 ? (m.total() - m.external_work_J) / impact_energy_J : 0.0},
        {"balance_rel_error", impact_energy_J > 0.0 ? residual_J_ / impact_energy_J : 0.0},
        {"macro_steps", model_.steps()},
        {"prestress_work_J", prestress_work_J_},
        {"macro_max_y_move_m", max_move_m_[0]},
        {"macro_max_z_move_m", max_move_m_[1]},
        {"macro_critical_time_step_s", critical_s_}};
  }

 private:
  macro::Model model_;
  int axes_ = 1;  ///< macro_motion: 1 "x", 2 "xy", 3 "xyz"
  std::vector<std::size_t> face_node_, front_, back_;
  std::vector<double> back_centre_;  ///< per back node: its cell centre's displacement over the node's
  Giving across_, joints_;           // across "gives", joint "law"
  std::vector<Vec3> node_force_;
  std::vector<StructurePart::Face> faces_;
  std::vector<Vec3> last_force_, settled_, at_peak_;  // the plates' forces: last step, settled, at the axial peak
  double critical_s_;                                 // the macro part's (s)
  double peak_axial_N_ = 0.0;
  double max_move_m_[2] = {0.0, 0.0};  // the largest |y| and |z| moves of a macro node (m)
  /// The plates' forces at the impact's first step, which the macro part
  /// holds as pre-stress (3-D; zero in x-only; empty before that step),
  /// and their work on the nodes' moves (J).
  std::vector<Vec3> prestress_;
  double prestress_work_J_ = 0.0;
  double work_on_fine_J_ = 0.0;  // the plates' work on the bodies, -sum F . d
  double fine0_ = 0.0, residual_J_ = 0.0;
  bool started_ = false;
  std::string failure_;
};

StructurePart partOf(const Plan& p, Coupler* coupler) {
  StructurePart part;
  part.cells = p.resolved;
  part.faces = p.faces;
  part.beside_follow = p.beside_follow;
  part.in_plane = p.in_plane;
  part.lid_plates = p.lid_below;
  if (coupler) {
    part.drive = [coupler](double t, double dt, const std::vector<Vec3>& f, std::vector<Vec3>& d) {
      coupler->drive(t, dt, f, d);
    };
    part.faces_moved = [coupler] { return coupler->facesMoved(); };
    part.archive = [coupler](bridge::StateArchive& a) { coupler->archive(a); };
    part.record = [coupler](const micro::Engine& e) { coupler->record(e); };
    part.failure = [coupler] { return coupler->failure(); };
  }
  return part;
}

void check(const JsonDocument& doc) {
  const Plan p = plan(doc);
  const JsonDocument micro(p.micro_case, p.micro_file);
  micro::lab::checkStructurePart(micro, partOf(p, nullptr));
  micro.finish();
}

std::optional<bridge::Estimate> estimate(const JsonDocument& doc) {
  const Plan p = plan(doc);
  const JsonDocument micro(p.micro_case, p.micro_file);
  return micro::lab::estimateStructurePart(micro, partOf(p, nullptr));
}

bridge::RunOutcome run(const JsonDocument& doc, const bridge::RunContext& ctx) {
  const Plan p = plan(doc);
  const JsonDocument micro(p.micro_case, p.micro_file);
  auto coupler = std::make_unique<Coupler>(p);
  bridge::RunOutcome out = micro::lab::runStructurePart(micro, partOf(p, coupler.get()), ctx);
  json& r = out.results;
  const double energy = r.value("impact_energy_J", 0.0);
  json h = coupler->report(energy);
  h["within_m"] = p.within_m;
  h["depth"] = p.whole_depth ? "whole" : "reach";
  if (p.whole_depth) h["behind_within_m"] = p.behind_within_m;
  h["below"] = p.cells_below ? "cells" : p.below_gives ? "gives" : p.lid_below ? "lid" : "plates";
  h["above"] = p.weight_above ? "weight" : "fixed";
  h["beside"] = p.beside_follow ? "follow" : "fixed";
  h["in_plane"] = p.in_plane == StructurePart::InPlane::Follow ? "follow"
                  : p.in_plane == StructurePart::InPlane::Free ? "free"
                                                               : "still";
  h["across"] = p.across_gives ? "gives" : "fixed";
  h["joint"] = p.joints ? "law" : "none";
  h["joint_tiles"] = p.joint_tiles;
  h["macro_motion"] = std::string("xyz").substr(0, static_cast<std::size_t>(p.macro_axes));
  json cells = json::array(), faces = json::array();
  const int nx = p.structure.nx, ny = p.structure.ny;
  for (const int c : p.resolved) cells.push_back({c % nx, (c / nx) % ny, c / (nx * ny)});
  const json forces = coupler->interfaceForces();
  const std::vector<double> across = coupler->movedAcross(), closed = coupler->jointClosed();
  for (std::size_t k = 0; k < p.faces.size(); ++k) {
    const StructurePart::Face& f = p.faces[k];
    json face = {{"cell", {f.cell % nx, (f.cell / nx) % ny, f.cell / (nx * ny)}},
                 {"axis", std::string(1, "xyz"[f.axis])},
                 {"side", f.side},
                 {"macro_node", p.structure.node_of[static_cast<std::size_t>(f.other)]}};
    if (f.tiles > 1) face["tile"] = {f.tile % f.tiles, f.tile / f.tiles};
    face.update(forces[k]);
    if (!std::isnan(across[k])) face["moved_across_m"] = across[k];
    if (!std::isnan(closed[k])) face["joint_closed_m"] = closed[k];
    faces.push_back(face);
  }
  h["resolved_cells"] = cells;
  h["interfaces"] = faces;
  h["macro_nodes"] = p.structure.nodeCount();
  r["hybrid"] = h;
  if (const auto w = cellSizeMismatch(p.structure.edge_m, r, "the macro part")) r["warnings"].push_back(*w);
  std::ostringstream a;
  a.precision(3);
  a << "hybrid: " << p.resolved.size() << " of " << p.structure.nx * p.structure.ny * p.structure.nz
    << " cells resolved (within " << p.within_m << " m of the aim" << (p.whole_depth ? ", through the depth" : "");
  if (p.whole_depth && p.behind_within_m != p.within_m) a << ", within " << p.behind_within_m << " m behind the front";
  a << (p.cells_below ? ", and the cells below them" : "") << (p.below_gives ? ", the plates under them giving" : "")
    << (p.lid_below ? ", the plates under them at the lids below" : "")
    << (p.weight_above ? ", the weight of the cells above on them" : "")
    << (p.beside_follow ? ", the plates beside coming down with them" : "")
    << (p.in_plane == StructurePart::InPlane::Follow ? ", the plates moving in their planes with them" : "")
    << (p.in_plane == StructurePart::InPlane::Free ? ", the plates free along x and y" : "")
    << (p.across_gives ? ", the plates across x giving" : "") << (p.joints ? ", joints closing at the x faces" : "")
    << (p.joint_tiles > 1 ? " in " + std::to_string(p.joint_tiles) + " x " + std::to_string(p.joint_tiles) + " tiles"
                          : "")
    << (p.macro_axes == 2 ? ", the macro nodes moving along x and y" : "")
    << (p.macro_axes == 3 ? ", the macro nodes moving along x, y and z" : "") << "), " << p.faces.size()
    << " interface plates; energy balance of both parts " << h["balance_rel_error"].get<double>()
    << ", interface mismatch " << h["interface_mismatch_J"].get<double>() << " J\n";
  out.answer = a.str() + out.answer;
  return out;
}

}  // namespace

std::optional<std::string> cellSizeMismatch(double law_edge_m, const json& res, const std::string& who) {
  if (!(law_edge_m > 0.0)) return std::nullopt;
  double size = NAN, tolerance = 0.05;
  std::string what = "nominal edge";
  const json pitch = res.value("cell_pitch_m", json());
  if (res.contains("cell_edge_m") && res["cell_edge_m"].is_number()) {
    size = res["cell_edge_m"].get<double>();
  } else if (pitch.is_array() && pitch.size() == 3) {
    size = (pitch[0].get<double>() + pitch[1].get<double>() + pitch[2].get<double>()) / 3.0;
    tolerance = 0.2, what = "extent";
  }
  if (!std::isfinite(size) || std::fabs(size - law_edge_m) <= tolerance * law_edge_m) return std::nullopt;
  std::ostringstream m;
  m << "the laws' cell edge (" << law_edge_m << " m) and the resolved cell's " << what << " (" << size
    << " m) differ by more than " << 100.0 * tolerance << " %: " << who
    << " is not the same structure (laws fitted from another cell?)";
  return m.str();
}

bridge::CaseKind withHybrid(const bridge::CaseKind& impact) {
  bridge::CaseKind k = impact;
  const auto hybrid = [](const JsonDocument& doc) { return doc.root().has("resolve"); };
  k.description += "; with \"resolve\", the cells near the aim point resolved at the fine scale (hybrid)";
  k.check = [impact, hybrid](const JsonDocument& doc) {
    if (hybrid(doc))
      check(doc);
    else
      impact.check(doc);
  };
  k.run = [impact, hybrid](const JsonDocument& doc, const bridge::RunContext& ctx) {
    return hybrid(doc) ? run(doc, ctx) : impact.run(doc, ctx);
  };
  k.estimate = [impact, hybrid](const JsonDocument& doc) -> std::optional<bridge::Estimate> {
    if (hybrid(doc)) return estimate(doc);
    return impact.estimate ? impact.estimate(doc) : std::nullopt;
  };
  return k;
}

}  // namespace gabion::app
