// A run with outputs (mpmsdem-run without --bench; needs HDF5): the step loop with its records,
// snapshots, progress lines, stop rules and failure handling. In the output folder:
//   mpm.h5          HDF5 (pkg/io/Hdf5Writer.hpp): /series/{time, step, dt, kinetic_energy,
//                   front_x, height_z, centre_of_mass (3), max_speed, flowing_fraction,
//                   gasified_fraction} every run.series_every, /snapshots every
//                   run.output_every (each a file in mpm.snapshots/, linked from mpm.h5;
//                   pkg/run/OutputCadence.hpp), root attributes units, parameters (scene JSON),
//                   solver, and on failure "failure" (message) and "failure_snapshot".
//                   mpm.h5.restart (and coupled.h5.restart): the file as of the last snapshot,
//                   for --restart.
//   particles.pvd + vtk/particles_NNNNNN.vtp   ParaView series (unless run.vtk = "none").
//   With blocks: coupled.h5 (pkg/coupling/CoupledOutput.hpp: per-block pos, vel, rotation,
//                   flow_force, face_force, edge_force, flow_torque, contacts, and the energies
//                   flow_kinetic, flow_potential, block_kinetic, dissipated, every
//                   run.series_every) and scene.pvd (particles, blocks and the point–block
//                   contacts, every run.output_every) in place of particles.pvd.
//                   coupled.checkpoint.json after every snapshot: what --restart needs
//                   besides the particles (block states, contact histories).
//   With "flow_probes": /series/probe_depth, probe_velocity, probe_points (one value per
//                   probe and record) in mpm.h5, and flow_probes.json at the end: why the run
//                   stopped ("duration", "steps", "probes", "front_still", "failure", "signal"), the
//                   time, and per probe its spec, arrival (null: the front never came), h_f,
//                   v_f, Fr = v_f / sqrt(|g| h_f) and the number of records. run.stop_when_probed
//                   and run.stop_when_front_still end the run early (MpmScene.hpp). Such a run
//                   is not restarted (its probe records are not in the checkpoint).
//   With run.snapshot_when_front_at: front_snapshot.json (and with blocks
//                   front_snapshot.checkpoint.json), the state --flow-from starts from; for a
//                   list of x, front_snapshot_<k>.json for each (a restart keeps those older than
//                   the restart point).
// Progress lines go to stdout (pkg/run/Progress.hpp). A RuntimeFailure in the step loop (NaN,
// blow-up, a step above the stable one) writes the last good state as a final snapshot (with
// "keep_last_good_state": false, names the last snapshot written as the last good state) and
// ends the run with RunEnd::Failure; a SIGINT or SIGTERM saves the state and ends it with
// RunEnd::Stopped (pkg/run/StopSignal.hpp). A coupled run ends with the split of the step loop's
// wall time and the smallest contact step of the run and when it occurred.
#pragma once

#include <cmath>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "common/Types.hpp"
#include "coupling/CoupledOutput.hpp"
#include "io/Hdf5Writer.hpp"
#include "io/VtkWriter.hpp"
#include "mpm/Diagnostics.hpp"
#include "scene/MpmScene.hpp"
#include "run/RunLoop.hpp"

namespace mpmsdem {
namespace run {

class OutputRun {
 public:
  // restart: append to the outputs already in the folder instead of starting them anew;
  // referenceOrientations: what the blocks' rotation is measured from, when not their
  // orientations now (a restart's checkpoint, or the scene's for a run started from another's
  // flow: its blocks settled before); null: now, or no blocks. startPositions: the blocks'
  // centroids at the scene's start, where the run does not begin there (coupled.h5's attribute
  // start_positions, what travel is counted from); null: now.
  OutputRun(Stepper& stepper, const mpm::MpmScene& scene, bool restart, const std::vector<Quat>* referenceOrientations,
            const std::vector<Vec3>* startPositions = nullptr);

  // The step loop to maxSteps (0: to run.duration), with its outputs; SIGINT and SIGTERM are
  // caught from its start (pkg/run/StopSignal.hpp).
  RunEnd run(long maxSteps);

  // Load-time warnings (e.g. a block that can never touch the flow) as the root attribute
  // "warnings" of mpm.h5 and coupled.h5, one per line; none: no attribute.
  void recordWarnings(const std::vector<std::string>& warnings);

 private:
  mpm::Diagnostics diagnose();
  // The flow probes' records and the run's stop rules, at a series record of time t.
  void recordProbes(const mpm::Diagnostics& d, double t);
  // A restart: the probes and the front's stop rule take again the records the run kept (a
  // front that arrived before the restart point keeps its arrival and its means so far).
  void replayProbes();
  // flow_probes.json: why the run stopped and each probe's result (scenes with flow_probes).
  void writeProbeResults(const std::string& stopped);
  // A progress line's estimate of when run.stop_when_probed ends the run, from the front's speed
  // since the last line and the wall time per simulated second so far: " (stops at its probes in
  // ~3.5min)", or "" (no such rule, or no estimate yet). Advances the front's last line.
  std::string probesEta(const mpm::Diagnostics& d, double t, double wallPerSimSecond);
  void recordSeries(const mpm::Diagnostics& d, double dt = 0);
  // One coupled.h5 record: block series and energies (§5.4) at the solver's time; d: the
  // particles' diagnostics at that time.
  void recordBlocks(const mpm::Diagnostics& d);
  // The record of run.snapshot_when_front_at's k-th x (front_snapshot.json for a single number).
  std::filesystem::path frontPath(std::size_t k) const;
  // The x of run.snapshot_when_front_at that the front has reached since the last record: the
  // state now as a snapshot (the one just written, if it is of now) and a record naming it for
  // each, with the blocks' coupled state beside it (the run's own checkpoint is replaced at every
  // snapshot).
  void writeFrontSnapshots();
  // checkpoint: also write the coupled state beside it (blocks and particles at one time).
  long writeSnapshot(bool checkpoint = true);

  Stepper& stepper_;
  mpm::MpmSolver& solver_;
  const mpm::MpmScene& scene_;
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
  double lineFront_ = NAN, lineTime_ = NAN;  // the front at the last progress line, and when [m, s]
};

}  // namespace run
}  // namespace mpmsdem
