// mpmsdem-run: plain C++ driver (no YADE, no Python) for JSON-described MPM scenes, and coupled
// MPM–SDEM scenes when the scene has "blocks" (pkg/coupling/CoupledScene.hpp).
//
//   mpmsdem-run scene.json [--backend cpu|cuda] [--precision float|double] [--out DIR]
//                          [--steps N] [--restart | --flow-from DIR|FILE] [--bench]
//
// The scene schema is documented in pkg/mpm/MpmScene.hpp (flow), pkg/coupling/CoupledScene.hpp
// (blocks) and examples/scenes/README.md.
// Options override the scene's "run" settings:
//   --backend, --precision   solver backend and precision (either precision on either backend)
//   --out DIR                output folder (run.output_dir)
//   --steps N                run exactly N steps (N >= 1) instead of run.duration
//   --restart                continue from the last snapshot of the output folder's mpm.h5
//                            (its particles, time and step), appending to its outputs as
//                            they were at that snapshot (mpm.h5.restart, coupled.h5.restart);
//                            --steps then counts the steps of this run. The scene must be
//                            the one the run was started with (the file's "parameters"),
//                            except for kRestartFree (pkg/io/StoredScene.cpp; exit 2 naming what changed).
//                            With blocks, from the snapshot that coupled.checkpoint.json
//                            names (pkg/coupling/CoupledCheckpoint.hpp): the same run, bit
//                            for bit, on the CPU and on CUDA (whose sums have a fixed order)
//   --flow-from DIR|FILE     start from the flow of the run in DIR, at the state it saved when
//                            its front reached run.snapshot_when_front_at (DIR/front_snapshot.json,
//                            or the record FILE, e.g. DIR/front_snapshot_2.json for a list of x):
//                            a scene of the same flow (checkFlowFromScene: the keys a restart
//                            keeps, but for grid cells added on free sides) with blocks that the
//                            flow had not reached, its own fixed blocks first (a bed). The other
//                            blocks take their steps before that state alone, so the run is the
//                            one this scene would give from the start, bit for bit, without
//                            computing the flow's way to them again (coupling::startFromFlow).
//                            Needs a fixed run.dt, the same in both, and no flow_probes;
//                            --steps counts the steps of this run
//   --bench                  write no files, take no diagnostics; print one JSON line on
//                            stdout at the end: backend, precision, solver, particles,
//                            steps, seconds (step loop wall time), particle_updates_per_s
//                            (over the steps after the first kBenchWarmupSteps, which sort the
//                            particles from their seeded order and first touch the second
//                            state buffer; their time is warmup_seconds), warmup_steps,
//                            bytes_per_particle (solver memoryBytes()/particles), threads;
//                            with blocks also time, stage_seconds, contact_step_min(_time)
//                            and moving_blocks (BlockRecord: travel, rotation, peak flow
//                            force of each moving block), narrow_phase_pairs (block pairs
//                            the narrow phase computed, all steps) and block_contacts (the
//                            blocks' contacts with blocks and terrain after the last step)
//   --device-stages          with --bench on CUDA: time the MPM step's stages on the device
//                            (events; lists, sort, p2g, grid, g2p, columns) and add device_stage_seconds to
//                            the JSON line; in a coupled run also the coupling's parts
//                            (coupling_stage_seconds: MpSdemCoupling::setStageTiming)
// Outputs (not with --bench), in the output folder:
//   mpm.h5          HDF5 (pkg/io/Hdf5Writer.hpp): /series/{time, step, dt, kinetic_energy,
//                   front_x, height_z, centre_of_mass (3), max_speed, flowing_fraction,
//                   gasified_fraction} every run.series_every, /snapshots every
//                   run.output_every (each a file in mpm.snapshots/, linked from mpm.h5),
//                   root attributes units, parameters (scene JSON), solver, and on failure
//                   "failure" (message) and "failure_snapshot". mpm.h5.restart (and
//                   coupled.h5.restart): the file as of the last snapshot, for --restart.
//   particles.pvd + vtk/particles_NNNNNN.vtp   ParaView series (unless run.vtk = "none").
//   With blocks: coupled.h5 (pkg/coupling/CoupledOutput.hpp: per-block pos, vel, rotation,
//                   flow_force, face_force, edge_force, flow_torque, contacts, and the energies
//                   flow_kinetic, flow_potential, block_kinetic, dissipated, every
//                   run.series_every) and scene.pvd (particles, blocks and the point–block
//                   contacts, every run.output_every) in place of particles.pvd. The time step is the smaller
//                   of the MPM step and the contact step (CoupledWorld::criticalTimeStep).
//                   coupled.checkpoint.json after every snapshot: what --restart needs
//                   besides the particles (block states, contact histories).
//   With "flow_probes": /series/probe_depth, probe_velocity, probe_points (one value per
//                   probe and record) in mpm.h5, and flow_probes.json at the end: why the run
//                   stopped ("duration", "steps", "probes", "front_still", "failure", "signal"), the
//                   time, and per probe its spec, arrival (null: the front never came), h_f,
//                   v_f, Fr = v_f / sqrt(|g| h_f) and the number of records. run.stop_when_probed
//                   and run.stop_when_front_still end the run early (MpmScene.hpp). Such a run
//                   is not restarted (its probe records are not in the checkpoint); --bench
//                   takes no records, so it ignores the probes and those two stop rules.
//   With run.snapshot_when_front_at: front_snapshot.json (and with blocks
//                   front_snapshot.checkpoint.json), the state --flow-from starts from; for a
//                   list of x, front_snapshot_<k>.json for each (a restart keeps those older than
//                   the restart point).
// Progress lines go to stdout (stderr with --bench) every 5 % of the run and at least every
// run.progress_every seconds of wall time (10), with the step and what sets it (the flow's CFL
// step, a contact, a block's approach naming the block). With "dt": "auto" a step below
// run.min_step_fraction of the flow's CFL step stops the run (exit 3, the last good state
// saved), naming what forced it. At load, a block faster than run.max_block_speed or more than
// 100 grid diagonals from the grid is refused (exit 2); one that lies wholly outside the grid
// is a warning on stderr and in the outputs' "warnings" attribute. A coupled run ends
// with the split of the step loop's wall time (MPM step, MP-block coupling, blocks, the rest)
// and the smallest contact step of the run and when it occurred, also in --bench's JSON as
// "stage_seconds" and "contact_step_min" / "contact_step_min_time" (null while nothing touched).
// SIGINT or SIGTERM (Ctrl-C, `timeout`, a batch system's end of allocation) ends the run after the
// step in progress: the state is saved as a snapshot with its coupled checkpoint, so that
// --restart continues the same run, and the exit status is 4. A second SIGINT (Ctrl-C twice) ends
// the process at once (the outputs are then those of the last snapshot, as after a kill); more
// SIGTERMs change nothing, so that a runner may pass one on to a driver that had its own. With
// --bench, or before the step loop has begun, either signal ends the process at once.
// Exit status: 0 done; 2 bad parameters or command line (a scene too large for the memory
// included); 3 run failure (NaN, blow-up, step
// above the stable one), after writing the last good state as a final snapshot (with
// "keep_last_good_state": false, naming the last snapshot written as the last good state); 4
// stopped by a signal, the state saved; 1 other errors (e.g. I/O).
#include <omp.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <new>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "common/Error.hpp"
#include "coupling/CoupledCheckpoint.hpp"
#include "coupling/CoupledScene.hpp"
#include "coupling/CoupledWorld.hpp"
#ifdef MPMSDEM_WITH_HDF5
#include "coupling/CoupledOutput.hpp"
#include "io/Hdf5Writer.hpp"
#include "io/StoredScene.hpp"
#endif
#include "io/VtkWriter.hpp"
#include "mpm/Diagnostics.hpp"
#include "mpm/MpmScene.hpp"
#include "mpm/MpmSolver.hpp"

