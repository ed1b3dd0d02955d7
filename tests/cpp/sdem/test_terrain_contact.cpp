// Blocks on a terrain (SdemEngine::setTerrain): the flow's height field as the ground the blocks
// rest on and slide over, against the slab cases of test_engine.cpp and the paper's Eq 19.
// Cubes are 0.1 m with R = 0.005 m (core half side 0.045 m); the terrain's own radius is 0, so a
// contact's barrier reaches R from the core.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "common/Error.hpp"
#include "sdem/SdemEngine.hpp"

using namespace mpmsdem;
using namespace mpmsdem::sdem;
using Law = Law2_SdemGeom_BarrierPhys_Coulomb;

namespace {

const Real a = 0.045, R = 0.005, rho = 3000, g0 = 9.81;

// The plane z = -tan(theta) x over [-2, 2]^2 on a raster of `spacing`.
mpm::TerrainSpec slope(Real thetaDeg, Real spacing) {
  mpm::TerrainSpec t;
  t.nx = t.ny = static_cast<int>(std::round(4.0 / spacing)) + 1;
  t.x0 = t.y0 = -2.0;
  t.spacing = spacing;
  const Real tanT = std::tan(thetaDeg * M_PI / 180);
  for (int i = 0; i < t.nx; ++i)
    for (int j = 0; j < t.ny; ++j) t.heights.push_back(-tanT * (t.x0 + i * spacing));
  return t;
}

struct OnTerrain {
  SdemWorld world;
  int block = -1;
  Real mass = 0;
};

// A cube lying on the slope of theta (falling towards +x), yawed by yawDeg about the slope's
// normal, its bottom core face `gap` from the surface along the normal, centred above (x, y) of
// the surface.
void cubeOnSlope(OnTerrain& s, const SdemMaterial& m, Real thetaDeg, Real spacing, Real gap, Real yawDeg, Real x) {
  const int mat = s.world.engine.addMaterial(m);
  s.world.engine.setTerrain(slope(thetaDeg, spacing), mat);
  auto cube = SpheroPolyhedron::box(Vec3::Constant(0.05), R);
  s.block = s.world.engine.addBody(cube, mat, rho * cube->volume, rho * cube->inertiaPerDensity, 7);
  s.mass = s.world.engine.mass(s.block);
  const Real th = thetaDeg * M_PI / 180;
  const Vec3 n(std::sin(th), 0, std::cos(th));
  const Quat q = Quat(Eigen::AngleAxis<Real>(th, Vec3::UnitY())) * Quat(Eigen::AngleAxis<Real>(yawDeg * M_PI / 180, Vec3::UnitZ()));
  const Vec3 foot(x, 0, -std::tan(th) * x);
  s.world.engine.setState(s.block, foot + (gap + a) * n, q, Vec3::Zero(), Vec3::Zero());
}

Real rotationAngle(const Quat& q0, const Quat& q1) { return Eigen::AngleAxis<Real>(q0.conjugate() * q1).angle(); }

}  // namespace

// Face-down on a flat terrain, dropped from first touch and settled under normal damping: the
// 4 corner contacts carry exactly the weight at any yaw, on a raster coarser and finer than the
// cube, without rotating or drifting it.
TEST(TerrainContact, CubeRestsFaceDownAtAnyYaw) {
  for (Real spacing : {1.0, 0.02})
    for (Real yaw : {0.0, 17.0, 45.0}) {
      OnTerrain s;
      SdemMaterial m;
      m.density = rho;
      m.friction = 0.5;
      m.normalDamping = 0.5;
      cubeOnSlope(s, m, 0.0, spacing, R, yaw, 0.013);
      const Vec3 x0 = s.world.engine.position(s.block);
      const Quat q0 = s.world.engine.orientation(s.block);
      for (int k = 0; k < 4000; ++k) s.world.step(1e-4);
      const SdemEngine& e = s.world.engine;
      EXPECT_EQ(e.contacts().size(), 4u) << "yaw " << yaw << " spacing " << spacing;
      for (const ContactRecord& c : e.contacts()) {
        EXPECT_EQ(c.key.bodyB, kTerrainBody);
        EXPECT_EQ(c.externalB, -1);
        EXPECT_NEAR(c.normal.z(), -1.0, 1e-12);  // from the block down into the ground
      }
      EXPECT_NEAR(e.force(s.block).z() / (s.mass * g0), 1.0, 5e-3) << "yaw " << yaw;
      EXPECT_NEAR(rotationAngle(q0, e.orientation(s.block)), 0.0, 1e-8) << "yaw " << yaw;
      EXPECT_NEAR(e.position(s.block).x(), x0.x(), 1e-9);
      EXPECT_NEAR(e.position(s.block).y(), x0.y(), 1e-9);
      // at rest, the overlap the weight needs on 4 contacts of sweep radius R
      const Real delta = Law::overlapForForce(1e4, R, s.mass * g0 / 4);
      EXPECT_NEAR(e.position(s.block).z(), a + R - delta, 1e-6);
      EXPECT_GT(e.criticalTimeStep(), 1e-4);
    }
}

