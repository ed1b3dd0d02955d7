// Restart state of a coupled driver run (mpmsdem-run --restart) that an mpm.h5 snapshot does
// not hold: the blocks' poses and motion, the angular momentum their rotation update carries,
// the tangential histories of block–block and MP–block contacts, the cumulative dissipations,
// the flow's impulses on the blocks, the steps the automatic time step is chosen from, and the
// orientations the "rotation" series
// is measured from. The driver writes it to <dir>/coupled.checkpoint.json after every snapshot,
// naming that snapshot; numbers are written with round-trip precision, so a run continued from
// it takes the same steps as the run that was not stopped, bit for bit.
//
// File (JSON): {"format": "mpmsdem-driver-coupled-1", "snapshot", "step", "time", "world_time",
//   "last_dt", "contact_step", "contact_step_low": [step, time], "particle_approach_step",
//   "bodies": [{"pos", "ori" (w x y z), "vel", "ang_vel", "ang_mom" (or null)}],
//   "sdem_histories": [[bodyA, bodyB, kindA, kindB, indexA, indexB, xi_x, xi_y, xi_z]],
//   "sdem_dissipation": [friction, damping], "history_slots", "history_particles",
//   "coupling_histories": [[slot, key, xi_x, xi_y, xi_z]] (occupied slots only),
//   "coupling_dissipation": [friction, damping], "coupling_impulse": [[J_x, J_y, J_z, L_x, L_y, L_z]]
//   (per block: the flow's impulse and angular impulse since the run's start, which coupled.h5's
//   flow_impulse series go on from; absent from checkpoints written before they were kept, and
//   then they count from the restart), "coupling_first_contact": [t or null] (per block: when
//   the flow first touched it, CouplingReport::firstContact, null before it or where not kept;
//   absent from checkpoints written before it was kept, and then a block the impulses say was
//   touched, or every block where the impulses are absent too, keeps none),
//   "reference_orientations": [[w, x, y, z]]}.
// A step of +inf (no contact) is written as null.
#pragma once
#include <string>
#include <vector>

#include "coupling/CoupledWorld.hpp"

namespace mpmsdem {
namespace coupling {

struct CoupledCheckpoint {
  long snapshot = -1;     // index of the mpm.h5 snapshot holding the particles of this state
  long step = 0;          // solver step count
  double time = 0;        // solver time [s]
  double worldTime = 0;   // the blocks' clock [s]
  double lastDt = 0;      // the step that led here [s] (the automatic step's growth cap)
  double contactStep = 0; // CoupledWorld::contactStep() [s]
  CoupledWorld::ContactStepLow contactStepLow;
  double particleApproachStep = 0;  // MpSdemCoupling::particleApproachStep() [s]
  std::vector<Vec3> pos, vel, angVel;
  std::vector<Quat> ori;
  std::vector<char> hasAngMom;
  std::vector<Vec3> angMom;
  std::vector<sdem::ContactHistoryEntry> sdemHistories;
  double sdemFriction = 0, sdemDamping = 0;
  int historySlots = 0;
  long historyParticles = 0;             // particles the MP–block histories were sized for (0: none yet)
  std::vector<long long> historyIndex;   // occupied slot: particle number x slots + k
  std::vector<long long> historyKey;
  std::vector<double> historyXi;         // 3 per occupied slot
  double couplingFriction = 0, couplingDamping = 0;
  std::vector<double> couplingImpulse;  // CouplingReport::kImpulseValues per block (empty: zero)
  std::vector<double> couplingFirstContact;  // per block [s], NaN: none (empty: not kept)
  std::vector<Quat> referenceOrientations;
};

// The state of `world` now (after its last step), for the snapshot numbered `snapshot`.
CoupledCheckpoint captureCheckpoint(CoupledWorld& world, long snapshot, double lastDt,
                                    const std::vector<Quat>& referenceOrientations);

// Write atomically (a temporary file renamed over `path`): a run killed while writing leaves
// the previous checkpoint. RuntimeFailure naming the path when it cannot be written.
void writeCheckpoint(const std::string& path, const CoupledCheckpoint& c);

// ParameterError naming the path (and the command-line option that asked for it) when it is
// missing, not such a checkpoint, or malformed.
CoupledCheckpoint readCheckpoint(const std::string& path, const std::string& option = "--restart");

// Put `world` (blocks added, particles of the snapshot loaded) into the checkpointed state.
// ParameterError when the checkpoint does not fit the scene (number of blocks or particles).
void restoreCheckpoint(const CoupledCheckpoint& c, CoupledWorld& world);

// A run's state when its front first reached run.snapshot_when_front_at: the driver writes it
// as <dir>/front_snapshot.json, naming the snapshot of mpm.h5 that holds the particles, and
// with blocks their MP contacts in <dir>/front_snapshot.checkpoint.json (a CoupledCheckpoint).
// File (JSON): {"format": "mpmsdem-front-snapshot-1", "x", "front_x", "snapshot", "time",
//   "step", "checkpoint" (the checkpoint's file name, or null for a run without blocks)}.
struct FrontSnapshot {
  double x = 0;        // run.snapshot_when_front_at [m]
  double frontX = 0;   // the front then [m]
  long snapshot = -1;  // index in mpm.h5
  double time = 0;     // [s]
  long step = 0;
  std::string checkpoint;  // file name beside it; empty: no blocks
};
void writeFrontSnapshot(const std::string& path, const FrontSnapshot& f);
// ParameterError naming the path when it is missing or malformed.
FrontSnapshot readFrontSnapshot(const std::string& path);

// Start `world` from the flow of another run (mpmsdem-run --flow-from): a run of the same flow
// whose blocks, all fixed, are the first blocks of `world` (a flume's bed, walls), saved
// before its particles came near the others. `world` holds the scene's blocks and a solver
// without particles. The other blocks first take, alone, the `step` steps of `dt` [s] that the
// scene's own run gives them before the flow arrives (they settle on the fixed ones); then the
// solver takes `particles` at (time, step), and the coupling the MP–block state of `source`
// (the other run's checkpoint of that time; null: it had no blocks). The run then goes on as the
// scene's own run from the start would, to the bit. ParameterError when the source's blocks
// are not the world's first ones, fixed and in place, when `step` steps of `dt` do not reach
// `time`, or when a particle lies within `reach` [m] of another block's bounding sphere (the
// flow had reached it: start from an earlier state).
void startFromFlow(CoupledWorld& world, mpm::ParticleSlices& particles, long step, double time, double dt,
                   const CoupledCheckpoint* source, double reach);

}  // namespace coupling
}  // namespace mpmsdem
