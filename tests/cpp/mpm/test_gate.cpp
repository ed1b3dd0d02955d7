// Grid-node hooks (MpmSolver::addGridHook) and their first user, the release gate
// (mpm/Gate.hpp): where the hook runs in the step, a column held at rest (momentum balance
// with the gate's impulse, lateral earth thrust), instant release equal to a restart without
// the gate, a finite lift that releases from the bottom and later, CPU vs CUDA, bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numeric>
#include <stdexcept>

#include "common/Error.hpp"
#include "mpm/Gate.hpp"
#include "mpm/MpmKernelsCommon.hpp"
#include "scene/MpmScene.hpp"
#include "mpm/MpmSolver.hpp"
#include "mpm/Seeding.hpp"

#include "AgreementHelpers.hpp"
#include "GranularColumn.hpp"

using namespace mpmsdem;
using namespace mpmsdem::mpm;

namespace {

constexpr double kG = 9.81;

// Glass beads of the flume experiments (Table 1), all walls free slip.
MpmParams glassParams(double dx, std::array<int, 3> cells) {
  MpmParams p = testing_scenes::tableOneBeads(cells, dx);
  p.material.I0 = 0.279;
  p.material.grainDiameter = 0.002;
  p.material.solidDensity = 2500;
  for (auto& w : p.walls) w.friction = 0;
  return p;
}

double totalMass(const ParticleSet& ps) { return std::accumulate(ps.mass.begin(), ps.mass.end(), 0.0); }

double momentumX(const ParticleSet& ps) {
  double m = 0;
  for (std::size_t p = 0; p < ps.size(); ++p) m += ps.mass[p] * ps.v[3 * p];
  return m;
}

double maxSpeed(const ParticleSet& ps) {
  double v = 0;
  for (std::size_t p = 0; p < ps.size(); ++p)
    v = std::max(v, std::sqrt(ps.v[3 * p] * ps.v[3 * p] + ps.v[3 * p + 1] * ps.v[3 * p + 1] +
                              ps.v[3 * p + 2] * ps.v[3 * p + 2]));
  return v;
}

double front(const ParticleSet& ps) {
  double f = -1e30;
  for (std::size_t p = 0; p < ps.size(); ++p) f = std::max(f, ps.x[3 * p]);
  return f;
}

Gate& gateOf(MpmSolver& s) {
  Gate* g = s.findGridHook<Gate>();
  if (!g) throw std::runtime_error("no gate installed");
  return *g;
}

// Records what it was shown, then pushes every non-empty node toward +x at 1 m/s.
struct PushingHook : GridHook {
  int calls = 0;
  GridView seen;
  double massSum = 0;
  void apply(const GridView& g) override {
    ++calls;
    seen = g;
    const double* m = static_cast<const double*>(g.mass);
    double* vx = static_cast<double*>(g.v[0]);
    massSum = 0;
    for (long n = 0; n < long(g.nodes[0]) * g.nodes[1] * g.nodes[2]; ++n) {
      const long r = g.record(n);  // the CPU stores the node columns the particles reached
      if (r < 0) continue;
      const long e = r * g.stride;
      massSum += m[e];
      if (m[e] > 0) vx[e] = 1.0;
    }
  }
};

}  // namespace

