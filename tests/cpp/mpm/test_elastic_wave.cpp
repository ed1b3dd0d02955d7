// Dynamics of the elastic part of the MPM solver against an exact solution: a column in
// uniaxial strain (free-slip side walls, rigid base, free top) under gravity switched on at
// t = 0. Every mode of the fixed-free bar, sin((2n-1) pi z / 2H), has a period T/(2n-1) with
// T = 4H/c, c = sqrt(M/rho), M = lambda + 2G, so the top moves exactly T-periodically:
// u_top(t) = sum_n a_n (1 - cos((2n-1) 2 pi t / T)); at t = T/2 every mode is at its peak and
// u_top = 2 u_s with the static u_s = rho g H^2 / (2M); at t = T it is back at 0.
// Poisson ratio 0.45 keeps tau/p = (2G/sqrt(3)) / (lambda + 2G/3) = 0.12 below mu_s: the
// material stays elastic, and the compression keeps it dense (rho_c set below rho_0 so that
// round-off at the unloaded top never gasifies it).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "mpm/MpmSolver.hpp"
#include "mpm/Seeding.hpp"

#include "AgreementHelpers.hpp"

using namespace mpmsdem;
using namespace mpmsdem::mpm;

// On every backend in both precisions: the float run must resolve the 0.17 mm settlement of a
// 0.2 m column (float spacing there: 1.5e-8 m) as well as double does.
class MpmElasticWave : public agreement::EveryBackend {};
INSTANTIATE_TEST_SUITE_P(EveryBackend, MpmElasticWave, ::testing::ValuesIn(agreement::everyKind()),
                         agreement::kindName);

TEST_P(MpmElasticWave, ColumnUnderSuddenGravityOscillatesWithPeriod4HOverC) {
  const double dx = 0.01, H = 0.2, rho = 1600, E = 1e6, nu = 0.45, g = 9.81;
  MpmParams prm;
  prm.dx = dx;
  prm.origin = {-2 * dx, -2 * dx, -2 * dx};
  prm.cells = {6, 5, 30};  // material region x in [0, 2dx], y in [0, dx], z in [0, 26 dx]
  prm.gravity = {0, 0, -g};
  prm.flip = FlipBlend::alphaPerStep(1.0);  // pure FLIP: no PIC damping of the oscillation
  for (auto& w : prm.walls) w.friction = 0;  // free slip everywhere; the base stops the fall
  prm.material.density = rho;
  prm.material.youngModulus = E;
  prm.material.poissonRatio = nu;
  prm.material.criticalDensity = 0.95 * rho;
  ParticleSet ps;
  seedBox(prm, {0, 0, 0}, {2 * dx, dx, H}, 8, ps);
  auto s = solver(prm);
  s->setParticles(ps);

  const double lambda = E * nu / ((1 + nu) * (1 - 2 * nu)), G = E / (2 * (1 + nu));
  const double M = lambda + 2 * G, c = std::sqrt(M / rho), T = 4 * H / c;
  const double us = rho * g * H * H / (2 * M);  // static settlement of the top [m]
  ASSERT_LT((2 * G / std::sqrt(3.0)) / (lambda + 2 * G / 3), prm.material.muS);  // stays elastic

  std::vector<int> top;
  for (std::size_t p = 0; p < ps.size(); ++p)
    if (ps.x[3 * p + 2] > H - dx / 2) top.push_back(static_cast<int>(p));
  auto topDisplacement = [&](const ParticleSet& o) {
    double sum = 0;
    for (int p : top) sum += ps.x[3 * p + 2] - o.x[3 * p + 2];
    return sum / top.size();  // settlement, positive downwards
  };
  const double dt = 0.2 * s->stableTimeStep();
  std::vector<double> t, u;
  ParticleSet o;
  while (s->time() < 1.25 * T) {
    s->step(dt);
    s->getParticles(o);
    t.push_back(s->time());
    u.push_back(topDisplacement(o));
  }
  // first peak: time and height
  std::size_t k = 0;
  for (std::size_t i = 0; i < u.size() && t[i] < 0.75 * T; ++i)
    if (u[i] > u[k]) k = i;
  std::printf("%s: first peak at %.4f T/2, %.4f x 2 u_s\n", s->name().c_str(), t[k] / (0.5 * T), u[k] / (2 * us));
  EXPECT_NEAR(t[k] / (0.5 * T), 1.0, 0.03);  // T/2 = 2H/c = 8.2 ms
  EXPECT_NEAR(u[k] / (2 * us), 1.0, 0.05);   // 2 u_s = 0.17 mm
  // back up at t = T
  std::size_t j = 0;
  while (t[j] < T) ++j;
  EXPECT_LT(std::abs(u[j]), 0.15 * us);
}
