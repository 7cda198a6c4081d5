#include "macro/model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace gabion::macro {

void BoulderSpec::setMass(double mass, bool keep_diameter) {
  const double pi = 3.14159265358979323846;
  mass_kg = mass;
  if (keep_diameter)
    density_kg_m3 = mass / (pi / 6.0 * diameter_m * diameter_m * diameter_m);
  else
    diameter_m = std::cbrt(6.0 * mass / (pi * density_kg_m3));
}

namespace {

// One link's cell law (bridge::cellResponse: the return mapping shared with
// the fine DEM's F_lim cap, plus the lock-up): the force (N) for compression
// `u` (m), with the plastic memory `up` (m) updated and the plastic work and
// the stored elastic energy added to the stage's sums (J); `rate` (m/s) is
// the shortening rate a law with a rate term reads (the impact law's).
inline double linkLaw(const bridge::CellSpring& law, double u, double& up, double& plastic, double& elastic,
                      double rate = 0.0, double* overstress = nullptr) {
  const auto r = bridge::cellResponse(law, u, up, rate, overstress);
  up = r.plastic_m;
  plastic += r.plastic_work_J;
  elastic += r.elastic_J;
  return r.force_N;
}

}  // namespace

using bridge::frictionUpdate1d;
using bridge::frictionUpdate2d;

Model::Model(Structure structure, Kinematics kinematics)
    : s_(std::move(structure)), kin_(kinematics), three_d_(kinematics == Kinematics::ThreeD) {
  const std::size_t n = s_.nodeCount();
  for (auto* v : {&ux_, &uy_, &uz_, &vx_, &vy_, &vz_, &fx_, &fy_, &fz_, &cell_axial_}) v->assign(n, 0.0);
  const std::size_t na = s_.axial.a.size(), nl = s_.lateral.a.size(), ng = s_.ground.node.size();
  for (auto* v : {&axial_plastic_, &axial_force_, &axial_ft1_, &axial_ft2_, &axial_dashpot_}) v->assign(na, 0.0);
  for (auto* v : {&lat_ftx_, &lat_fto_, &lat_plastic_, &lat_force_}) v->assign(nl, 0.0);
  for (auto* v : {&gnd_ftx_, &gnd_fty_, &gnd_plastic_, &gnd_force_}) v->assign(ng, 0.0);
  front_plastic_.assign(s_.front.node.size(), 0.0);
  front_overstress_.assign(s_.front.node.size(), 0.0);
  front_ft_.assign(s_.front.node.size(), Vec3::Zero());
  front_kt_.assign(s_.front.node.size(), 0.0);
}

