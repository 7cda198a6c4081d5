#include "micro/scene_run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <sstream>

#include "bridge/cost.hpp"
#include "bridge/errors.hpp"
#include "bridge/interrupt.hpp"
#include "bridge/output.hpp"
#include "micro/blocks/block_fill.hpp"
#include "micro/cell/cell_file.hpp"
#include "micro/cell/porosity.hpp"
#include "micro/checkpoint.hpp"

namespace gabion::micro {
namespace {

// Scalar series, kept in memory (a few numbers per sample) and written at the
// end; body snapshots are streamed to the file as they are taken.
struct Series {
  std::vector<double> time;
  std::vector<std::vector<double>> energy;  // per term
  std::vector<double> contacts;
  std::vector<std::vector<double>> wall_force, wall_position;  // per wall, (n, 3) flat
};

// Where the step loop's time went, as a small table (printed after a run):
// each stage's wall time and share, with several threads the share of the
// stage its threads were busy on average (below 100 %: waiting, or serial
// parts), and the rest of the loop (series, snapshots, progress) as "other".
std::string timingReport(const Engine& engine, long long steps_run, double loop_s, double body_steps_per_s,
                         int threads) {
  const StageProfile& prof = engine.profile();
  std::ostringstream r;
  r.setf(std::ios::fixed);
  r.precision(2);
  r << "step loop: " << steps_run << " steps in " << loop_s << " s, " << body_steps_per_s / 1e6 << " M body-steps/s, "
    << threads << (threads == 1 ? " thread, " : " threads, ") << engine.neighbourRebuilds() << " neighbour rebuilds\n";
  r << "  stage          wall s   share" << (threads > 1 ? "   threads busy" : "") << "\n";
  double staged = 0.0;
  const auto row = [&](const std::string& name, double s) {
    r << "  " << name << std::string(name.size() < 12 ? 12 - name.size() : 1, ' ');
    r.width(9);
    r.precision(3);
    r << s;
    r.width(7);
    r.precision(1);
    r << (loop_s > 0.0 ? 100.0 * s / loop_s : 0.0) << " %";
    r.precision(2);
  };
  for (int k = 0; k < StageProfile::kStageCount; ++k) {
    const double s = prof.wall_s[static_cast<std::size_t>(k)];
    staged += s;
    row(StageProfile::name(k), s);
    if (threads > 1 && k != StageProfile::kEnergy && s > 0.0) {
      double sum = 0.0;
      for (const auto& p : prof.thread_busy_s) sum += p[static_cast<std::size_t>(k)];
      const double mean = sum / static_cast<double>(prof.thread_busy_s.size());
      r.width(11);
      r.precision(0);
      r << 100.0 * mean / s << " %";
      r.precision(2);
    }
    r << "\n";
  }
  row("other", std::max(0.0, loop_s - staged));
  r << "   (series, snapshots, progress)\n";
  return r.str();
}

}  // namespace

bridge::Estimate sceneEstimate(const Scene& scene, double dt) {
  double bodies = static_cast<double>(scene.spheres.size());
  for (const BlockSpec& b : scene.blocks) bodies += static_cast<double>(b.member_radii_m.size());
  const RunSpec& rs = scene.run;
  const double steps = std::ceil(rs.duration_s / dt);
  // (the links' stage: each link once per sub-step of the link nodes)
  const double link_substeps = scene.links.empty() ? 0.0
                                                   : static_cast<double>(scene.links.size()) *
                                                         linkSubsteps(dt, linkDtSafety(rs), criticalLinkStep(scene));
  // (a snapshot holds each sphere and each block once)
  const double records = static_cast<double>(scene.spheres.size() + scene.blocks.size());
  return bridge::microRun(
      bodies, steps, rs.output_interval_s > 0.0 ? std::floor(rs.duration_s / rs.output_interval_s) + 1 : 101.0, records,
      rs.series_interval_s > 0.0 ? std::floor(rs.duration_s / rs.series_interval_s) + 1 : 101.0, link_substeps);
}

// The step to use: dt_s if given (refused above the critical step unless
// run.allow_dt_above_critical), else dt_safety x critical. `file` names the
// case in the error.
double chooseDt(const Scene& scene, double critical, const std::string& file) {
  const RunSpec& rs = scene.run;
  double dt = rs.series_interval_s;  // (nothing moves: any step is stable)
  if (rs.dt_s > 0.0) {
    if (rs.dt_s > critical && !rs.allow_dt_above_critical) {
      std::ostringstream m;
      m << "dt_s = " << rs.dt_s << " s is above the critical time step " << critical
        << " s (set run.allow_dt_above_critical = true to run anyway)";
      throw bridge::InputError(file, "/run/dt_s", m.str());
    }
    dt = rs.dt_s;
  } else if (std::isfinite(critical)) {
    dt = rs.dt_safety * critical;
  }
  // A step that underflows (a radius of 1e-200 m) or a run of more steps
  // than any machine gets through is refused before it starts, not run as
  // "0 steps, ok" or left to run for years.
  const double steps = rs.duration_s / dt;
  if (!(dt > 0.0) || !std::isfinite(steps) || steps > kMaxSteps) {
    std::ostringstream m;
    m << "the time step would be " << dt << " s (critical " << critical << " s), " << steps << " steps for "
      << rs.duration_s << " s: more than " << kMaxSteps
      << "; check the bodies' sizes, masses and stiffnesses, or shorten run.duration_s";
    throw bridge::InputError(file, rs.dt_s > 0.0 ? "/run/dt_s" : "/run/duration_s", m.str());
  }
  return dt;
}

void removeKeptEnd(const std::filesystem::path& outdir) {
  std::error_code ec;
  std::filesystem::remove_all(outdir / "checkpoint", ec);
}

bridge::RunOutcome runScene(Scene scene, const std::string& file, const bridge::RunContext& ctx,
                            const SceneRunHooks& hooks) {
  const std::size_t sphere_count = scene.spheres.size();
  Engine engine(scene, ctx.threads);
  if (!scene.save_cell && !hooks.end) {
    std::vector<SphereSpec>().swap(scene.spheres);  // the engine has its own copy
    std::vector<BlockSpec>().swap(scene.blocks);
  }
  const double dt = chooseDt(scene, engine.criticalDt(), file);
  engine.setDt(dt);
  if (hooks.start) hooks.start(engine);
  const auto steps = static_cast<long long>(std::ceil(scene.run.duration_s / dt - 1e-9));
  const long long series_every = std::max(1LL, std::llround(scene.run.series_interval_s / dt));
  const long long output_every = std::max(1LL, std::llround(scene.run.output_interval_s / dt));

  const std::size_t nb = engine.bodyCount(), nw = engine.wallCount(), nblk = engine.blockCount();
  std::vector<Vec3> initial_wall_position(nw);
  for (std::size_t w = 0; w < nw; ++w) initial_wall_position[w] = engine.wallPosition(w);
  Series series;
  series.energy.resize(energyTerms().size());
  series.wall_force.resize(nw);
  series.wall_position.resize(nw);
  bridge::H5Writer h5(ctx.outdir / "result.h5");
  SnapshotLog log(h5);  // the snapshots streamed into h5, for the checkpoints
  Checkpoints checkpoints(ctx.outdir / "checkpoint", scene.run.checkpoint_every_s,
                          runIdentity(ctx.case_digest, hooks.label, engine,
                                      {dt, static_cast<double>(steps), static_cast<double>(series_every),
                                       static_cast<double>(output_every)}));
  std::vector<double> snap_t, row(3 * nb), row_q(4 * nblk);
  // The intact links at each snapshot, for the XDMF lines: a new table each
  // time links have broken since the last one.
  bridge::XdmfLines lines;
  std::size_t tables = 0, broken_in_table = 0;
  // The sphere indices of the links (the intact ones only, or all), row by row.
  const auto linkEnds = [&](bool intact_only) {
    std::vector<long long> ends;
    for (std::size_t l = 0; l < engine.linkCount(); ++l)
      if (!intact_only || !engine.linkBroken(l))
        ends.push_back(static_cast<long long>(engine.linkEnds(l).first)),
            ends.push_back(static_cast<long long>(engine.linkEnds(l).second));
    return ends;
  };
  const auto snapshotLinks = [&] {
    const std::size_t broken = engine.linkEvents().size();
    if (tables == 0 || broken != broken_in_table) {
      const std::vector<long long> ends = linkEnds(true);
      lines.dataset.push_back("/links/intact/" + std::to_string(tables++));
      lines.count.push_back(ends.size() / 2);
      log.writeInts(lines.dataset.back(), ends, {ends.size() / 2, 2});
      broken_in_table = broken;
    } else {
      lines.dataset.push_back(lines.dataset.back());
      lines.count.push_back(lines.count.back());
    }
  };
  const auto snapshot = [&](double t) {
    snap_t.push_back(t);
    if (engine.linkCount() > 0) snapshotLinks();
    const std::pair<const char*, Vec3 BodyState::*> fields[3] = {
        {"position_m", &BodyState::position_m},
        {"velocity_m_s", &BodyState::velocity_m_s},
        {"angular_velocity_rad_s", &BodyState::angular_velocity_rad_s}};
    const char* units[3] = {"m", "m/s", "rad/s"};
    for (int f = 0; f < 3; ++f) {
      for (std::size_t b = 0; b < nb; ++b) {
        const Vec3 v = engine.body(b).*(fields[f].second);
        row[3 * b] = v.x(), row[3 * b + 1] = v.y(), row[3 * b + 2] = v.z();
      }
      log.appendRow(std::string("/bodies/") + fields[f].first, row, {nb, 3}, units[f]);
    }
    if (nblk == 0) return;
    for (std::size_t k = 0; k < nblk; ++k) {
      const Eigen::Quaterniond q = engine.blockOrientation(k);
      row_q[4 * k] = q.w(), row_q[4 * k + 1] = q.x(), row_q[4 * k + 2] = q.y(), row_q[4 * k + 3] = q.z();
    }
    log.appendRow("/blocks/orientation", row_q, {nblk, 4}, "1");
  };
  const auto record = [&](double t) {
    series.time.push_back(t);
    const EnergyTotals& e = engine.energy();
    for (std::size_t k = 0; k < energyTerms().size(); ++k) series.energy[k].push_back(e.*(energyTerms()[k].second));
    series.contacts.push_back(static_cast<double>(engine.contactCount()));
    for (std::size_t w = 0; w < nw; ++w) {
      const Vec3 f = engine.wallForce(w), p = engine.wallPosition(w);
      for (int c = 0; c < 3; ++c) {
        series.wall_force[w].push_back(f[c]);
        series.wall_position[w].push_back(p[c]);
      }
    }
  };

  // The wall-clock seconds stepped by the runs stopped before this one (their
  // checkpoints carry them on): a resumed run's wall time is the whole run's.
  double earlier_s = 0.0;
  auto t0 = std::chrono::steady_clock::now();
  bool ended = false;  // the kind's test is over before the duration

  // The run's own state for a checkpoint: its series so far, its snapshot
  // times and link tables, the seconds stepped so far, and the kind's state.
  const auto loop_state = [&](bridge::StateArchive& a) {
    double stepped_s =
        a.loading() ? 0.0 : earlier_s + std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (a.has("stepped_wall_time_s")) a("stepped_wall_time_s", stepped_s);  // (older checkpoints: 0)
    if (a.loading()) earlier_s = stepped_s;
    bridge::StateArchive sa = a.group("series");
    sa("time_s", series.time);
    for (std::size_t k = 0; k < energyTerms().size(); ++k) sa(energyTerms()[k].first, series.energy[k]);
    sa("contacts", series.contacts);
    for (std::size_t w = 0; w < nw; ++w) {
      bridge::StateArchive wa = sa.group("walls/" + std::to_string(w));
      wa("force_N", series.wall_force[w]), wa("position_m", series.wall_position[w]);
    }
    a("snapshot_time_s", snap_t);
    if (a.has("ended")) a("ended", ended);  // (a kept end: micro/scene_run.hpp keep_end)
    bridge::StateArchive la = a.group("link_tables");
    la("per_snapshot", lines.dataset), la("count", lines.count), la("tables", tables);
    la("broken_in_table", broken_in_table);
    if (hooks.archive) {
      bridge::StateArchive ka = a.group("kind");
      hooks.archive(ka);
    }
  };

  long long first = 0;  // the step the loop starts from: 0, or a checkpoint's
  const Checkpoints::Found found = checkpoints.find();
  const bool resumed = found == Checkpoints::Found::Ours;
  if (found == Checkpoints::Found::Other)
    std::cerr << hooks.label << ": the checkpoint in " << checkpoints.dir().string()
              << " is of another run (case, threads or version): starting from the beginning\n";
  bool at_end = false;  // the checkpoint is the end this run kept (keep_end): nothing to step
  if (resumed) {
    checkpoints.load(engine, log, loop_state);
    first = engine.steps();
    at_end = ended || first >= steps;
    std::cerr << hooks.label
              << (at_end ? ": taking its end from the checkpoint of step "
                         : ": continuing from the checkpoint of step ")
              << first << " (t = " << engine.time() << " s) in " << checkpoints.dir().string() << "\n";
  } else {
    snapshot(0.0);
  }
  bridge::Progress progress(ctx, hooks.label);
  StepStatus status = StepStatus::Ok;
  bool stopped = false;  // SIGINT or SIGTERM asked the run to stop
  t0 = std::chrono::steady_clock::now();
  for (long long n = first; n < steps && !ended; ++n) {
    const bool measure = n % series_every == 0 || n + 1 == steps;
    const double t = engine.time();
    if (bridge::interrupted()) {
      stopped = true;
      checkpoints.save(engine, log, loop_state);  // (what --resume continues)
      break;
    }
    status = engine.step(measure);
    if (status != StepStatus::Ok) break;
    if (measure) {
      record(t);
      if (hooks.record) hooks.record(engine, t);
      if (hooks.control) hooks.control(engine);
      ended = hooks.done && hooks.done(engine);
    }
    if ((n + 1) % output_every == 0 || n + 1 == steps || ended) snapshot(engine.time());
    if (!ended && n + 1 < steps && checkpoints.due()) checkpoints.save(engine, log, loop_state);
    progress.update(static_cast<double>(n + 1) * dt, scene.run.duration_s, n + 1);
  }
  const double loop_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  progress.finish();
  const bool ok = status == StepStatus::Ok && !stopped;
  if (!ok) snapshot(engine.time());
  // (a stage's end, kept for the longer run it is part of)
  if (ok && hooks.keep_end && !at_end) checkpoints.save(engine, log, loop_state);

  // Result files (the snapshots are in h5 already).
  {
    h5.write("/series/time_s", series.time, "s");
    for (std::size_t k = 0; k < energyTerms().size(); ++k) {
      const std::string& name = energyTerms()[k].first;
      h5.write("/series/" + name, series.energy[k], name == "balance_rel_error" ? "1" : "J");
    }
    h5.write("/series/contacts", series.contacts, "1");
    const std::size_t ns = series.time.size();
    // Each wall's series under its name: a program reads the "lid" curve, not "wall 5".
    for (std::size_t w = 0; w < nw; ++w) {
      const std::string base = "/series/walls/" + engine.wallName(w) + "/";
      h5.write(base + "force_N", series.wall_force[w], {ns, 3}, "N");
      h5.write(base + "position_m", series.wall_position[w], {ns, 3}, "m");
      std::vector<double> disp(series.wall_position[w]);
      for (std::size_t k = 0; k < disp.size(); ++k) disp[k] -= initial_wall_position[w][k % 3];
      h5.write(base + "displacement_m", disp, {ns, 3}, "m");
    }
    if (engine.linkCount() > 0) {
      // Links that broke: time, link index, position (an empty table if none did).
      const auto& events = engine.linkEvents();
      std::vector<double> t, link, pos;
      for (const LinkEvent& ev : events) {
        t.push_back(ev.time_s);
        link.push_back(static_cast<double>(ev.link));
        for (int c = 0; c < 3; ++c) pos.push_back(ev.position_m[c]);
      }
      h5.write("/links/broken/time_s", t, "s");
      h5.write("/links/broken/link", link, "1");
      h5.write("/links/broken/position_m", pos, {events.size(), 3}, "m");
      h5.writeInts("/links/ends", linkEnds(false), {engine.linkCount(), 2});
    }
    if (hooks.write) hooks.write(engine, h5);
    std::vector<double> radius(nb);
    for (std::size_t b = 0; b < nb; ++b) radius[b] = engine.bodyRadius(b);
    h5.write("/bodies/time_s", snap_t, "s");
    h5.write("/bodies/radius_m", radius, "m");
    h5.attribute("/", "format", "gabion.micro.scene/2");
    h5.commit();
    bridge::writeXdmfPoints(ctx.outdir / "result.xdmf", "result.h5", snap_t, nb, "/bodies/position_m",
                            {{"velocity_m_s", "/bodies/velocity_m_s", 3, true},
                             {"angular_velocity_rad_s", "/bodies/angular_velocity_rad_s", 3, true},
                             {"radius_m", "/bodies/radius_m", 1, false}},
                            lines);
  }

  bridge::RunOutcome out;
  const EnergyTotals& e = engine.energy();
  nlohmann::json energy;
  for (const auto& [name, member] : energyTerms()) energy[name] = e.*member;
  out.results["steps"] = engine.steps();
  out.results["dt_s"] = dt;
  out.results["dt_critical_s"] = engine.criticalDt();
  if (engine.linkCount() > 0) {
    out.results["link_substeps"] = engine.linkSubsteps();
    out.results["dt_link_critical_s"] = engine.linkCriticalDt();
  }
  out.results["bodies"] = nb;
  out.results["spheres"] = sphere_count;
  out.results["blocks"] = nblk;
  out.results["walls"] = nw;
  out.results["links"] = engine.linkCount();
  out.results["broken_links"] = engine.linkEvents().size();
  out.results["size_classes"] = engine.sizeClassCount();
  out.results["step_status"] = statusName(status);
  if (resumed) {
    out.results["resumed_from_step"] = first;
    out.results[bridge::kWallTimeBeforeResume] = earlier_s;
  }
  out.results["checkpoints"] = checkpoints.saved();
  for (const auto& [key, report] : scene.generated.items()) out.results[key] = report;
  if (scene.generated.contains("block_fills")) writeGradingFigures(ctx.outdir, scene.generated["block_fills"]);
  if (scene.porosity.enabled) {
    // The final packing's porosity in the box (each point counted once).
    std::vector<Vec3> centers;
    std::vector<double> radii;
    engine.sphereGeometry(centers, radii);
    const PorosityBox& b = scene.porosity;
    if (b.blocks_only) {  // the free spheres come first: keep the blocks' members
      centers.erase(centers.begin(), centers.begin() + static_cast<std::ptrdiff_t>(sphere_count));
      radii.erase(radii.begin(), radii.begin() + static_cast<std::ptrdiff_t>(sphere_count));
    }
    out.results["porosity"] = 1.0 - solidFraction(centers, radii, b.min_m, b.max_m, b.spacing_m);
  }
  out.results["ended_by"] = stopped ? "interrupt" : !ok ? "failure" : ended ? "test" : "duration";
  out.results["energy"] = energy;
  out.results["contacts"] = engine.contactCount();
  out.results["neighbour_rebuilds"] = engine.neighbourRebuilds();
  out.results["step_loop_wall_time_s"] = loop_s;
  const double body_steps_per_s =
      loop_s > 0.0 ? static_cast<double>(nb) * static_cast<double>(engine.steps() - first) / loop_s : 0.0;
  out.results["body_steps_per_s"] = body_steps_per_s;
  // Where the time went (docs/micro.md, Output): per stage, and per thread.
  const StageProfile& prof = engine.profile();
  nlohmann::json stage_wall = nlohmann::json::object(), busy = nlohmann::json::object();
  for (int k = 0; k < StageProfile::kStageCount; ++k) {
    stage_wall[StageProfile::name(k)] = prof.wall_s[static_cast<std::size_t>(k)];
    nlohmann::json per = nlohmann::json::array();
    for (const auto& p : prof.thread_busy_s) per.push_back(p[static_cast<std::size_t>(k)]);
    if (k != StageProfile::kEnergy) busy[StageProfile::name(k)] = per;
  }
  out.results["profile"] = {{"stage_wall_time_s", stage_wall}, {"thread_busy_time_s", busy}};
  out.report = timingReport(engine, engine.steps() - first, loop_s, body_steps_per_s, ctx.threads);
  if (scene.save_cell && ok) {
    // The packed state, for later runs (`from_cell`), with what this run measured.
    nlohmann::json summary = {{"time_s", engine.time()}, {"steps", engine.steps()}};
    if (out.results.contains("porosity")) summary["porosity"] = out.results["porosity"];
    writeCellFile(ctx.outdir / "cell.h5", scene, engine, summary);
  }
  if (ok && hooks.end) hooks.end(engine, scene);
  // (a run that ended, ok or failed, has nothing to continue; a stage's end
  // is kept for the run it is part of)
  if (!stopped && !(ok && hooks.keep_end)) checkpoints.remove();
  if (stopped) {
    std::ostringstream m;
    m << "interrupted by " << bridge::signalName(bridge::interruptSignal()) << " at step " << engine.steps()
      << ", t = " << engine.time() << " s of " << scene.run.duration_s << " s; its state is in "
      << checkpoints.dir().string() << " (gabion run --resume continues it)";
    out.status = bridge::RunOutcome::Status::Interrupted;
    out.message = m.str();
  } else if (!ok) {
    out.status = bridge::RunOutcome::Status::NumericalFailure;
    out.message = engine.failure();
  }
  return out;
}

}  // namespace gabion::micro
