#include "run/RunLoop.hpp"

#include <algorithm>
#include <cstdio>
#include <limits>
#include <sstream>
#include <string>

#include "common/Error.hpp"

namespace mpmsdem {
namespace run {

double nextStep(Stepper& st, const mpm::RunSettings& run, bool byTime) {
  mpm::MpmSolver& solver = st.solver;
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
                        : solver.stableStepName().c_str());
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

bool finished(const mpm::MpmSolver& solver, const mpm::RunSettings& run, long maxSteps) {
  if (maxSteps > 0) return solver.steps() >= maxSteps;
  return solver.time() >= run.duration * (1 - 1e-12);
}

long endStep(long start, long steps, const std::string& from) {
  if (start < 0 || steps < 0 || start > std::numeric_limits<long>::max() - steps)
    throw ParameterError(from + " is at step " + std::to_string(start) + ": with --steps " + std::to_string(steps) +
                         " the run would end past step " + std::to_string(std::numeric_limits<long>::max()) +
                         " (a step count no run of this driver reaches)");
  return start + steps;
}

double progressFraction(const mpm::MpmSolver& solver, const mpm::RunSettings& run, long maxSteps, long firstStep) {
  return maxSteps > 0 ? double(solver.steps() - firstStep) / double(maxSteps - firstStep)
                      : solver.time() / run.duration;
}

}  // namespace run
}  // namespace mpmsdem