double Model::criticalTimeStep() const {
  // Sum of the tangent stiffnesses acting on each degree of freedom.
  const std::size_t n = s_.nodeCount();
  std::vector<double> kx(n, 0.0), ky(n, 0.0), kz(n, 0.0), cx(n, 0.0);
  auto add = [](std::vector<double>& v, int node, double k) {
    if (node >= 0) v[static_cast<std::size_t>(node)] += k;
  };
  // The stiffest tangent of a law: unloading past lock-up, k + k_L.
  auto tangent = [&](int law) { return bridge::maxTangentStiffness(s_.axial_laws[static_cast<std::size_t>(law)]); };
  for (std::size_t l = 0; l < s_.axial.a.size(); ++l) {
    const double k = tangent(s_.axial.law[l]);
    // The fill's rate term as a damping: eta, and the momentum flux's
    // tangent d(c_m r^2)/dr = 2 c_m r at the fastest shortening expected,
    // twice the boulder's speed (a node struck by a heavier boulder moves
    // at up to twice its speed).
    const bridge::CellSpring& spring = s_.axial_springs[static_cast<std::size_t>(s_.axial.law[l])];
    const double damping = spring.viscosity_N_s_m + 2.0 * spring.flux_kg_m * 2.0 * flux_rate_bound_m_s_;
    for (int node : {s_.axial.a[l], s_.axial.b[l]}) add(cx, node, damping);
    const double kt = s_.friction_laws[static_cast<std::size_t>(s_.axial.friction[l])].tangential_stiffness_N_m;
    for (int node : {s_.axial.a[l], s_.axial.b[l]}) {
      add(kx, node, k);
      add(ky, node, kt);
      add(kz, node, kt);
    }
  }
  for (std::size_t l = 0; l < s_.lateral.a.size(); ++l) {
    const double k = tangent(s_.lateral.law[l]);
    const double kt = s_.friction_laws[static_cast<std::size_t>(s_.lateral.friction[l])].tangential_stiffness_N_m;
    const bool y = s_.lateral.dir[l] == 1;
    for (int node : {s_.lateral.a[l], s_.lateral.b[l]}) {
      add(kx, node, kt);
      add(ky, node, y ? k : kt);
      add(kz, node, y ? kt : k);
    }
  }
  for (std::size_t l = 0; l < s_.ground.node.size(); ++l) {
    const double kt = s_.friction_laws[static_cast<std::size_t>(s_.ground.friction[l])].tangential_stiffness_N_m;
    const double k = tangent(s_.ground.law[l]);
    add(kx, s_.ground.node[l], kt);
    add(ky, s_.ground.node[l], kt);
    add(kz, s_.ground.node[l], k);
  }
  double kimp_max = 0.0;
  for (std::size_t e = 0; e < s_.front.node.size(); ++e) {
    // The impact law, and in 3-D the face friction's tangential spring.
    const double k = tangent(s_.front.law[e]) + (three_d_ && boulder_.present ? front_kt_[e] : 0.0);
    kimp_max = std::max(kimp_max, k);
    if (boulder_.present) {
      add(kx, s_.front.node[e], k);
      add(ky, s_.front.node[e], k);
      add(kz, s_.front.node[e], k);
    }
  }
  double w2 = 0.0, dt_damped = INFINITY;
  for (std::size_t i = 0; i < n; ++i) {
    double k = kx[i];
    if (three_d_) k = std::max({k, ky[i], kz[i]});
    const double w2i = 2.0 * k * s_.inv_mass[i];
    w2 = std::max(w2, w2i);
    // A dashpot on the node (the axial links' viscosity, along x): the
    // leapfrog with the half-step velocity in the force is stable for
    // w^2 dt^2 + 2 beta dt < 4, beta = 2 c / m (as w^2 = 2 k / m), i.e.
    // dt < 2 / w (sqrt(1 + zeta^2) - zeta) with zeta = beta / (2 w).
    if (cx[i] > 0.0 && kx[i] > 0.0) {
      const double beta = 2.0 * cx[i] * s_.inv_mass[i], wx2 = 2.0 * kx[i] * s_.inv_mass[i];
      dt_damped = std::min(dt_damped, (std::sqrt(beta * beta + 4.0 * wx2) - beta) / wx2);
    }
  }
  if (boulder_.present) {
    // The boulder can touch at most the front elements within its diameter.
    const double per_axis = std::ceil(2.0 * boulder_.radius_m / s_.edge_m) + 1.0;
    const double touching = std::min(static_cast<double>(s_.front.node.size()), per_axis * per_axis);
    w2 = std::max(w2, 2.0 * touching * kimp_max / boulder_.mass_kg);
    if (three_d_) {  // rotation: a tangential spring k_t at arm R against I = 2/5 M R^2 gives 2.5 k_t / M
      double kt_max = 0.0;
      for (const double kt : front_kt_) kt_max = std::max(kt_max, kt);
      w2 = std::max(w2, 2.0 * touching * 2.5 * kt_max / boulder_.mass_kg);
    }
  }
  const double dt = w2 > 0.0 ? 2.0 / std::sqrt(w2) : INFINITY;
  return std::min(dt, dt_damped);
}

