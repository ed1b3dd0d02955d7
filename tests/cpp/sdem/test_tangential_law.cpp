// Coulomb tangential law (Eqs 9, 11) with the elastic tangential force as history: a change of
// the overlap alone, with no tangential motion, must not change the force or do work, and the
// stick-slip response under a constant normal load must follow the Coulomb cap exactly.
#include <gtest/gtest.h>

#include <cmath>

#include "sdem/Law2_SdemGeom_BarrierPhys_Coulomb.hpp"

#include "LawGeometry.hpp"

using namespace mpmsdem;
using namespace mpmsdem::sdem;
using Law = Law2_SdemGeom_BarrierPhys_Coulomb;

namespace {
const Real kc = 1e4, R = 0.01, nu = 0.25;

SdemGeom geomAlongZ(Real delta) { return testing_geometry::geomAlongZ(R, delta); }

Real tangentialStiffness(Real delta) { return Law::normalStiffness(kc, R, delta) / (2 * (1 + nu)); }

// Work done by the relative motion against a rigid-plastic-capped linear spring along x over
// a displacement dx at constant stiffness kt, starting from force fOld (|fOld| <= cap): the
// exact integral of -F dx for an elastic stage up to the cap followed by slip at the cap. It
// is the reference the law's spring energy and slip work must add up to.
Real exactWork(Real fOld, Real kt, Real cap, Real dx) {
  if (dx == 0) return 0;
  const Real fCap = dx > 0 ? -cap : cap;
  const Real sStick = (fOld - fCap) / kt;  // displacement at which the cap is reached
  if (std::abs(sStick) >= std::abs(dx)) {
    const Real fNew = fOld - kt * dx;
    return -0.5 * (fOld + fNew) * dx;
  }
  return -0.5 * (fOld + fCap) * sStick - fCap * (dx - sStick);
}

BarrierPhys undampedPhys(Real mu) {
  BarrierPhys p;
  p.barrierStiffness = kc;
  p.friction = mu;
  p.poisson = nu;
  p.normalDamping = 0;
  p.tangentialDamping = 0;
  return p;
}

// Energy books of a run of steps.
struct Books {
  Real work = 0, friction = 0, damping = 0, spring = 0;
  Real balance() const { return spring + friction + damping - work; }
};

// One step moving tangentially (x) by v dt and normally from delta to deltaNext; the work of
// the motion is booked against the force the spring had at the start of the step.
LawResult step(const BarrierPhys& p, Real delta, Real deltaNext, Real v, Real dt, ContactHistory& h, Books& b) {
  const Real fOld = h.xi.x();
  const Vec3 relVel(v, 0, -(deltaNext - delta) / dt);  // overlap grows while B approaches A
  const LawResult r = Law::go(geomAlongZ(deltaNext), R, p, relVel, 1.0, dt, h, 0, 1);
  b.work += exactWork(fOld, r.tangentialStiffness, p.friction * r.normalForce, v * dt);
  b.friction += r.frictionDissipation;
  b.damping += r.dampingDissipation;
  b.spring = r.springEnergy;
  return r;
}
}  // namespace

// Load the spring at delta0, hold the tangential displacement while the overlap is pushed to
// 3 delta0 and back, then unload. A displacement history would scale the force with
// k_n(delta) (more than 3x here) with no tangential motion; the force history must keep it.
TEST(TangentialLaw, OverlapCycleAtHeldDisplacementKeepsForceAndDoesNoWork) {
  const BarrierPhys p = undampedPhys(0.5);
  const Real delta0 = 0.002, delta1 = 0.006, dt = 1e-3, v = 0.02;
  const int nLoad = 10, nCycle = 40;
  ContactHistory h;
  Books b;
  for (int i = 0; i < nLoad; ++i) {
    const LawResult r = step(p, delta0, delta0, v, dt, h, b);
    ASSERT_FALSE(r.sliding);
  }
  const Real kt0 = tangentialStiffness(delta0);
  const Real f0 = h.xi.x(), x0 = nLoad * v * dt;
  EXPECT_NEAR(f0, -kt0 * x0, 1e-12 * kt0 * x0);
  const Real spring0 = b.spring;
  EXPECT_NEAR(spring0, 0.5 * kt0 * x0 * x0, 1e-12 * spring0);
  EXPECT_NEAR(b.balance(), 0, 1e-12 * spring0);

  // Overlap up then down, no tangential motion.
  Real delta = delta0;
  for (int i = 1; i <= 2 * nCycle; ++i) {
    const Real next = i <= nCycle ? delta0 + (delta1 - delta0) * i / nCycle
                                  : delta1 - (delta1 - delta0) * (i - nCycle) / nCycle;
    const LawResult r = step(p, delta, next, 0.0, dt, h, b);
    delta = next;
    ASSERT_FALSE(r.sliding);
    EXPECT_EQ(r.tangentialForce.x(), f0) << "step " << i;
    EXPECT_EQ(r.tangentialForce.y(), 0.0);
    if (i == nCycle) {
      // What F_t = -K_t xi would give with xi = x0 held: a force change of more than 3x.
      const Real oldLaw = -tangentialStiffness(delta1) * x0;
      EXPECT_GT(std::abs(oldLaw - f0), 2.0 * std::abs(f0));
      EXPECT_EQ(r.tangentialForce.x(), f0);
    }
  }
  EXPECT_DOUBLE_EQ(delta, delta0);
  EXPECT_EQ(h.xi.x(), f0);
  EXPECT_NEAR(b.spring, spring0, 1e-14 * spring0);
  EXPECT_EQ(b.friction, 0.0);
  EXPECT_EQ(b.damping, 0.0);
  EXPECT_NEAR(b.balance(), 0, 1e-12 * spring0);

  // Unload the same distance: force and the net work of the whole closed path back to zero.
  for (int i = 0; i < nLoad; ++i) step(p, delta0, delta0, -v, dt, h, b);
  EXPECT_NEAR(h.xi.x(), 0, 1e-12 * std::abs(f0));
  EXPECT_NEAR(b.spring, 0, 1e-20);
  EXPECT_NEAR(b.work, 0, 1e-12 * spring0);
  EXPECT_NEAR(b.balance(), 0, 1e-12 * spring0);
}

