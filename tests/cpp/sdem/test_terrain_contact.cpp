// Blocks on a terrain (SdemEngine::setTerrain): the flow's height field as the ground the blocks
// rest on and slide over, against the slab cases of test_engine.cpp and the paper's Eq 19.
// Cubes are 0.1 m with R = 0.005 m (core half side 0.045 m); the terrain's own radius is 0, so a
// contact's barrier reaches R from the core.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "common/Error.hpp"
#include "sdem/Ig2_SpheroPolyhedron_Terrain.hpp"
#include "sdem/SdemEngine.hpp"

using namespace mpmsdem;
using namespace mpmsdem::sdem;
using Law = Law2_SdemGeom_BarrierPhys_Coulomb;

namespace {

const Real a = 0.045, R = 0.005, rho = 3000, g0 = 9.81;

// The plane z = -tan(theta) x over [-2, 2]^2 on a raster of `spacing`.
mpmsdem::TerrainSpec slope(Real thetaDeg, Real spacing) {
  mpmsdem::TerrainSpec t;
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

// One step of a scene whose terrain reaches into the core: refused, the message naming both.
void expectRefused(OnTerrain& s, const std::string& who, const std::string& why) {
  try {
    s.world.step(1e-6);
    ADD_FAILURE() << "terrain in a core was accepted";
  } catch (const RuntimeFailure& e) {
    EXPECT_NE(std::string(e.what()).find(who), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
  }
}

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
  expectRefused(deep, "SDEM body 7: core vertex", "below the terrain");
  EXPECT_THROW(deep.world.engine.setTerrain(slope(0.0, 0.1), 5), ParameterError);
  mpmsdem::TerrainSpec bad = slope(0.0, 0.1);
  bad.heights.pop_back();
  EXPECT_THROW(deep.world.engine.setTerrain(bad, 0), ParameterError);
}

// ---------------------------------------------------------------- relief finer than the core
namespace {

// Flat ground z = 0 on [-1, 1]^2, raster `spacing`, with the heights `raise` adds.
template <typename F>
mpmsdem::TerrainSpec relief(Real spacing, F raise) {
  mpmsdem::TerrainSpec t;
  t.nx = t.ny = static_cast<int>(std::round(2.0 / spacing)) + 1;
  t.x0 = t.y0 = -1.0;
  t.spacing = spacing;
  for (int i = 0; i < t.nx; ++i)
    for (int j = 0; j < t.ny; ++j) t.heights.push_back(raise(i, j));
  return t;
}

// Eq 10 (the barrier's force) at overlap delta for a contact reach Rc and k_c 1e4 N/m.
Real eq10(Real delta, Real Rc) {
  return -1e4 * delta * (2 * std::log((Rc - delta) / Rc) - Rc / (Rc - delta) + 1);
}

// The cube of these tests at rest, face-down and unturned, centred over (x, y), its bottom core
// face at height zb; gravity off, so that one step shows the contacts of that pose.
void cubeAt(OnTerrain& s, const mpmsdem::TerrainSpec& t, Real x, Real y, Real zb, const SdemMaterial& m) {
  const int mat = s.world.engine.addMaterial(m);
  s.world.engine.setTerrain(t, mat);
  auto cube = SpheroPolyhedron::box(Vec3::Constant(0.05), R);
  s.block = s.world.engine.addBody(cube, mat, rho * cube->volume, rho * cube->inertiaPerDensity, 7);
  s.mass = s.world.engine.mass(s.block);
  s.world.engine.setState(s.block, Vec3(x, y, zb + a), Quat::Identity(), Vec3::Zero(), Vec3::Zero());
}

}  // namespace

// Which raster edges are convex: none on a plane or in a valley; on a ridge along y only the
// ridge's own edges (the diagonals beside it join coplanar triangles); a peak's four axis edges
// and the two diagonals that run to it; crest nodes are their ends.
TEST(TerrainCrest, ConvexEdgesAreTheRidgesAndPeaks) {
  const Real s = 0.1;
  const int mid = 10;  // node of x = 0 (and y = 0)
  auto flags = [](const mpmsdem::TerrainSpec& t) {
    Ig2_SpheroPolyhedron_Terrain g;
    g.setTerrain(t);
    return g;
  };
  for (const mpmsdem::TerrainSpec& t : {relief(s, [](int i, int j) { return 0.3 * i - 0.1 * j; }),
                                    relief(s, [&](int i, int) { return 0.05 * std::abs(i - mid); })}) {
    const Ig2_SpheroPolyhedron_Terrain g = flags(t);
    for (int i = 0; i < t.nx; ++i)
      for (int j = 0; j < t.ny; ++j) {
        EXPECT_FALSE(g.crestNode(i, j));
        for (int d = 0; d < 3; ++d) EXPECT_FALSE(g.convexEdge(i, j, d));
      }
  }
  const Ig2_SpheroPolyhedron_Terrain ridge = flags(relief(s, [&](int i, int) { return -0.05 * std::abs(i - mid); }));
  int convex = 0;
  for (int i = 0; i < 21; ++i)
    for (int j = 0; j < 21; ++j) {
      EXPECT_EQ(ridge.crestNode(i, j), i == mid) << i << " " << j;
      for (int d = 0; d < 3; ++d) {
        const bool expect = d == 1 && i == mid && j < 20;
        EXPECT_EQ(ridge.convexEdge(i, j, d), expect) << i << " " << j << " " << d;
        convex += ridge.convexEdge(i, j, d);
      }
    }
  EXPECT_EQ(convex, 20);
  const Ig2_SpheroPolyhedron_Terrain peak = flags(relief(s, [&](int i, int j) { return i == mid && j == mid ? 0.05 : 0.0; }));
  EXPECT_TRUE(peak.convexEdge(mid, mid, 0) && peak.convexEdge(mid - 1, mid, 0));
  EXPECT_TRUE(peak.convexEdge(mid, mid, 1) && peak.convexEdge(mid, mid - 1, 1));
  EXPECT_TRUE(peak.convexEdge(mid - 1, mid, 2) && peak.convexEdge(mid, mid - 1, 2));  // (mid, mid) to (mid-1, mid+1), (mid+1, mid-1)
  EXPECT_FALSE(peak.convexEdge(mid - 1, mid - 1, 2) || peak.convexEdge(mid, mid, 2));
  int crests = 0;
  for (int i = 0; i < 21; ++i)
    for (int j = 0; j < 21; ++j) crests += peak.crestNode(i, j);
  EXPECT_EQ(crests, 7);  // the peak and the six ends of its convex edges
}

// A spike on flat ground under the middle of the cube's bottom face, 2.5 mm (R/2) below it: its
// node is the one contact (the corners are 5 cm above the ground), along -z with Eq 10's force
// at overlap R/2. Before the crest pairs the cube felt nothing.
TEST(TerrainCrest, APeakUnderAFaceIsACrestNodeContact) {
  const Real H = 0.05;
  OnTerrain s;
  SdemMaterial m;
  m.density = rho;
  cubeAt(s, relief(0.02, [&](int i, int j) { return i == 50 && j == 50 ? H : 0.0; }), 0.003, -0.004, H + 0.5 * R, m);
  s.world.gravity = Vec3::Zero();
  s.world.step(1e-6);
  const std::vector<ContactRecord>& c = s.world.engine.contacts();
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].key.kindB, FeatureKind::Vertex);
  EXPECT_EQ(c[0].key.indexB, 50 * 101 + 50);
  EXPECT_NEAR(c[0].overlap, 0.5 * R, 1e-12);
  EXPECT_NEAR(c[0].normal.z(), -1.0, 1e-12);
  EXPECT_NEAR(c[0].normalForce / eq10(0.5 * R, R), 1.0, 1e-9);
  EXPECT_NEAR(s.world.engine.force(s.block).z() / eq10(0.5 * R, R), 1.0, 1e-9);
}