void Model::placeBoulder(const BoulderSpec& b) {
  if (!(b.diameter_m > 0.0) || !(b.mass_kg > 0.0)) throw std::invalid_argument("boulder diameter and mass must be > 0");
  const double speed = b.velocity_m_s.norm();
  if (!(b.velocity_m_s.x() > 0.0))
    throw std::invalid_argument("the boulder must move towards the front face (velocity x component > 0)");
  if (!three_d_ && (b.velocity_m_s.y() != 0.0 || b.velocity_m_s.z() != 0.0))
    throw std::invalid_argument("x-only kinematics needs a normal impact (velocity along x); use kinematics '3d'");
  const Vec3 dir = b.velocity_m_s / speed;
  int min_offset = s_.nx;
  for (int off : s_.front_offset_cells) min_offset = std::min(min_offset, off);
  const double r = 0.5 * b.diameter_m;
  const Vec3 aim(min_offset * s_.edge_m, b.aim_y_m, b.aim_z_m);
  if (!(b.face_friction >= 0.0) || !(b.face_tangential_stiffness_N_m >= 0.0) || !(b.gravity_m_s2 >= 0.0))
    throw std::invalid_argument("boulder face friction, tangential stiffness and gravity must be >= 0");
  if (!three_d_ && b.gravity_m_s2 > 0.0)
    throw std::invalid_argument("gravity on the boulder needs kinematics '3d' (x-only guides it along x)");
  boulder_ = {true, r, b.mass_kg, 0.4 * b.mass_kg * r * r, b.face_friction, b.gravity_m_s2, 0.0};
  bpos_ = aim - dir * ((r + b.initial_gap_m) / dir.x());
  boulder_.z0_m = bpos_.z();
  for (std::size_t e = 0; e < front_kt_.size(); ++e)
    front_kt_[e] = b.face_tangential_stiffness_N_m > 0.0
                       ? b.face_tangential_stiffness_N_m
                       : s_.axial_laws[static_cast<std::size_t>(s_.front.law[e])].stiffness_N_m;
  std::fill(front_ft_.begin(), front_ft_.end(), Vec3::Zero());
  bspin_.setZero();
  bspin_full_.setZero();
  bpos_force_ = bpos_;
  bvel_ = b.velocity_m_s;
  bvel_full_ = bvel_;
  flux_rate_bound_m_s_ = std::max(flux_rate_bound_m_s_, speed);
  bforce_.setZero();
  max_indent_ = 0.0;
  n_contacts_ = 0;
  lost_front_ = -1;
  lost_past_middle_ = false;
  crushed_link_ = crushed_front_ = -1;
}

void Model::removeBoulder() {
  boulder_.present = false;
  std::fill(front_ft_.begin(), front_ft_.end(), Vec3::Zero());
  bspin_.setZero();
  bspin_full_.setZero();
  energy_.potential_J = 0.0;
  bvel_.setZero();
  bvel_full_.setZero();
  bforce_.setZero();
  n_contacts_ = 0;
  max_indent_ = 0.0;
}

void Model::stopNodes() {
  for (auto* v : {&vx_, &vy_, &vz_}) std::fill(v->begin(), v->end(), 0.0);
  energy_.kinetic_J = 0.0;
}

StepStatus Model::step(double dt, double damping_rate_1_s) {
  clearForces();
  computeAxialForces(dt);
  computeBoulderContacts(dt);
  computeLateralForces(dt);
  computeGroundForces(dt);
  integrate(dt, damping_rate_1_s);
  return checkState();
}

void Model::setExternalForce(std::size_t node, const Vec3& force_N) {
  if (ext_x_.empty())
    for (auto* v : {&ext_x_, &ext_y_, &ext_z_}) v->assign(s_.nodeCount(), 0.0);
  ext_x_.at(node) = force_N.x(), ext_y_[node] = force_N.y(), ext_z_[node] = force_N.z();
}

void Model::clearExternalForces() {
  for (auto* v : {&ext_x_, &ext_y_, &ext_z_}) v->clear();
}