// Tangential loading and unloading while the overlap changes: each force increment takes the
// stiffness of the current overlap, and the force depends on nothing else (the spring energy
// |F_el|^2 / (2 K_t) is not balanced step by step on such a path: the incremental law is
// hypoelastic, exact only for a held force or a constant overlap).
TEST(TangentialLaw, LoadingWhileOverlapChangesUsesCurrentStiffness) {
  const BarrierPhys p = undampedPhys(0.5);
  const Real dt = 1e-3, v = 0.01;
  ContactHistory h;
  Books b;
  Real delta = 0.002, fExpected = 0;
  for (int i = 1; i <= 60; ++i) {
    const Real next = 0.002 + 0.003 * std::sin(M_PI * i / 30.0) * std::sin(M_PI * i / 30.0);
    const LawResult r = step(p, delta, next, i <= 30 ? v : -v, dt, h, b);
    ASSERT_FALSE(r.sliding);
    fExpected -= tangentialStiffness(next) * (i <= 30 ? v : -v) * dt;
    EXPECT_NEAR(r.tangentialForce.x(), fExpected, 1e-12 * std::abs(fExpected) + 1e-15);
    delta = next;
  }
}

// Constant normal load: load forward into slip, reverse into slip the other way. Slip steps
// sit on the cap exactly, stick steps follow K_t, and the slip work is the cap times the
// slipped distance.
TEST(TangentialLaw, StickSlipCycleGivesCoulombCap) {
  const Real mu = 0.4, delta = 0.004, dt = 1e-3, v = 0.013;
  const BarrierPhys p = undampedPhys(mu);
  const Real fn = Law::normalForce(kc, R, delta), kt = tangentialStiffness(delta), cap = mu * fn;
  const Real xCap = cap / kt;
  const int nForward = static_cast<int>(std::ceil(2.3 * xCap / (v * dt)));
  const int nBack = static_cast<int>(std::ceil(3.7 * xCap / (v * dt)));
  ContactHistory h;
  Books b;
  Real x = 0;
  int slipSteps = 0;
  for (int i = 0; i < nForward; ++i) {
    const LawResult r = step(p, delta, delta, v, dt, h, b);
    x += v * dt;
    EXPECT_EQ(r.sliding, x > xCap * (1 + 1e-12)) << "step " << i;
    if (r.sliding) {
      ++slipSteps;
      EXPECT_NEAR(r.tangentialForce.x(), -cap, 1e-13 * cap);
    } else {
      EXPECT_NEAR(r.tangentialForce.x(), -kt * x, 1e-12 * cap);
    }
    EXPECT_LE(r.tangentialForce.norm(), cap * (1 + 1e-14));
  }
  EXPECT_GT(slipSteps, 5);
  const Real slipForward = x - xCap;
  EXPECT_NEAR(b.friction, cap * slipForward, 1e-12 * cap * slipForward);

  // Reverse: the spring unloads and reloads over 2 x_cap before slipping backwards.
  Real back = 0;
  slipSteps = 0;
  for (int i = 0; i < nBack; ++i) {
    const LawResult r = step(p, delta, delta, -v, dt, h, b);
    back += v * dt;
    EXPECT_EQ(r.sliding, back > 2 * xCap * (1 + 1e-12)) << "step " << i;
    if (r.sliding) {
      ++slipSteps;
      EXPECT_NEAR(r.tangentialForce.x(), cap, 1e-13 * cap);
    } else {
      EXPECT_NEAR(r.tangentialForce.x(), -cap + kt * back, 1e-12 * cap);
    }
  }
  EXPECT_GT(slipSteps, 5);
  const Real slipped = slipForward + (back - 2 * xCap);
  EXPECT_NEAR(b.friction, cap * slipped, 1e-12 * cap * slipped);
  EXPECT_NEAR(b.spring, cap * cap / (2 * kt), 1e-12 * cap * cap / kt);
  EXPECT_NEAR(b.balance(), 0, 1e-12 * b.work);
}

// The tangential dashpot never pushes the force past the cap, and while slipping it is off.
TEST(TangentialLaw, DampedStickSlipStaysOnCap) {
  const Real mu = 0.4, delta = 0.004, dt = 1e-3, v = 0.013;
  BarrierPhys p = undampedPhys(mu);
  p.tangentialDamping = 0.3;
  const Real cap = mu * Law::normalForce(kc, R, delta);
  const int nForward = static_cast<int>(std::ceil(2.5 * cap / tangentialStiffness(delta) / (v * dt)));
  ContactHistory h;
  Books b;
  int slipSteps = 0;
  for (int i = 0; i < 3 * nForward; ++i) {
    const LawResult r = step(p, delta, delta, i < nForward ? v : -v, dt, h, b);
    EXPECT_LE(r.tangentialForce.norm(), cap * (1 + 1e-14));
    EXPECT_LE(h.xi.norm(), cap * (1 + 1e-14));
    if (r.sliding) {
      ++slipSteps;
      EXPECT_NEAR(r.tangentialForce.norm(), cap, 1e-13 * cap);
      EXPECT_EQ(r.dampingDissipation, 0.0);
    } else {
      EXPECT_GE(r.dampingDissipation, 0.0);
    }
  }
  EXPECT_GT(slipSteps, 10);
  EXPECT_GT(b.damping, 0.0);
}