// §3.1 on a terrain: the slope is the ground's (gravity vertical), raster cells 0.1 m, so the
// corners slide across a triangle edge every few centimetres with one tangential history each.
// mu = 0.1 at 30 deg: Eq 19, S = t^2/2 g (sin theta - mu cos theta) = 0.50692 m after 0.5 s, as
// the block on the inclined slab (test_engine.cpp) within 1 %, straight down the slope.
TEST(TerrainContact, BlockSlidesDownASlopeEq19) {
  const Real theta = 30 * M_PI / 180, mu = 0.1, T = 0.5;
  OnTerrain s;
  SdemMaterial m;
  m.density = rho;
  m.friction = mu;
  const Real delta = Law::overlapForForce(1e4, R, 3000 * 0.1 * 0.1 * 0.1 * g0 * std::cos(theta) / 4);
  cubeOnSlope(s, m, 30.0, 0.1, R - delta, 0.0, -0.5);
  const Vec3 x0 = s.world.engine.position(s.block);
  const int steps = 5000;
  for (int k = 0; k < steps; ++k) s.world.step(T / steps);
  const Real S = 0.5 * T * T * g0 * (std::sin(theta) - mu * std::cos(theta));
  const Vec3 along(std::cos(theta), 0, -std::sin(theta));
  const Vec3 d = s.world.engine.position(s.block) - x0;
  EXPECT_NEAR(d.dot(along) / S, 1.0, 0.01);
  EXPECT_NEAR(d.y(), 0.0, 1e-9);
  EXPECT_NEAR(d.dot(Vec3(std::sin(theta), 0, std::cos(theta))), 0.0, 1e-5);  // it stays on the slope
  EXPECT_GT(s.world.engine.criticalTimeStep(), T / steps);
  EXPECT_NEAR(s.world.engine.frictionDissipation() / (mu * s.mass * g0 * std::cos(theta) * S), 1.0, 0.02);
}

// Below its friction angle (20 deg, tan 20 deg = 0.364 < mu = 0.5) a block at rest on a terrain
// slope loads its tangential springs and stays: it creeps less than 1e-4 m over 1 s, on a raster
// finer than the block (its corners on different triangles).
TEST(TerrainContact, BlockBelowItsFrictionAngleCreepsLessThanATenthOfAMillimetreInOneSecond) {
  const Real theta = 20 * M_PI / 180;
  OnTerrain s;
  SdemMaterial m;
  m.density = rho;
  m.friction = 0.5;
  m.normalDamping = 0.3;
  m.tangentialDamping = 0.5;
  const Real delta = Law::overlapForForce(1e4, R, 3000 * 0.1 * 0.1 * 0.1 * g0 * std::cos(theta) / 4);
  cubeOnSlope(s, m, 20.0, 0.03, R - delta, 10.0, 0.0);
  for (int k = 0; k < 2000; ++k) s.world.step(1e-4);  // the elastic shift of the springs
  const Vec3 x1 = s.world.engine.position(s.block);
  for (int k = 0; k < 10000; ++k) s.world.step(1e-4);
  const Vec3 x2 = s.world.engine.position(s.block);
  EXPECT_LT((x2 - x1).norm(), 1e-4);
  EXPECT_LT((x2 - x1).norm(), 2e-6);  // measured 4.2e-7 m: the springs hold it
  EXPECT_EQ(s.world.engine.contacts().size(), 4u);
  for (const ContactRecord& c : s.world.engine.contacts()) EXPECT_FALSE(c.sliding);
}

// The terrain's contacts go into checkpoints like the block pairs'; a history naming the terrain
// is refused by an engine without one. A core vertex below the ground stops the run.
TEST(TerrainContact, HistoriesCheckpointAndACoreBelowTheGroundIsRefused) {
  OnTerrain s;
  SdemMaterial m;
  m.density = rho;
  cubeOnSlope(s, m, 10.0, 0.05, 0.5 * R, 0.0, 0.0);
  s.world.step(1e-4);
  const std::vector<ContactHistoryEntry> h = s.world.engine.contactHistories();
  ASSERT_EQ(h.size(), 4u);
  for (const ContactHistoryEntry& e : h) EXPECT_EQ(e.key.bodyB, kTerrainBody);
  EXPECT_NO_THROW(s.world.engine.setContactHistories(h));
  SdemEngine plain;
  plain.addMaterial(m);
  auto cube = SpheroPolyhedron::box(Vec3::Constant(0.05), R);
  plain.addBody(cube, 0, 3.0, Vec3::Ones(), 7);
  EXPECT_THROW(plain.setContactHistories(h), ParameterError);

  OnTerrain deep;
  cubeOnSlope(deep, m, 10.0, 0.05, -0.001, 0.0, 0.0);  // its bottom core face 1 mm into the ground
  try {
    deep.world.step(1e-4);
    ADD_FAILURE() << "a core below the terrain was accepted";
  } catch (const RuntimeFailure& e) {
    EXPECT_NE(std::string(e.what()).find("SDEM body 7: core vertex"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("below the terrain"), std::string::npos) << e.what();
  }
  EXPECT_THROW(deep.world.engine.setTerrain(slope(0.0, 0.1), 5), ParameterError);
  mpm::TerrainSpec bad = slope(0.0, 0.1);
  bad.heights.pop_back();
  EXPECT_THROW(deep.world.engine.setTerrain(bad, 0), ParameterError);
}
