// Pairs of bodies that cannot move never reach the narrow phase: fixed bodies, and bodies with
// all six degrees of freedom blocked, which count as fixed. Scene: a fixed slab (top outer
// face z = 0) with a row of fixed cubes standing on it, each touching the slab and its
// neighbours, and free cubes resting on the slab; every test checks that the skipped work
// leaves the free cubes' motion bit for bit as it is without it.
#include <gtest/gtest.h>

#include <random>

#include "sdem/Bo1_SpheroPolyhedron_Aabb.hpp"
#include "sdem/SdemEngine.hpp"

using namespace mpmsdem;
using namespace mpmsdem::sdem;

namespace {

const Real h = 0.02, R = 0.003, rho = 2000, dt = 1e-5;
const int kWall = 8;  // cubes in the fixed row

enum class Wall { None, Fixed, BlockedDofs };

struct Scene {
  SdemWorld world;
  std::vector<int> wall, free;
};

int addBox(Scene& sc, const Vec3& half, const Vec3& pos, const Vec3& vel = Vec3::Zero()) {
  static const SdemMaterial mat = [] {
    SdemMaterial m;
    m.density = rho;
    m.friction = 0.4;
    m.normalDamping = 0.2;
    m.tangentialDamping = 0.1;
    return m;
  }();
  SdemEngine& e = sc.world.engine;
  if (e.numMaterials() == 0) e.addMaterial(mat);
  auto s = SpheroPolyhedron::box(half, R);
  const int i = e.addBody(s, 0, rho * s->volume, rho * s->inertiaPerDensity, e.numBodies());
  e.setState(i, pos, Quat::Identity(), vel, Vec3::Zero());
  return i;
}

// The slab, the row of cubes along x at y = -0.1 (each 0.1 mm into the slab and into its
// neighbour), one free cube set 0.1 mm into the slab away from the row and, with `pusher`,
// one sliding at 0.1 m/s on the slab into the row's last cube, 0.1 mm away.
Scene build(Wall wall, bool pusher) {
  Scene sc;
  const int slab = addBox(sc, Vec3(0.4, 0.3, 0.02), Vec3(0, 0, -0.02));
  sc.world.engine.setFixed(slab, true);
  if (wall != Wall::None)
    for (int k = 0; k < kWall; ++k) {
      const int i = addBox(sc, Vec3::Constant(h), Vec3(-0.2 + k * (2 * h - 1e-4), -0.1, h - 1e-4));
      if (wall == Wall::Fixed)
        sc.world.engine.setFixed(i, true);
      else
        sc.world.setBlockedDofs(i, "xyzXYZ");
      sc.wall.push_back(i);
    }
  sc.free.push_back(addBox(sc, Vec3::Constant(h), Vec3(0.1, 0.1, h - 1e-4)));
  if (pusher) {
    const Real xEnd = -0.2 + (kWall - 1) * (2 * h - 1e-4);
    sc.free.push_back(addBox(sc, Vec3::Constant(h), Vec3(xEnd + 2 * h + 1e-4, -0.1, h - 1e-4), Vec3(-0.1, 0, 0)));
  }
  return sc;
}

// Steps the scene; returns whether body `touched` had a contact at any step.
bool run(Scene& sc, int steps, int touched = -1) {
  bool hit = false;
  for (int s = 0; s < steps; ++s) {
    sc.world.step(dt);
    for (const ContactRecord& c : sc.world.engine.contacts()) hit = hit || c.key.bodyA == touched || c.key.bodyB == touched;
  }
  return hit;
}

void expectSameMotion(const SdemEngine& a, int ia, const SdemEngine& b, int ib) {
  EXPECT_EQ(a.position(ia), b.position(ib));
  EXPECT_EQ(a.orientation(ia).coeffs(), b.orientation(ib).coeffs());
  EXPECT_EQ(a.velocity(ia), b.velocity(ib));
  EXPECT_EQ(a.angularVelocity(ia), b.angularVelocity(ib));
}

}  // namespace