TEST(GridHook, SeesTheGridInHostMemoryAndRunsBeforeTheWalls) {
  MpmParams prm = glassParams(0.01, {12, 8, 8});
  prm.gravity = {0, 0, 0};
  prm.flip = FlipBlend::alphaPerStep(0);  // PIC: a particle's velocity is exactly the weighted node velocity
  ParticleSet ps;
  seedBox(prm, {0.05, 0.03, 0.03}, {0.10, 0.05, 0.05}, 8, ps);  // touches the +x wall's layer
  auto s = makeSolver(prm);
  s->setParticles(ps);
  auto hook = std::make_shared<PushingHook>();
  s->addGridHook(hook);
  const double dt = 0.5 * s->stableTimeStep();
  s->step(dt);
  ASSERT_EQ(hook->calls, 1);
  const GridView& g = hook->seen;
  EXPECT_EQ(g.precision, Precision::Double);
  EXPECT_FALSE(g.device);
  EXPECT_EQ(g.nodes[0], 13);
  EXPECT_EQ(g.nodes[1], 9);
  EXPECT_EQ(g.nodes[2], 9);
  EXPECT_EQ(g.dx, 0.01);
  EXPECT_EQ(g.origin[0], 0.0);
  EXPECT_EQ(g.time, 0.0);
  EXPECT_EQ(g.dt, dt);
  EXPECT_NEAR(hook->massSum, totalMass(ps), 1e-12 * totalMass(ps));
  ParticleSet out;
  s->getParticles(out);
  // The +x wall acts on nodes 10..12 (x >= 0.10) after the hook and removes their +x velocity,
  // so a particle moves at 1 m/s less its B-spline weight on those nodes.
  int free = 0, walled = 0;
  for (std::size_t p = 0; p < out.size(); ++p) {
    const double xi = ps.x[3 * p] / prm.dx;
    double wWall = 0;
    for (int i = 10; i <= 12; ++i) {
      const double r = std::abs(xi - i);
      wWall += r < 0.5 ? 0.75 - r * r : (r < 1.5 ? 0.5 * (1.5 - r) * (1.5 - r) : 0.0);
    }
    EXPECT_NEAR(out.v[3 * p], 1.0 - wWall, 1e-12);
    EXPECT_NEAR(out.v[3 * p + 1], 0.0, 1e-12);
    (wWall > 0 ? walled : free) += 1;
  }
  EXPECT_GT(free, 0);
  EXPECT_GT(walled, 0);
  s->step(dt);
  EXPECT_EQ(hook->calls, 2);
  EXPECT_EQ(hook->seen.time, dt);
  EXPECT_THROW(s->addGridHook(nullptr), ParameterError);
}

// The gate on every backend in both precisions (the float host grid of cpu-float, the device
// grid of CUDA).
class GateInPrecision : public agreement::EveryBackend {};
INSTANTIATE_TEST_SUITE_P(EveryBackend, GateInPrecision, ::testing::ValuesIn(agreement::everyKind()),
                         agreement::kindName);

TEST_P(GateInPrecision, HoldsAColumnOnAnInclineAndTheMomentumBalances) {
  // Column on a 10 deg incline, free-slip bed and sides, away from the back wall: only the
  // gate holds it downslope. Material x momentum: dP = M g sin(a) t + J_gate, exactly (P2G,
  // the grid update and G2P conserve momentum); at rest the gate carries M g sin(a).
  const double a = 10 * M_PI / 180, xg = 0.11;
  MpmParams prm = glassParams(0.01, {17, 6, 12});
  prm.gravity = {kG * std::sin(a), 0, -kG * std::cos(a)};
  prm.flip = FlipBlend::alphaPerStep(0);  // PIC damps the elastic settling
  prm.gate.enabled = true;
  prm.gate.x = xg;
  prm.gate.bottom = 0;
  prm.gate.openAt = 100;  // stays closed
  ParticleSet ps;
  seedBox(prm, {0.05, 0.02, 0.02}, {xg, 0.04, 0.08}, 8, ps);
  auto s = solver(prm);
  s->setParticles(ps);
  ParticleSet in;  // the state as the solver holds it (float: rounded once)
  s->getParticles(in);
  const double M = totalMass(in), p0 = momentumX(in);
  const double dt = 0.5 * s->stableTimeStep();
  const int steps = static_cast<int>(0.3 / dt), window = static_cast<int>(0.1 / dt);
  std::array<double, 3> jWindow{};
  for (int i = 0; i < steps; ++i) {
    if (i == steps - window) jWindow = gateOf(*s).impulse();
    s->step(dt);
  }
  ParticleSet out;
  s->getParticles(out);
  const std::array<double, 3> J = gateOf(*s).impulse();
  const double t = s->time(), weight = M * kG * std::sin(a);
  // Round-off of the balance: each step rounds every node's momentum sum p + dt f, whose
  // internal-force terms add up to at most M g H/dx (H = 6 dx): |error| <= eps (H/dx) M g t at
  // worst, 4e-6 of M g sin(a) t in float (measured 4e-8). In double that is below the
  // round-off of this check's own sums: 1e-10 there, as always.
  const double tol = std::max(1e-10, agreement::roundOff(precision()) * 6 / std::sin(a));
  EXPECT_NEAR(momentumX(out) - p0, weight * t + J[0], tol * weight * t);
  EXPECT_EQ(J[1], 0.0);  // smooth gate: no tangential impulse
  EXPECT_EQ(J[2], 0.0);
  const double force = -(J[0] - jWindow[0]) / (window * dt);
  std::printf("closed gate on a %.0f deg incline, %s: force %.4f N, downslope weight %.4f N, momentum balance error %.2e N s = %.2e M g sin(a) t\n",
              10.0, s->name().c_str(), force, weight, momentumX(out) - p0 - weight * t - J[0],
              (momentumX(out) - p0 - weight * t - J[0]) / (weight * t));
  EXPECT_NEAR(force / weight, 1.0, 0.03) << "gate force " << force << " N, downslope weight " << weight << " N";
  EXPECT_LT(maxSpeed(out), 0.02);  // at rest: far below sqrt(g H) = 0.8 m/s
  EXPECT_LT(front(out), xg + 0.01 * prm.dx);
  EXPECT_GT(front(out), xg - 0.5 * prm.dx);  // pressed against it, not drifted back
}