using namespace mpmsdem;
using namespace mpmsdem::mpm;

namespace {

constexpr int kExitStopped = 4;

// The number of the SIGINT or SIGTERM that asked the step loop to stop (0: none). SIGINT gets its
// default action back, so that a second Ctrl-C ends a run whose saving hangs.
volatile std::sig_atomic_t gStopSignal = 0;

extern "C" void onStopSignal(int sig) {
  if (!gStopSignal) gStopSignal = sig;
  if (sig == SIGINT) std::signal(sig, SIG_DFL);
}

const char* signalName(int sig) { return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : "a signal"; }

const char* const kUsage =
    "usage: mpmsdem-run scene.json [--backend cpu|cuda] [--precision float|double] [--out DIR] [--steps N] "
    "[--restart | --flow-from DIR|FILE] [--bench [--device-stages]]\n";

struct Options {
  std::string scene;
  std::optional<Backend> backend;
  std::optional<Precision> precision;
  std::optional<std::string> out;
  long steps = 0;  // 0: run for run.duration
  bool restart = false;
  std::optional<std::string> flowFrom;  // the run whose flow this one starts from: its folder or a front record
  bool bench = false;
  bool deviceStages = false;
};

Options parseArgs(int argc, char** argv) {
  Options o;
  auto value = [&](int& i, const char* flag) -> std::string {
    if (i + 1 >= argc) throw ParameterError(std::string(flag) + ": missing value\n" + kUsage);
    return argv[++i];
  };
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--backend") {
      const std::string v = value(i, "--backend");
      if (v != "cpu" && v != "cuda") throwParameter("--backend", v, "", "cpu or cuda");
      o.backend = v == "cuda" ? Backend::Cuda : Backend::Cpu;
    } else if (a == "--precision") {
      const std::string v = value(i, "--precision");
      if (v != "float" && v != "double") throwParameter("--precision", v, "", "float or double");
      o.precision = v == "float" ? Precision::Float : Precision::Double;
    } else if (a == "--out") {
      o.out = value(i, "--out");
    } else if (a == "--steps") {
      const std::string v = value(i, "--steps");
      char* end = nullptr;
      o.steps = std::strtol(v.c_str(), &end, 10);
      if (v.empty() || *end != '\0' || o.steps < 1) throwParameter("--steps", v, "", "an integer >= 1");
    } else if (a == "--restart") {
      o.restart = true;
    } else if (a == "--flow-from") {
      o.flowFrom = value(i, "--flow-from");
    } else if (a == "--bench") {
      o.bench = true;
    } else if (a == "--device-stages") {
      o.deviceStages = true;
    } else if (a == "-h" || a == "--help") {
      std::cout << kUsage;
      std::exit(0);
    } else if (!a.empty() && a[0] == '-') {
      throw ParameterError("unknown option '" + a + "'\n" + kUsage);
    } else if (o.scene.empty()) {
      o.scene = a;
    } else {
      throw ParameterError("more than one scene file given ('" + o.scene + "', '" + a + "')\n" + kUsage);
    }
  }
  if (o.scene.empty()) throw ParameterError(std::string("no scene file given\n") + kUsage);
  if (o.restart && o.bench) throw ParameterError("--restart and --bench: choose one (a benchmark writes no files)");
  if (o.restart && o.flowFrom)
    throw ParameterError("--restart and --flow-from: choose one (a run started from another's flow is restarted from "
                         "its own outputs, with --restart alone)");
  if (o.deviceStages && !o.bench) throw ParameterError(std::string("--device-stages: only with --bench\n") + kUsage);
  return o;
}

