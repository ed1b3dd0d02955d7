// Barrier normal law (Eq 10 read as a force), Coulomb tangential law (Eqs 9, 11), pair
// physics (Ip2) and material validation.
#include <gtest/gtest.h>

#include <cmath>

#include "common/Error.hpp"
#include "sdem/Ip2_SdemMat_SdemMat_BarrierPhys.hpp"
#include "sdem/Law2_SdemGeom_BarrierPhys_Coulomb.hpp"

#include "LawGeometry.hpp"

using namespace mpmsdem;
using namespace mpmsdem::sdem;
using Law = Law2_SdemGeom_BarrierPhys_Coulomb;

namespace {
const Real kc = 1e4, R = 0.01;  // paper's k_c; R = R_A + R_B for two 0.005 m sweep radii

SdemGeom geomAlongZ(Real delta) { return testing_geometry::geomAlongZ(R, delta); }
}  // namespace

// F_n = -k_c delta [2 ln((R-delta)/R) - R/(R-delta) + 1], by hand with k_c = 1e4 N/m, R = 0.01 m:
//  delta = 0.001: 2 ln 0.9 = -0.2107210, -1/0.9 + 1 = -0.1111111, sum -0.3218321 -> 3.218321 N
//  delta = 0.005: 2 ln 0.5 = -1.3862944, -2 + 1 = -1,             sum -2.3862944 -> 119.31472 N
//  delta = 0.009: 2 ln 0.1 = -4.6051702, -10 + 1 = -9,            sum -13.605170 -> 1224.4653 N
TEST(Law, NormalForceEq10) {
  EXPECT_NEAR(Law::normalForce(kc, R, 0.001), 3.2183214, 1e-6);
  EXPECT_NEAR(Law::normalForce(kc, R, 0.005), 119.314718, 1e-5);
  EXPECT_NEAR(Law::normalForce(kc, R, 0.009), 1224.46532, 1e-4);
  EXPECT_EQ(Law::normalForce(kc, R, 0.0), 0.0);
  EXPECT_EQ(Law::normalForce(kc, R, -1e-3), 0.0);
}

// Near first touch F_n = 3 k_c delta^2 / R (1 + 2 x / 3 + O(x^2)), x = delta/R; at x = 1e-4 the
// ratio is 1 + 6.7e-5.
TEST(Law, SmallOverlapLimit) {
  const Real d = 1e-4 * R;
  EXPECT_NEAR(Law::normalForce(kc, R, d) / (3 * kc * d * d / R), 1.0 + 2e-4 / 3, 1e-7);
  EXPECT_NEAR(Law::normalStiffness(kc, R, d) / (6 * kc * d / R), 1.0, 2e-4);
}

// k_n = dF_n/ddelta against a central difference; F_n = db/ddelta likewise (b: barrier energy).
TEST(Law, StiffnessAndEnergyAreDerivatives) {
  for (Real x : {0.01, 0.2, 0.5, 0.8, 0.95}) {
    const Real d = x * R, h = 1e-6 * d;
    const Real fd = (Law::normalForce(kc, R, d + h) - Law::normalForce(kc, R, d - h)) / (2 * h);
    EXPECT_NEAR(Law::normalStiffness(kc, R, d) / fd, 1.0, 1e-6) << "x = " << x;
    const Real bd = (Law::barrierEnergy(kc, R, d + h) - Law::barrierEnergy(kc, R, d - h)) / (2 * h);
    EXPECT_NEAR(Law::normalForce(kc, R, d) / bd, 1.0, 1e-6) << "x = " << x;
  }
  // b(0.005) = -k_c delta^2 ln(0.5) = 1e4 * 2.5e-5 * 0.6931472 = 0.17328680 J
  EXPECT_NEAR(Law::barrierEnergy(kc, R, 0.005), 0.17328680, 1e-8);
  // inverse: the overlap carrying 119.314718 N is 0.005 m
  EXPECT_NEAR(Law::overlapForForce(kc, R, 119.3147181), 0.005, 1e-12);
}

// Tangential stick: one step with v_t = 1e-3 m/s, dt = 1e-3 s moves 1e-6 m, so the history
// (elastic tangential force) is F_t = -K_t 1e-6 m with K_t = k_n/(2(1+nu)) (no damping here),
// well under mu F_n.
TEST(Law, TangentialStick) {
  BarrierPhys p;
  p.friction = 0.5;
  p.poisson = 0.25;
  p.tangentialDamping = 0;
  ContactHistory h;
  const Real delta = 0.005;
  auto r = Law::go(geomAlongZ(delta), R, p, Vec3(1e-3, 0, 0), 1.0, 1e-3, h, 0, 1);
  const Real kn = Law::normalStiffness(kc, R, delta);
  EXPECT_NEAR(r.tangentialStiffness, kn / 2.5, 1e-9 * kn);
  EXPECT_NEAR(h.xi.x(), -kn / 2.5 * 1e-6, 1e-12 * kn);
  EXPECT_NEAR(r.tangentialForce.x(), -kn / 2.5 * 1e-6, 1e-12 * kn);
  EXPECT_NEAR(r.normalForce, 119.314718, 1e-5);
  EXPECT_FALSE(r.sliding);
  EXPECT_NEAR(r.springEnergy, 0.5 * kn / 2.5 * 1e-12, 1e-12 * 0.5 * kn / 2.5 * 1e-12);
}

