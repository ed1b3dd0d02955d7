// A coupled step does only the work its scene needs: without material points no MPM step and
// no coupling pass, without blocks no coupling pass; blocks with all six DOFs blocked in a
// scene file are fixed. Each case against the run without the skipped work, bit for bit.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "../mpm/GranularColumn.hpp"
#include "coupling/CoupledScene.hpp"
#include "coupling/CoupledWorld.hpp"
#include "mpm/Seeding.hpp"

using namespace mpmsdem;
using namespace mpmsdem::coupling;
using sdem::SpheroPolyhedron;

namespace {

// A solver that counts the steps and force-buffer openings it passes on to a CPU solver.
class CountingSolver : public mpm::MpmSolver {
 public:
  explicit CountingSolver(std::unique_ptr<mpm::MpmSolver> inner) : inner_(std::move(inner)) {}
  int stepCalls = 0, forceBufferCalls = 0;

  std::string name() const override { return inner_->name(); }
  const mpm::MpmParams& params() const override { return inner_->params(); }
  void setParticles(const mpm::ParticleSet& p) override { inner_->setParticles(p); }
  void getParticles(mpm::ParticleSet& out) override { inner_->getParticles(out); }
  std::size_t numParticles() const override { return inner_->numParticles(); }
  void setExternalForces(const std::vector<double>& f) override { inner_->setExternalForces(f); }
  mpm::ParticleView openForceBuffer() override {
    ++forceBufferCalls;
    return inner_->openForceBuffer();
  }
  void step(double dt) override {
    ++stepCalls;
    inner_->step(dt);
    setClock(inner_->time(), inner_->steps());
  }
  double cflTimeStep() override { return inner_->cflTimeStep(); }
  std::size_t memoryBytes() const override { return inner_->memoryBytes(); }

 private:
  std::unique_ptr<mpm::MpmSolver> inner_;
};

mpm::MpmParams grid() { return mpm::testing_scenes::tableOneBeads({24, 14, 14}, 0.01); }

// A blob of 4 x 4 x 4 cells at 8 points per cell, moving at 0.5 m/s along x.
mpm::ParticleSet blob(const std::array<double, 3>& lo = {0.04, 0.05, 0.03}) {
  mpm::ParticleSet ps;
  mpm::seedBox(grid(), lo, {lo[0] + 0.04, lo[1] + 0.04, lo[2] + 0.04}, 8, ps);
  for (std::size_t p = 0; p < ps.size(); ++p) ps.v[3 * p] = 0.5;
  return ps;
}

std::unique_ptr<CountingSolver> solverWith(const mpm::ParticleSet& ps) {
  auto s = std::make_unique<CountingSolver>(mpm::makeSolver(grid()));
  s->setParticles(ps);
  return s;
}

// A fixed slab (top outer face z = 0.02 m) and a cube dropped 0.2 mm onto it, sliding at 0.2 m/s.
void slabAndCube(sdem::SdemWorld& w) {
  sdem::SdemMaterial m;
  m.density = 2000;
  m.friction = 0.3;
  m.normalDamping = 0.1;
  const int mat = w.engine.addMaterial(m);
  auto slab = SpheroPolyhedron::box(Vec3(0.2, 0.2, 0.01), 0.003);
  auto cube = SpheroPolyhedron::box(Vec3::Constant(0.02), 0.003);
  const int s = w.engine.addBody(slab, mat, 1.0, Vec3::Ones(), 0);
  w.engine.setState(s, Vec3(0.12, 0.07, 0.01), Quat::Identity(), Vec3::Zero(), Vec3::Zero());
  w.engine.setFixed(s, true);
  const int c = w.engine.addBody(cube, mat, 2000 * cube->volume, 2000 * cube->inertiaPerDensity, 1);
  w.engine.setState(c, Vec3(0.1, 0.07, 0.0402), Quat::Identity(), Vec3(0.2, 0, 0), Vec3::Zero());
}

sdem::BarrierPhys flowPair() {
  sdem::BarrierPhys p;
  p.friction = 0.3;
  return p;
}

}  // namespace

// Blocks without material points: the coupled world moves them bit for bit as the SDEM world
// alone, never steps the MPM solver nor opens its force buffer, and keeps the flow's clock.
TEST(SceneNeeds, CoupledStepWithoutParticlesIsTheBlocksStep) {
  const double dt = 2e-5;
  const int steps = 1500;
  auto owned = solverWith(mpm::ParticleSet{});
  CountingSolver& solver = *owned;
  CoupledWorld coupled(std::move(owned));
  slabAndCube(coupled.world);
  coupled.world.gravity = Vec3(0, 0, -9.81);
  coupled.coupling.setPair(0, flowPair());
  sdem::SdemWorld alone;
  slabAndCube(alone);
  for (int s = 0; s < steps; ++s) {
    coupled.step(dt);
    alone.step(dt);
  }
  ASSERT_FALSE(alone.engine.contacts().empty());
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(coupled.world.engine.position(i), alone.engine.position(i));
    EXPECT_EQ(coupled.world.engine.orientation(i).coeffs(), alone.engine.orientation(i).coeffs());
    EXPECT_EQ(coupled.world.engine.velocity(i), alone.engine.velocity(i));
    EXPECT_EQ(coupled.world.engine.angularVelocity(i), alone.engine.angularVelocity(i));
    EXPECT_EQ(coupled.coupling.force(i), Vec3::Zero());
  }
  EXPECT_EQ(solver.stepCalls, 0);
  EXPECT_EQ(solver.forceBufferCalls, 0);
  EXPECT_EQ(solver.time(), coupled.time());
  EXPECT_EQ(solver.steps(), steps);
  EXPECT_EQ(coupled.criticalTimeStep(), std::min(solver.stableTimeStep(), coupled.world.engine.criticalTimeStep()));
}