TEST(Gate, CarriesTheLateralEarthThrustOfAColumnAtRest) {
  // Column between the back wall and a closed gate, frictionless bed and sides: every
  // vertical section carries the same horizontal force, so the gate's force equals the
  // section force -sum(sigma_xx V) / L of the column's own stresses, and the thrust
  // coefficient K = F / (rho g H^2 W / 2) lies between Rankine's active and passive values
  // for mu_s (any static stress state of a Mohr-Coulomb material does).
  const double dx = 0.01, L = 0.1, W = 0.04, H = 0.06, xg = 0.02 + L;
  MpmParams prm = glassParams(dx, {16, 8, 10});
  prm.flip = FlipBlend::alphaPerStep(0);
  prm.gate.enabled = true;
  prm.gate.x = xg;
  prm.gate.openAt = 100;
  ParticleSet ps;
  seedBox(prm, {0.02, 0.02, 0.02}, {xg, 0.02 + W, 0.02 + H}, 8, ps);
  auto s = makeSolver(prm);
  s->setParticles(ps);
  const double dt = 0.9 * s->stableTimeStep();
  const int steps = static_cast<int>(0.45 / dt), window = static_cast<int>(0.1 / dt);
  std::array<double, 3> jWindow{};
  double section = 0;
  int samples = 0;
  ParticleSet out;
  for (int i = 0; i < steps; ++i) {
    if (i == steps - window) jWindow = gateOf(*s).impulse();
    s->step(dt);
    if (i >= steps - window && (steps - i) % 50 == 0) {
      s->getParticles(out);
      double sum = 0;
      for (std::size_t p = 0; p < out.size(); ++p) sum += out.stress[6 * p] * out.J[p] * out.volume0[p];
      section += -sum / L;
      ++samples;
    }
  }
  const double F = -(gateOf(*s).impulse()[0] - jWindow[0]) / (window * dt);
  section /= samples;
  EXPECT_NEAR(F / section, 1.0, 0.03) << "gate " << F << " N, section force " << section << " N";
  const double sinphi = std::sin(std::atan(prm.material.muS));
  const double Ka = (1 - sinphi) / (1 + sinphi), Kp = (1 + sinphi) / (1 - sinphi);
  const double K = F / (0.5 * prm.material.density * kG * H * H * W);
  std::printf("closed gate: F = %.4f N, section force %.4f N, K = %.3f (Rankine [%.3f, %.3f])\n", F, section, K, Ka,
              Kp);
  EXPECT_GE(K, Ka);
  EXPECT_LE(K, Kp);
  s->getParticles(out);
  EXPECT_LT(maxSpeed(out), 0.01);
  EXPECT_LT(front(out), xg + 0.01 * dx);
}

