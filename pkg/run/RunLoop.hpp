// The step loop's parts shared by the output run (pkg/run/OutputRun.hpp) and the benchmark
// (pkg/run/BenchRun.hpp): what a step advances, the time step each step takes, when the run is
// over and how far along it is, and how it ended.
//
// The time step is run.dt when fixed (checked against the stable step before every step), or
// with "dt": "auto" run.dt_factor times the flow's CFL step, with blocks the smaller of that and
// the contact and approach steps (coupling::autoStepTerms, CoupledWorld::criticalTimeStep). An
// automatic step below run.min_step_fraction of the flow's CFL step stops the run with a
// RuntimeFailure naming what forced it.
#pragma once

#include <string>

#include "coupling/CoupledWorld.hpp"
#include "scene/MpmScene.hpp"
#include "mpm/MpmSolver.hpp"

namespace mpmsdem {
namespace run {

// How a run ended (the driver maps these to its exit statuses): it went to run.duration or
// --steps, or a stop rule ended it; a RuntimeFailure ended it, the last good state saved; a
// SIGINT or SIGTERM ended it, the state saved (pkg/run/StopSignal.hpp).
enum class RunEnd { Done, Failure, Stopped };

// What a step advances: the MPM solver alone, or the coupled world that owns it.
struct Stepper {
  // world: the coupled world that owns mpm, or null for the solver alone
  explicit Stepper(mpm::MpmSolver& mpm, coupling::CoupledWorld* world = nullptr) : solver(mpm), coupled(world) {}
  mpm::MpmSolver& solver;
  coupling::CoupledWorld* coupled;
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
    return coupled ? terms.describe() : solver.stableStepName();
  }
};

// A fixed run.dt may exceed the stable step by this factor (round-off), as in
// MpmSolver::checkTimeStep.
constexpr double kStepSlack = 1.0001;

// Time step for the next step [s]: fixed or auto, never past run.duration when running by time
// (byTime). Throws RuntimeFailure when a fixed run.dt exceeds the stable step, when the last
// automatic step was above twice the contact step it ended with, or when the automatic step
// falls below run.min_step_fraction of the CFL step.
double nextStep(Stepper& st, const mpm::RunSettings& run, bool byTime);

// maxSteps: the step count at which to stop (0: stop at run.duration).
bool finished(const mpm::MpmSolver& solver, const mpm::RunSettings& run, long maxSteps);

// The step count at which a run of `steps` more steps (--steps N counts this run's steps) stops,
// started from a state at step `start` (a restart point, another run's front). ParameterError
// naming `from` and both counts when the sum does not fit a long: a state from a file that no
// run of ours wrote.
long endStep(long start, long steps, const std::string& from);

// Fraction of the run done, by steps (maxSteps > 0, counted from firstStep) or by simulated time.
double progressFraction(const mpm::MpmSolver& solver, const mpm::RunSettings& run, long maxSteps, long firstStep = 0);

}  // namespace run
}  // namespace mpmsdem