// Material points without blocks: the coupled world steps the flow bit for bit as the solver
// alone and never opens the force buffer (no bins, no particle pass).
TEST(SceneNeeds, CoupledStepWithoutBlocksIsTheMpmStep) {
  const double dt = 1e-4;
  const int steps = 200;
  const mpm::ParticleSet ps = blob();
  auto owned = solverWith(ps);
  CountingSolver& solver = *owned;
  CoupledWorld coupled(std::move(owned));
  auto alone = mpm::makeSolver(grid());
  alone->setParticles(ps);
  for (int s = 0; s < steps; ++s) {
    coupled.step(dt);
    alone->step(dt);
  }
  mpm::ParticleSet a, b;
  coupled.mpm().getParticles(a);
  alone->getParticles(b);
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.v, b.v);
  EXPECT_EQ(a.stress, b.stress);
  EXPECT_EQ(solver.stepCalls, steps);
  EXPECT_EQ(solver.forceBufferCalls, 0);
  EXPECT_EQ(coupled.coupling.totalContacts(), 0);
}

// A block added later is coupled from its first step on (the skipped steps left no state).
TEST(SceneNeeds, BlockAddedToAFlowWithoutBlocksIsCoupled) {
  auto owned = solverWith(blob());
  CountingSolver& solver = *owned;
  CoupledWorld coupled(std::move(owned));
  coupled.world.gravity = Vec3::Zero();
  for (int s = 0; s < 20; ++s) coupled.step(1e-4);
  sdem::SdemMaterial m;
  m.density = 2000;
  coupled.coupling.setPair(coupled.world.engine.addMaterial(m), flowPair());
  auto wall = SpheroPolyhedron::box(Vec3(0.01, 0.06, 0.06), 0.003);
  const int i = coupled.world.engine.addBody(wall, 0, 1.0, Vec3::Ones(), 7);
  coupled.world.engine.setFixed(i, true);
  coupled.world.engine.setState(i, Vec3(0.1, 0.07, 0.05), Quat::Identity(), Vec3::Zero(), Vec3::Zero());
  int hit = 0;
  for (int s = 0; s < 600 && !hit; ++s) {
    coupled.step(1e-4);
    hit = coupled.coupling.contactCount(i);
  }
  EXPECT_GT(hit, 0) << "the blob never reached the wall";
  EXPECT_GT(solver.forceBufferCalls, 0);
  EXPECT_GT(coupled.coupling.force(i).x(), 0.0);  // pushed downstream
}

// A scene file's block with blocked_dofs "xyzXYZ" is fixed in the engine, as "fixed": true is;
// five blocked DOFs leave it moving.
TEST(SceneNeeds, SceneBlockWithAllDofsBlockedIsFixed) {
  const nlohmann::json scene = {
      {"block_materials", {{"steel", {{"density", 7800}, {"flow", {{"friction", 0.2}}}}}}},
      {"blocks",
       {{{"material", "steel"}, {"box", {0.2, 0.2, 0.01}}, {"sweep_radius", 0.003}, {"position", {0.12, 0.07, 0.01}}, {"fixed", true}},
        {{"material", "steel"}, {"box", {0.02, 0.02, 0.02}}, {"sweep_radius", 0.003}, {"position", {0.05, 0.07, 0.04}},
         {"blocked_dofs", "xyzXYZ"}},
        {{"material", "steel"}, {"box", {0.02, 0.02, 0.02}}, {"sweep_radius", 0.003}, {"position", {0.15, 0.07, 0.04}},
         {"blocked_dofs", "xyzXY"}}}}};
  CoupledWorld coupled(solverWith(blob({0.18, 0.05, 0.08})));  // clear of the blocks
  addBlocks(parseBlocks(scene.dump()), coupled);
  const sdem::SdemEngine& e = coupled.world.engine;
  EXPECT_TRUE(e.isFixed(0));
  EXPECT_TRUE(e.isFixed(1));
  EXPECT_FALSE(e.isFixed(2));
  coupled.step(1e-5);
  EXPECT_EQ(e.narrowPhasePairs(), 1);  // the five-DOF block on the slab; the blocked one is not tested
}