void Model::archive(bridge::StateArchive& a) {
  for (auto [name, v] : {std::pair<const char*, std::vector<double>*>{"ux", &ux_},
                         {"uy", &uy_},
                         {"uz", &uz_},
                         {"vx", &vx_},
                         {"vy", &vy_},
                         {"vz", &vz_},
                         {"cell_axial", &cell_axial_},
                         {"ext_x", &ext_x_},
                         {"ext_y", &ext_y_},
                         {"ext_z", &ext_z_},
                         {"axial_plastic", &axial_plastic_},
                         {"axial_force", &axial_force_},
                         {"axial_ft1", &axial_ft1_},
                         {"axial_ft2", &axial_ft2_},
                         {"axial_dashpot", &axial_dashpot_},
                         {"lat_ftx", &lat_ftx_},
                         {"lat_fto", &lat_fto_},
                         {"lat_plastic", &lat_plastic_},
                         {"lat_force", &lat_force_},
                         {"gnd_ftx", &gnd_ftx_},
                         {"gnd_fty", &gnd_fty_},
                         {"gnd_plastic", &gnd_plastic_},
                         {"gnd_force", &gnd_force_},
                         {"front_plastic", &front_plastic_},
                         {"front_overstress", &front_overstress_},
                         {"front_kt", &front_kt_}})
    a(name, *v);
  a("front_ft", front_ft_);
  bridge::StateArchive b = a.group("boulder");
  b("present", boulder_.present), b("radius_m", boulder_.radius_m), b("mass_kg", boulder_.mass_kg);
  b("inertia_kg_m2", boulder_.inertia_kg_m2), b("friction", boulder_.friction);
  b("gravity_m_s2", boulder_.gravity_m_s2), b("z0_m", boulder_.z0_m);
  b("position", bpos_), b("position_at_forces", bpos_force_), b("velocity", bvel_), b("velocity_full", bvel_full_);
  b("force", bforce_), b("spin", bspin_), b("spin_full", bspin_full_), b("torque", btorque_);
  a("max_indent", max_indent_), a("contacts", n_contacts_), a("lost_front", lost_front_),
      a("lost_past_middle", lost_past_middle_);
  a("crushed_link", crushed_link_), a("crushed_front", crushed_front_);
  a("time_s", time_), a("steps", steps_), a("flux_rate_bound_m_s", flux_rate_bound_m_s_);
  bridge::StateArchive e = a.group("energy");
  e("kinetic_J", energy_.kinetic_J), e("elastic_J", energy_.elastic_J), e("plastic_J", energy_.plastic_J);
  e("friction_J", energy_.friction_J), e("potential_J", energy_.potential_J);
  e("external_work_J", energy_.external_work_J);
  a("failure", failure_);
}

void Model::clearForces() {
  const bool ext = !ext_x_.empty();
  if (ext)
    fx_ = ext_x_;
  else
    std::fill(fx_.begin(), fx_.end(), 0.0);
  std::fill(cell_axial_.begin(), cell_axial_.end(), 0.0);
  if (three_d_) {
    if (ext) {
      fy_ = ext_y_, fz_ = ext_z_;
    } else {
      std::fill(fy_.begin(), fy_.end(), 0.0);
      std::fill(fz_.begin(), fz_.end(), 0.0);
    }
  }
  bforce_.setZero();
  btorque_.setZero();
  elastic_acc_ = 0.0;
}

// x-neighbours and the back wall: the cell law in compression, no tension.
void Model::computeAxialForces(double dt) {
  // Local sums: the loop's stores to the force arrays cannot alias them.
  double elastic = 0.0, friction = 0.0, plastic = 0.0;
  const auto& L = s_.axial;
  const std::size_t nl = L.a.size();
  for (std::size_t l = 0; l < nl; ++l) {
    const auto a = static_cast<std::size_t>(L.a[l]);
    const int bi = L.b[l];
    const auto b = static_cast<std::size_t>(bi);
    const double shortening = ux_[a] - (bi >= 0 ? ux_[b] : 0.0);
    const auto law = static_cast<std::size_t>(L.law[l]);
    double F = linkLaw(s_.axial_springs[law], shortening, axial_plastic_[l], plastic, elastic);
    if (const bridge::CellSpring& spring = s_.axial_springs[law]; spring.hasRateForce()) {
      // The fill's rate term (viscosity, momentum flux) on the shortening
      // rate (half-step velocities, the leapfrog's latest). Its work over
      // the last step takes the force at both ends (the trapezoidal rule, as
      // the leapfrog's work of the other forces), so it keeps last step's.
      const double rate = vx_[a] - (bi >= 0 ? vx_[b] : 0.0);
      const double fd = spring.rateForce(shortening, rate, F);
      plastic += 0.5 * (axial_dashpot_[l] + fd) * rate * dt;
      axial_dashpot_[l] = fd;
      F += fd;
    }
    if (shortening > s_.axial_crush_m[law] && crushed_link_ < 0) crushed_link_ = static_cast<int>(l);
    axial_force_[l] = F;
    fx_[a] -= F;
    cell_axial_[a] += 0.5 * F;
    if (bi >= 0) {
      fx_[b] += F;
      cell_axial_[b] += 0.5 * F;
    }
    if (three_d_) {
      // Friction on the face, its normal force the axial force.
      const auto& fp = s_.friction_laws[static_cast<std::size_t>(L.friction[l])];
      const double du1 = dt * (vy_[a] - (bi >= 0 ? vy_[b] : 0.0));
      const double du2 = dt * (vz_[a] - (bi >= 0 ? vz_[b] : 0.0));
      friction += frictionUpdate2d(fp, F, du1, du2, axial_ft1_[l], axial_ft2_[l]);
      elastic += 0.5 * (axial_ft1_[l] * axial_ft1_[l] + axial_ft2_[l] * axial_ft2_[l]) / fp.tangential_stiffness_N_m;
      fy_[a] -= axial_ft1_[l];
      fz_[a] -= axial_ft2_[l];
      if (bi >= 0) {
        fy_[b] += axial_ft1_[l];
        fz_[b] += axial_ft2_[l];
      }
    }
  }
  elastic_acc_ += elastic;
  energy_.friction_J += friction;
  energy_.plastic_J += plastic;
}

