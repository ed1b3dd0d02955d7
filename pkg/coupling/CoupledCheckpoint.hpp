// Restart state of a coupled driver run (mpmsdem-run --restart) that an mpm.h5 snapshot does
// not hold: the blocks' poses and motion, the angular momentum their rotation update carries,
// the tangential histories of block–block and MP–block contacts, the cumulative dissipations,
// the steps the automatic time step is chosen from, and the orientations the "rotation" series
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
//   "coupling_dissipation": [friction, damping], "reference_orientations": [[w, x, y, z]]}.
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
  std::vector<Quat> referenceOrientations;
};

// The state of `world` now (after its last step), for the snapshot numbered `snapshot`.
CoupledCheckpoint captureCheckpoint(CoupledWorld& world, long snapshot, double lastDt,
                                    const std::vector<Quat>& referenceOrientations);

// Write atomically (a temporary file renamed over `path`): a run killed while writing leaves
// the previous checkpoint. RuntimeFailure naming the path when it cannot be written.
void writeCheckpoint(const std::string& path, const CoupledCheckpoint& c);

// ParameterError naming the path when it is missing, not such a checkpoint, or malformed.
CoupledCheckpoint readCheckpoint(const std::string& path);

// Put `world` (blocks added, particles of the snapshot loaded) into the checkpointed state.
// ParameterError when the checkpoint does not fit the scene (number of blocks or particles).
void restoreCheckpoint(const CoupledCheckpoint& c, CoupledWorld& world);

}  // namespace coupling
}  // namespace mpmsdem