// A ridge along y on a raster coarser than the cube (0.2 m: its nodes 5.5 cm beyond the core's
// sides), under the bottom face, R/2 below it: the face rests on the ridge where its two edges
// across the ridge cross it (the corners of their contact patch), two contacts of Eq 10's force
// at overlap R/2, and none at the corners (1.1 cm above the slopes) or the ridge's nodes.
TEST(TerrainCrest, ARidgeBetweenItsNodesIsMetByTheCoreEdgesAcrossIt) {
  const Real H = 0.04;
  OnTerrain s;
  SdemMaterial m;
  m.density = rho;
  cubeAt(s, relief(0.2, [&](int i, int) { return i == 5 ? H : 0.0; }), 0.0, 0.1, H + 0.5 * R, m);
  s.world.gravity = Vec3::Zero();
  s.world.step(1e-6);
  const std::vector<ContactRecord>& c = s.world.engine.contacts();
  ASSERT_EQ(c.size(), 2u);
  Real ySum = 0;
  for (const ContactRecord& r : c) {
    EXPECT_EQ(r.key.kindA, FeatureKind::Edge);
    EXPECT_EQ(r.key.kindB, FeatureKind::Edge);
    EXPECT_EQ(r.key.indexB, 3 * (5 * 11 + 5) + 1);  // the y edge from node (5, 5), (0, 0) to (0, 0.2)
    EXPECT_NEAR(r.overlap, 0.5 * R, 1e-12);
    EXPECT_NEAR(r.normal.z(), -1.0, 1e-12);
    EXPECT_NEAR(r.point.x(), 0.0, 1e-12);
    EXPECT_NEAR(std::abs(r.point.y() - 0.1), a, 1e-12);
    ySum += r.point.y();
    EXPECT_NEAR(r.normalForce / eq10(0.5 * R, R), 1.0, 1e-9);
  }
  EXPECT_NEAR(ySum, 0.2, 1e-12);  // one at each side: no torque about x
  EXPECT_NEAR(s.world.engine.torque(s.block).norm(), 0.0, 1e-12);
  // their histories go into checkpoints as the vertex contacts' do
  EXPECT_NO_THROW(s.world.engine.setContactHistories(s.world.engine.contactHistories()));
  EXPECT_EQ(s.world.engine.contactHistories().size(), 2u);
  // the face 2 mm below the ridge: the ridge runs through the core, between its features
  OnTerrain deep;
  cubeAt(deep, relief(0.2, [&](int i, int) { return i == 5 ? H : 0.0; }), 0.0, 0.1, H - 0.002, m);
  expectRefused(deep, "SDEM body 7: terrain ridge edge 181", "passes through the core");
}