// The boulder against the front cubes through the impact law: the indentation
// is the sphere's overlap with the cube (radius minus the distance from the
// centre to the nearest point of the cube), the force acts along that line.
// A boulder that sinks into a cell by more than its radius (the struck cell
// cratered, or pushed back at it by the cells behind) is embedded: its centre
// is inside the cube, the indentation is the radius plus the centre's depth
// behind the front face and the force acts along -x, which continues both
// across the front face. The model follows it so until the centre passes the
// cube's middle or comes nearer an open side face (one no cell covers) than
// the front face: the cube's faces no longer say where the fill pushes, and
// the impact ends `perforated`.
void Model::computeBoulderContacts(double dt) {
  // Local sums: the loop's stores to the force arrays cannot alias them.
  double elastic = 0.0, friction = 0.0, plastic = 0.0;
  max_indent_ = 0.0;
  n_contacts_ = 0;
  if (!boulder_.present) return;
  const double R = boulder_.radius_m, e = s_.edge_m;
  const auto& F = s_.front;
  for (std::size_t el = 0; el < F.node.size(); ++el) {
    const auto node = static_cast<std::size_t>(F.node[el]);
    const double x0 = F.x_min[el] + ux_[node];
    if (bpos_.x() + R <= x0) {  // in front of the face: no contact possible
      front_ft_[el].setZero();
      front_overstress_[el] = 0.0;
      continue;
    }
    const double y0 = F.y_min[el] + (three_d_ ? uy_[node] : 0.0);
    const double z0 = F.z_min[el] + (three_d_ ? uz_[node] : 0.0);
    const double dy = bpos_.y() - std::clamp(bpos_.y(), y0, y0 + e);
    const double dz = bpos_.z() - std::clamp(bpos_.z(), z0, z0 + e);
    const double dyz2 = dy * dy + dz * dz;
    if (dyz2 >= R * R) {  // beside the cube
      front_ft_[el].setZero();
      front_overstress_[el] = 0.0;
      continue;
    }
    const double dx = bpos_.x() - std::clamp(bpos_.x(), x0, x0 + e);
    const double d2 = dx * dx + dyz2;
    if (d2 >= R * R) {
      front_ft_[el].setZero();
      front_overstress_[el] = 0.0;
      continue;
    }
    double indent = 0.0, nx = -1.0, ny = 0.0, nz = 0.0;  // n: from the cube to the centre
    if (d2 > 0.0) {
      const double d = std::sqrt(d2);
      indent = R - d;
      nx = dx / d, ny = dy / d, nz = dz / d;
    } else {  // embedded: the centre is inside the cube
      const double depth = bpos_.x() - x0;
      const bool past_middle = depth > 0.5 * e;
      if (past_middle || depth > openSideDistance(el, y0, z0)) {
        if (lost_front_ < 0) lost_front_ = static_cast<int>(el), lost_past_middle_ = past_middle;
        continue;
      }
      indent = R + depth;
    }
    // Indentation rate: the boulder's approach to the cube along the normal,
    // from the half-step velocities v(n-1/2) (the leapfrog's latest).
    const double vny = three_d_ ? vy_[node] : 0.0, vnz = three_d_ ? vz_[node] : 0.0;
    const double rate = -(nx * (bvel_.x() - vx_[node]) + ny * (bvel_.y() - vny) + nz * (bvel_.z() - vnz));
    const auto law = static_cast<std::size_t>(F.law[el]);
    const double f =
        linkLaw(s_.axial_springs[law], indent, front_plastic_[el], plastic, elastic, rate, &front_overstress_[el]);
    if (!(f > 0.0)) {  // inside the dent left by an earlier impact (and short of lock-up): no force
      front_ft_[el].setZero();
      front_overstress_[el] = 0.0;
      continue;
    }
    if (indent > s_.axial_crush_m[law] && crushed_front_ < 0) crushed_front_ = static_cast<int>(el);
    bforce_ += f * Vec3(nx, ny, nz);
    fx_[node] -= f * nx;
    cell_axial_[node] -= 0.5 * f * nx;
    if (three_d_) {
      fy_[node] -= f * ny;
      fz_[node] -= f * nz;
      friction += faceFriction(el, node, Vec3(nx, ny, nz), f, dt, elastic);
    }
    max_indent_ = std::max(max_indent_, indent);
    ++n_contacts_;
  }
  if (!three_d_) bforce_.y() = bforce_.z() = 0.0;  // x-only: the boulder is guided along x
  elastic_acc_ += elastic;
  energy_.friction_J += friction;
  energy_.plastic_J += plastic;
}