// Slip: a large increment saturates at |F_t| = mu F_n and rescales the force history to mu F_n;
// the dissipated energy is mu F_n times the slipped length (the move less the stretch mu F_n / K_t).
TEST(Law, TangentialSlipCap) {
  BarrierPhys p;
  p.friction = 0.3;
  p.poisson = 0.3;
  ContactHistory h;
  const Real delta = 0.005;
  auto r = Law::go(geomAlongZ(delta), R, p, Vec3(0, 2.0, 0), 1.0, 1e-3, h, 0, 1);
  const Real fn = Law::normalForce(kc, R, delta);
  EXPECT_TRUE(r.sliding);
  EXPECT_NEAR(r.tangentialForce.norm(), 0.3 * fn, 1e-9 * fn);
  EXPECT_NEAR(r.tangentialForce.y(), -0.3 * fn, 1e-9 * fn);
  EXPECT_NEAR(h.xi.norm(), 0.3 * fn, 1e-9 * fn);
  const Real slipped = 2e-3 - h.xi.norm() / r.tangentialStiffness;
  EXPECT_NEAR(r.frictionDissipation, 0.3 * fn * slipped, 1e-9);
  // Reversing: the spring unloads first, no slip for a small reversal.
  auto r2 = Law::go(geomAlongZ(delta), R, p, Vec3(0, -1e-3, 0), 1.0, 1e-3, h, 0, 1);
  EXPECT_FALSE(r2.sliding);
  EXPECT_LT(r2.tangentialForce.norm(), 0.3 * fn);
}

// Frictionless: no tangential force at all.
TEST(Law, Frictionless) {
  BarrierPhys p;
  p.friction = 0;
  ContactHistory h;
  auto r = Law::go(geomAlongZ(0.002), R, p, Vec3(0.5, 0.1, 0), 1.0, 1e-4, h, 0, 1);
  EXPECT_EQ(r.tangentialForce.norm(), 0.0);
}

// History rotation: projected on the new tangent plane, length kept.
TEST(Law, HistoryRotationKeepsLength) {
  Vec3 xi(3e-4, 4e-4, 0);  // |xi| = 5e-4
  const Vec3 n = Vec3(0.1, -0.2, 1).normalized();
  Law::rotateHistory(xi, n);
  EXPECT_NEAR(xi.norm(), 5e-4, 1e-18);
  EXPECT_NEAR(xi.dot(n), 0, 1e-18);
}

// Normal damping: c_n = 2 zeta sqrt(m k_n) opposes approach; force never adhesive.
TEST(Law, NormalDamping) {
  BarrierPhys p;
  p.normalDamping = 0.5;
  p.friction = 0;
  ContactHistory h;
  const Real delta = 0.005, m = 2.0;
  const Real kn = Law::normalStiffness(kc, R, delta);
  auto approach = Law::go(geomAlongZ(delta), R, p, Vec3(0, 0, -0.1), m, 1e-4, h, 0, 1);
  EXPECT_NEAR(approach.normalForce, 119.314718 + 2 * 0.5 * std::sqrt(m * kn) * 0.1, 1e-5);
  auto separate = Law::go(geomAlongZ(delta), R, p, Vec3(0, 0, 1e3), m, 1e-4, h, 0, 1);
  EXPECT_EQ(separate.normalForce, 0.0);
}

TEST(Law, CoresTouchingIsAFailure) {
  BarrierPhys p;
  ContactHistory h;
  try {
    Law::go(geomAlongZ(R), R, p, Vec3::Zero(), 1.0, 1e-4, h, 7, 9);
    FAIL() << "expected RuntimeFailure";
  } catch (const RuntimeFailure& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("bodies 7 and 9"), std::string::npos) << msg;
  }
}

// Pair physics: min friction, harmonic-mean k_c, mean nu and dampings.
TEST(Law, Ip2Combination) {
  SdemMaterial a, b;
  a.friction = 0.6;
  b.friction = 0.2;
  a.barrierStiffness = 1e4;
  b.barrierStiffness = 3e4;  // harmonic mean 2*1e4*3e4/4e4 = 1.5e4
  a.poisson = 0.2;
  b.poisson = 0.4;
  a.normalDamping = 0.1;
  b.normalDamping = 0.3;
  a.tangentialDamping = 0;
  b.tangentialDamping = 0.2;
  const BarrierPhys p = Ip2_SdemMat_SdemMat_BarrierPhys::go(a, b);
  EXPECT_NEAR(p.friction, 0.2, 1e-15);
  EXPECT_NEAR(p.barrierStiffness, 1.5e4, 1e-9);
  EXPECT_NEAR(p.poisson, 0.3, 1e-15);
  EXPECT_NEAR(p.normalDamping, 0.2, 1e-15);
  EXPECT_NEAR(p.tangentialDamping, 0.1, 1e-15);
}

TEST(Law, MaterialValidation) {
  SdemMaterial m;
  EXPECT_NO_THROW(m.validate());
  m.poisson = 0.5;
  EXPECT_THROW(m.validate(), ParameterError);
  m.poisson = 0.3;
  m.barrierStiffness = 0;
  try {
    m.validate();
    FAIL() << "expected ParameterError";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("barrierStiffness"), std::string::npos);
  }
  m.barrierStiffness = 1e4;
  m.density = -1;
  EXPECT_THROW(m.validate(), ParameterError);
  m.density = 1000;
  m.friction = -0.1;
  EXPECT_THROW(m.validate(), ParameterError);
}