std::string formatDuration(double s) {
  char buf[32];
  if (s < 120)
    std::snprintf(buf, sizeof buf, "%.0fs", s);
  else if (s < 7200)
    std::snprintf(buf, sizeof buf, "%.1fmin", s / 60);
  else
    std::snprintf(buf, sizeof buf, "%.1fh", s / 3600);
  return buf;
}

// What a step advances: the MPM solver alone, or the coupled world that owns it.
struct Stepper {
  MpmSolver& solver;
  coupling::CoupledWorld* coupled = nullptr;
  double lastDt = 0;  // the step taken last [s]
  void step(double dt) {
    coupled ? coupled->step(dt) : solver.step(dt);
    lastDt = dt;
  }
  // MPM CFL step, and with blocks the contact step of the last step's contacts [s]
  double stableStep() { return coupled ? coupled->criticalTimeStep() : solver.stableTimeStep(); }
  // Whether nextStep chooses the step, and with blocks the terms of its last choice
  bool automatic = false;
  coupling::AutoStepTerms terms;
  // What set the step chosen last, in words
  std::string limit() const {
    if (!automatic) return "the fixed run.dt";
    return coupled ? terms.describe() : "the flow's CFL step";
  }
};

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// A fixed run.dt may exceed the stable step by this factor (round-off), as in
// MpmSolver::checkTimeStep.
constexpr double kStepSlack = 1.0001;