// Distance from the boulder's centre, inside front cube `el` (corner x0 +
// ux, y0, z0), to the nearest of the cube's open side faces; infinity if all
// four are covered.
double Model::openSideDistance(std::size_t el, double y0, double z0) const {
  using F = Structure::FrontElements;
  const unsigned char open = s_.front.open_sides[el];
  const double e = s_.edge_m;
  double d = std::numeric_limits<double>::infinity();
  if (open & F::kOpenYMinus) d = std::min(d, bpos_.y() - y0);
  if (open & F::kOpenYPlus) d = std::min(d, y0 + e - bpos_.y());
  if (open & F::kOpenZMinus) d = std::min(d, bpos_.z() - z0);
  if (open & F::kOpenZPlus) d = std::min(d, z0 + e - bpos_.z());
  return d;
}

// Boulder-face friction on front element `el` (3-D): the tangential spring
// force on the boulder, carried in the contact's tangent plane (turned with the
// normal, its magnitude kept), updated with the sliding of the contact point
// over the step and limited to mu times the normal force `fn`
// (bridge::frictionUpdate<3>). It acts on the boulder at its contact point
// (a torque) and on the cell opposite. Returns the dissipated energy; adds
// the tangential spring's energy to `elastic`.
double Model::faceFriction(std::size_t el, std::size_t node, const Vec3& n, double fn, double dt, double& elastic) {
  Vec3& ft = front_ft_[el];
  const double old = ft.norm();
  ft -= ft.dot(n) * n;
  const double now = ft.norm();
  if (now > 0.0) ft *= old / now;
  const Vec3 arm = -boulder_.radius_m * n;  // centre to contact point
  const Vec3 v_rel = bvel_ + bspin_.cross(arm) - Vec3(vx_[node], vy_[node], vz_[node]);
  const Vec3 du = -dt * (v_rel - v_rel.dot(n) * n);  // the cell's slide relative to the boulder
  const bridge::FrictionParams fp{boulder_.friction, front_kt_[el]};
  const double dissipated = bridge::frictionUpdate<3>(fp, fn, du.data(), ft.data());
  bforce_ += ft;
  btorque_ += arm.cross(ft);
  fx_[node] -= ft.x();
  fy_[node] -= ft.y();
  fz_[node] -= ft.z();
  elastic += 0.5 * ft.squaredNorm() / fp.tangential_stiffness_N_m;
  return dissipated;
}

