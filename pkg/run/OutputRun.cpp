#include "run/OutputRun.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>

#include "common/Error.hpp"
#include "coupling/CoupledCheckpoint.hpp"
#include "run/OutputCadence.hpp"
#include "run/Progress.hpp"
#include "run/StopSignal.hpp"

namespace mpmsdem {
namespace run {

OutputRun::OutputRun(Stepper& stepper, const mpm::MpmScene& scene, bool restart,
                     const std::vector<Quat>* referenceOrientations, const std::vector<Vec3>* startPositions)
    : stepper_(stepper),
      solver_(stepper.solver),
      scene_(scene),
      restart_(restart),
      dir_(scene.run.outputDir),
      h5_((std::filesystem::create_directories(dir_), (dir_ / "mpm.h5").string()),
          restart ? io::Hdf5Writer::Mode::Append : io::Hdf5Writer::Mode::Truncate, true),
      pvd_(scene.run.vtk == "none" || stepper.coupled
               ? std::nullopt
               : std::optional<io::PvdCollection>(std::in_place, (dir_ / "particles.pvd").string(), restart)) {
  if (pvd_) std::filesystem::create_directories(dir_ / "vtk");
  if (restart) {
    // A killed run wrote series rows and ParaView entries past its last snapshot, where this
    // run continues from: drop them, or the series would go back in time and repeat.
    // A coupled run continues from its checkpoint's snapshot, which is the last one unless
    // the run was killed between writing a snapshot and its checkpoint.
    const double t = solver_.time() * (1 + 1e-12);
    h5_.truncateSeriesAfter("time", t);
    h5_.dropSnapshotsAfter(t);
    if (pvd_) pvd_->dropAfter(t);
  }
  if (stepper.coupled) {
    coupled_.emplace(dir_.string(), restart, stepper.coupled->world.engine);
    coupled_->h5().setAttribute("parameters", scene.sourceJson);
    // the ParaView contacts: on CUDA they stay on the device unless recorded
    stepper.coupled->coupling.setRecordContacts(scene.run.vtk != "none");
    if (restart) coupled_->dropAfter(solver_.time() * (1 + 1e-12));
    if (referenceOrientations) coupled_->setReferenceOrientations(*referenceOrientations);
    if (!restart) {  // (a restart's file has it from the run's start)
      const sdem::SdemEngine& e = stepper.coupled->world.engine;
      nlohmann::json start = nlohmann::json::array();
      for (int i = 0; i < e.numBodies(); ++i) {
        const Vec3& p = startPositions ? (*startPositions)[i] : e.position(i);
        start.push_back({p.x(), p.y(), p.z()});
      }
      coupled_->h5().setAttribute("start_positions", start.dump());
    }
  }
  // A restart keeps the front snapshots before its restart point (a run killed between a
  // snapshot and its record writes it again); a new run removes an earlier run's.
  for (std::size_t k = 0; k < scene.run.snapshotsWhenFrontAt.size(); ++k) {
    std::error_code ec;
    if (restart && frontsWritten_ == k && std::filesystem::exists(frontPath(k)) &&
        coupling::readFrontSnapshot(frontPath(k).string()).time <= solver_.time())
      frontsReached_ = frontsWritten_ = k + 1;
    else
      std::filesystem::remove(frontPath(k), ec);
  }
  io::writeMpmHeader(h5_, scene.sourceJson, scene.params, solver_.name());
  if (coupled_) coupled_->h5().setAttribute("flip_blend", scene.params.flip.describe(scene.params.dx));
  for (const mpm::FlowProbeSpec& p : scene.probes) probes_.emplace_back(p);
  if (restart) replayProbes();
}

void OutputRun::replayProbes() {
  std::size_t width = 0;
  const std::vector<double> time = h5_.series("time"), front = h5_.series("front_x");
  const std::vector<double> depth = h5_.series("probe_depth", &width), velocity = h5_.series("probe_velocity"),
                            points = h5_.series("probe_points");
  if (!probes_.empty() && (width != probes_.size() || depth.size() != time.size() * width ||
                           velocity.size() != depth.size() || points.size() != depth.size()))
    throw ParameterError("--restart: " + h5_.path() + " holds " + std::to_string(depth.size()) +
                         " probe values in records of " + std::to_string(width) + " for " +
                         std::to_string(time.size()) + " series records, where the scene has " +
                         std::to_string(probes_.size()) + " flow_probes: not the same run (start it again "
                         "without --restart)");
  for (std::size_t r = 0; r < time.size(); ++r) {
    for (std::size_t k = 0; k < probes_.size(); ++k)
      probes_[k].add(time[r], {depth[r * width + k], velocity[r * width + k], std::lround(points[r * width + k])});
    if (r < front.size() && front[r] > front_ + 0.5 * scene_.params.dx) front_ = front[r], frontAt_ = time[r];
  }
}

RunEnd OutputRun::run(long maxSteps) {
  const mpm::RunSettings& run = scene_.run;
  const std::size_t n = solver_.numParticles();
  const long firstStep = solver_.steps();
  if (restart_) {
    state_time_ = solver_.time();  // the snapshot we start from is already in the file
  } else {
    recordSeries(diagnose());
    writeSnapshot();
    writeFrontSnapshots();
  }
  // next record and snapshot times: the first multiples of their intervals after now
  OutputCadence series(run.seriesEvery, solver_.time()), output(run.outputEvery, solver_.time());
  const auto t0 = Clock::now();
  const double tStart = solver_.time();
  ProgressSchedule progress(ProgressSchedule::markAfter(progressFraction(solver_, run, maxSteps, firstStep)),
                            run.progressEvery);
  const bool byTime = maxSteps == 0;
  std::printf("mpmsdem-run: FLIP/PIC blend %s\n", scene_.params.flip.describe(scene_.params.dx).c_str());
  std::printf("mpmsdem-run: %s, %zu particles, %s, output in %s\n", solver_.name().c_str(), n,
              byTime ? ("duration " + std::to_string(run.duration) + " s").c_str()
                     : (std::to_string(maxSteps) + " steps").c_str(),
              dir_.string().c_str());
  std::fflush(stdout);
  double dt = 0, recordSeconds = 0, snapshotSeconds = 0;
  auto timedSnapshot = [this, &snapshotSeconds] {
    const auto start = Clock::now();
    writeSnapshot();
    snapshotSeconds += since(start);
  };
  catchStopSignals();
  try {
    while (!finished(solver_, run, maxSteps) && stopReason_.empty() && !stopSignal()) {
      dt = nextStep(stepper_, run, byTime);
      stepper_.step(dt);
      const double t = solver_.time();
      const bool seriesDue = series.due(t), outputDue = output.due(t);
      const double f = progressFraction(solver_, run, maxSteps, firstStep);
      bool report = progress.due(f, finished(solver_, run, maxSteps));
      // one pass over the particles serves the series record and the progress line
      const auto recordStart = Clock::now();
      std::optional<mpm::Diagnostics> d;
      if (seriesDue || report) d = diagnose();
      if (seriesDue) {
        recordSeries(*d, dt);
        report = report || !stopReason_.empty();  // a stop rule ended the run at this record
        series.passed(t);
      }
      recordSeconds += since(recordStart);
      if (outputDue) {
        timedSnapshot();
        output.passed(t);
      }
      if (frontsReached_ > frontsWritten_) {
        const auto start = Clock::now();
        writeFrontSnapshots();
        snapshotSeconds += since(start);
      }
      if (report) {
        const double el = since(t0);
        std::printf("[%5.1f%%] t=%.5g s step=%ld dt=%.3g s (%s) KE=%.5g J front=%.5g m rate=%.3g upd/s ETA=%s%s\n",
                    100 * f, t, solver_.steps(), dt, stepper_.limit().c_str(), d->kineticEnergy, d->frontX,
                    n * double(solver_.steps() - firstStep) / el,
                    formatDuration(f > 0 ? el * (1 - f) / f : 0).c_str(),
                    probesEta(*d, t, t > tStart ? el / (t - tStart) : NAN).c_str());
        std::fflush(stdout);
        progress.reported(f);
      }
    }
  } catch (const RuntimeFailure& e) {
    if (!solver_.holdsLastGoodState()) {
      // One copy of the particles (keep_last_good_state false): the failed step changed some.
      h5_.setAttribute("failure", e.what());
      if (coupled_) coupled_->h5().setAttribute("failure", e.what());
      std::fprintf(stderr, "mpmsdem-run: run failure: %s\nmpmsdem-run: last good state: the last snapshot in %s "
                           "(t = %.6g s; keep_last_good_state is false, so the state at the failure was not kept)\n",
                   e.what(), h5_.path().c_str(), state_time_);
      writeProbeResults("failure");
      return RunEnd::Failure;
    }
    // The solver keeps the state at the start of the failed step: save it. The blocks have
    // moved past it, so the checkpoint stays that of the last snapshot before.
    const long index = writeSnapshot(false);
    if (coupled_) {
      recordBlocks(diagnose());
      coupled_->h5().setAttribute("failure", e.what());
    }
    h5_.setAttribute("failure", e.what());
    h5_.setAttribute("failure_snapshot", double(index));
    std::fprintf(stderr, "mpmsdem-run: run failure: %s\nmpmsdem-run: last good state (t = %.6g s, step %ld) "
                         "saved as snapshot %ld in %s\n",
                 e.what(), solver_.time(), solver_.steps(), index, h5_.path().c_str());
    writeProbeResults("failure");
    return RunEnd::Failure;
  }
  if (solver_.time() > state_time_) timedSnapshot();
  const double loop = since(t0);
  if (stopSignal()) {
    std::printf("mpmsdem-run: stopped by %s at t = %.6g s, step %ld, %.3g s wall: the state is saved as the last "
                "snapshot of %s%s; --restart continues the run\n",
                signalName(stopSignal()), solver_.time(), solver_.steps(), loop, h5_.path().c_str(),
                coupled_ ? " with coupled.checkpoint.json" : "");
    writeProbeResults("signal");
    std::fflush(stdout);
    return RunEnd::Stopped;
  }
  if (!stopReason_.empty())
    std::printf("mpmsdem-run: stopped before run.duration: %s\n",
                stopReason_ == "probes" ? "every flow probe has its result (run.stop_when_probed)"
                                        : "the front has not advanced for run.stop_when_front_still");
  writeProbeResults(stopReason_.empty() ? (maxSteps > 0 ? "steps" : "duration") : stopReason_);
  std::printf("mpmsdem-run: done, t = %.6g s, %ld steps, %.3g s wall\n", solver_.time(), solver_.steps(), loop);
  if (stepper_.coupled) {
    std::printf("mpmsdem-run: step loop: %s\n",
                stageSplit(*stepper_.coupled, loop, recordSeconds, snapshotSeconds).c_str());
    const auto& low = stepper_.coupled->contactStepLow();
    if (std::isfinite(low.step))
      std::printf("mpmsdem-run: smallest contact step %.4g s at t = %.6g s (a fixed run.dt must stay below it)\n",
                  low.step, low.time);
    else
      std::printf("mpmsdem-run: no contact in this run\n");
  } else {
    std::printf("mpmsdem-run: step loop: records %.1f %%, snapshots %.1f %%, the rest (MPM step, time-step control) "
                "%.1f %%\n",
                100 * recordSeconds / loop, 100 * snapshotSeconds / loop,
                100 * (loop - recordSeconds - snapshotSeconds) / loop);
  }
  return RunEnd::Done;
}

void OutputRun::recordWarnings(const std::vector<std::string>& warnings) {
  if (warnings.empty()) return;
  std::string text;
  for (const std::string& w : warnings) text += (text.empty() ? "" : "\n") + w;
  h5_.setAttribute("warnings", text);
  if (coupled_) coupled_->h5().setAttribute("warnings", text);
}

mpm::Diagnostics OutputRun::diagnose() {
  return mpm::diagnose(solver_, slices_, solver_.params().gravity, scene_.probes);
}

void OutputRun::recordProbes(const mpm::Diagnostics& d, double t) {
  if (probes_.empty() && scene_.run.stopWhenFrontStill == 0 && scene_.run.snapshotsWhenFrontAt.empty()) return;
  std::vector<double> depth, velocity, points;
  bool complete = true;
  for (std::size_t k = 0; k < probes_.size(); ++k) {
    probes_[k].add(t, d.probes[k]);
    complete = complete && probes_[k].complete();
    depth.push_back(d.probes[k].depth);
    velocity.push_back(d.probes[k].velocity);
    points.push_back(double(d.probes[k].points));
  }
  if (!probes_.empty()) {
    h5_.appendVector("probe_depth", depth);
    h5_.appendVector("probe_velocity", velocity);
    h5_.appendVector("probe_points", points);
  }
  if (d.frontX > front_ + 0.5 * scene_.params.dx) front_ = d.frontX, frontAt_ = t;
  const std::vector<double>& at = scene_.run.snapshotsWhenFrontAt;
  while (frontsReached_ < at.size() && d.frontX >= at[frontsReached_]) ++frontsReached_, frontXAtSnapshot_ = d.frontX;
  if (scene_.run.stopWhenProbed && complete)
    stopReason_ = "probes";
  else if (scene_.run.stopWhenFrontStill > 0 && t - frontAt_ > scene_.run.stopWhenFrontStill)
    stopReason_ = "front_still";
}

std::string OutputRun::probesEta(const mpm::Diagnostics& d, double t, double wallPerSimSecond) {
  const double speed = t > lineTime_ ? (d.frontX - lineFront_) / (t - lineTime_) : NAN;
  lineFront_ = d.frontX, lineTime_ = t;
  if (!scene_.run.stopWhenProbed || !std::isfinite(wallPerSimSecond)) return "";
  std::vector<ProbeProgress> probes;
  for (const mpm::FlowProbeRecord& r : probes_)
    probes.push_back({r.spec().x - r.spec().halfWidth, r.spec().window, r.arrival()});
  const std::optional<double> left = probesTimeLeft(t, d.frontX, speed, probes);
  return left ? " (stops at its probes in ~" + formatDuration(*left * wallPerSimSecond) + ")" : "";
}

void OutputRun::writeProbeResults(const std::string& stopped) {
  if (probes_.empty()) return;
  const auto& g = scene_.params.gravity;
  const double gravity = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
  nlohmann::json list = nlohmann::json::array();
  for (const mpm::FlowProbeRecord& r : probes_) {
    const mpm::FlowProbeSpec& p = r.spec();
    nlohmann::json j = {{"x", p.x},           {"half_width", p.halfWidth}, {"bed_z", p.bedZ},
                        {"min_points", p.minPoints}, {"window", p.window}, {"records", r.records()},
                        {"complete", r.complete()}};
    const bool arrived = r.arrival().has_value();
    j["arrival"] = arrived ? nlohmann::json(*r.arrival()) : nlohmann::json();
    j["h_f"] = arrived ? nlohmann::json(r.depth()) : nlohmann::json();
    j["v_f"] = arrived ? nlohmann::json(r.velocity()) : nlohmann::json();
    j["Fr"] = arrived && r.depth() > 0 ? nlohmann::json(r.velocity() / std::sqrt(gravity * r.depth()))
                                       : nlohmann::json();
    list.push_back(j);
  }
  const nlohmann::json out = {{"stopped", stopped},
                              {"time", solver_.time()},
                              {"front_x", front_},
                              {"front_still_since", frontAt_},
                              {"flip_blend", scene_.params.flip.describe(scene_.params.dx)},
                              {"probes", list}};
  const std::filesystem::path path = dir_ / "flow_probes.json";
  std::ofstream f(path);
  f << out.dump(1) << "\n";
  if (!f) throw RuntimeFailure("cannot write " + path.string());
}

void OutputRun::recordSeries(const mpm::Diagnostics& d, double dt) {
  h5_.appendScalar("time", solver_.time());
  h5_.appendScalar("step", double(solver_.steps()));
  h5_.appendScalar("dt", dt);
  h5_.appendScalar("kinetic_energy", d.kineticEnergy);
  h5_.appendScalar("front_x", d.frontX);
  h5_.appendScalar("height_z", d.heightZ);
  h5_.appendVector("centre_of_mass", {d.com[0], d.com[1], d.com[2]});
  h5_.appendScalar("max_speed", d.maxSpeed);
  h5_.appendScalar("flowing_fraction", d.flowing);
  h5_.appendScalar("gasified_fraction", d.gasified);
  recordProbes(d, solver_.time());
  if (coupled_) recordBlocks(d);
}

void OutputRun::recordBlocks(const mpm::Diagnostics& d) {
  coupling::CoupledWorld& w = *stepper_.coupled;
  const sdem::SdemEngine& e = w.world.engine;
  coupled_->record(solver_.time(), solver_.steps(), e, w.coupling);
  coupled_->appendSeries("flow_kinetic", d.kineticEnergy);
  coupled_->appendSeries("flow_potential", d.potential);
  coupled_->appendSeries("block_kinetic", w.world.kineticEnergy());
  coupled_->appendSeries("dissipated", w.coupling.frictionDissipation() + w.coupling.dampingDissipation() +
                                           e.frictionDissipation() + e.dampingDissipation());
}

std::filesystem::path OutputRun::frontPath(std::size_t k) const {
  return dir_ / (scene_.run.snapshotsIndexed ? "front_snapshot_" + std::to_string(k) + ".json"
                                             : std::string("front_snapshot.json"));
}

void OutputRun::writeFrontSnapshots() {
  if (frontsReached_ == frontsWritten_) return;
  const long index = state_time_ == solver_.time() ? lastSnapshot_ : writeSnapshot();
  for (; frontsWritten_ < frontsReached_; ++frontsWritten_) {
    const std::filesystem::path path = frontPath(frontsWritten_);
    coupling::FrontSnapshot f{scene_.run.snapshotsWhenFrontAt[frontsWritten_], frontXAtSnapshot_, index,
                              solver_.time(), solver_.steps(), ""};
    if (coupled_) {
      f.checkpoint = path.stem().string() + ".checkpoint.json";
      coupling::writeCheckpoint((dir_ / f.checkpoint).string(),
                                coupling::captureCheckpoint(*stepper_.coupled, index, stepper_.lastDt,
                                                            coupled_->referenceOrientations()));
    }
    coupling::writeFrontSnapshot(path.string(), f);
    std::printf("mpmsdem-run: the front reached x = %.6g m (run.snapshot_when_front_at %.6g m) at t = %.6g s: "
                "snapshot %ld, %s (mpmsdem-run --flow-from %s starts other scenes there)\n",
                f.frontX, f.x, f.time, index, path.filename().c_str(),
                (scene_.run.snapshotsIndexed ? path : dir_).string().c_str());
  }
  std::fflush(stdout);
}

long OutputRun::writeSnapshot(bool checkpoint) {
  const long index = h5_.writeSnapshot(slices_, solver_.time(), solver_.steps());
  if (coupled_ && scene_.run.vtk != "none") coupled_->writeVtk(solver_.time(), slices_, stepper_.coupled->world.engine,
                                                               stepper_.coupled->coupling);
  if (pvd_) {
    char name[64];
    std::snprintf(name, sizeof name, "vtk/particles_%06ld.vtp", index);
    io::writeParticlesVtp((dir_ / name).string(), slices_,
                          scene_.run.vtk == "ascii" ? io::VtkEncoding::Ascii : io::VtkEncoding::AppendedRaw);
    pvd_->add(solver_.time(), name);
  }
  // What a restart goes back to: the files as they are now, then (coupled) the checkpoint
  // naming this snapshot, so every checkpoint finds its records in the copies.
  if (coupled_) coupled_->h5().commit();
  h5_.commit();
  if (checkpoint && coupled_)
    coupling::writeCheckpoint((dir_ / "coupled.checkpoint.json").string(),
                              coupling::captureCheckpoint(*stepper_.coupled, index, stepper_.lastDt,
                                                          coupled_->referenceOrientations()));
  state_time_ = solver_.time();
  lastSnapshot_ = index;
  return index;
}

}  // namespace run
}  // namespace mpmsdem
