#include "run/RunScene.hpp"

#include <cstdio>
#include <filesystem>
#include <utility>
#include <vector>

#include "common/Error.hpp"
#include "coupling/CoupledCheckpoint.hpp"
#include "coupling/CoupledWorld.hpp"
#ifdef MPMSDEM_WITH_HDF5
#include "io/Hdf5Writer.hpp"
#include "io/StoredScene.hpp"
#include "run/OutputRun.hpp"
#endif
#include "mpm/MpmSolver.hpp"
#include "run/BenchRun.hpp"
#include "run/Progress.hpp"

namespace mpmsdem {
namespace run {

RunEnd runScene(const mpm::MpmScene& scene, const coupling::SceneBlocks& blocks, const RunRequest& request) {
  auto solver = mpm::makeSolver(scene.params, scene.run.backend, scene.run.precision);
  long maxSteps = request.steps;
  std::optional<coupling::CoupledCheckpoint> checkpoint;
#ifndef MPMSDEM_WITH_HDF5
  if (!request.bench)
    throw ParameterError("this mpmsdem-run was built without HDF5 (an MPM-only build, CMakeLists.txt): it runs "
                         "--bench only; build with libhdf5 for outputs and --restart");
#else
  // --flow-from: the state started from (its particles, record, and the blocks' MP contacts)
  std::optional<io::SnapshotSlices> flowParticles;
  std::optional<coupling::FrontSnapshot> flowFront;
  std::optional<coupling::CoupledCheckpoint> flowCheckpoint;
  if (request.restart) {
    const std::filesystem::path dir(scene.run.outputDir);
    const std::string h5 = (dir / "mpm.h5").string();
    // Back to the files as they were at the last snapshot: a run killed while it flushed
    // one of them may have left it unreadable.
    if (!io::resumeFromCommit(h5))
      throwParameter("--restart", dir.string(), "",
                     "an output folder with a restart point (mpm.h5.restart, copied with every snapshot); there is "
                     "none: the run was stopped before its first snapshot was complete, or it was written by a "
                     "version without restart points. Run the scene again without --restart");
    if (!blocks.empty()) io::resumeFromCommit((dir / "coupled.h5").string());
    io::checkRestartScene(scene, h5);
    long last = io::readNumSnapshots(h5) - 1;
    if (last < 0) throwParameter("--restart", h5, "", "a file holding at least one snapshot");
    if (!blocks.empty()) {
      checkpoint = coupling::readCheckpoint((dir / "coupled.checkpoint.json").string());
      if (checkpoint->snapshot < 0 || checkpoint->snapshot > last)
        throwParameter("--restart: coupled.checkpoint.json snapshot", checkpoint->snapshot, "",
                       "a snapshot of " + h5 + ", 0 to " + std::to_string(last));
      last = checkpoint->snapshot;
    }
    io::SnapshotSlices particles(h5, last);
    const double time = particles.time();
    const long step = particles.step();
    if (checkpoint && (checkpoint->step != step || checkpoint->time != time))
      throw ParameterError("--restart: coupled.checkpoint.json (step " + std::to_string(checkpoint->step) +
                           ") and snapshot " + std::to_string(last) + " of " + h5 + " (step " +
                           std::to_string(step) + ") are not of one time: the outputs were not written by one run");
    solver->setParticles(particles);
    solver->setClock(time, step);
    if (maxSteps > 0) maxSteps = endStep(step, maxSteps, "--restart: snapshot " + std::to_string(last) + " of " + h5);
    std::printf("mpmsdem-run: restarting from snapshot %ld of %s (t = %.6g s, step %ld)\n", last, h5.c_str(), time,
                step);
  } else if (request.flowFrom) {
    // a run's folder (its front_snapshot.json) or one of its front snapshot records
    const std::filesystem::path given(*request.flowFrom);
    const bool folder = std::filesystem::is_directory(given);
    const std::filesystem::path src = folder ? given : given.parent_path();
    const std::string h5 = (src / "mpm.h5").string();
    flowFront = coupling::readFrontSnapshot((folder ? given / "front_snapshot.json" : given).string());
    if (!(scene.run.dt > 0))
      throwParameter("--flow-from: run.dt", "\"auto\"", "",
                     "a fixed step, the one of the run started from: the blocks' steps before its state are "
                     "taken again, and an automatic step would depend on the flow they did not see");
    if (!scene.probes.empty())
      throw ParameterError("--flow-from: this scene has flow_probes, which would miss the flow before the state "
                           "it starts from; probe the run started from instead");
    io::checkFlowFromScene(scene, h5);
    const long count = io::readNumSnapshots(h5);
    if (flowFront->snapshot < 0 || flowFront->snapshot >= count)
      throwParameter("--flow-from: front_snapshot.json snapshot", flowFront->snapshot, "",
                     "a snapshot of " + h5 + ", 0 to " + std::to_string(count - 1));
    flowParticles.emplace(h5, flowFront->snapshot);
    if (flowParticles->step() != flowFront->step || flowParticles->time() != flowFront->time)
      throw ParameterError("--flow-from: front_snapshot.json (step " + std::to_string(flowFront->step) +
                           ") and snapshot " + std::to_string(flowFront->snapshot) + " of " + h5 +
                           " are not of one time: the folder's files were not written by one run");
    if (!flowFront->checkpoint.empty()) {
      flowCheckpoint = coupling::readCheckpoint((src / flowFront->checkpoint).string(), "--flow-from");
      if (flowCheckpoint->step != flowFront->step || flowCheckpoint->time != flowFront->time)
        throw ParameterError("--flow-from: " + flowFront->checkpoint + " and front_snapshot.json in " + src.string() +
                             " are not of one time: the folder's files were not written by one run");
    }
    if (blocks.empty()) {  // a flow alone: the state as it was
      solver->setParticles(*flowParticles);
      solver->setClock(flowFront->time, flowFront->step);
    }
    if (maxSteps > 0) maxSteps = endStep(flowFront->step, maxSteps, "--flow-from: the front state in " + src.string());
  } else
#endif
  {
    mpm::SeededParticles seeded = mpm::seedParticleSlices(scene);
    solver->setParticles(seeded);
  }
  mpm::MpmSolver& mpm = *solver;
  std::optional<coupling::CoupledWorld> coupled;
  std::vector<std::string> warnings;
  std::vector<Quat> sceneOrientations;  // the blocks' at the scene's start
  std::vector<Vec3> scenePositions;
  if (!blocks.empty()) {
    coupled.emplace(std::move(solver));
    coupling::addBlocks(blocks, *coupled);
    warnings = coupling::checkBlockStates(blocks, *coupled, scene.run.maxBlockSpeed);
    for (const std::string& w : warnings) std::fprintf(stderr, "mpmsdem-run: warning: %s\n", w.c_str());
    if (checkpoint) coupling::restoreCheckpoint(*checkpoint, *coupled);
#ifdef MPMSDEM_WITH_HDF5
    if (flowFront) {
      for (int i = 0; i < coupled->world.engine.numBodies(); ++i) {
        sceneOrientations.push_back(coupled->world.engine.orientation(i));
        scenePositions.push_back(coupled->world.engine.position(i));
      }
      const auto start = Clock::now();
      // a point nearer than a grid cell and a point's radius may already be in the broad phase
      coupling::startFromFlow(*coupled, *flowParticles, flowFront->step, flowFront->time, scene.run.dt,
                              flowCheckpoint ? &*flowCheckpoint : nullptr, 2 * scene.params.dx);
      std::printf("mpmsdem-run: the blocks took the %ld steps before it alone (%.3g s wall)\n", flowFront->step,
                  since(start));
    }
#endif
  }
#ifdef MPMSDEM_WITH_HDF5
  if (flowFront)
    std::printf("mpmsdem-run: starting from the flow of %s (t = %.6g s, step %ld; its front at x = %.6g m)\n",
                request.flowFrom->c_str(), flowFront->time, flowFront->step, flowFront->frontX);
#endif
  Stepper stepper(mpm, coupled ? &*coupled : nullptr);
  if (checkpoint) stepper.lastDt = checkpoint->lastDt;
  if (scene.run.dt > 0 && scene.run.dt > mpm.stableTimeStep() * kStepSlack) {
    char range[128];
    std::snprintf(range, sizeof range, "<= the stable step %.6g s (cfl dx / wave speed), or \"auto\"",
                  mpm.stableTimeStep());
    throwParameter("run.dt", scene.run.dt, "s", range);
  }
  if (request.deviceStages) {
    mpm.setStageTiming(true);
    if (coupled) coupled->coupling.setStageTiming(true);
  }
#ifdef MPMSDEM_WITH_HDF5
  if (request.bench) {
    runBench(stepper, scene, maxSteps);
    return RunEnd::Done;
  }
  OutputRun out(stepper, scene, request.restart,
                checkpoint ? &checkpoint->referenceOrientations : flowFront && coupled ? &sceneOrientations : nullptr,
                flowFront && coupled ? &scenePositions : nullptr);
  out.recordWarnings(warnings);
  return out.run(maxSteps);
#else
  runBench(stepper, scene, maxSteps);  // other runs were refused above
  return RunEnd::Done;
#endif
}

}  // namespace run
}  // namespace mpmsdem