// Lateral neighbours: normal reaction = reaction coefficient x axial force of
// the cells (the larger of the two: the cell that expands more pushes, the
// other only reacts), Coulomb friction with a tangential spring on the face.
void Model::computeLateralForces(double dt) {
  // Local sums: the loop's stores to the force arrays cannot alias them.
  double elastic = 0.0, friction = 0.0, plastic = 0.0;
  const auto& L = s_.lateral;
  const std::size_t nl = L.a.size();
  for (std::size_t l = 0; l < nl; ++l) {
    const auto a = static_cast<std::size_t>(L.a[l]);
    const auto b = static_cast<std::size_t>(L.b[l]);
    double normal = std::max(s_.reaction_coefficient[a] * cell_axial_[a], s_.reaction_coefficient[b] * cell_axial_[b]);
    const auto& fp = s_.friction_laws[static_cast<std::size_t>(L.friction[l])];
    if (!three_d_) {
      double ft = lat_ftx_[l];  // a local copy: the force arrays' stores could alias the member
      friction += frictionUpdate1d(fp, normal, dt * (vx_[a] - vx_[b]), ft);
      lat_ftx_[l] = ft;
      elastic += ft * ft * s_.friction_half_inv_k[static_cast<std::size_t>(L.friction[l])];
      fx_[a] -= ft;
      fx_[b] += ft;
      continue;
    }
    // 3-D: the cell law across the face resists lateral approach.
    const bool y = L.dir[l] == 1;
    auto& un = y ? uy_ : uz_;
    auto& fn = y ? fy_ : fz_;
    auto& vo = y ? vz_ : vy_;
    auto& fo = y ? fz_ : fy_;
    const double fnorm =
        linkLaw(s_.axial_springs[static_cast<std::size_t>(L.law[l])], un[a] - un[b], lat_plastic_[l], plastic, elastic);
    lat_force_[l] = fnorm;
    fn[a] -= fnorm;
    fn[b] += fnorm;
    normal += fnorm;
    friction += frictionUpdate2d(fp, normal, dt * (vx_[a] - vx_[b]), dt * (vo[a] - vo[b]), lat_ftx_[l], lat_fto_[l]);
    elastic += 0.5 * (lat_ftx_[l] * lat_ftx_[l] + lat_fto_[l] * lat_fto_[l]) / fp.tangential_stiffness_N_m;
    fx_[a] -= lat_ftx_[l];
    fx_[b] += lat_ftx_[l];
    fo[a] -= lat_fto_[l];
    fo[b] += lat_fto_[l];
  }
  elastic_acc_ += elastic;
  energy_.friction_J += friction;
  energy_.plastic_J += plastic;
}

// Base cells on the ground: Coulomb friction under the column's weight (and,
// in 3-D, the half-cell law against sinking into the ground).
void Model::computeGroundForces(double dt) {
  // Local sums: the loop's stores to the force arrays cannot alias them.
  double elastic = 0.0, friction = 0.0, plastic = 0.0;
  const auto& G = s_.ground;
  for (std::size_t l = 0; l < G.node.size(); ++l) {
    const auto i = static_cast<std::size_t>(G.node[l]);
    const auto& fp = s_.friction_laws[static_cast<std::size_t>(G.friction[l])];
    double normal = G.weight_N[l];
    if (!three_d_) {
      friction += frictionUpdate1d(fp, normal, dt * vx_[i], gnd_ftx_[l]);  // few links: no local copy needed
      elastic += 0.5 * gnd_ftx_[l] * gnd_ftx_[l] / fp.tangential_stiffness_N_m;
      fx_[i] -= gnd_ftx_[l];
      continue;
    }
    const double fz =
        linkLaw(s_.axial_springs[static_cast<std::size_t>(G.law[l])], -uz_[i], gnd_plastic_[l], plastic, elastic);
    gnd_force_[l] = fz;
    fz_[i] += fz;
    normal += fz;
    friction += frictionUpdate2d(fp, normal, dt * vx_[i], dt * vy_[i], gnd_ftx_[l], gnd_fty_[l]);
    elastic += 0.5 * (gnd_ftx_[l] * gnd_ftx_[l] + gnd_fty_[l] * gnd_fty_[l]) / fp.tangential_stiffness_N_m;
    fx_[i] -= gnd_ftx_[l];
    fy_[i] -= gnd_fty_[l];
  }
  elastic_acc_ += elastic;
  energy_.friction_J += friction;
  energy_.plastic_J += plastic;
}

