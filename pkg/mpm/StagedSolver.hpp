// The order of one MPM step, written once for every backend (the CPU loops, the CUDA kernels):
// a backend derives from StagedSolver and supplies the stages, and step() runs them in this order.
//   1. checks: no failed step left the particles partly advanced, the force buffer is whole, and
//      (on the first step and every 100th) the step is within the stable one;
//   2. P2G: the grid cleared where the last step wrote it, the particles binned or sorted, their
//      mass, momentum, stress divergence and external forces (Eq 14) spread to the nodes;
//   3. the grid: the nodes' new velocities; where grid hooks are set (a gate), the velocities
//      first, then the hooks in the order added, then the walls and the terrain; otherwise all in
//      one pass over the nodes;
//   4. G2P: the particles' velocities, positions and stresses from the nodes (Eq 4, Appendix B);
//   5. the step's end: a failing particle reported (the state left as holdsLastGoodState says),
//      else the new state taken;
//   6. the clock: time and step count.
// A backend that queues its steps on a device (queuesSteps()) queues stages 2-4 in runStages()
// and waits for them in stage 5: its launchStep and finishStep are the two halves of step().
#pragma once
#include "mpm/MpmSolver.hpp"

namespace mpmsdem {
namespace mpm {

class StagedSolver : public MpmSolver {
 public:
  void step(double dt) final {
    runStages(dt);
    endStages(dt);
  }

 protected:
  // Stages 1 to 4.
  void runStages(double dt) {
    beforeChecks();
    requireLastGoodState("step");
    requireCompleteForces("step");
    if (steps_ % 100 == 0) checkTimeStep(dt);
    stageP2G(dt);
    if (hooks_.empty()) {
      stageGrid(dt);
    } else {
      stageGridVelocity(dt);
      applyGridHooks(gridView(dt));
      stageGridBoundaries();
    }
    stageG2P(dt);
  }
  // Stages 5 and 6.
  void endStages(double dt) {
    stageEnd(dt);
    time_ += dt;
    ++steps_;
  }

  // Whatever refuses a step before the checks (a device with a step still in flight).
  virtual void beforeChecks() {}
  virtual void stageP2G(double dt) = 0;
  // The nodes' new velocities, walls and terrain in one pass (no grid hooks).
  virtual void stageGrid(double dt) = 0;
  // The nodes' new velocities only, for the hooks to read and change.
  virtual void stageGridVelocity(double dt) = 0;
  // The grid's arrays for the hooks (gridViewFrame with this backend's precision and arrays).
  virtual GridView gridView(double dt) = 0;
  // The walls and the terrain on the velocities the hooks left.
  virtual void stageGridBoundaries() = 0;
  virtual void stageG2P(double dt) = 0;
  // Throws RuntimeFailure naming a failing particle; otherwise the new state becomes the current one.
  virtual void stageEnd(double dt) = 0;
};

}  // namespace mpm
}  // namespace mpmsdem
