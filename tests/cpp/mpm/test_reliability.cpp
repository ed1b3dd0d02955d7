// Runs that go wrong must stop with a clear failure, not finish with a non-physical state
// (issue 8): material points crushed to a vanishing volume by a loading the step cannot
// follow are a run failure naming J, like the other blow-ups.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "common/Error.hpp"
#include "mpm/MpmKernelsCommon.hpp"
#include "mpm/MpmSolver.hpp"
#include "mpm/Seeding.hpp"

#include "AgreementHelpers.hpp"

using namespace mpmsdem;
using namespace mpmsdem::mpm;

namespace {

// A 6 cm cube of material resting on a no-slip floor under gravity g [m/s^2] (downward).
std::unique_ptr<MpmSolver> cubeUnderGravity(double g, Precision precision) {
  MpmParams prm;
  prm.dx = 0.01;
  prm.cells = {12, 12, 14};
  prm.gravity = {0, 0, -g};
  prm.walls[4].friction = -1;
  ParticleSet ps;
  seedBox(prm, {0.03, 0.03, 0.02}, {0.09, 0.09, 0.08}, 8, ps);
  auto solver = makeSolver(prm, Backend::Cpu, precision);
  solver->setParticles(ps);
  return solver;
}

double minJ(MpmSolver& s) {
  ParticleSet ps;
  s.getParticles(ps);
  return *std::min_element(ps.J.begin(), ps.J.end());
}

// On the CPU backend in both precisions.
class MpmReliability : public ::testing::TestWithParam<Precision> {};
INSTANTIATE_TEST_SUITE_P(CpuBothPrecisions, MpmReliability, ::testing::Values(Precision::Double, Precision::Float),
                         agreement::paramName);

}  // namespace

TEST_P(MpmReliability, ParticlesCrushedByAHugeGravityStopTheRunNamingJ) {
  // 1e5 m/s^2 on a 6 cm column of E = 1 MPa: the base would be compressed by rho g h / E ~ 10,
  // far beyond anything the material can take; the auto step follows the wave speed, not
  // this loading, and the particles flatten (J -> 1e-13 before the bound existed).
  auto solver = cubeUnderGravity(1e5, GetParam());
  std::string message;
  long steps = 0;
  try {
    for (; steps < 20000; ++steps) solver->step(0.9 * solver->stableTimeStep());
  } catch (const RuntimeFailure& e) {
    message = e.what();
  }
  ASSERT_FALSE(message.empty()) << "ran " << steps << " steps to min J = " << minJ(*solver);
  EXPECT_NE(message.find("volume ratio J outside [0.001, 1000]"), std::string::npos) << message;
  // it stopped for J itself (not the speed): the J printed is below the bound
  const std::size_t at = message.rfind("J = ");
  ASSERT_NE(at, std::string::npos) << message;
  EXPECT_LT(std::stod(message.substr(at + 4)), kMinJ) << message;
  // the state kept is the one at the start of the failed step: still admissible
  EXPECT_GE(minJ(*solver), kMinJ);
}

TEST_P(MpmReliability, OrdinaryGravityKeepsJNearOne) {
  // The bound never stops a sound run: the same cube under 9.81 m/s^2 settles with J ~ 1.
  auto solver = cubeUnderGravity(9.81, GetParam());
  for (int i = 0; i < 300; ++i) solver->step(0.9 * solver->stableTimeStep());
  EXPECT_GT(minJ(*solver), 0.9);
}