// Time step for the next step: fixed or auto, never past the end time when running by time.
double nextStep(Stepper& st, const RunSettings& run, bool byTime) {
  MpmSolver& solver = st.solver;
  double dt;
  if (run.dt > 0) {
    const double stable = st.stableStep();
    if (run.dt > stable * kStepSlack) {
      char msg[320];
      std::snprintf(msg, sizeof msg,
                    "run.dt = %.6g s exceeds the stable step %.6g s at t = %.6g s, step %ld (%s; use \"dt\": "
                    "\"auto\" or a smaller dt)",
                    run.dt, stable, solver.time(), solver.steps(),
                    st.coupled && stable < solver.stableTimeStep()
                        ? "the contact step of the MP-block and block contacts, sqrt(m/k) times the safety factor"
                        : "the MPM CFL step");
      throw RuntimeFailure(msg);
    }
    dt = run.dt;
  } else {
    // The automatic step was chosen from the contacts of the step before it, so a contact that
    // started within it may have a smaller critical step; up to twice that (the leapfrog's own
    // limit) the step was stable and the next one shrinks, beyond it the run stops.
    if (st.coupled && st.lastDt > 2 * st.coupled->contactStep()) {
      char msg[400];
      std::snprintf(msg, sizeof msg,
                    "the step to t = %.6g s (step %ld) was dt = %.6g s, above twice the contact step %.6g s it "
                    "ended with (the stability limit): a contact started or stiffened within it faster than \"dt\": "
                    "\"auto\" follows; use a smaller run.dt_factor (now %g)",
                    solver.time(), solver.steps(), st.lastDt, st.coupled->contactStep(), run.dtFactor);
      throw RuntimeFailure(msg);
    }
    const double cfl = solver.stableTimeStep();
    st.automatic = true;
    if (st.coupled) {
      st.terms = coupling::autoStepTerms(st.coupled->world.engine, run.dtFactor, cfl, st.coupled->contactStep(),
                                         st.coupled->coupling.particleApproachStep(), st.lastDt);
      dt = st.terms.step();
    } else {
      dt = run.dtFactor * cfl;
    }
    if (dt < run.minStepFraction * cfl) {
      std::ostringstream m;
      m.precision(4);
      m << "the automatic step fell to " << dt << " s at t = " << solver.time() << " s (step " << solver.steps()
        << "), below run.min_step_fraction = " << run.minStepFraction << " of the flow's CFL step " << cfl
        << " s: the rest of the run would take " << (run.duration - solver.time()) / dt
        << " steps or more. It is set by " << st.limit()
        << ". Check the scene (block velocities, barrier stiffness), or lower run.min_step_fraction (0: no floor)";
      throw RuntimeFailure(m.str());
    }
  }
  if (byTime) dt = std::min(dt, run.duration - solver.time());
  return dt;
}

// maxSteps: the step count at which to stop (0: stop at run.duration).
bool finished(const MpmSolver& solver, const RunSettings& run, long maxSteps) {
  if (maxSteps > 0) return solver.steps() >= maxSteps;
  return solver.time() >= run.duration * (1 - 1e-12);
}

// Fraction of the run done, by steps (--steps, counted from firstStep) or by simulated time.
double progressFraction(const MpmSolver& solver, const RunSettings& run, long maxSteps, long firstStep = 0) {
  return maxSteps > 0 ? double(solver.steps() - firstStep) / double(maxSteps - firstStep)
                      : solver.time() / run.duration;
}