TEST(Gate, InstantOpeningEqualsARestartFromTheHeldStateWithoutGate) {
  // Quasi-2D column on a rough bed behind a rough gate; t_open between steps N and N + 1.
  const int N = 1500, M = 1500;  // 0.075 s each: the free column spreads past x_g in N
  MpmParams prm = glassParams(0.01, {30, 5, 16});
  prm.walls[4].friction = 0.4;
  const double xg = 0.08;
  ParticleSet ps;
  seedBox(prm, {0.02, 0.02, 0.02}, {xg, 0.03, 0.12}, {2, 1, 2}, ps);
  double dt;
  {
    auto probe = makeSolver(prm);
    probe->setParticles(ps);
    dt = 0.5 * probe->stableTimeStep();
  }
  MpmParams gated = prm;
  gated.gate.enabled = true;
  gated.gate.x = xg;
  gated.gate.openAt = (N + 0.5) * dt;
  gated.gate.friction = 0.3;

  auto a = makeSolver(gated);  // through the opening
  a->setParticles(ps);
  for (int i = 0; i < N; ++i) a->step(dt);
  ParticleSet held;
  a->getParticles(held);
  const std::array<double, 3> J = gateOf(*a).impulse();
  for (int i = 0; i < M; ++i) a->step(dt);
  EXPECT_EQ(gateOf(*a).impulse(), J);  // gone: no impulse after t_open
  ParticleSet ra;
  a->getParticles(ra);

  auto b = makeSolver(prm);  // restarted from the held state, no gate
  b->setParticles(held);
  b->setClock(N * dt, N);
  for (int i = 0; i < M; ++i) b->step(dt);
  ParticleSet rb;
  b->getParticles(rb);
  agreement::expectBitIdentical(ra, rb);

  // The gate did hold: without it the column spreads past x_g in the same N steps.
  auto free = makeSolver(prm);
  free->setParticles(ps);
  for (int i = 0; i < N; ++i) free->step(dt);
  ParticleSet f;
  free->getParticles(f);
  EXPECT_LT(front(held), xg + 0.01 * prm.dx);
  EXPECT_GT(front(f), xg + prm.dx);
  EXPECT_GT(front(ra), xg + prm.dx);  // and released after t_open
  // Rough gate: the settling column slides down along it, so the gate pushes up, by at most
  // mu times its normal impulse (Coulomb at every node, all normal impulses toward -x).
  EXPECT_LT(J[0], 0.0);
  EXPECT_GT(J[2], 0.0);
  EXPECT_LE(J[2], 0.3 * -J[0] * (1 + 1e-12));
}

TEST(Gate, FiniteLiftReleasesFromTheBottomAndLaterThanAnInstantOpening) {
  // Quasi-2D column (H = 0.12 m, L = 0.06 m) on a rough bed behind a gate whose edge starts on
  // the bed at t_open = 0.02 s, instant or lifted at v = 0.5 m/s (the edge passes the top at
  // t_open + H / v = 0.26 s).
  const double dx = 0.01, H = 0.12, xg = 0.08, bed = 0.02, t0 = 0.02, v = 0.5, T = 0.25;
  MpmParams prm = glassParams(dx, {40, 5, 18});
  prm.walls[4].friction = 0.4;
  prm.gate.enabled = true;
  prm.gate.x = xg;
  prm.gate.bottom = bed;
  prm.gate.openAt = t0;
  ParticleSet ps;
  seedBox(prm, {0.02, 0.02, bed}, {xg, 0.03, bed + H}, {2, 1, 2}, ps);
  double dt;
  {
    auto probe = makeSolver(prm);
    probe->setParticles(ps);
    dt = 0.5 * probe->stableTimeStep();
  }
  // Time at which the front first passes x_g + 2 dx; for the lifted gate also checks at every
  // sample that no point at or above the edge is past the gate's plane.
  auto run = [&](double speed, int& checked, int& passed) {
    MpmParams q = prm;
    q.gate.speed = speed;
    auto s = makeSolver(q);
    s->setParticles(ps);
    const Gate& gate = gateOf(*s);
    double leave = -1;
    ParticleSet out;
    while (s->time() < T) {
      for (int i = 0; i < 10; ++i) s->step(dt);
      s->getParticles(out);
      if (leave < 0 && front(out) > xg + 2 * dx) leave = s->time();
      if (speed == 0) continue;
      const double zg = gate.edgeHeight(s->time());
      for (std::size_t p = 0; p < out.size(); ++p) {
        // a point moves by v dt ~ 0.01 dx in z within the step: the margin covers it
        if (out.x[3 * p + 2] < zg + 0.1 * dx) continue;
        ++checked;
        EXPECT_LE(out.x[3 * p], xg + 0.01 * dx) << "point " << p << " above the edge z_g = " << zg << " m at t = "
                                                << s->time() << " s is past the gate";
      }
    }
    passed = 0;
    for (std::size_t p = 0; p < out.size(); ++p) passed += out.x[3 * p] > xg;
    return leave;
  };
  int checkedI = 0, passedI = 0, checkedF = 0, passedF = 0;
  const double leaveInstant = run(0, checkedI, passedI);
  const double leaveLifted = run(v, checkedF, passedF);
  std::printf("front past x_g + 2 dx: instant gate %.4f s, lifted at %.2f m/s %.4f s; points out at %.2f s: %d, %d of %zu\n",
              leaveInstant, v, leaveLifted, T, passedI, passedF, ps.size());
  ASSERT_GT(leaveInstant, t0);
  // Later, by more than the time the edge takes to rise one cell (until then the bottom
  // points keep most of their B-spline weight on held nodes) and by less than the time it
  // takes to clear the whole column (after that both gates are gone).
  EXPECT_GT(leaveLifted - leaveInstant, dx / v);
  EXPECT_LT(leaveLifted - leaveInstant, H / v);
  EXPECT_GT(checkedF, 1000);  // the check above was not empty
  EXPECT_GT(passedF, 0);      // material flowed out under the rising edge
  EXPECT_LT(passedF, passedI);
}

