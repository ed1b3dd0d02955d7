// CoupledWorld: one coupled MPM–SDEM scene stepped in C++ (tests, the mpmsdem-run driver),
// owning the order of a step (paper §2.3):
//   1. MP–block contacts at the state of time t (MpSdemCoupling): particle forces into the
//      MPM external-force buffer, the opposite forces and torques onto the blocks;
//   2. block–block contacts and the rigid-body update with those extra forces (SdemWorld,
//      the same leapfrog as YADE's NewtonIntegrator);
//   3. the MPM step, which spreads the particle forces to the grid (Eq 14).
// Steps 2 and 3 do not read each other's results: a solver on a device (MpmSolver::queuesSteps)
// runs step 3 while the host waits for step 1's block sums and does step 2.
// Inside YADE mpmsdem.CoupledEngine takes the same step (coupledStep), with NewtonIntegrator
// moving the blocks after it.
#pragma once
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "coupling/MpSdemCoupling.hpp"
#include "mpm/MpmSolver.hpp"
#include "sdem/SdemEngine.hpp"

namespace mpmsdem {
namespace coupling {

// Wall time of each stage of coupled steps [s], for benchmarks: the MP–block contacts, the
// blocks (block–block contacts and the rigid-body update, or the YADE bridge's hand-over of the
// forces), the MPM step. On the CPU each is its own work. On CUDA, coupling is the contacts' host
// part and the wait for their block sums, mpm the queuing of the MPM step and the wait for it
// after the blocks: the device's MPM time that the blocks hide is in neither.
struct CoupledStageSeconds {
  double coupling = 0, blocks = 0, mpm = 0;
};

// One coupled step around its blocks' part, in the order above, for CoupledWorld and the YADE
// bridge alike: the MP–block contacts at the blocks' states of time t, then `others` where given
// (the contacts of further bodies with the flow, LevelSet bodies: they add to the force buffer
// the MP–block contacts opened, solver.extendForceBuffer()), the flow's step queued behind them
// where the solver queues steps, the contacts' block sums (coupling.force/torque), blocks(),
// which takes them, then the flow's step or the wait for it. A failure in the contacts or in
// blocks() abandons a queued flow step, so that the flow stays at the step's start as it does
// on the CPU. Their wall time is added to `stages` (others' to the coupling's).
void coupledStep(mpm::MpmSolver& solver, MpSdemCoupling& coupling, double dt, const std::function<void()>& blocks,
                 CoupledStageSeconds& stages, const std::function<void()>& others = {});

class CoupledWorld {
 public:
  // The solver must already hold its particles; blocks are added to world.engine.
  explicit CoupledWorld(std::unique_ptr<mpm::MpmSolver> solver);

  sdem::SdemWorld world;
  MpSdemCoupling coupling{world.engine};
  mpm::MpmSolver& mpm() { return *solver_; }

  void step(double dt);
  double time() const { return world.time(); }

  // Largest stable step of the coupled scene [s]: the smallest of the MPM CFL step, the MP
  // side of MP–block contacts sqrt(m_p / k) and, per block, sqrt(m / (sum k_SDEM + sum k_MP))
  // and its rotational counterpart, times the SDEM time-step safety factor; the contact part
  // as the last step left it (inf before the first).
  double criticalTimeStep();
  // The contact part of criticalTimeStep() (coupledContactStep) at the start of the last step [s].
  double contactStep() const { return contactStep_; }

  // Wall time spent in each stage of step() since construction [s] (CoupledStageSeconds).
  const CoupledStageSeconds& stageSeconds() const { return stageSeconds_; }

  // The smallest contact step (coupledContactStep) after any step since construction [s], and
  // the time it was reached [s]: how close a run came to its contact limit, which a fixed step
  // must stay under (inf and NaN while nothing has touched).
  struct ContactStepLow {
    double step = std::numeric_limits<double>::infinity();
    double time = std::numeric_limits<double>::quiet_NaN();
  };
  const ContactStepLow& contactStepLow() const { return contactStepLow_; }
  // What a checkpointed run's steps left: the contact step of its last step (inf: no contact),
  // which the next automatic step is chosen from, and the lowest one so far.
  void restoreContactSteps(double contactStep, const ContactStepLow& low);

 private:
  std::unique_ptr<mpm::MpmSolver> solver_;
  std::vector<Vec3> blockForce_, blockTorque_;
  CoupledStageSeconds stageSeconds_;
  double contactStep_ = std::numeric_limits<double>::infinity();  // coupledContactStep after the last step
  ContactStepLow contactStepLow_;
};

// The flow's part of a coupled step: the MPM step, or for a solver without material points
// only its clock (time + dt, one more step). An empty grid stays empty whatever the step does
// to it, so a coupled scene without particles costs what its blocks cost.
void advanceFlow(mpm::MpmSolver& solver, double dt);

// The contact part of the coupled critical step (without the MPM CFL limit), shared with the
// YADE bridge: per block sqrt(m / (k_SDEM + k_MP)) and sqrt(I_min / (k_r,SDEM + k_r,MP)) over
// moving blocks, and the MP side, times the SDEM safety factor [s].
double coupledContactStep(const sdem::SdemEngine& sdem, const MpSdemCoupling& coupling);

// The next step of automatic time stepping in a coupled scene [s], for the driver's "dt": "auto"
// and CoupledEngine.dtAuto alike: sdem::autoTimeStep (factor times the coupled critical step,
// a tenth of the blocks' approach step, the growth cap), and at most the particles' approach
// step (MpSdemCoupling::particleApproachStep), which is not scaled by the factor: it is the
// contact step of contacts that are known only once the step has begun, and the step check
// allows twice it.
double coupledAutoStep(double factor, double critical, double blockApproach, double particleApproach, double lastDt);

// The inputs of coupledAutoStep as they are when a step is chosen (the contacts and speeds
// change within the step): step() is that step, describe() says which term set it.
struct AutoStepTerms {
  double factor = 1;             // dt factor, in (0, 1]
  double cfl = 0, contact = 0;   // the flow's CFL step (or a bound on it), the contacts' critical step [s]
  double approach = 0;           // SdemEngine::approachTimeStep [s] (inf: no block moves)
  int block = -1;                // the block that sets it (external id), its point speed bound [m/s]
  double blockSpeed = 0, blockSweep = 0;  // and its sweep radius [m]
  double particleApproach = 0;   // MpSdemCoupling::particleApproachStep [s]
  double lastDt = 0;             // the step before [s] (0: first step)
  double step() const;
  // In words, for progress lines and the step-floor refusal: the flow's CFL step, the contacts'
  // critical step, a block's approach (naming the block and its speed), a material point closing
  // on a barrier, or the growth cap.
  std::string describe() const;
};
AutoStepTerms autoStepTerms(const sdem::SdemEngine& sdem, double factor, double cfl, double contact,
                            double particleApproach, double lastDt);

}  // namespace coupling
}  // namespace mpmsdem