// Where the step loop's wall time went in a coupled run: "MPM step 71.2 %, ...". The records
// (diagnostics read from every particle, series, progress) and the snapshots are timed by the
// loop; the rest is the time-step control.
std::string stageSplit(const coupling::CoupledWorld& world, double loopSeconds, double recordSeconds,
                       double snapshotSeconds) {
  const auto& s = world.stageSeconds();
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "MPM step %.1f %%, MP-block coupling %.1f %%, blocks %.1f %%, records %.1f %%, snapshots %.1f %%, "
                "time-step control %.1f %%",
                100 * s.mpm / loopSeconds, 100 * s.coupling / loopSeconds, 100 * s.blocks / loopSeconds,
                100 * recordSeconds / loopSeconds, 100 * snapshotSeconds / loopSeconds,
                100 * (loopSeconds - s.mpm - s.coupling - s.blocks - recordSeconds - snapshotSeconds) / loopSeconds);
  return buf;
}

// What a benchmark run did to each moving block, so that backends and precisions can be
// compared on physics as well as speed without output files: the start and end of its centroid,
// its end velocity, the angle it turned, and the largest flow force on it (|F| and the x
// component, the downstream force in a flume's frame) with when it came (null: no such force).
class BlockRecord {
 public:
  explicit BlockRecord(const sdem::SdemEngine& e) {
    for (int i = 0; i < e.numBodies(); ++i)
      if (!e.isFixed(i)) blocks_.push_back({i, e.position(i), e.orientation(i)});
  }
  void afterStep(const coupling::CoupledWorld& w) {
    for (Block& b : blocks_) {
      const Vec3 f = w.coupling.force(b.index);
      if (f.norm() > b.peak) b.peak = f.norm(), b.peakTime = w.time();
      if (f.x() > b.peakX) b.peakX = f.x(), b.peakXTime = w.time();
    }
  }
  nlohmann::json summary(const sdem::SdemEngine& e) const {
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

 private:
  struct Block {
    int index;
    Vec3 pos0;
    Quat ori0;
    double peak = 0, peakTime = 0, peakX = 0, peakXTime = 0;
  };
  std::vector<Block> blocks_;
};

// Steps at the start of a benchmark that are timed apart: as many as a peer's warm-up
// (scripts/bench/peers: one step per copy of the particles), so that both rates are of the
// steps a long run repeats.
constexpr long kBenchWarmupSteps = 2;

int runBench(Stepper& st, const MpmScene& scene, long maxSteps) {
  MpmSolver& solver = st.solver;
  const std::size_t n = solver.numParticles();
  std::optional<BlockRecord> blocks;
  if (st.coupled) blocks.emplace(st.coupled->world.engine);
  const auto t0 = Clock::now();
  auto lastReport = t0;
  double nextReport = 0.05;
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
    if (f >= nextReport || since(lastReport) >= scene.run.progressEvery) {
      const double el = since(t0);
      std::fprintf(stderr, "[%5.1f%%] t=%.5g s step=%ld dt=%.3g s (%s) rate=%.3g upd/s ETA=%s\n", 100 * f,
                   solver.time(), solver.steps(), st.lastDt, st.limit().c_str(), n * double(solver.steps()) / el,
                   formatDuration(f > 0 ? el * (1 - f) / f : 0).c_str());
      nextReport = std::floor(f / 0.05 + 1) * 0.05;
      lastReport = Clock::now();
    }
  }
  solver.stableTimeStep();  // a reduction over all particles: waits for outstanding device work
  const double seconds = since(t0);
  nlohmann::json out = {{"backend", backendName(scene.run.backend)},
                        {"precision", precisionName(scene.run.precision)},
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
                        {"flip_blend", mpm::describeFlipBlend(scene.params)},
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
  return 0;
}

#ifdef MPMSDEM_WITH_HDF5
class OutputRun {
 public:
  // restart: append to the outputs already in the folder instead of starting them anew;
  // referenceOrientations: what the blocks' rotation is measured from, when not their
  // orientations now (a restart's checkpoint, or the scene's for a run started from another's
  // flow: its blocks settled before); null: now, or no blocks. startPositions: the blocks'
  // centroids at the scene's start, where the run does not begin there (coupled.h5's attribute
  // start_positions, what travel is counted from); null: now.
  OutputRun(Stepper& stepper, const MpmScene& scene, bool restart, const std::vector<Quat>* referenceOrientations,
            const std::vector<Vec3>* startPositions = nullptr)
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
    if (coupled_) coupled_->h5().setAttribute("flip_blend", mpm::describeFlipBlend(scene.params));
    for (const mpm::FlowProbeSpec& p : scene.probes) probes_.emplace_back(p);
  }

