#include "macro/impact.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace gabion::macro {

namespace {

double maxOver(const std::vector<int>& nodes, const std::vector<double>& u) {
  double m = -INFINITY;
  for (int n : nodes) m = std::max(m, u[static_cast<std::size_t>(n)]);
  return nodes.empty() ? 0.0 : m;
}

// The boulder has left for good once it has been away, moving back, for
// this fraction of the time it was in contact (and 20 steps at least).
constexpr double kAwayOverContact = 0.5;
// The back face's largest displacement "grows" when it passes its last
// value by this fraction (a creep below it does not hold the impact open).
constexpr double kBackFaceGrowth = 1e-3;

std::string fmt(double v) {
  std::ostringstream s;
  s.precision(4);
  s << v;
  return s.str();
}

}  // namespace

const char* outcomeName(Outcome o) {
  switch (o) {
    case Outcome::Stopped:
      return "stopped";
    case Outcome::Rebounded:
      return "rebounded";
    case Outcome::Perforated:
      return "perforated";
    case Outcome::Unfinished:
      break;
  }
  return "unfinished";
}

long long relax(Model& model, double dt, long long max_steps, double tolerance_J, bool& converged) {
  // Kinetic damping (dynamic relaxation): undamped steps, and every node
  // stopped each time the kinetic energy passes a peak. The slow modes that
  // hold the residual motion lose their energy in a few of their own
  // periods, whatever the ratio of the fastest to the slowest frequency (a
  // viscous rate tuned to the fast ones overdamps the slow ones and crawls).
  // A plateau is a peak too: a cell that the rebound threw out of the wall
  // (the cells carry no tension) drifts with no force on it, its kinetic
  // energy exactly constant, and would otherwise drift to the last step.
  // (Not right after a stop, where the energy may be zero two steps running:
  // stopping again then would freeze the structure instead of relaxing it.)
  converged = false;
  long long n = 0;
  double previous = 0.0;
  while (n < max_steps) {
    if (model.step(dt) != StepStatus::Ok) return n;
    ++n;
    const double kinetic = model.energy().kinetic_J;
    if (previous > 0.0 && kinetic <= previous) {
      model.stopNodes();
      previous = 0.0;
    } else {
      previous = kinetic;
    }
    if (n % 64 == 0 && kinetic < tolerance_J) {
      converged = true;
      break;
    }
  }
  return n;
}

