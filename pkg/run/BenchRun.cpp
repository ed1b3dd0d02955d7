#include "run/BenchRun.hpp"

#include <omp.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>

#include "run/Progress.hpp"

namespace mpmsdem {
namespace run {

BlockRecord::BlockRecord(const sdem::SdemEngine& e) {
  for (int i = 0; i < e.numBodies(); ++i)
    if (!e.isFixed(i)) blocks_.push_back({i, e.position(i), e.orientation(i)});
}

void BlockRecord::afterStep(const coupling::CoupledWorld& w) {
  for (Block& b : blocks_) {
    const Vec3 f = w.coupling.force(b.index);
    if (f.norm() > b.peak) b.peak = f.norm(), b.peakTime = w.time();
    if (f.x() > b.peakX) b.peakX = f.x(), b.peakXTime = w.time();
  }
}

nlohmann::json BlockRecord::summary(const sdem::SdemEngine& e) const {
  nlohmann::json out = nlohmann::json::array();
  const auto vec = [](const Vec3& v) { return nlohmann::json{v.x(), v.y(), v.z()}; };
  const auto when = [](double peak, double t) { return peak > 0 ? nlohmann::json(t) : nlohmann::json(); };
  for (const Block& b : blocks_) {
    const double turned = e.orientation(b.index).angularDistance(b.ori0);
    out.push_back({{"block", b.index}, {"start", vec(b.pos0)}, {"end", vec(e.position(b.index))},
                   {"velocity", vec(e.velocity(b.index))}, {"rotation_deg", turned * 180 / M_PI},
                   {"peak_flow_force", b.peak}, {"peak_flow_force_time", when(b.peak, b.peakTime)},
                   {"peak_flow_force_x", b.peakX}, {"peak_flow_force_x_time", when(b.peakX, b.peakXTime)}});
  }
  return out;
}

void runBench(Stepper& st, const mpm::MpmScene& scene, long maxSteps) {
  mpm::MpmSolver& solver = st.solver;
  const std::size_t n = solver.numParticles();
  std::optional<BlockRecord> blocks;
  if (st.coupled) blocks.emplace(st.coupled->world.engine);
  const auto t0 = Clock::now();
  ProgressSchedule progress(0.05, scene.run.progressEvery);
  const long firstStep = solver.steps();
  double warmupSeconds = 0;
  long warmupSteps = 0;
  while (!finished(solver, scene.run, maxSteps)) {
    if (solver.steps() - firstStep == kBenchWarmupSteps) {
      solver.stableTimeStep();  // waits for outstanding device work
      warmupSeconds = since(t0);
      warmupSteps = kBenchWarmupSteps;
    }
    st.step(nextStep(st, scene.run, maxSteps == 0));
    if (blocks) blocks->afterStep(*st.coupled);
    const double f = progressFraction(solver, scene.run, maxSteps);
    if (progress.due(f)) {
      const double el = since(t0);
      std::fprintf(stderr, "[%5.1f%%] t=%.5g s step=%ld dt=%.3g s (%s) rate=%.3g upd/s ETA=%s\n", 100 * f,
                   solver.time(), solver.steps(), st.lastDt, st.limit().c_str(), n * double(solver.steps()) / el,
                   formatDuration(f > 0 ? el * (1 - f) / f : 0).c_str());
      progress.reported(f);
    }
  }
  solver.stableTimeStep();  // a reduction over all particles: waits for outstanding device work
  const double seconds = since(t0);
  nlohmann::json out = {{"backend", mpm::backendName(scene.run.backend)},
                        {"precision", mpm::precisionName(scene.run.precision)},
                        {"solver", solver.name()},
                        {"particles", n},
                        {"steps", solver.steps()},
                        {"seconds", seconds},
                        {"warmup_steps", warmupSteps},
                        {"warmup_seconds", warmupSeconds},
                        {"particle_updates_per_s",
                         n * double(solver.steps() - firstStep - warmupSteps) / (seconds - warmupSeconds)},
                        {"bytes_per_particle", n ? double(solver.memoryBytes()) / n : 0.0},
                        {"threads", omp_get_max_threads()},
                        {"flip_blend", scene.params.flip.describe(scene.params.dx)},
                        {"blocks", st.coupled ? st.coupled->world.engine.numBodies() : 0}};
  const auto device = solver.stageSeconds();
  if (!device.empty()) {
    out["device_stage_seconds"] = nlohmann::json::object();
    for (const auto& [name, sec] : device) out["device_stage_seconds"][name] = sec;
  }
  if (st.coupled) {
    const auto& s = st.coupled->stageSeconds();
    out["stage_seconds"] = {{"mpm", s.mpm}, {"coupling", s.coupling}, {"blocks", s.blocks}};
    const auto couplingStages = st.coupled->coupling.stageSeconds();
    if (!couplingStages.empty()) {
      out["coupling_stage_seconds"] = nlohmann::json::object();
      for (const auto& [name, sec] : couplingStages) out["coupling_stage_seconds"][name] = sec;
    }
    const auto& low = st.coupled->contactStepLow();
    out["contact_step_min"] = std::isfinite(low.step) ? nlohmann::json(low.step) : nlohmann::json();
    out["contact_step_min_time"] = std::isfinite(low.step) ? nlohmann::json(low.time) : nlohmann::json();
    out["moving_blocks"] = blocks->summary(st.coupled->world.engine);
    out["time"] = solver.time();
    const sdem::SdemEngine& e = st.coupled->world.engine;
    out["narrow_phase_pairs"] = e.narrowPhasePairs();
    out["block_contacts"] = e.contacts().size();
  }
  std::cout << out.dump() << std::endl;
}

}  // namespace run
}  // namespace mpmsdem