  int run(long maxSteps) {
    const RunSettings& run = scene_.run;
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
    const double t0sim = solver_.time();
    double nextSeries = (std::floor(t0sim / run.seriesEvery * (1 + 1e-12)) + 1) * run.seriesEvery;
    double nextOutput = (std::floor(t0sim / run.outputEvery * (1 + 1e-12)) + 1) * run.outputEvery;
    double nextReport = std::floor(progressFraction(solver_, run, maxSteps, firstStep) / 0.05 + 1) * 0.05;
    const auto t0 = Clock::now();
    auto lastReport = t0;
    const bool byTime = maxSteps == 0;
    std::printf("mpmsdem-run: FLIP/PIC blend %s\n", mpm::describeFlipBlend(scene_.params).c_str());
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
    std::signal(SIGINT, onStopSignal);
    std::signal(SIGTERM, onStopSignal);
    try {
      while (!finished(solver_, run, maxSteps) && stopReason_.empty() && !gStopSignal) {
        dt = nextStep(stepper_, run, byTime);
        stepper_.step(dt);
        const double t = solver_.time();
        const bool series = t >= nextSeries * (1 - 1e-12), output = t >= nextOutput * (1 - 1e-12);
        const double f = progressFraction(solver_, run, maxSteps, firstStep);
        bool report = f >= nextReport || finished(solver_, run, maxSteps) || since(lastReport) >= run.progressEvery;
        // one pass over the particles serves the series record and the progress line
        const auto recordStart = Clock::now();
        std::optional<mpm::Diagnostics> d;
        if (series || report) d = diagnose();
        if (series) {
          recordSeries(*d, dt);
          report = report || !stopReason_.empty();  // a stop rule ended the run at this record
          while (nextSeries <= t * (1 + 1e-12)) nextSeries += run.seriesEvery;
        }
        recordSeconds += since(recordStart);
        if (output) {
          timedSnapshot();
          while (nextOutput <= t * (1 + 1e-12)) nextOutput += run.outputEvery;
        }
        if (frontsReached_ > frontsWritten_) {
          const auto start = Clock::now();
          writeFrontSnapshots();
          snapshotSeconds += since(start);
        }
        if (report) {
          const double el = since(t0);
          std::printf("[%5.1f%%] t=%.5g s step=%ld dt=%.3g s (%s) KE=%.5g J front=%.5g m rate=%.3g upd/s ETA=%s\n",
                      100 * f, t, solver_.steps(), dt, stepper_.limit().c_str(), d->kineticEnergy, d->frontX,
                      n * double(solver_.steps() - firstStep) / el,
                      formatDuration(f > 0 ? el * (1 - f) / f : 0).c_str());
          std::fflush(stdout);
          nextReport = std::floor(f / 0.05 + 1) * 0.05;
          lastReport = Clock::now();
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
        return 3;
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
      return 3;
    }
    if (solver_.time() > state_time_) timedSnapshot();
    const double loop = since(t0);
    if (gStopSignal) {
      std::printf("mpmsdem-run: stopped by %s at t = %.6g s, step %ld, %.3g s wall: the state is saved as the last "
                  "snapshot of %s%s; --restart continues the run\n",
                  signalName(gStopSignal), solver_.time(), solver_.steps(), loop, h5_.path().c_str(),
                  coupled_ ? " with coupled.checkpoint.json" : "");
      writeProbeResults("signal");
      std::fflush(stdout);
      return kExitStopped;
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
    return 0;
  }

  // Load-time warnings (e.g. a block that can never touch the flow) as the root attribute
  // "warnings" of mpm.h5 and coupled.h5, one per line; none: no attribute.
  void recordWarnings(const std::vector<std::string>& warnings) {
    if (warnings.empty()) return;
    std::string text;
    for (const std::string& w : warnings) text += (text.empty() ? "" : "\n") + w;
    h5_.setAttribute("warnings", text);
    if (coupled_) coupled_->h5().setAttribute("warnings", text);
  }

 private:
  mpm::Diagnostics diagnose() { return mpm::diagnose(solver_, slices_, solver_.params().gravity, scene_.probes); }

  // The flow probes' records and the run's stop rules, at a series record of time t.
  void recordProbes(const mpm::Diagnostics& d, double t) {
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

  // flow_probes.json: why the run stopped and each probe's result (scenes with flow_probes).
  void writeProbeResults(const std::string& stopped) {
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
                                {"flip_blend", mpm::describeFlipBlend(scene_.params)},
                                {"probes", list}};
    const std::filesystem::path path = dir_ / "flow_probes.json";
    std::ofstream f(path);
    f << out.dump(1) << "\n";
    if (!f) throw RuntimeFailure("cannot write " + path.string());
  }

  void recordSeries(const mpm::Diagnostics& d, double dt = 0) {
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

  // One coupled.h5 record: block series and energies (§5.4) at the solver's time; d: the
  // particles' diagnostics at that time.
  void recordBlocks(const mpm::Diagnostics& d) {
    coupling::CoupledWorld& w = *stepper_.coupled;
    const sdem::SdemEngine& e = w.world.engine;
    coupled_->record(solver_.time(), solver_.steps(), e, w.coupling);
    coupled_->appendSeries("flow_kinetic", d.kineticEnergy);
    coupled_->appendSeries("flow_potential", d.potential);
    coupled_->appendSeries("block_kinetic", w.world.kineticEnergy());
    coupled_->appendSeries("dissipated", w.coupling.frictionDissipation() + w.coupling.dampingDissipation() +
                                             e.frictionDissipation() + e.dampingDissipation());
  }


  // The record of run.snapshot_when_front_at's k-th x (front_snapshot.json for a single number).
  std::filesystem::path frontPath(std::size_t k) const {
    return dir_ / (scene_.run.snapshotsIndexed ? "front_snapshot_" + std::to_string(k) + ".json"
                                               : std::string("front_snapshot.json"));
  }

  // The x of run.snapshot_when_front_at that the front has reached since the last record: the
  // state now as a snapshot (the one just written, if it is of now) and a record naming it for
  // each, with the blocks' coupled state beside it (the run's own checkpoint is replaced at every
  // snapshot).
  void writeFrontSnapshots() {
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

  // checkpoint: also write the coupled state beside it (blocks and particles at one time).
  long writeSnapshot(bool checkpoint = true) {
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

  Stepper& stepper_;
  MpmSolver& solver_;
  const MpmScene& scene_;
  bool restart_;
  std::filesystem::path dir_;
  io::Hdf5Writer h5_;
  std::optional<io::PvdCollection> pvd_;
  std::optional<coupling::CoupledOutput> coupled_;
  // Outputs read the particles in slices: a whole host copy would add 145 B per particle to
  // the solver's memory while it is written.
  mpm::SolverParticleSlices slices_{solver_, 1 << 16};
  double state_time_ = -1;  // time of the last snapshot written
  long lastSnapshot_ = -1;  // and its index
  std::size_t frontsReached_ = 0, frontsWritten_ = 0;  // run.snapshot_when_front_at's x reached, saved
  double frontXAtSnapshot_ = 0;                        // the front when the last was reached [m]
  std::vector<mpm::FlowProbeRecord> probes_;
  double front_ = -INFINITY, frontAt_ = 0;  // the front's largest x so far and when it got there [m, s]
  std::string stopReason_;                  // a stop rule that ended the run ("probes", "front_still")
};

#endif  // MPMSDEM_WITH_HDF5

}  // namespace

int main(int argc, char** argv) {
#ifdef MPMSDEM_WITH_HDF5
  io::skipHdf5CleanupAtExit();  // a failed write (a full disk) must end with its message, not a crash at exit
#endif
  std::string sceneSize;  // for an out-of-memory message
  try {
    const Options opt = parseArgs(argc, argv);
    MpmScene scene = loadScene(opt.scene);
    sceneSize = sceneSizeDescription(scene);
    if (opt.backend) scene.run.backend = *opt.backend;
    if (opt.precision) scene.run.precision = *opt.precision;
    if (opt.out) scene.run.outputDir = *opt.out;
    const coupling::SceneBlocks blocks = coupling::parseBlocks(scene.sourceJson);
    if (opt.deviceStages && scene.run.backend != Backend::Cuda)
      throw ParameterError("--device-stages: times the CUDA step; this run is on the " +
                           std::string(backendName(scene.run.backend)) + " backend (--backend cuda)");
    auto solver = makeSolver(scene.params, scene.run.backend, scene.run.precision);
    long maxSteps = opt.steps;
    std::optional<coupling::CoupledCheckpoint> checkpoint;
    // --flow-from: the state started from (its particles, record, and the blocks' MP contacts)
    std::optional<io::SnapshotSlices> flowParticles;
    std::optional<coupling::FrontSnapshot> flowFront;
    std::optional<coupling::CoupledCheckpoint> flowCheckpoint;
#ifndef MPMSDEM_WITH_HDF5
    if (!opt.bench)
      throw ParameterError("this mpmsdem-run was built without HDF5 (an MPM-only build, CMakeLists.txt): it runs "
                           "--bench only; build with libhdf5 for outputs and --restart");
#else
    if (opt.restart) {
      if (!scene.probes.empty())
        throw ParameterError("--restart: this scene has flow_probes, whose records are not kept in a restart point; "
                             "run it again without --restart (a free-flow probe run is short)");
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
      if (maxSteps > 0) maxSteps += step;
      std::printf("mpmsdem-run: restarting from snapshot %ld of %s (t = %.6g s, step %ld)\n", last, h5.c_str(), time,
                  step);
    } else if (opt.flowFrom) {
      // a run's folder (its front_snapshot.json) or one of its front snapshot records
      const std::filesystem::path given(*opt.flowFrom);
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
      if (maxSteps > 0) maxSteps += flowFront->step;
    } else
#endif
    {
      SeededParticles seeded = seedParticleSlices(scene);
      solver->setParticles(seeded);
    }
    MpmSolver& mpm = *solver;
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
                  opt.flowFrom->c_str(), flowFront->time, flowFront->step, flowFront->frontX);
#endif
    Stepper stepper{mpm, coupled ? &*coupled : nullptr};
    if (checkpoint) stepper.lastDt = checkpoint->lastDt;
    if (scene.run.dt > 0 && scene.run.dt > mpm.stableTimeStep() * kStepSlack) {
      char range[128];
      std::snprintf(range, sizeof range, "<= the stable step %.6g s (cfl dx / wave speed), or \"auto\"",
                    mpm.stableTimeStep());
      throwParameter("run.dt", scene.run.dt, "s", range);
    }
    if (opt.deviceStages) {
      mpm.setStageTiming(true);
      if (coupled) coupled->coupling.setStageTiming(true);
    }
#ifdef MPMSDEM_WITH_HDF5
    if (opt.bench) return runBench(stepper, scene, maxSteps);
    OutputRun out(stepper, scene, opt.restart,
                  checkpoint ? &checkpoint->referenceOrientations : flowFront && coupled ? &sceneOrientations : nullptr,
                  flowFront && coupled ? &scenePositions : nullptr);
    out.recordWarnings(warnings);
    return out.run(maxSteps);
#else
    return runBench(stepper, scene, maxSteps);  // other runs were refused above
#endif
  } catch (const ParameterError& e) {
    std::fprintf(stderr, "mpmsdem-run: parameter error: %s\n", e.what());
    return 2;
  } catch (const RuntimeFailure& e) {
    std::fprintf(stderr, "mpmsdem-run: failure: %s\n", e.what());
    return 3;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "mpmsdem-run: parameter error: out of memory for %s: reduce grid.cells (a coarser dx or "
                         "a smaller domain) or the particles per cell (ppc)\n",
                 sceneSize.empty() ? "the scene" : sceneSize.c_str());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mpmsdem-run: error: %s\n", e.what());
    return 1;
  }
}