TEST(Gate, CpuAndCudaAgree) {
  if (!cudaAvailable()) GTEST_SKIP() << "no CUDA device in this build/machine: CPU-vs-CUDA gate check skipped";
  // A rough gate lifted at 1 m/s from t = 0.005 s, half-way through the 200 steps.
  MpmParams prm = glassParams(0.01, {20, 5, 22});
  prm.walls[4].friction = 0.4;
  prm.material.criticalDensity = 0.5 * prm.material.density;  // keep away from the (discontinuous) gasification switch
  prm.gate.enabled = true;
  prm.gate.x = 0.10;
  prm.gate.bottom = 0.02;
  prm.gate.speed = 1.0;
  prm.gate.friction = 0.3;
  ParticleSet ps;
  seedBox(prm, {0.02, 0.02, 0.02}, {0.10, 0.03, 0.18}, {2, 1, 2}, ps);
  double dt;
  {
    auto probe = makeSolver(prm);
    probe->setParticles(ps);
    dt = 0.8 * probe->stableTimeStep();  // as in MpmSolver.CpuAndCudaAgree: the bound falls with speed
  }
  prm.gate.openAt = 100 * dt;
  for (auto prec : {Precision::Double, Precision::Float}) {
    auto cpu = makeSolver(prm, Backend::Cpu, Precision::Double);
    auto gpu = makeSolver(prm, Backend::Cuda, prec);
    ParticleSet a, b;
    agreement::runPair(*cpu, *gpu, ps, dt, 200, a, b);
    // Tolerances as in MpmSolver.CpuAndCudaAgree: double 1e-9 (summation order only), float
    // 1e-4 (single-precision round-off over 200 steps), relative to each field's scale.
    const double tol = prec == Precision::Double ? 1e-9 : 1e-4;
    agreement::expectAgree(a, b, tol, 0.2, 100.0, gpu->name());
    const std::array<double, 3> ja = gateOf(*cpu).impulse(), jb = gateOf(*gpu).impulse();
    EXPECT_LT(ja[0], 0.0);
    for (int d = 0; d < 3; ++d) EXPECT_NEAR(jb[d], ja[d], tol * std::abs(ja[0])) << gpu->name() << " impulse " << d;
  }
}