// Dropped on the spike, the cube is held off the ground by it, tips off it onto the flat ground
// and comes to rest there beside it: the spike never enters its core (the run would stop), and
// at rest the ground and the spike carry its weight. Without the crest node the cube fell flat
// onto the ground around the spike, which ended inside its core.
TEST(TerrainCrest, ACubeDroppedOnASpikeNeverTakesItInside) {
  const Real H = 0.03;
  OnTerrain s;
  SdemMaterial m;
  m.density = rho;
  m.friction = 0.5;
  m.normalDamping = 0.5;
  m.tangentialDamping = 0.5;
  const mpmsdem::TerrainSpec t = relief(0.02, [&](int i, int j) { return i == 50 && j == 50 ? H : 0.0; });
  cubeAt(s, t, 0.02, 0.01, H + 0.9 * R, m);
  for (int k = 0; k < 12000; ++k) s.world.step(1e-4);
  const SdemEngine& e = s.world.engine;
  const Vec3 spike(0, 0, H);
  const SpheroPolyhedron::PointQuery q =
      SpheroPolyhedron::box(Vec3::Constant(0.05), R)->closestPoint(e.orientation(s.block).conjugate() * (spike - e.position(s.block)));
  EXPECT_GT(q.distance, 0.5 * R);  // outside the core, beyond the barrier's stiff half
  EXPECT_LT(e.velocity(s.block).norm(), 1e-3);
  EXPECT_NEAR(e.force(s.block).z() / (s.mass * g0), 1.0, 0.02);
  EXPECT_GT(Eigen::AngleAxis<Real>(e.orientation(s.block)).angle(), 0.1);  // it leans on the spike
}

