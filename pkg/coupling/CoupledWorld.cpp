#include "coupling/CoupledWorld.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

#include "common/Error.hpp"

namespace mpmsdem {
namespace coupling {

CoupledWorld::CoupledWorld(std::unique_ptr<mpm::MpmSolver> solver) : solver_(std::move(solver)) {
  if (!solver_) throw ParameterError("CoupledWorld: solver = null: must be an MPM solver");
}

namespace {
using Clock = std::chrono::steady_clock;
double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }
}  // namespace

void CoupledWorld::step(double dt) {
  coupledStep(*solver_, coupling, dt, [this, dt] {
    coupling.blockForces(blockForce_, blockTorque_);
    world.step(dt, &blockForce_, &blockTorque_);
  }, stageSeconds_);
  contactStep_ = coupledContactStep(world.engine, coupling);
  if (contactStep_ < contactStepLow_.step) contactStepLow_ = {contactStep_, solver_->time()};
}

void coupledStep(mpm::MpmSolver& solver, MpSdemCoupling& coupling, double dt, const std::function<void()>& blocks,
                 CoupledStageSeconds& stages, const std::function<void()>& others) {
  // work between the contacts' launch and their collection: a failure collects them first (the
  // contacts' step is over; its own failure, if any, comes first)
  const auto beforeCollect = [&coupling](const std::function<void()>& work) {
    try {
      work();
    } catch (...) {
      coupling.collectForces();
      throw;
    }
  };
  const auto t0 = Clock::now();
  coupling.launchForces(solver, dt);
  if (others) beforeCollect(others);
  const auto t1 = Clock::now();
  // A solver on a device runs its step while the host waits for the block sums and moves the
  // blocks: the step reads the particle forces the contacts leave on the device (queued after
  // them) and nothing the blocks' update changes.
  const bool queued = solver.queuesSteps() && solver.numParticles() > 0;
  if (queued) beforeCollect([&] { solver.launchStep(dt); });
  const auto t2 = Clock::now();
  auto t3 = t2, t4 = t2;
  try {
    coupling.collectForces();
    t3 = Clock::now();
    blocks();
    t4 = Clock::now();
  } catch (...) {
    if (queued) solver.abandonStep();
    throw;
  }
  if (queued)
    solver.finishStep();
  else
    advanceFlow(solver, dt);
  const auto t5 = Clock::now();
  stages.coupling += seconds(t0, t1) + seconds(t2, t3);
  stages.blocks += seconds(t3, t4);
  stages.mpm += seconds(t1, t2) + seconds(t4, t5);
}

void advanceFlow(mpm::MpmSolver& solver, double dt) {
  if (solver.numParticles() > 0)
    solver.step(dt);
  else
    solver.setClock(solver.time() + dt, solver.steps() + 1);
}

double coupledContactStep(const sdem::SdemEngine& sdem, const MpSdemCoupling& coupling) {
  double dt = coupling.particleCriticalStep();
  const int n = std::min(sdem.numBodies(), coupling.numBlocks());
  for (int i = 0; i < n; ++i) {
    if (sdem.isFixed(i)) continue;
    const double k = sdem.stiffnessSum(i) + coupling.stiffnessSum(i);
    const double kr = sdem.rotationalStiffnessSum(i) + coupling.rotationalStiffnessSum(i);
    if (k > 0) dt = std::min(dt, std::sqrt(sdem.mass(i) / k));
    if (kr > 0) dt = std::min(dt, std::sqrt(sdem.principalInertia(i).minCoeff() / kr));
  }
  return sdem.timeStepSafety() * dt;
}

double coupledAutoStep(double factor, double critical, double blockApproach, double particleApproach, double lastDt) {
  return std::min(sdem::autoTimeStep(factor, critical, blockApproach, lastDt), particleApproach);
}

AutoStepTerms autoStepTerms(const sdem::SdemEngine& e, double factor, double cfl, double contact,
                            double particleApproach, double lastDt) {
  AutoStepTerms t;
  t.factor = factor;
  t.cfl = cfl;
  t.contact = contact;
  int body;
  t.approach = e.approachTimeStep(&body);
  if (body >= 0) {
    t.block = e.externalId(body);
    t.blockSpeed = e.pointSpeedBound(body);
    t.blockSweep = e.shape(body).sweepRadius;
  }
  t.particleApproach = particleApproach;
  t.lastDt = lastDt;
  return t;
}

double AutoStepTerms::step() const {
  return coupledAutoStep(factor, std::min(cfl, contact), approach, particleApproach, lastDt);
}

std::string AutoStepTerms::describe() const {
  const double dt = step();
  const auto near = [dt](double term) { return std::abs(term - dt) <= 1e-9 * dt; };
  std::ostringstream s;
  s.precision(4);
  if (near(factor * contact)) {
    s << "the contacts' critical step sqrt(m/k)";
  } else if (near(factor * cfl)) {
    s << "the flow's CFL step";
  } else if (block >= 0 && near(sdem::kApproachFraction * approach)) {
    s << "block " << block << "'s approach: it moves at " << blockSpeed << " m/s and may cross its sweep radius "
      << blockSweep << " m in no fewer than " << 1 / sdem::kApproachFraction << " steps";
  } else if (near(particleApproach)) {
    s << "a material point closing on a block's barrier (the contact step it will have on arrival)";
  } else if (lastDt > 0 && near(sdem::kAutoStepGrowth * lastDt)) {
    s << "the growth cap (1 % a step)";
  }
  return s.str();
}

void CoupledWorld::restoreContactSteps(double contactStep, const ContactStepLow& low) {
  if (!(contactStep > 0)) throwParameter("contact step", contactStep, "s", "> 0 (inf: no contact)");
  if (!(low.step > 0)) throwParameter("lowest contact step", low.step, "s", "> 0 (inf: no contact)");
  contactStep_ = contactStep;
  contactStepLow_ = low;
}

double CoupledWorld::criticalTimeStep() { return std::min(solver_->stableTimeStep(), contactStep_); }

}  // namespace coupling
}  // namespace mpmsdem