ImpactResult runImpact(Model& model, const BoulderSpec& boulder, const RunSettings& run, int impact_index,
                       Recording* rec) {
  ImpactResult res;
  const Structure& s = model.structure();
  model.placeBoulder(boulder);
  const double dt_crit = model.criticalTimeStep();
  const double dt = run.time_step_s > 0.0 ? run.time_step_s : run.time_step_fraction * dt_crit;
  res.time_step_s = dt;
  res.critical_time_step_s = dt_crit;
  res.input_energy_J = 0.5 * boulder.mass_kg * boulder.velocity_m_s.squaredNorm();
  if (dt > dt_crit) {
    res.ok = false;
    res.message = "time step " + fmt(dt) + " s is above the critical time step " + fmt(dt_crit) + " s";
    model.removeBoulder();
    return res;
  }
  // Penetration, rebound and the outcome are measured along the wall's depth
  // axis x (into the structure from its front face), not along the
  // boulder's path: a boulder that strikes obliquely and glances off along
  // the face goes no deeper for travelling far along its path. For a normal
  // impact the two are the same.
  const Vec3 dir = Vec3::UnitX();
  const double v0 = boulder.velocity_m_s.dot(dir);  // (the normal speed: what a rebound is measured against)
  const double t_max = run.max_duration_s > 0.0 ? run.max_duration_s : 20.0 * run.duration_s;
  const auto nsteps = static_cast<long long>(std::ceil(t_max / dt - 1e-9));
  // The structure's back plane, x = its deepest back cell's back face:
  // beyond it (the boulder wholly past it in x, whatever its direction) the
  // boulder went through.
  double back_plane = -INFINITY;
  for (const int b : s.back_nodes)
    back_plane = std::max(back_plane, s.x0[static_cast<std::size_t>(b)] + 0.5 * s.edge_m);
  double t_away = -1.0;  // since when the boulder has been away from the structure, moving back
  const Energy e_before = model.energy();
  const double t0 = model.time_s();
  const std::size_t n = s.nodeCount();
  std::vector<double> peak_axial(n, 0.0);

  // Contact bookkeeping: the force of the previous two samples serves the
  // linear interpolation of the contact's start and end between samples.
  bool touched = false, in_contact = false;
  double f_prev = 0.0, f_prev2 = 0.0, t_first = 0.0, f_first = 0.0, t_start = 0.0, t_end = 0.0, touch_proj = 0.0;
  long long first_contact_step = -1;
  double t_back_rise = 0.0;  // when the back face's largest displacement last grew
  double e_ref = 0.0;
  const long long snap_count = std::max(2, run.snapshots);
  long long next_snap = 0;

  // A snapshot of the nodes (displacement, axial force) at impact time t.
  const auto snapshot = [&](double t) {
    rec->snap_time_s.push_back(rec->time_offset_s + t);
    for (std::size_t i = 0; i < n; ++i) {
      rec->snap_displacement_m.push_back(model.ux()[i]);
      rec->snap_displacement_m.push_back(model.uy()[i]);
      rec->snap_displacement_m.push_back(model.uz()[i]);
      rec->snap_axial_force_N.push_back(model.cellAxialForce()[i]);
    }
  };

  long long k = 0;
  for (; k < nsteps; ++k) {
    const StepStatus st = model.step(dt);
    // The step evaluated forces at x(n), t(n) = time - dt.
    const double t = model.time_s() - dt - t0;
    if (st == StepStatus::Perforation) {  // an answer, not a failure
      res.outcome = Outcome::Perforated;
      res.perforation = model.failure();
      res.end_time_s = t;
      ++k;
      break;
    }
    if (st != StepStatus::Ok) {
      res.ok = false;
      res.message = model.failure();
      break;
    }
    const Energy& e = model.energy();
    const double e_now = e.kinetic_J + e.elastic_J + e.potential_J + (e.plastic_J - e_before.plastic_J) +
                         (e.friction_J - e_before.friction_J);
    if (k == 0) e_ref = e_now;
    const double bal = std::abs(e_now - e_ref) / e_ref;
    res.balance_rel_error = std::max(res.balance_rel_error, bal);
    if (bal > run.max_balance_error) {
      res.ok = false;
      res.message = "energy balance error " + fmt(bal) + " above " + fmt(run.max_balance_error) + " at t = " + fmt(t) +
                    " s: time step too large for the contact stiffness?";
      break;
    }
    const double force = model.boulderForce().norm();
    const bool contact = model.contacts() > 0;
    const double proj = model.boulderPositionAtForces().dot(dir);
    if (contact) {
      if (!touched) {
        touched = true;
        first_contact_step = k;
        t_first = t_start = t;
        f_first = force;
        touch_proj = proj - model.indentation();  // back off the first indentation to the touching position
      } else if (k == first_contact_step + 1 && force > f_first) {
        // Force ~ linear in time near the onset.
        t_start = t_first - std::min(1.0, f_first / (force - f_first)) * dt;
      }
      if (!in_contact) ++res.contact_episodes;
      in_contact = true;
      if (res.contact_episodes == 1) t_end = t;
      if (force > res.peak_force_N) {
        res.peak_force_N = force;
        res.time_of_peak_s = t;
      }
      res.max_indentation_m = std::max(res.max_indentation_m, model.indentation());
    } else if (in_contact) {
      in_contact = false;
      // Separation after the last contact sample (t - dt), extrapolating its force decay.
      double t_sep = t - dt;
      if (f_prev2 > f_prev) t_sep += std::min(1.0, f_prev / (f_prev2 - f_prev)) * dt;
      if (res.contact_episodes == 1) t_end = t_sep;
      res.last_separation_s = t_sep;
    }
    if (touched) res.max_penetration_m = std::max(res.max_penetration_m, proj - touch_proj);
    f_prev2 = f_prev;
    f_prev = force;
    const auto& ux = model.ux();
    const double back = maxOver(s.back_nodes, ux);
    if (back > res.max_back_face_displacement_m * (1.0 + kBackFaceGrowth)) t_back_rise = t;
    res.max_back_face_displacement_m = std::max(res.max_back_face_displacement_m, back);
    res.max_front_face_displacement_m = std::max(res.max_front_face_displacement_m, maxOver(s.front.node, ux));
    const auto& ax = model.cellAxialForce();
    for (std::size_t i = 0; i < n; ++i) peak_axial[i] = std::max(peak_axial[i], ax[i]);

    if (rec != nullptr) {
      if (k % run.series_every_steps == 0) {
        rec->time_s.push_back(rec->time_offset_s + t);
        rec->impact.push_back(impact_index);
        rec->force_N.push_back(force);
        rec->force_x_N.push_back(-model.boulderForce().x());
        rec->velocity_x_m_s.push_back(model.boulderVelocity().x());
        rec->speed_m_s.push_back(model.boulderVelocity().norm());
        rec->penetration_m.push_back(touched ? proj - touch_proj : 0.0);
        rec->indentation_m.push_back(model.indentation());
        rec->contacts.push_back(model.contacts());
        rec->kinetic_J.push_back(e.kinetic_J);
        rec->elastic_J.push_back(e.elastic_J);
        rec->plastic_J.push_back(e.plastic_J - e_before.plastic_J);
        rec->friction_J.push_back(e.friction_J - e_before.friction_J);
        rec->back_displacement_m.push_back(maxOver(s.back_nodes, ux));
      }
      // Every duration_s / (snapshots - 1), for as long as the impact lasts.
      if (t + 0.5 * dt >= run.duration_s * static_cast<double>(next_snap) / static_cast<double>(snap_count - 1)) {
        snapshot(t);
        ++next_snap;
      }
    }
    // The outcome, once the boulder has touched: it passed the back plane;
    // it has been away, moving back, for half as long as it was in contact
    // (the face does not catch it up again), and the back face has not moved
    // further for as long (the wave the impact sent through the wall may
    // reach it after the boulder left), and its speed back tells rebounded
    // from stopped; or it rests on the structure, everything at rest and
    // the face no longer pushing it.
    if (!touched) continue;
    const double back_speed = -model.boulderVelocity().dot(dir);
    if (model.boulderPositionAtForces().x() - boulder.diameter_m * 0.5 > back_plane) {
      res.outcome = Outcome::Perforated;
      res.perforation = "the boulder passed the structure's back plane";
    } else if (!contact && back_speed >= 0.0) {
      if (t_away < 0.0) t_away = t;
      const double in_contact_for = t_away - t_start;
      const double window = std::max(kAwayOverContact * in_contact_for, 20.0 * dt);
      if (t - t_away >= window && t - t_back_rise >= window)
        res.outcome = back_speed >= run.rebound_restitution * v0 ? Outcome::Rebounded : Outcome::Stopped;
    } else {
      t_away = -1.0;
      // (at rest, and pushed no more: at its deepest the boulder is at rest too, pushed hardest)
      if (contact && e.kinetic_J < 1e-6 * res.input_energy_J && force < 1e-3 * res.peak_force_N)
        res.outcome = Outcome::Stopped;
    }
    if (res.outcome != Outcome::Unfinished) {
      res.end_time_s = t;
      ++k;
      break;
    }
  }
  if (res.ok && res.outcome == Outcome::Unfinished) res.end_time_s = static_cast<double>(k) * dt;
  if (touched) {
    res.final_penetration_m = std::max(0.0, model.boulderPositionAtForces().dot(dir) - touch_proj);
    res.max_penetration_m = std::max(res.max_penetration_m, res.final_penetration_m);  // (a perforating step's too)
  }
  res.steps = k;  // steps of this impact (up to a failure)
  if (!res.ok) {
    model.removeBoulder();
    return res;
  }
  // Contact end interpolated from the force's linear decay over the last two contact samples.
  if (touched) {
    res.contact_at_end = in_contact;
    res.contact_duration_s = t_end - t_start;
    res.time_of_peak_s -= t_start;
    res.last_separation_s = in_contact ? res.end_time_s - t_start : res.last_separation_s - t_start;
  } else {
    res.ok = false;
    res.message = "the boulder never touched the structure within max_duration_s = " + fmt(t_max) + " s";
  }
  // The state the impact ended in.
  if (rec != nullptr && (rec->snap_time_s.empty() || rec->snap_time_s.back() < rec->time_offset_s + res.end_time_s))
    snapshot(res.end_time_s);
  const Energy& e = model.energy();
  res.kinetic_J = e.kinetic_J;
  res.elastic_J = e.elastic_J;
  res.plastic_J = e.plastic_J - e_before.plastic_J;
  res.friction_J = e.friction_J - e_before.friction_J;
  res.potential_J = e.potential_J;
  res.rebound_velocity_m_s = -model.boulderVelocity().dot(dir);
  res.final_spin_rad_s = model.boulderSpin().norm();
  res.final_velocity_m_s = model.boulderVelocity();
  for (std::size_t i = 0; i < n; ++i)
    if (peak_axial[i] > 0.1 * res.peak_force_N) ++res.loaded_cells;
  model.removeBoulder();
  if (run.relax && res.ok) {
    res.relaxed = true;
    res.relax_steps =
        relax(model, dt, run.relax_max_steps, run.relax_tolerance * res.input_energy_J, res.relax_converged);
    res.residual_back_face_displacement_m = maxOver(s.back_nodes, model.ux());
    res.residual_front_face_displacement_m = maxOver(s.front.node, model.ux());
    for (const int node : s.front.node)
      if (model.ux()[static_cast<std::size_t>(node)] > 0.1 * s.edge_m) ++res.front_cells_pushed_in;
  }
  return res;
}

}  // namespace gabion::macro