// Leapfrog: v(n+1/2) = v(n-1/2) + dt F(n)/m, x(n+1) = x(n) + dt v(n+1/2).
void Model::integrate(double dt, double damping_rate_1_s) {
  const std::size_t n = s_.nodeCount();
  double kinetic = 0.0;
  const double h = 0.5 * damping_rate_1_s * dt;
  const double keep = (1.0 - h) / (1.0 + h), gain = dt / (1.0 + h);
  auto advance = [&](std::vector<double>& v, std::vector<double>& u, const std::vector<double>& f) {
    for (std::size_t i = 0; i < n; ++i) {
      const double vnew = keep * v[i] + gain * f[i] * s_.inv_mass[i];
      kinetic += 0.5 * s_.mass_kg[i] * v[i] * vnew;
      v[i] = vnew;
      u[i] += dt * vnew;
    }
  };
  // Work of the external forces over the step, F(n) . (u(n+1) - u(n)).
  auto external = [&](const std::vector<double>& f, const std::vector<double>& v) {
    double w = 0.0;
    for (std::size_t i = 0; i < n; ++i) w += f[i] * dt * v[i];
    return w;
  };
  advance(vx_, ux_, fx_);
  if (!ext_x_.empty()) energy_.external_work_J += external(ext_x_, vx_);
  if (three_d_) {
    advance(vy_, uy_, fy_);
    advance(vz_, uz_, fz_);
    if (!ext_x_.empty()) energy_.external_work_J += external(ext_y_, vy_) + external(ext_z_, vz_);
  }
  if (boulder_.present) {
    const Vec3 weight(0.0, 0.0, -boulder_.mass_kg * boulder_.gravity_m_s2);
    energy_.potential_J = boulder_.mass_kg * boulder_.gravity_m_s2 * (bpos_.z() - boulder_.z0_m);  // at x(n)
    const Vec3 vnew = bvel_ + dt * (bforce_ + weight) / boulder_.mass_kg;
    kinetic += 0.5 * boulder_.mass_kg * bvel_.dot(vnew);
    bvel_full_ = 0.5 * (bvel_ + vnew);
    bpos_force_ = bpos_;
    bvel_ = vnew;
    bpos_ += dt * bvel_;
    if (three_d_) {
      const Vec3 wnew = bspin_ + dt * btorque_ / boulder_.inertia_kg_m2;
      kinetic += 0.5 * boulder_.inertia_kg_m2 * bspin_.dot(wnew);
      bspin_full_ = 0.5 * (bspin_ + wnew);
      bspin_ = wnew;
    }
  }
  energy_.kinetic_J = kinetic;
  energy_.elastic_J = elastic_acc_;
  time_ += dt;
  ++steps_;
}

StepStatus Model::checkState() {
  if (!std::isfinite(energy_.total()) || !bpos_.allFinite()) {
    failure_ = "non-finite state (energy or boulder position) at step " + std::to_string(steps_);
    return StepStatus::NonFinite;
  }
  if (lost_front_ >= 0) {
    const auto node = static_cast<std::size_t>(s_.front.node[static_cast<std::size_t>(lost_front_)]);
    const std::string cell = "(" + std::to_string(s_.gi[node]) + ", " + std::to_string(s_.gj[node]) + ", " +
                             std::to_string(s_.gk[node]) + ")";
    failure_ = (lost_past_middle_ ? "the boulder's centre went past the middle of front cell " + cell
                                  : "the boulder's centre came nearer an open side of front cell " + cell +
                                        " than its front (it entered the cell from the side)") +
               " at step " + std::to_string(steps_);
    return StepStatus::Perforation;
  }
  if (crushed_front_ >= 0) {
    const auto node = static_cast<std::size_t>(s_.front.node[static_cast<std::size_t>(crushed_front_)]);
    failure_ = "the boulder crushed front cell (" + std::to_string(s_.gi[node]) + ", " + std::to_string(s_.gj[node]) +
               ", " + std::to_string(s_.gk[node]) + ") beyond its lock-up at step " + std::to_string(steps_);
    return StepStatus::Perforation;
  }
  if (crushed_link_ >= 0) {
    const auto a = static_cast<std::size_t>(s_.axial.a[static_cast<std::size_t>(crushed_link_)]);
    failure_ = "cell (" + std::to_string(s_.gi[a]) + ", " + std::to_string(s_.gj[a]) + ", " + std::to_string(s_.gk[a]) +
               ") was crushed beyond its lock-up at step " + std::to_string(steps_);
    return StepStatus::Perforation;
  }
  return StepStatus::Ok;
}

}  // namespace gabion::macro