TEST(Gate, RejectsBadParametersNamingThem) {
  auto expectError = [](const MpmParams& p, const std::string& name, const std::string& range) {
    try {
      makeSolver(p);
      ADD_FAILURE() << name << " accepted";
    } catch (const ParameterError& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.rfind(name, 0), 0u) << msg;
      EXPECT_NE(msg.find(range), std::string::npos) << msg;
    }
  };
  MpmParams ok;  // 10 cells of 0.01 m: the material region is [0.02, 0.08] on every axis
  ok.gate.enabled = true;
  ok.gate.x = 0.05;
  EXPECT_NO_THROW(makeSolver(ok));
  MpmParams p = ok;
  p.gate.x = 0.01; expectError(p, "gate.x", "in [0.02, 0.08]");
  p.gate.x = 0.09; expectError(p, "gate.x", "in [0.02, 0.08]");
  p.gate.x = NAN; expectError(p, "gate.x", "in [0.02, 0.08]");
  p = ok; p.gate.bottom = INFINITY; expectError(p, "gate.bottom", "finite");
  p = ok; p.gate.speed = -1; expectError(p, "gate.speed", "in [0, inf)");
  p = ok; p.gate.speed = NAN; expectError(p, "gate.speed", "in [0, inf)");
  p = ok; p.gate.openAt = -0.1; expectError(p, "gate.open_at", "in [0, inf)");
  p = ok; p.gate.openAt = INFINITY; expectError(p, "gate.open_at", "in [0, inf)");
  p = ok; p.gate.friction = -0.1; expectError(p, "gate.friction", "in [0, inf)");
  // a disabled gate is not checked (and not installed)
  p = ok; p.gate.enabled = false; p.gate.x = -5;
  EXPECT_EQ(makeSolver(p)->findGridHook<Gate>(), nullptr);
  // infinite speed is instant removal, like 0
  p = ok; p.gate.speed = INFINITY; p.gate.openAt = 0.5;
  Gate g(p.gate);
  EXPECT_EQ(g.edgeHeight(0.5), 0.0);
  EXPECT_TRUE(std::isinf(g.edgeHeight(0.5 + 1e-12)));
}

TEST(Gate, SceneKeysAndErrors) {
  nlohmann::json j = nlohmann::json::parse(R"({
    "grid": {"dx": 0.01, "cells": [40, 10, 20]},
    "material": {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24, "mu_2": 0.65},
    "particles": [{"lo": [0.02, 0.02, 0.02], "hi": [0.2, 0.08, 0.1]}],
    "gate": {"x": 0.2, "bottom": 0.02, "speed": 0.5, "open_at": 0.1, "friction": 0.3},
    "run": {"duration": 0.5}
  })");
  const MpmScene s = parseScene(j.dump());
  const GateSpec& g = s.params.gate;
  EXPECT_TRUE(g.enabled);
  EXPECT_EQ(g.x, 0.2);
  EXPECT_EQ(g.bottom, 0.02);
  EXPECT_EQ(g.speed, 0.5);
  EXPECT_EQ(g.openAt, 0.1);
  EXPECT_EQ(g.friction, 0.3);
  auto s2 = makeSolver(s.params);
  s2->setParticles(seedParticles(s));
  ASSERT_NE(s2->findGridHook<Gate>(), nullptr);
  EXPECT_NEAR(s2->findGridHook<Gate>()->edgeHeight(0.3), 0.02 + 0.5 * 0.2, 1e-15);
  EXPECT_FALSE(parseScene(R"({"grid": {"dx": 0.01, "cells": [40, 10, 20]},
    "material": {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24, "mu_2": 0.65},
    "particles": [{"lo": [0.02, 0.02, 0.02], "hi": [0.2, 0.08, 0.1]}], "run": {"duration": 0.5}})")
                   .params.gate.enabled);

  auto expectError = [](const nlohmann::json& scene, const std::string& needle) {
    try {
      parseScene(scene.dump());
      ADD_FAILURE() << "accepted: " << scene.dump();
    } catch (const ParameterError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  auto bad = [&](const char* key, nlohmann::json value) {
    nlohmann::json b = j;
    b["gate"][key] = value;
    return b;
  };
  expectError(bad("x", 0.39), "gate.x = 0.39 m: must be in [0.02, 0.38]");
  expectError(bad("speed", -0.5), "gate.speed");
  expectError(bad("open_at", -1), "gate.open_at");
  expectError(bad("friction", -0.2), "gate.friction");
  expectError(bad("speed", "fast"), "gate.speed");
  expectError(bad("height", 0.1), "unknown key 'gate.height'");
  nlohmann::json noX = j;
  noX["gate"].erase("x");
  expectError(noX, "missing required key 'gate.x'");
  nlohmann::json notObject = j;
  notObject["gate"] = 0.2;
  expectError(notObject, "gate");
}