// The cube edge-down (turned 45 deg about y) across a ridge along x, between the ridge's nodes
// (0.2 m raster): no face lies near either slope (45 deg against 11 deg), so the lowest core
// edge and the ridge meet by the edge pair's general rule, in one contact at their crossing.
TEST(TerrainCrest, ACoreEdgeAcrossARidgeIsOneEdgePairContact) {
  const Real H = 0.04;
  OnTerrain s;
  SdemMaterial m;
  m.density = rho;
  const int mat = s.world.engine.addMaterial(m);
  s.world.engine.setTerrain(relief(0.2, [&](int, int j) { return j == 5 ? H : 0.0; }), mat);
  auto cube = SpheroPolyhedron::box(Vec3::Constant(0.05), R);
  s.block = s.world.engine.addBody(cube, mat, rho * cube->volume, rho * cube->inertiaPerDensity, 7);
  const Quat q(Eigen::AngleAxis<Real>(M_PI / 4, Vec3::UnitY()));
  s.world.engine.setState(s.block, Vec3(0.1, 0.0, H + 0.5 * R + a * std::sqrt(2.0)), q, Vec3::Zero(), Vec3::Zero());
  s.world.gravity = Vec3::Zero();
  s.world.step(1e-6);
  const std::vector<ContactRecord>& c = s.world.engine.contacts();
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].key.kindA, FeatureKind::Edge);
  EXPECT_EQ(c[0].key.kindB, FeatureKind::Edge);
  EXPECT_EQ(c[0].key.indexB, 3 * (5 * 11 + 5) + 0);  // the x edge from node (5, 5), (0, 0) to (0.2, 0)
  EXPECT_NEAR(c[0].overlap, 0.5 * R, 1e-12);
  EXPECT_NEAR(c[0].normal.z(), -1.0, 1e-12);
  EXPECT_NEAR(c[0].point.x(), 0.1, 1e-12);
  EXPECT_NEAR(c[0].point.y(), 0.0, 1e-12);
  EXPECT_NEAR(c[0].normalForce / eq10(0.5 * R, R), 1.0, 1e-9);
}

namespace {

// Flat ground z = 0 up to x = 0.1 m (node 55 of the 0.02 m raster), then a wall rising at 80 deg.
const Real wallX = 0.1, wallAngle = 80 * M_PI / 180;
mpmsdem::TerrainSpec wall() {
  return relief(0.02, [](int i, int) { return i > 55 ? std::tan(wallAngle) * (-1.0 + 0.02 * i - wallX) : 0.0; });
}

}  // namespace

// The cube's bottom face 6 mm above the ground (beyond R), its front core corners 1.5 mm short of
// the wall's foot and R/2 from the wall's plane: both corners touch the wall, each with Eq 10's
// force at overlap R/2 along the wall's normal, and nothing touches the ground. Before the wall
// pair the cube felt nothing until a corner was over the wall, with the overlap R - z cos 80 deg.
TEST(TerrainWall, AVertexBesideASteepWallIsAFaceContactWithIt) {
  const Real zb = 0.006, sinW = std::sin(wallAngle), cosW = std::cos(wallAngle);
  const Real dx = (0.5 * R - cosW * zb) / sinW;  // the corners' distance to the wall's foot
  ASSERT_GT(dx, 0.0);
  OnTerrain s;
  SdemMaterial m;
  m.density = rho;
  cubeAt(s, wall(), wallX - dx - a, 0.01, zb, m);
  s.world.gravity = Vec3::Zero();
  s.world.step(1e-6);
  const std::vector<ContactRecord>& c = s.world.engine.contacts();
  ASSERT_EQ(c.size(), 2u);
  for (const ContactRecord& r : c) {
    EXPECT_EQ(r.key.kindA, FeatureKind::Vertex);
    EXPECT_EQ(r.key.kindB, FeatureKind::Face);
    EXPECT_GE(r.key.indexB, 2 * (55 * 101));  // a triangle of the wall's first cells
    EXPECT_LT(r.key.indexB, 2 * (56 * 101));
    EXPECT_NEAR(r.overlap, 0.5 * R, 1e-12);
    EXPECT_NEAR(r.normal.x(), sinW, 1e-12);
    EXPECT_NEAR(r.normal.z(), -cosW, 1e-12);
    EXPECT_NEAR(r.normalForce / eq10(0.5 * R, R), 1.0, 1e-9);
  }
  const Vec3 f = s.world.engine.force(s.block) / (2 * eq10(0.5 * R, R));
  EXPECT_NEAR(f.x(), -sinW, 1e-9);
  EXPECT_NEAR(f.z(), cosW, 1e-9);
}

