#include "micro/cell/cell_assembly.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bridge/errors.hpp"
#include "bridge/output.hpp"
#include "bridge/plot.hpp"
#include "micro/blocks/block_fill.hpp"
#include "micro/cell/cell_file.hpp"
#include "micro/cell/cell_view.hpp"
#include "micro/cell/porosity.hpp"
#include "micro/netting/mesh.hpp"
#include "micro/netting/netting_input.hpp"
#include "micro/rigid_body.hpp"
#include "micro/scene_run.hpp"

namespace gabion::micro {
namespace {

using bridge::Check;
using bridge::JsonReader;

struct CellCase {
  double edge_m = 0.5;
  double target_porosity = 0.436;
  std::uint64_t seed = 1;
  int threads = 1;  // the engine's, whatever the run's: with the seed, they define the cell
  Vec3 gravity = Vec3(0, 0, -9.81);
  Material rock, formwork;
  NettingInput netting;
  std::optional<JsonReader> blocks;
  double mass_kg = 0.0;  // rock to fill the cell to the target porosity
  struct {
    double max_duration_s = 2.0, settled_kinetic_ratio = 1e-3;
    double friction = -1.0;  // the rock's friction while it falls in (< 0: its own)
    double overfill = 0.03;  // rock beyond the target's mass, as a fraction of it
  } fill;
  struct {
    double frequency_hz = 20.0, amplitude_m = 0.002, max_duration_s = 1.5, check_interval_s = 0.05;
    double surcharge_Pa = 1000.0;
    Vec3 direction = Vec3::UnitZ();  // of the shaking, unit
    double friction = -1.0;          // the rock's friction while shaking (< 0: its own)
  } vibration;
  struct {
    double pressure_Pa = 10000.0, speed_m_s = 0.2, max_duration_s = 0.5;
    bool vibrate = true;  // the shaking goes on while the plate presses (the fill at its shaking friction)
  } closing;
  struct {
    double max_duration_s = 2.0, kinetic_ratio = 1e-6, max_bulge_m = 0.02, max_settlement_m = 0.02;
  } standing;
  double porosity_spacing_m = 0.002;
  RunSpec run;
};

Material parseNamedMaterial(const std::string& name, const JsonReader& r) {
  Material m = parseMaterial(name, r);
  m.name = name;
  return m;
}

// A cell's netting, unless the case says otherwise: wires that bend (a
// pin-jointed net is a mechanism under the fill), one bead on every single
// wire (the rock meets the wire between the twists instead of passing the
// wire's line into the opening) and node masses scaled by 8 (their inertia;
// docs/cell.md, Time step).
MeshSpec cellMeshDefaults() {
  MeshSpec m;
  m.bending = true;
  m.wire_beads = 1;
  m.node_mass_scale = 8.0;
  return m;
}

CellCase parseCase(const bridge::JsonDocument& doc) {
  const JsonReader root = doc.root();
  CellCase c;
  c.edge_m = root.number("edge_m", c.edge_m, Check::Positive);
  c.target_porosity = root.number("target_porosity", c.target_porosity, Check::Positive);
  if (c.target_porosity >= 1.0) root.fail("target_porosity", "must be below 1");
  c.seed = root.seed("seed", 1);
  c.threads = static_cast<int>(root.integer("threads", c.threads, 1));
  if (c.threads > 256) root.fail("threads", "must be at most 256");
  c.gravity = root.vec3("gravity_m_s2", c.gravity);
  if (!(c.gravity.z() < 0.0)) root.fail("gravity_m_s2", "a cell is filled under gravity: its z component must be < 0");
  c.rock = parseNamedMaterial("rock", root.object("rock"));
  c.formwork = c.rock;
  c.formwork.name = "formwork";
  if (const auto f = root.optionalObject("formwork")) c.formwork = parseNamedMaterial("formwork", *f);
  c.netting = parseNetting(root.object("netting"), cellMeshDefaults());
  c.netting.contact.name = "netting";
  c.blocks = root.object("blocks");
  if (c.netting.mesh.opening_m > c.edge_m) root.fail("edge_m", "the cell must be at least one mesh opening wide");
  if (const auto f = root.optionalObject("fill")) {
    c.fill.max_duration_s = f->number("max_duration_s", c.fill.max_duration_s, Check::Positive);
    c.fill.settled_kinetic_ratio = f->number("settled_kinetic_ratio", c.fill.settled_kinetic_ratio, Check::Positive);
    c.fill.friction = f->number("friction", c.rock.friction, Check::NonNegative);
    c.fill.overfill = f->number("overfill", c.fill.overfill, Check::NonNegative);
    if (c.fill.overfill > 0.2) f->fail("overfill", "at most 0.2 (20 % more rock than the target porosity takes)");
  }
  // The rock to fill the cell to the target porosity, and the overfill that
  // the closing presses down (blocks the plate cannot press in are taken off).
  c.mass_kg = (1.0 - c.target_porosity) * c.rock.density_kg_m3 * std::pow(c.edge_m, 3) * (1.0 + c.fill.overfill);
  if (const auto v = root.optionalObject("vibration")) {
    c.vibration.frequency_hz = v->number("frequency_hz", c.vibration.frequency_hz, Check::Positive);
    c.vibration.amplitude_m = v->number("amplitude_m", c.vibration.amplitude_m, Check::Positive);
    c.vibration.max_duration_s = v->number("max_duration_s", c.vibration.max_duration_s, Check::NonNegative);
    c.vibration.check_interval_s = v->number("check_interval_s", c.vibration.check_interval_s, Check::Positive);
    c.vibration.surcharge_Pa = v->number("surcharge_Pa", c.vibration.surcharge_Pa, Check::NonNegative);
    c.vibration.direction = v->vec3("direction", c.vibration.direction);
    if (!(c.vibration.direction.norm() > 0.0)) v->fail("direction", "must not be zero");
    c.vibration.direction.normalize();
    c.vibration.friction = v->number("friction", c.rock.friction, Check::NonNegative);
  }
  if (const auto k = root.optionalObject("closing")) {
    c.closing.pressure_Pa = k->number("pressure_Pa", c.closing.pressure_Pa, Check::Positive);
    c.closing.speed_m_s = k->number("speed_m_s", c.closing.speed_m_s, Check::Positive);
    c.closing.max_duration_s = k->number("max_duration_s", c.closing.max_duration_s, Check::Positive);
    c.closing.vibrate = k->boolean("vibrate", c.closing.vibrate);
  }
  if (const auto s = root.optionalObject("standing")) {
    c.standing.max_duration_s = s->number("max_duration_s", c.standing.max_duration_s, Check::Positive);
    c.standing.kinetic_ratio = s->number("kinetic_ratio", c.standing.kinetic_ratio, Check::Positive);
    c.standing.max_bulge_m = s->number("max_bulge_m", c.standing.max_bulge_m, Check::Positive);
    c.standing.max_settlement_m = s->number("max_settlement_m", c.standing.max_settlement_m, Check::Positive);
  }
  c.porosity_spacing_m = root.number("porosity_spacing_m", c.porosity_spacing_m, Check::Positive);
  if (c.porosity_spacing_m > 0.05 * c.edge_m) root.fail("porosity_spacing_m", "must be at most 5 % of the edge");
  c.run = parseRun(root.object("run"), c.fill.max_duration_s);
  return c;
}

// The netting of the cell: a closed box whose nodes' inner surfaces are the
// cell's faces (the box of edge + 2 r placed at -r: the node contact radius
// is a contact device and must not eat the cell's volume), split into the
// basket (bottom and sides, filled first) and the lid's own nodes.
struct CellNetting {
  Netting box;
  std::vector<bool> lid_only;             // node of the top face and of no other
  std::vector<bool> rim;                  // basket node on the top edge of a side face
  std::vector<std::uint32_t> basket_of;   // box node -> basket sphere index (basket nodes)
  std::vector<std::uint32_t> basket_ids;  // basket sphere -> box node
  Vec3 origin;
  double mass_scale = 1.0;  // of the nodes (netting.node_mass_scale)
};

CellNetting makeNetting(const CellCase& c, const std::string& file) {
  CellNetting n;
  const double r = c.netting.mesh.nodeRadius();
  try {
    n.box = closedBox(c.netting.mesh, c.edge_m + 2.0 * r, false);
  } catch (const std::invalid_argument& e) {
    throw bridge::InputError(file, "/edge_m", e.what());
  }
  n.origin = Vec3::Constant(-r);
  n.mass_scale = c.netting.mesh.node_mass_scale;
  const std::size_t nn = n.box.node_m.size();
  std::vector<int> faces_of(nn, 0);
  for (std::size_t f = 0; f < 6; ++f)
    for (const std::uint32_t k : n.box.faces[f]) faces_of[k] += f == 1 ? 1 : 2;  // top counts 1, others 2
  n.lid_only.assign(nn, false);
  n.rim.assign(nn, false);
  n.basket_of.assign(nn, 0);
  const double top = c.edge_m + 2.0 * r;
  for (std::size_t k = 0; k < nn; ++k) {
    n.lid_only[k] = faces_of[k] == 1;
    n.rim[k] = !n.lid_only[k] && n.box.node_m[k].z() > top - 0.5 * r;
    if (!n.lid_only[k]) {
      n.basket_of[k] = static_cast<std::uint32_t>(n.basket_ids.size());
      n.basket_ids.push_back(static_cast<std::uint32_t>(k));
    }
  }
  return n;
}

SphereSpec nodeSphere(const CellNetting& n, std::size_t k, int material) {
  SphereSpec sp;
  sp.mass_scale = n.mass_scale;
  sp.center_m = n.origin + n.box.node_m[k];
  sp.radius_m = n.box.node_radius_m;
  sp.mass_kg = n.box.node_mass_kg[k];
  sp.inertia_kg_m2 = n.box.node_inertia_kg_m2[k];
  sp.material = material;
  sp.group = 1;
  return sp;
}

enum Mat { kRock = 0, kFormwork = 1, kNetting = 2 };

// Stage 1: the basket in its formwork (floor and four sides just outside the
// nodes) and the blocks laid out in a column above its base, ready to fall.
// The basket's rim is tied to the formwork (its nodes held where they are)
// until the lid is laced on: a pin-jointed net has no bending stiffness to
// stand up in, and its sides would fold down onto the floor under their own
// weight and the rock sliding past them.
Scene fillScene(const CellCase& c, const CellNetting& n, nlohmann::json& fill_report) {
  Scene s;
  s.gravity_m_s2 = c.gravity;
  s.materials = {c.rock, c.formwork, c.netting.contact};
  if (c.fill.friction >= 0.0) s.materials[kRock].friction = c.fill.friction;
  s.run = c.run;
  s.run.duration_s = c.fill.max_duration_s;
  for (const std::uint32_t k : n.basket_ids) {
    s.spheres.push_back(nodeSphere(n, k, kNetting));
    s.spheres.back().fixed = n.rim[k];
  }
  for (const NettingLink& l : n.box.links)
    if (!n.lid_only[l.a] && !n.lid_only[l.b]) {
      NettingLink b = l;
      b.a = n.basket_of[l.a], b.b = n.basket_of[l.b];
      s.links.push_back(linkSpec(c.netting.mesh, b, 0));
    }
  const double r = n.box.node_radius_m, e = c.edge_m;
  // The blocks: a column over the cell, tall enough for any loose layout.
  fill_report = addBlockFill(*c.blocks, s, kRock, Vec3(0.002, 0.002, 0.002), Vec3(e - 0.002, e - 0.002, 12.0 * e),
                             c.mass_kg, c.seed, [&](const std::string& m) { c.blocks->failHere(m); });
  s.walls = {fixedWall("floor", Vec3(0, 0, -2 * r), Vec3::UnitZ(), kFormwork),
             fixedWall("x_minus", Vec3(-2 * r, 0, 0), Vec3::UnitX(), kFormwork),
             fixedWall("x_plus", Vec3(e + 2 * r, 0, 0), -Vec3::UnitX(), kFormwork),
             fixedWall("y_minus", Vec3(0, -2 * r, 0), Vec3::UnitY(), kFormwork),
             fixedWall("y_plus", Vec3(0, e + 2 * r, 0), -Vec3::UnitY(), kFormwork)};
  // (no porosity box of the scene's: the cell measures its own porosity,
  // with the rock in the mesh openings, where each stage ends)
  return s;
}

// The rock's spheres (the block members), for porosities and heights.
void rockSpheres(const Engine& engine, std::size_t spheres, std::vector<Vec3>& x, std::vector<double>& r) {
  engine.sphereGeometry(x, r);
  x.erase(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(spheres));
  r.erase(r.begin(), r.begin() + static_cast<std::ptrdiff_t>(spheres));
}

// The cell's porosity, 1 - (volume of rock) / edge^3, with the rock that
// the netting holds below the rim: inside the faces, and in the mesh
// openings out to `pocket` beyond them (the formwork's planes). pocket = 0:
// the rock inside the faces only.
double cellPorosity(const std::vector<Vec3>& x, const std::vector<double>& r, const Vec3& base, double edge,
                    double spacing, double pocket) {
  const Vec3 lo = base - Vec3(pocket, pocket, 0.0), hi = base + Vec3(edge + pocket, edge + pocket, edge);
  const double region = (hi - lo).prod();
  return 1.0 - solidFraction(x, r, lo, hi, spacing) * region / (edge * edge * edge);
}

double cellPorosity(const Engine& engine, std::size_t spheres, const Vec3& base, double edge, double spacing,
                    double pocket) {
  std::vector<Vec3> x;
  std::vector<double> r;
  rockSpheres(engine, spheres, x, r);
  return cellPorosity(x, r, base, edge, spacing, pocket);
}

// The member spheres of a scene's blocks as placed (centres, radii), appended.
void blockSpheres(const Scene& s, std::vector<Vec3>& x, std::vector<double>& r) {
  for (const BlockSpec& b : s.blocks)
    for (std::size_t k = 0; k < b.member_radii_m.size(); ++k)
      x.push_back(b.position_m + b.orientation * b.member_centers_m[k]), r.push_back(b.member_radii_m[k]);
}

// The highest point of the rock in a scene (its blocks' member spheres, as placed).
double rockTop(const Scene& s) {
  std::vector<Vec3> x;
  std::vector<double> r;
  blockSpheres(s, x, r);
  double top = -1e300;
  for (std::size_t k = 0; k < x.size(); ++k) top = std::max(top, x[k].z() + r[k]);
  return top;
}

// A stage's run in OUTDIR/<name>: the scene run with the stage's hooks; the
// state it ends in goes to `state`. A failure is in `outcome`, named by stage.
// Its summary, with its wall time, joins `stages` (what the stages so far gave).
struct StageRun {
  bridge::RunOutcome outcome;
  Scene state;
  double wall_s = 0.0;
};

StageRun runStage(const std::string& name, Scene scene, const std::string& file, const bridge::RunContext& ctx,
                  SceneRunHooks hooks, nlohmann::json& stages) {
  StageRun out;
  bridge::RunContext sub = ctx;
  sub.outdir = ctx.outdir / name;
  std::filesystem::create_directories(sub.outdir);
  hooks.label = "micro.cell " + name;
  hooks.end = [&](const Engine& e, const Scene& in) { out.state = stateScene(in, e); };
  const auto t0 = std::chrono::steady_clock::now();
  out.outcome = runScene(std::move(scene), file, sub, hooks);
  out.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (out.outcome.status != bridge::RunOutcome::Status::Ok)
    out.outcome.message = "stage '" + name + "': " + out.outcome.message;
  stages[name] = out.outcome.results;
  stages[name]["wall_time_s"] = out.wall_s;
  return out;
}

// A stage that failed ends the run: its numerical failure, with what the
// stages so far gave (each in its own folder).
bridge::RunOutcome failed(const StageRun& st, const nlohmann::json& stages) {
  bridge::RunOutcome out = st.outcome;
  out.results = {{"stages", stages}};
  return out;
}

// Kinetic energy (J), translational and rotational, at the last measuring step.
double kinetic(const Engine& e) {
  return e.kineticEnergyNow();
}

void check(const bridge::JsonDocument& doc) {
  const CellCase c = parseCase(doc);
  const CellNetting n = makeNetting(c, doc.file());
  nlohmann::json report;
  const Scene s = fillScene(c, n, report);
  validateScene(s, doc.file());
  chooseDt(s, criticalTimeStep(s), doc.file());
}

// Every stage runs the fill's bodies (fewer once the surplus is removed),
// each at most its max_duration_s, at the fill's step.
std::optional<bridge::Estimate> estimate(const bridge::JsonDocument& doc) {
  const CellCase c = parseCase(doc);
  const CellNetting n = makeNetting(c, doc.file());
  nlohmann::json report;
  Scene s = fillScene(c, n, report);
  const double dt = chooseDt(s, criticalTimeStep(s), doc.file());
  s.run.duration_s =
      c.fill.max_duration_s + c.vibration.max_duration_s + c.closing.max_duration_s + c.standing.max_duration_s;
  return sceneEstimate(s, dt);
}

bridge::RunOutcome run(const bridge::JsonDocument& doc, const bridge::RunContext& run_ctx) {
  const CellCase c = parseCase(doc);
  // The cell's own thread count, not the run's: a granular fill is chaotic,
  // and the order of the force sums changes with the threads, so the same
  // seed on another thread count is another cell (docs/cell.md, Seed and
  // threads).
  bridge::RunContext ctx = run_ctx;
  ctx.threads = c.threads;
  const std::string file = doc.file();
  const CellNetting n = makeNetting(c, file);
  const double e = c.edge_m, r = n.box.node_radius_m;
  nlohmann::json fill_report;
  Scene scene = fillScene(c, n, fill_report);
  const std::size_t basket = scene.spheres.size();
  bridge::RunOutcome out;

  // --- 1. Fill: until the blocks are nearly at rest (kinetic energy below
  // a fraction of the work gravity did) or the time limit.
  double pe0 = NAN;
  SceneRunHooks fill_hooks;
  fill_hooks.done = [&](const Engine& eng) {
    if (std::isnan(pe0)) pe0 = eng.energy().gravity_potential_J;
    const double work = pe0 - eng.energy().gravity_potential_J;
    return eng.time() > 0.2 && work > 0.0 && kinetic(eng) < c.fill.settled_kinetic_ratio * work;
  };
  fill_hooks.archive = [&](bridge::StateArchive& a) { a("pe0", pe0); };
  nlohmann::json stages;
  StageRun fill = runStage("fill", std::move(scene), file, ctx, fill_hooks, stages);
  if (fill.outcome.status != bridge::RunOutcome::Status::Ok) return failed(fill, stages);
  const double pocket = 2 * r;  // (the mesh openings reach out to the formwork)
  double porosity_gravity = NAN;
  {
    std::vector<Vec3> x;
    std::vector<double> rr;
    blockSpheres(fill.state, x, rr);
    porosity_gravity =
        cellPorosity(x, rr, Vec3(0, 0, fill.state.walls[0].point_m.z() + 2 * r), e, c.porosity_spacing_m, pocket);
  }

  // --- 2. Vibration: floor and formwork shake vertically together while a
  // plate presses the fill with the surcharge; until the porosity inside the
  // cell reaches the target (checked every check_interval_s) or the limit.
  Scene vib = fill.state;
  for (WallSpec& w : vib.walls) {
    w.program.kind = WallProgram::Kind::Sinusoid;
    w.program.direction = c.vibration.direction;
    w.program.amplitude_m = c.vibration.amplitude_m;
    w.program.frequency_hz = c.vibration.frequency_hz;
  }
  {
    // The plate: a bounded wall over the whole formwork that touches the
    // rock only (it passes over the rim's nodes). Were it only as wide as
    // the opening, a stone bulging into a side opening would slip under its
    // edge and come out inside it, half its radius deep in the plate.
    const double top = rockTop(fill.state);
    WallSpec press = fixedWall("press", Vec3(0.5 * e, 0.5 * e, std::max(top, e) + 0.002), -Vec3::UnitZ(), kFormwork);
    press.bounded = true;
    press.axis_u = Vec3::UnitX();
    press.half_u_m = press.half_v_m = 0.5 * e + 2 * r;
    press.skip_groups = 1u << 1;  // (the netting's nodes are group 1: nodeSphere)
    const double force = c.vibration.surcharge_Pa * e * e;
    if (force > 0.0) {
      press.program.kind = WallProgram::Kind::Servo;
      press.program.target_force_N = force;
      // Down onto the heap the fill left at up to 0.5 m/s, then it holds the
      // force with a gentle gain (a stiff servo's speed follows the contacts'
      // chatter, and its work, force x speed, is then biased).
      press.program.max_speed_m_s = 0.5;
      press.program.gain_m_s_N = 0.05 / force;
    }
    vib.walls.push_back(press);
  }
  vib.materials[kRock].friction = c.vibration.friction;
  vib.run.duration_s = std::max(c.vibration.max_duration_s, vib.run.series_interval_s);
  std::vector<double> vib_t, vib_n;
  double next_check = 0.0, porosity_vibrated = porosity_gravity;
  SceneRunHooks vib_hooks;
  vib_hooks.done = [&](const Engine& eng) {
    if (eng.time() + 1e-12 < next_check) return false;
    next_check += c.vibration.check_interval_s;
    const double floor_dz = eng.wallPosition(0).z() + 2 * r;
    porosity_vibrated = cellPorosity(eng, basket, Vec3(0, 0, floor_dz), e, 2.0 * c.porosity_spacing_m, pocket);
    vib_t.push_back(eng.time()), vib_n.push_back(porosity_vibrated);
    return porosity_vibrated <= c.target_porosity;
  };
  vib_hooks.archive = [&](bridge::StateArchive& a) {
    a("check_time_s", vib_t), a("porosity", vib_n), a("next_check", next_check);
    a("porosity_vibrated", porosity_vibrated);
  };
  StageRun vibration = runStage("vibration", std::move(vib), file, ctx, vib_hooks, stages);
  if (vibration.outcome.status != bridge::RunOutcome::Status::Ok) return failed(vibration, stages);

  // --- 3. Closing: the plate presses the fill down to the rim (a force
  // servo at closing.pressure_Pa x edge^2, at most closing.speed_m_s) while
  // the shaking goes on (closing.vibrate; else it stops and the rock has its
  // own friction again), until the plate's face reaches the cell's top face,
  // or the time limit. Blocks whose centre still stands above the top face
  // are then taken off: the fill is levelled with the rim before the lid
  // goes on.
  Scene close = vibration.state;
  if (!c.closing.vibrate) {
    close.materials[kRock] = c.rock;
    for (WallSpec& w : close.walls) w.program = WallProgram{};
  }
  const std::size_t press_wall = close.walls.size() - 1;
  {
    WallProgram& pr = close.walls[press_wall].program;
    const double force = c.closing.pressure_Pa * e * e;
    pr.kind = WallProgram::Kind::Servo;
    pr.target_force_N = force;
    pr.max_speed_m_s = c.closing.speed_m_s;
    pr.gain_m_s_N = c.closing.speed_m_s / force;
  }
  close.run.duration_s = c.closing.max_duration_s;
  // (the cell's top face over the floor, where the shaking has it)
  const auto topFace = [&](double floor_z) { return floor_z + 2 * r + e; };
  double press_force = 0.0;
  SceneRunHooks close_hooks;
  close_hooks.done = [&](const Engine& eng) {
    press_force = eng.wallForce(press_wall).z();  // the rock pushes it up
    return eng.wallPosition(press_wall).z() <= topFace(eng.wallPosition(0).z());
  };
  close_hooks.archive = [&](bridge::StateArchive& a) { a("press_force", press_force); };
  StageRun closing = runStage("closing", std::move(close), file, ctx, close_hooks, stages);
  if (closing.outcome.status != bridge::RunOutcome::Status::Ok) return failed(closing, stages);
  const double top_face = topFace(closing.state.walls[0].point_m.z());
  const double press_gap = closing.state.walls[press_wall].point_m.z() - top_face;
  double rock_mass = fill_report["mass_kg"].get<double>(), levelled_mass = 0.0;
  std::size_t levelled = 0;
  {
    std::vector<BlockSpec> kept;
    for (const BlockSpec& b : closing.state.blocks) {
      const MassProperties m = clusterMassProperties(b.member_centers_m, b.member_radii_m, c.rock.density_kg_m3);
      if ((b.position_m + b.orientation * m.center_m).z() > top_face) {
        ++levelled, levelled_mass += m.mass_kg;
        continue;
      }
      kept.push_back(b);
    }
    closing.state.blocks = kept;
    rock_mass -= levelled_mass;
  }

  // --- 4. Standing: the lid's nodes are laced on over the fill, the
  // formwork and plate are taken away, the floor stays as the rigid base.
  Scene stand = closing.state;
  stand.materials[kRock] = c.rock;  // its own friction again
  // The cell starts its standing test at rest; the rim is untied from the formwork.
  for (SphereSpec& sp : stand.spheres) sp.velocity_m_s.setZero(), sp.angular_velocity_rad_s.setZero(), sp.fixed = false;
  for (BlockSpec& b : stand.blocks) b.velocity_m_s.setZero(), b.angular_velocity_rad_s.setZero();
  {
    // (the floor where the vibration left it: stateScene moved it there)
    const double floor_z = stand.walls[0].point_m.z();
    stand.walls.resize(1);
    stand.walls[0].program = WallProgram{};
    // The lid is laid on the fill: each of its nodes rests on the highest
    // rock sphere or basket node under it (or at the rim's plane where there
    // is none), and every wire of the lid takes its length as it lies (no
    // pull at closing).
    const double shift = floor_z + 2 * r;
    std::vector<Vec3> rock_x;
    std::vector<double> rock_r;
    for (const SphereSpec& sp : stand.spheres) rock_x.push_back(sp.center_m), rock_r.push_back(sp.radius_m);
    blockSpheres(stand, rock_x, rock_r);
    std::vector<std::uint32_t> sphere_of(n.box.node_m.size(), 0);
    for (std::size_t k = 0; k < n.box.node_m.size(); ++k) {
      if (!n.lid_only[k]) {
        sphere_of[k] = n.basket_of[k];
        continue;
      }
      sphere_of[k] = static_cast<std::uint32_t>(stand.spheres.size());
      SphereSpec sp = nodeSphere(n, k, kNetting);
      sp.center_m.z() += shift;
      double rest = -1e300;
      for (std::size_t m = 0; m < rock_x.size(); ++m) {
        const double reach = rock_r[m] + r, dx = sp.center_m.x() - rock_x[m].x(), dy = sp.center_m.y() - rock_x[m].y();
        const double d2 = dx * dx + dy * dy;
        if (d2 < reach * reach) rest = std::max(rest, rock_x[m].z() + std::sqrt(reach * reach - d2));
      }
      if (rest > -1e300) sp.center_m.z() = rest;
      stand.spheres.push_back(sp);
    }
    for (const NettingLink& l : n.box.links) {
      if (!n.lid_only[l.a] && !n.lid_only[l.b]) continue;
      NettingLink b = l;
      b.a = sphere_of[l.a], b.b = sphere_of[l.b];
      b.rest_length_m = (stand.spheres[b.a].center_m - stand.spheres[b.b].center_m).norm();
      stand.links.push_back(linkSpec(c.netting.mesh, b, 0));
    }
  }
  stand.run.duration_s = c.standing.max_duration_s;
  std::vector<Vec3> start;
  for (const SphereSpec& sp : stand.spheres) start.push_back(sp.center_m);
  double ke_ratio = NAN;
  double reference = NAN;  // the work gravity would do bringing every body down to the base (J)
  SceneRunHooks stand_hooks;
  stand_hooks.done = [&](const Engine& eng) {
    if (std::isnan(reference)) {
      // m g h over all bodies, h above the base: the potential less its value at the base.
      double mass = rock_mass;
      for (const SphereSpec& sp : stand.spheres) mass += sp.fixed ? 0.0 : sphereMass(stand, sp);
      reference = eng.energy().gravity_potential_J - mass * -c.gravity.z() * eng.wallPosition(0).z();
    }
    ke_ratio = kinetic(eng) / reference;
    return eng.time() > 0.1 && ke_ratio < c.standing.kinetic_ratio;
  };
  stand_hooks.archive = [&](bridge::StateArchive& a) { a("ke_ratio", ke_ratio), a("reference", reference); };
  StageRun standing = runStage("standing", std::move(stand), file, ctx, stand_hooks, stages);
  if (standing.outcome.status != bridge::RunOutcome::Status::Ok) return failed(standing, stages);

  // --- The cell as it stands.
  const Scene& fin = standing.state;
  const double base = fin.walls[0].point_m.z() + 2 * r;  // the rock's bottom face
  double bulge = 0.0, settlement = 0.0, lid_z0 = 0.0, lid_z1 = 0.0;
  std::size_t lid_nodes = 0;
  // Side faces (left, right, front, back: box faces 4, 5, 2, 3): the largest
  // outward move of a node from its plane at closing.
  const int side_face[4] = {4, 5, 2, 3};
  const int axis[4] = {0, 0, 1, 1};
  const double sign[4] = {-1, 1, -1, 1};
  for (int f = 0; f < 4; ++f)
    for (const std::uint32_t k : n.box.faces[static_cast<std::size_t>(side_face[f])]) {
      if (n.lid_only[k]) continue;
      const std::size_t s = n.basket_of[k];
      bulge = std::max(bulge, sign[f] * (fin.spheres[s].center_m[axis[f]] - start[s][axis[f]]));
    }
  for (std::size_t s = basket; s < fin.spheres.size(); ++s)
    lid_z0 += start[s].z(), lid_z1 += fin.spheres[s].center_m.z(), ++lid_nodes;
  lid_z0 /= static_cast<double>(lid_nodes), lid_z1 /= static_cast<double>(lid_nodes);
  settlement = lid_z0 - lid_z1;
  const double height = lid_z1 - r - base;
  const Engine final_state(fin, 1);  // the cell as it stands, for its porosity and its file
  const double porosity =
      cellPorosity(final_state, fin.spheres.size(), Vec3(0, 0, base), e, c.porosity_spacing_m, pocket);
  const double porosity_in_faces =
      cellPorosity(final_state, fin.spheres.size(), Vec3(0, 0, base), e, c.porosity_spacing_m, 0.0);
  const bool at_rest = ke_ratio < c.standing.kinetic_ratio;
  const bool stands = at_rest && bulge < c.standing.max_bulge_m && settlement < c.standing.max_settlement_m;

  nlohmann::json& res = out.results;
  res["porosity"] = porosity;
  res["porosity_in_faces"] = porosity_in_faces;
  res["porosity_after_gravity"] = porosity_gravity;
  res["porosity_after_vibration"] = porosity_vibrated;
  res["target_porosity"] = c.target_porosity;
  res["blocks"] = fin.blocks.size();
  res["seed"] = c.seed;
  res["threads"] = c.threads;
  res["mass_kg"] = rock_mass;
  res["closing"] = {{"press_gap_m", press_gap},
                    {"press_force_N", press_force},
                    {"levelled_blocks", levelled},
                    {"levelled_mass_kg", levelled_mass}};
  res["edge_m"] = e;  // (the nominal edge: a structure of these cells is laid out at it, docs/resolved.md)
  res["height_m"] = height;
  res["bulge_m"] = bulge;
  res["settlement_m"] = settlement;
  res["stands"] = stands;
  res["standing"] = {{"kinetic_ratio", ke_ratio},
                     {"kinetic_ratio_limit", c.standing.kinetic_ratio},
                     {"at_rest", at_rest},
                     {"max_bulge_m", c.standing.max_bulge_m},
                     {"max_settlement_m", c.standing.max_settlement_m}};
  res["block_fills"] = nlohmann::json::array({fill_report});
  writeGradingFigures(ctx.outdir, res["block_fills"]);
  res["stages"] = stages;
  res["wall_time_s"] = fill.wall_s + vibration.wall_s + closing.wall_s + standing.wall_s;
  // The porosity through the vibration, against the target.
  if (!vib_t.empty()) {
    bridge::PlotSpec plot;
    plot.title = "Vibration: porosity inside the cell";
    plot.x_label = "time (s)";
    plot.y_label = "porosity (-)";
    plot.series.push_back({"porosity", vib_t, vib_n, bridge::PlotSeries::Style::LineMarkers});
    plot.series.push_back({"target",
                           {vib_t.front(), vib_t.back()},
                           {c.target_porosity, c.target_porosity},
                           bridge::PlotSeries::Style::Line});
    bridge::writePlotPng(ctx.outdir / "vibration.png", plot);
  }
  writeCellFile(ctx.outdir / "cell.h5", fin, final_state, res);
  writeCellView(ctx.outdir / "cell_view.png", fin,
                "The cell: " + std::to_string(fin.blocks.size()) + " blocks in their netting");
  std::ostringstream rep;
  rep.setf(std::ios::fixed);
  rep.precision(3);
  rep << "cell: porosity " << porosity << " (after gravity " << porosity_gravity << ", after vibration "
      << porosity_vibrated << ", target " << c.target_porosity << "; inside the faces " << porosity_in_faces << "); "
      << fin.blocks.size() << " blocks, " << res["mass_kg"].get<double>() << " kg\n";
  rep << "standing: bulge " << 1000 * bulge << " mm, settlement " << 1000 * settlement << " mm, kinetic ratio "
      << ke_ratio << " -> " << (stands ? "stands" : "DOES NOT STAND") << "\n";
  rep << "closing: plate " << 1000 * press_gap << " mm above the rim at " << press_force << " N; " << levelled
      << " blocks (" << levelled_mass << " kg) above it taken off\n";
  rep << "stages (wall s): fill " << fill.wall_s << ", vibration " << vibration.wall_s << ", closing " << closing.wall_s
      << ", standing " << standing.wall_s << "\n";
  out.answer = rep.str();
  return out;
}

}  // namespace

bridge::CaseKind cellKind() {
  return {"micro.cell",
          "a gabion cell: netting basket filled with angular blocks by gravity, vibrated to a target porosity, "
          "closed and left to stand (docs/cell.md)",
          check, run, estimate};
}

}  // namespace gabion::micro