// Fixed blocks touching each other and the slab: no pair of them is ever tested, and the free
// cube on the slab moves bit for bit as on the slab alone.
TEST(FixedPairs, FixedBlocksInContactAreNeverTested) {
  Scene ref = build(Wall::None, false), sc = build(Wall::Fixed, false);
  const int steps = 2000;
  run(ref, steps);
  run(sc, steps);
  ASSERT_FALSE(sc.world.engine.contacts().empty());  // the free cube rests on the slab
  EXPECT_EQ(ref.world.engine.narrowPhasePairs(), steps);  // cube-slab, every step
  EXPECT_EQ(sc.world.engine.narrowPhasePairs(), steps);   // the same: no fixed-fixed pair
  expectSameMotion(ref.world.engine, ref.free[0], sc.world.engine, sc.free[0]);
  for (int i : sc.wall) EXPECT_EQ(sc.world.engine.force(i), Vec3::Zero());
}

// A body with its six DOFs blocked is fixed: its pairs with fixed bodies skip the narrow phase,
// it moves as a fixed body (kinematically), and the free cubes, one of them pushing against
// the row, move bit for bit as next to a fixed row.
TEST(FixedPairs, AllSixDofsBlockedCountsAsFixed) {
  Scene fixedRow = build(Wall::Fixed, true), blockedRow = build(Wall::BlockedDofs, true);
  for (int i : blockedRow.wall) EXPECT_TRUE(blockedRow.world.engine.isFixed(i));
  const int steps = 3000;
  run(fixedRow, steps);
  EXPECT_TRUE(run(blockedRow, steps, blockedRow.wall.back())) << "the pusher never reached the row";
  const SdemEngine &f = fixedRow.world.engine, &b = blockedRow.world.engine;
  EXPECT_GT(f.narrowPhasePairs(), 2L * steps);  // both free cubes on the slab, the pusher at the row
  EXPECT_EQ(b.narrowPhasePairs(), f.narrowPhasePairs());
  for (std::size_t k = 0; k < fixedRow.free.size(); ++k) expectSameMotion(f, fixedRow.free[k], b, blockedRow.free[k]);
  for (std::size_t k = 0; k < fixedRow.wall.size(); ++k) expectSameMotion(f, fixedRow.wall[k], b, blockedRow.wall[k]);
  EXPECT_DOUBLE_EQ(fixedRow.world.kineticEnergy(), blockedRow.world.kineticEnergy());
}

// Blocked DOFs make a body fixed only while all six are blocked; a body fixed by setFixed
// stays fixed whatever its DOFs.
TEST(FixedPairs, UnblockingADofReleasesTheBody) {
  Scene sc = build(Wall::BlockedDofs, false);
  const int i = sc.wall.front();
  sc.world.setBlockedDofs(i, "xyzXY");
  EXPECT_FALSE(sc.world.engine.isFixed(i));
  sc.world.setBlockedDofs(i, "xyzXYZ");
  EXPECT_TRUE(sc.world.engine.isFixed(i));
  sc.world.setBlockedDofs(i, "");
  EXPECT_FALSE(sc.world.engine.isFixed(i));
  const long before = sc.world.engine.narrowPhasePairs();
  sc.world.step(dt);
  EXPECT_GE(sc.world.engine.narrowPhasePairs() - before, 3);  // released cube: slab, neighbour, + free cube on the slab

  const int slab = 0;
  sc.world.setBlockedDofs(slab, "xyzXYZ");
  sc.world.setBlockedDofs(slab, "");
  EXPECT_TRUE(sc.world.engine.isFixed(slab));
}