// Gravity tilted 20 deg towards the wall, no friction: the cube slides 1 cm into the corner and
// rests there, its front corners held short of the wall's foot by the wall (each on the ground and
// on the wall: 6 contacts), the walls' push along x balancing m g sin 20 deg. Before the wall
// pair the corners ran over the foot (2.3 mm) and met the wall there with most of the barrier.
TEST(TerrainWall, ACubeSlidingIntoAWallRestsAgainstIt) {
  const Real tilt = 20 * M_PI / 180;
  OnTerrain s;
  SdemMaterial m;
  m.density = rho;
  m.friction = 0;
  m.normalDamping = 0.5;
  m.tangentialDamping = 0.5;
  cubeAt(s, wall(), wallX - 0.01 - a, 0.01, 0.9 * R, m);
  s.world.gravity = g0 * Vec3(std::sin(tilt), 0, -std::cos(tilt));
  const SdemEngine& e = s.world.engine;
  Real front = -1;
  for (int k = 0; k < 10000; ++k) {
    s.world.step(1e-4);
    front = std::max(front, e.position(s.block).x() + a);  // the unturned cube's front core face
  }
  EXPECT_LT(front, wallX);
  EXPECT_GT(front, wallX - R);  // it reached the wall
  EXPECT_LT(e.velocity(s.block).norm(), 1e-3);
  // a lean of the ground's overlaps (about 1 mm under each corner), the front corners carrying less
  EXPECT_LT(Eigen::AngleAxis<Real>(e.orientation(s.block)).angle(), 0.01);
  const Vec3 weight = s.mass * s.world.gravity;
  EXPECT_NEAR((e.force(s.block) + weight).norm() / weight.norm(), 0.0, 0.01);
  Real wallPush = 0;
  int walls = 0;
  for (const ContactRecord& r : e.contacts())
    if (r.key.indexB >= 0) {
      ++walls;
      wallPush -= r.normalForce * r.normal.x();
    }
  EXPECT_EQ(e.contacts().size(), 6u);
  EXPECT_EQ(walls, 2);
  EXPECT_NEAR(wallPush / weight.x(), -1.0, 0.01);
}

// A fold of the wall itself (0.002 m raster): flat ground to x = 0.1 m, one cell rising at 60 deg,
// then the wall at 80 deg. Each front core corner lies over the ground, 0.49 R from the 60 deg
// triangle's plane and 0.51 R from the 80 deg one's, the foot of its normal inside each: both are
// walls to it (steeper than 26 deg from the ground under it), but they lean only 20 deg from each
// other, the same slope: one contact a corner, with the nearer one, at Eq 10's force for its
// overlap. Counting both would push the corner out of the fold twice.
TEST(TerrainWall, AVertexInAFoldOfOneSlopeTouchesItOnce) {
  const Real s = 0.002, t60 = std::tan(M_PI / 3), t80 = std::tan(80 * M_PI / 180);
  const mpmsdem::TerrainSpec fold = relief(s, [&](int i, int) {
    return i <= 550 ? 0.0 : i == 551 ? s * t60 : s * t60 + (i - 551) * s * t80;  // node 550 at x = 0.1
  });
  const Real dA = 0.49 * R, dB = 0.51 * R, c = std::cos(M_PI / 9);  // the two walls' normals, 20 deg apart
  const Vec3 nA(-std::sin(M_PI / 3), 0, std::cos(M_PI / 3)), nB(-std::sin(80 * M_PI / 180), 0, std::cos(80 * M_PI / 180));
  const Vec3 kink(0.102, 0, s * t60);
  const Vec3 p = kink + (dA - c * dB) / (1 - c * c) * nA + (dB - c * dA) / (1 - c * c) * nB;
  ASSERT_LT(p.x(), 0.1);  // over the ground
  OnTerrain w;
  SdemMaterial m;
  m.density = rho;
  cubeAt(w, fold, p.x() - a, 0.01, p.z(), m);
  w.world.gravity = Vec3::Zero();
  w.world.step(1e-6);
  int walls = 0;
  for (const ContactRecord& r : w.world.engine.contacts()) {
    if (r.key.indexB < 0) continue;  // the ground under the bottom corners
    ++walls;
    EXPECT_EQ(r.key.kindA, FeatureKind::Vertex);
    EXPECT_GE(r.key.indexB, 2 * (550 * 1001));  // a triangle of the 60 deg cells
    EXPECT_LT(r.key.indexB, 2 * (551 * 1001));
    EXPECT_NEAR(r.overlap, R - dA, 1e-12);
    EXPECT_NEAR(r.normal.x(), -nA.x(), 1e-12);
    EXPECT_NEAR(r.normal.z(), -nA.z(), 1e-12);
    EXPECT_NEAR(r.normalForce / eq10(R - dA, R), 1.0, 1e-9);
  }
  EXPECT_EQ(walls, 2);
}