// A kinematic body (six DOFs blocked, a set velocity) moves exactly as a fixed one does.
TEST(FixedPairs, BlockedBodyMovesKinematically) {
  Scene a = build(Wall::None, false), b = build(Wall::None, false);
  const int ia = a.free[0], ib = b.free[0];
  const Vec3 v(0.02, -0.01, 0.03), w(0.5, -0.2, 1.0);
  a.world.engine.setState(ia, a.world.engine.position(ia), Quat::Identity(), v, w);
  b.world.engine.setState(ib, b.world.engine.position(ib), Quat::Identity(), v, w);
  a.world.engine.setFixed(ia, true);
  b.world.setBlockedDofs(ib, "xyzXYZ");
  run(a, 500);
  run(b, 500);
  expectSameMotion(a.world.engine, ia, b.world.engine, ib);
  EXPECT_EQ(b.world.engine.narrowPhasePairs(), 0);
}

// The broad phase (a sweep along x, then the other axes) finds exactly the pairs whose
// rounded-body boxes overlap (touching counts), fixed–fixed pairs left out: bodies of sizes over
// a factor of 10, turned at random on a jittered lattice, a slab far larger than them under them
// and a few fixed bodies among them, against the test of every pair (146 pairs).
TEST(BroadPhase, FindsEveryOverlappingPairOnce) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<Real> u(0.0, 1.0);
  SdemEngine e;
  SdemMaterial m;
  m.density = 1000;
  const int mat = e.addMaterial(m);
  auto slab = SpheroPolyhedron::box(Vec3(4, 4, 0.1), 0.01);
  const int bed = e.addBody(slab, mat, 1.0, Vec3::Ones(), 1000);
  e.setFixed(bed, true);
  e.setState(bed, Vec3(1.5, 1.5, -0.22), Quat::Identity(), Vec3::Zero(), Vec3::Zero());  // its top at z -0.12
  const Real pitch = 0.25;
  for (int a = 0; a < 10; ++a)
    for (int b = 0; b < 10; ++b)
      for (int c = 0; c < 2; ++c) {
        // half sides 0.015 ... 0.15 m, nearly all sweep radius: a core reaches 0.026 m from its
        // centre at most and centres are 0.21 m apart at least, so cores never meet, while the
        // boxes of two large neighbours do
        const Real h = 0.015 + 0.135 * u(rng);
        auto s = SpheroPolyhedron::box(Vec3(h, h, h), 0.9 * h);
        const int i = e.addBody(s, mat, 1.0, Vec3::Ones(), 100 * a + 10 * b + c);
        if (u(rng) < 0.1) e.setFixed(i, true);
        const Quat q = Quat(Eigen::AngleAxis<Real>(6.3 * u(rng), Vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng)).normalized()));
        const Vec3 x(a * pitch + 0.04 * (u(rng) - 0.5), b * pitch + 0.04 * (u(rng) - 0.5), c * pitch + 0.02 * u(rng));
        e.setState(i, x, q, Vec3::Zero(), Vec3::Zero());
      }
  e.computeForces(1e-5);
  // every pair by brute force, with the engine's boxes
  long expected = 0;
  std::vector<Vec3> lo(e.numBodies()), hi(e.numBodies());
  for (int i = 0; i < e.numBodies(); ++i) {
    PosedSpheroPolyhedron p;
    p.update(e.shape(i), e.position(i), e.orientation(i));
    Bo1_SpheroPolyhedron_Aabb::go(p, lo[i], hi[i]);
  }
  for (int i = 0; i < e.numBodies(); ++i)
    for (int j = i + 1; j < e.numBodies(); ++j) {
      if (e.isFixed(i) && e.isFixed(j)) continue;
      bool o = true;
      for (int k = 0; k < 3; ++k) o = o && !(lo[j][k] > hi[i][k] || lo[i][k] > hi[j][k]);
      expected += o;
    }
  EXPECT_GT(expected, 50);  // neighbours' boxes meet, and the slab's with the lowest layer
  EXPECT_EQ(e.narrowPhasePairs(), expected);
}
