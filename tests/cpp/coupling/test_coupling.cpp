// MP–SDEM coupling (paper §2.3): the shared geometry against the SDEM shape's own query,
// float against double, impulse balance (Eqs 17–18), momentum conservation, a block carried
// by a granular layer, thread-count independence, bad input.
#include <gtest/gtest.h>

#include <omp.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <tuple>

#include "../mpm/GranularColumn.hpp"
#include "common/Error.hpp"
#include "coupling/CoupledCheckpoint.hpp"
#include "coupling/CoupledWorld.hpp"
#include "mpm/Seeding.hpp"
#include "sdem/ShapeTable.hpp"

#include "../mpm/AgreementHelpers.hpp"

using namespace mpmsdem;
using namespace mpmsdem::coupling;
using sdem::SpheroPolyhedron;

namespace {

// The stored core table of the test hull (tests/data/hull_core.json), for builds without CGAL.
std::shared_ptr<SpheroPolyhedron> storedHull() {
  std::ifstream is(std::string(MPMSDEM_TEST_DATA) + "/hull_core.json");
  const nlohmann::json j = nlohmann::json::parse(is);
  std::vector<Vec3> v;
  for (const auto& p : j.at("vertices")) v.emplace_back(p[0].get<double>(), p[1].get<double>(), p[2].get<double>());
  return SpheroPolyhedron::fromCore(v, j.at("faces").get<std::vector<std::vector<int>>>(),
                                    j.at("sweep_radius").get<double>(), true);
}

std::vector<std::shared_ptr<SpheroPolyhedron>> testShapes() {
  std::vector<std::shared_ptr<SpheroPolyhedron>> s;
  s.push_back(SpheroPolyhedron::box(Vec3(0.05, 0.03, 0.02), 0.005));
#ifdef MPMSDEM_WITH_CGAL
  s.push_back(SpheroPolyhedron::convexHull(
      {Vec3(0, 0, 0), Vec3(0.1, 0, 0), Vec3(0, 0.08, 0), Vec3(0.02, 0.03, 0.09), Vec3(0.07, 0.06, 0.05)}, 0.004));
#else
  s.push_back(storedHull());
#endif
  s.push_back(SpheroPolyhedron::meshFile(std::string(MPMSDEM_TEST_DATA) + "/l_prism.obj", 0.01));
  return s;
}

mpm::MpmParams gridParams(std::array<int, 3> cells, double dx = 0.01) {
  mpm::MpmParams p = mpm::testing_scenes::tableOneBeads(cells, dx, {0, 0, 0});
  for (auto& w : p.walls) w.friction = 0;
  return p;
}

sdem::BarrierPhys pair(double mu = 0.3, double zetaN = 0.0) {
  sdem::BarrierPhys ph;
  ph.barrierStiffness = 1e4;
  ph.friction = mu;
  ph.poisson = 0.3;
  ph.normalDamping = zetaN;
  ph.tangentialDamping = 0.1;
  return ph;
}

// A world with one cube of outer half-size h and sweep radius R at pos.
int addCube(CoupledWorld& w, double h, double R, const Vec3& pos, double density, bool fixed = false) {
  static std::vector<std::shared_ptr<SpheroPolyhedron>> keep;
  keep.push_back(SpheroPolyhedron::box(Vec3::Constant(h), R));
  const auto& s = keep.back();
  sdem::SdemMaterial m;
  m.density = density;
  const int mat = w.world.engine.numMaterials() ? 0 : w.world.engine.addMaterial(m);
  const int i = w.world.engine.addBody(s, mat, density * s->volume, density * s->inertiaPerDensity, 100 + w.world.engine.numBodies());
  w.world.engine.setFixed(i, fixed);
  w.world.engine.setState(i, pos, Quat::Identity(), Vec3::Zero(), Vec3::Zero());
  return i;
}

Vec3 particleMomentum(mpm::MpmSolver& s) {
  mpm::ParticleSet ps;
  s.getParticles(ps);
  Vec3 m = Vec3::Zero();
  for (std::size_t p = 0; p < ps.size(); ++p)
    for (int d = 0; d < 3; ++d) m[d] += ps.mass[p] * ps.v[3 * p + d];
  return m;
}

// A CPU solver that queues its steps as the CUDA one does (MpmSolver::queuesSteps): launchStep
// keeps the step, finishStep takes it, abandonStep drops it. A CoupledWorld over it takes the
// order of a CUDA step on the CPU: the flow's step launched before the sums are collected and
// the blocks move, and run after them.
class QueuedCpuSolver : public mpm::MpmSolver {
 public:
  explicit QueuedCpuSolver(std::unique_ptr<mpm::MpmSolver> inner) : inner_(std::move(inner)) {}
  std::string name() const override { return "queued " + inner_->name(); }
  const mpm::MpmParams& params() const override { return inner_->params(); }
  void setParticles(const mpm::ParticleSet& ps) override { inner_->setParticles(ps); }
  using mpm::MpmSolver::setParticles;
  void getParticles(mpm::ParticleSet& out) override { inner_->getParticles(out); }
  std::size_t numParticles() const override { return inner_->numParticles(); }
  void setExternalForces(const std::vector<double>& f) override { inner_->setExternalForces(f); }
  mpm::ParticleView openForceBuffer() override { return inner_->openForceBuffer(); }
  void step(double dt) override {
    launchStep(dt);
    finishStep();
  }
  double cflTimeStep() override { return inner_->cflTimeStep(); }
  std::size_t memoryBytes() const override { return inner_->memoryBytes(); }
  bool queuesSteps() const override { return true; }
  void launchStep(double dt) override {
    if (launched_) throw RuntimeFailure("QueuedCpuSolver: launched twice");
    launched_ = true;
    dt_ = dt;
    ++launches;
  }
  void finishStep() override {
    if (!launched_) throw RuntimeFailure("QueuedCpuSolver: nothing launched to finish");
    launched_ = false;
    inner_->step(dt_);
    setClock(inner_->time(), inner_->steps());
  }
  void abandonStep() override {
    if (!launched_) throw RuntimeFailure("QueuedCpuSolver: nothing launched to abandon");
    launched_ = false;
    ++abandoned;
  }
  int launches = 0, abandoned = 0;

 private:
  std::unique_ptr<mpm::MpmSolver> inner_;
  bool launched_ = false;
  double dt_ = 0;
};

// Equal to the bit, or both NaN (a first contact not made yet).
bool sameBits(double a, double b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

// Zero gravity: a 4 x 4 x 4-cell blob of glass beads (8 points per cell) moving at vx along x
// in a grid of `cellsX` x 14 x 14 cells; its solver wrapped in a QueuedCpuSolver if `queued`.
std::unique_ptr<CoupledWorld> blobWorld(int cellsX, double vx, mpm::Backend backend = mpm::Backend::Cpu,
                                        mpm::Precision precision = mpm::Precision::Double, bool queued = false) {
  auto prm = gridParams({cellsX, 14, 14});
  mpm::ParticleSet ps;
  mpm::seedBox(prm, {0.04, 0.05, 0.05}, {0.08, 0.09, 0.09}, 8, ps);
  for (std::size_t p = 0; p < ps.size(); ++p) ps.v[3 * p] = vx;
  std::unique_ptr<mpm::MpmSolver> solver = mpm::makeSolver(prm, backend, precision);
  solver->setParticles(ps);
  if (queued) solver = std::make_unique<QueuedCpuSolver>(std::move(solver));
  auto w = std::make_unique<CoupledWorld>(std::move(solver));
  w->world.gravity = Vec3::Zero();
  return w;
}

// blobWorld(24, vx) with a 2 cm cube (R 3 mm, rho 2000) 0.0144 m ahead of the blob, free or
// fixed, coupled by pair(0.3) at barrier stiffness kc [N/m]; *cube is its index.
std::unique_ptr<CoupledWorld> blobAtCube(double vx, bool fixed, double kc, int* cube,
                                         mpm::Backend backend = mpm::Backend::Cpu,
                                         mpm::Precision precision = mpm::Precision::Double) {
  auto w = blobWorld(24, vx, backend, precision);
  *cube = addCube(*w, 0.02, 0.003, Vec3(0.115, 0.07, 0.07), 2000, fixed);
  sdem::BarrierPhys ph = pair(0.3);
  ph.barrierStiffness = kc;
  w->coupling.setPair(0, ph);
  return w;
}

// A blob thrown at 1 m/s at a free cube 0.0144 m ahead, 1500 steps of 1e-5 s: where the cube
// is, the impulse the flow gave it, the first step with a contact and the smallest particle
// approach step of the run.
struct BlobHit {
  Vec3 position, impulse;
  int firstContact = -1;
  double minApproach = std::numeric_limits<double>::infinity();
  std::vector<MpContactRecord> contacts;  // of the last step
};
BlobHit blobHitsCube(mpm::Backend backend, mpm::Precision precision, unsigned int deviceListCapacity = 0) {
  int cube;
  auto world = blobAtCube(1.0, false, 1e4, &cube, backend, precision);
  CoupledWorld& w = *world;
  w.coupling.setRecordContacts(true);
  if (deviceListCapacity > 0) w.coupling.setDeviceListCapacity(deviceListCapacity);
  BlobHit r;
  r.impulse = Vec3::Zero();
  for (int s = 0; s < 1500; ++s) {
    w.step(1e-5);
    if (r.firstContact < 0 && w.coupling.contactCount(cube) > 0) r.firstContact = s;
    r.impulse += 1e-5 * w.coupling.force(cube);
    r.minApproach = std::min(r.minApproach, w.coupling.particleApproachStep());
  }
  r.position = w.world.engine.position(cube);
  r.contacts = w.coupling.contacts();
  return r;
}

// The coupling with every backend's solver in both precisions (float: float contacts against
// float copies of the blocks and shapes, block sums in double).
class MpSdemCouplingInPrecision : public mpm::agreement::EveryBackend {};
INSTANTIATE_TEST_SUITE_P(EveryBackend, MpSdemCouplingInPrecision, ::testing::ValuesIn(mpm::agreement::everyKind()),
                         mpm::agreement::kindName);

}  // namespace

// A checkpoint (driver --restart) written while the blob presses a free cube against a fixed one
// and read back into a world built anew holds everything the steps carry: captured again it is
// the same to the last bit, and both worlds then take the same steps to the last bit, on every
// backend (on CUDA the histories come from and go back to the device, and the block sums and
// P2G have a fixed order).
class CoupledCheckpointEveryBackend : public mpm::agreement::EveryBackend {};
INSTANTIATE_TEST_SUITE_P(Kinds, CoupledCheckpointEveryBackend, ::testing::ValuesIn(mpm::agreement::everyKind()),
                         mpm::agreement::kindName);
TEST_P(CoupledCheckpointEveryBackend, RestoredWorldContinuesTheSameRunBitForBit) {
  auto build = [](std::unique_ptr<CoupledWorld> w) {
    addCube(*w, 0.02, 0.003, Vec3(0.115, 0.07, 0.07), 2000);
    addCube(*w, 0.02, 0.003, Vec3(0.1549, 0.07, 0.07), 2000, true);  // outer surfaces 0.1 mm into each other
    w->coupling.setPair(0, pair(0.3, 0.2));
    return w;
  };
  auto a = build(blobWorld(24, 1.0, backend(), precision()));
  a->world.engine.setState(0, Vec3(0.115, 0.07, 0.07), Quat::Identity(), Vec3::Zero(), Vec3(0.1, 0.2, 0.5));
  int s = 0;
  const double dt = 1e-5;
  do {
    a->step(dt);
  } while (!(a->coupling.contactCount(0) > 0 && std::isfinite(a->coupling.particleApproachStep())) && ++s < 1500);
  ASSERT_LT(s, 1500) << "the blob never touched the cube with a point still closing in";
  const CoupledCheckpoint c = captureCheckpoint(*a, 3, dt, {Quat::Identity(), Quat::Identity()});
  ASSERT_FALSE(c.historyIndex.empty());
  ASSERT_FALSE(c.sdemHistories.empty());
  ASSERT_TRUE(c.hasAngMom[0]);
  ASSERT_GT(c.sdemDamping + c.couplingDamping, 0.0);
  ASSERT_TRUE(std::isfinite(c.contactStep));
  const std::string path = (std::filesystem::temp_directory_path() / "mpmsdem_test_checkpoint.json").string();
  writeCheckpoint(path, c);
  const CoupledCheckpoint r = readCheckpoint(path);
  std::remove(path.c_str());

  mpm::ParticleSet ps;
  a->mpm().getParticles(ps);
  auto solver = this->solver(a->mpm().params());
  solver->setParticles(ps);
  solver->setClock(a->mpm().time(), a->mpm().steps());
  auto b = build(std::make_unique<CoupledWorld>(std::move(solver)));
  b->world.gravity = Vec3::Zero();
  restoreCheckpoint(r, *b);
  const CoupledCheckpoint again = captureCheckpoint(*b, 3, dt, r.referenceOrientations);
  EXPECT_EQ(again.time, c.time);
  EXPECT_EQ(again.worldTime, c.worldTime);
  EXPECT_EQ(again.contactStep, c.contactStep);
  EXPECT_EQ(again.contactStepLow.step, c.contactStepLow.step);
  EXPECT_EQ(again.contactStepLow.time, c.contactStepLow.time);
  EXPECT_EQ(again.particleApproachStep, c.particleApproachStep);
  for (std::size_t i = 0; i < c.pos.size(); ++i) {
    EXPECT_EQ(again.pos[i], c.pos[i]);
    EXPECT_EQ(again.ori[i].coeffs(), c.ori[i].coeffs());
    EXPECT_EQ(again.vel[i], c.vel[i]);
    EXPECT_EQ(again.angVel[i], c.angVel[i]);
    EXPECT_EQ(again.hasAngMom[i], c.hasAngMom[i]);
    EXPECT_EQ(again.angMom[i], c.angMom[i]);
  }
  // block-block histories come out of a hash map, in no particular order
  auto byKey = [](std::vector<sdem::ContactHistoryEntry> h) {
    auto tie = [](const sdem::ContactKey& k) {
      return std::make_tuple(k.bodyA, k.bodyB, static_cast<int>(k.kindA), static_cast<int>(k.kindB), k.indexA, k.indexB);
    };
    std::sort(h.begin(), h.end(), [&](const auto& x, const auto& y) { return tie(x.key) < tie(y.key); });
    return h;
  };
  const auto h0 = byKey(c.sdemHistories), h1 = byKey(again.sdemHistories);
  ASSERT_EQ(h1.size(), h0.size());
  for (std::size_t k = 0; k < h0.size(); ++k) {
    EXPECT_TRUE(h1[k].key == h0[k].key);
    EXPECT_EQ(h1[k].xi, h0[k].xi);
  }
  EXPECT_EQ(again.sdemFriction, c.sdemFriction);
  EXPECT_EQ(again.sdemDamping, c.sdemDamping);
  EXPECT_EQ(again.historyIndex, c.historyIndex);
  EXPECT_EQ(again.historyKey, c.historyKey);
  EXPECT_EQ(again.historyXi, c.historyXi);
  EXPECT_EQ(again.couplingFriction, c.couplingFriction);
  EXPECT_EQ(again.couplingDamping, c.couplingDamping);
  ASSERT_EQ(c.couplingImpulse.size(), 2u * CouplingReport::kImpulseValues);
  EXPECT_GT(Vec3(c.couplingImpulse[0], c.couplingImpulse[1], c.couplingImpulse[2]).norm(), 0.0);
  EXPECT_EQ(again.couplingImpulse, c.couplingImpulse);
  // the free cube was first touched within the run; the same bits (or NaN, not yet) come back
  ASSERT_EQ(c.couplingFirstContact.size(), 2u);
  EXPECT_GT(c.couplingFirstContact[0], 0.0);
  EXPECT_LE(c.couplingFirstContact[0], c.time);
  ASSERT_EQ(again.couplingFirstContact.size(), 2u);
  for (int i = 0; i < 2; ++i)
    EXPECT_TRUE(sameBits(again.couplingFirstContact[i], c.couplingFirstContact[i])) << "block " << i;

  for (int k = 0; k < 200; ++k) {
    a->step(dt);
    b->step(dt);
  }
  EXPECT_GT((a->world.engine.position(0) - c.pos[0]).norm(), 1e-4);  // the cube was pushed on
  EXPECT_EQ(a->world.engine.position(0), b->world.engine.position(0));
  EXPECT_EQ(a->world.engine.orientation(0).coeffs(), b->world.engine.orientation(0).coeffs());
  EXPECT_EQ(a->world.engine.angularVelocity(0), b->world.engine.angularVelocity(0));
  EXPECT_EQ(a->coupling.force(0), b->coupling.force(0));
  EXPECT_EQ(a->coupling.impulse(0), b->coupling.impulse(0));
  EXPECT_EQ(a->coupling.angularImpulse(0), b->coupling.angularImpulse(0));
  EXPECT_EQ(a->coupling.firstContact(0), c.couplingFirstContact[0]);  // kept, not set again
  for (int i = 0; i < 2; ++i) EXPECT_TRUE(sameBits(a->coupling.firstContact(i), b->coupling.firstContact(i)));
  mpm::ParticleSet pa, pb;
  a->mpm().getParticles(pa);
  b->mpm().getParticles(pb);
  mpm::agreement::expectBitIdentical(pa, pb);
}

// When the flow first touched a block: the start of the first step whose flow force on it is
// not zero (the flow's time before that step), NaN before it, and never set again. A restart keeps
// it; one from a state that did not keep it (a checkpoint written before it was) leaves a block
// already touched without one for good, and one not touched yet gets it at the same step as the
// run that was not stopped.
TEST(CoupledWorld, FirstContactIsTheStartOfTheFirstStepWithAFlowForce) {
  int cube;
  auto w = blobAtCube(1.0, false, 1e4, &cube);
  const double dt = 1e-5;
  struct State {
    CoupledCheckpoint c;
    mpm::ParticleSet ps;
    double time;
    long steps;
  };
  auto state = [&] {
    State s{captureCheckpoint(*w, 0, dt, {Quat::Identity()}), {}, w->mpm().time(), w->mpm().steps()};
    w->mpm().getParticles(s.ps);
    return s;
  };
  State before;  // the state one step before the touch
  double touch = std::numeric_limits<double>::quiet_NaN();
  for (int s = 0; s < 1500 && std::isnan(touch); ++s) {
    if (s > 0) EXPECT_TRUE(std::isnan(w->coupling.firstContact(cube))) << "step " << s;
    before = state();
    w->step(dt);
    if (w->coupling.force(cube).norm() > 0) touch = before.time;
  }
  ASSERT_FALSE(std::isnan(touch)) << "the blob never touched the cube";
  EXPECT_EQ(w->coupling.firstContact(cube), touch);
  EXPECT_GT(touch, 100 * dt);  // the blob closes 1 cm first: not the run's first steps
  for (int s = 0; s < 100; ++s) w->step(dt);
  EXPECT_EQ(w->coupling.firstContact(cube), touch);
  const State after = state();

  // restarts from checkpoints that did not keep the first contacts
  auto restarted = [&](const State& s) {
    int unused;
    auto r = blobAtCube(1.0, false, 1e4, &unused);
    r->mpm().setParticles(s.ps);
    r->mpm().setClock(s.time, s.steps);
    CoupledCheckpoint c = s.c;
    c.couplingFirstContact.clear();
    restoreCheckpoint(c, *r);
    return r;
  };
  auto fromBefore = restarted(before);
  fromBefore->step(dt);
  EXPECT_EQ(fromBefore->coupling.firstContact(cube), touch);  // not touched yet: set as in the whole run
  auto fromAfter = restarted(after);
  ASSERT_GT(after.c.couplingImpulse[0], 0.0);
  const double pushed = after.c.couplingImpulse[0];
  for (int s = 0; s < 100; ++s) {
    fromAfter->step(dt);
    EXPECT_TRUE(std::isnan(fromAfter->coupling.firstContact(cube))) << "step " << s;  // touched before: not kept
  }
  EXPECT_GT(fromAfter->coupling.impulse(cube)[0], pushed);  // the flow went on pushing
}

// A coupled run started from another run's flow (driver --flow-from): a blob falls onto a fixed
// bed and slides along it at 1 m/s towards a cube spinning in place 9 cm ahead (blocks without
// gravity). The run of the bed alone, stopped once the blob rests on the bed but is still
// short of the cube, with the cube's steps before it taken alone, goes on as the run of bed and
// cube from the start, to the last bit, on every backend; a state in which the blob already
// reaches the cube, and worlds that do not fit, are refused.
class StartFromFlowEveryBackend : public mpm::agreement::EveryBackend {};
INSTANTIATE_TEST_SUITE_P(Kinds, StartFromFlowEveryBackend, ::testing::ValuesIn(mpm::agreement::everyKind()),
                         mpm::agreement::kindName);
TEST_P(StartFromFlowEveryBackend, GoesOnAsTheRunFromTheStart) {
  const double dt = 1e-5;
  const long ahead = 3500, later = 6000, end = 10000;
  auto withBed = [](std::unique_ptr<CoupledWorld> w) {
    w->world.engine.addMaterial(sdem::SdemMaterial{});
    static const auto bed = SpheroPolyhedron::box(Vec3(0.11, 0.06, 0.01), 0.003);
    const int i = w->world.engine.addBody(bed, 0, 1.0, Vec3::Ones(), 7);
    w->world.engine.setFixed(i, true);
    w->world.engine.setState(i, Vec3(0.12, 0.07, 0.0385), Quat::Identity(), Vec3::Zero(), Vec3::Zero());
    w->coupling.setPair(0, pair(0.3, 0.2));
    return w;
  };
  auto withCube = [](std::unique_ptr<CoupledWorld> w) {
    const int i = addCube(*w, 0.01, 0.002, Vec3(0.17, 0.07, 0.07), 2000);
    w->world.engine.setState(i, Vec3(0.17, 0.07, 0.07), Quat::Identity(), Vec3::Zero(), Vec3(0, 0, 5));
    return w;
  };
  auto blob = [&] {  // blobWorld's, under gravity: it stays on the bed
    auto prm = gridParams({24, 14, 14});
    prm.gravity = {0, 0, -9.81};
    mpm::ParticleSet ps;
    mpm::seedBox(prm, {0.04, 0.05, 0.05}, {0.08, 0.09, 0.09}, 8, ps);
    for (std::size_t p = 0; p < ps.size(); ++p) ps.v[3 * p] = 1.0;
    auto solver = this->solver(prm);
    solver->setParticles(ps);
    auto w = std::make_unique<CoupledWorld>(std::move(solver));
    w->world.gravity = Vec3::Zero();
    return w;
  };
  auto fresh = [&](const mpm::MpmParams& p) {
    auto w = std::make_unique<CoupledWorld>(this->solver(p));
    w->world.gravity = Vec3::Zero();
    return w;
  };

  auto whole = withCube(withBed(blob()));
  double cubeImpulse = 0;
  for (long k = 0; k < end; ++k) {
    whole->step(dt);
    cubeImpulse += dt * whole->coupling.force(1).norm();
  }
  ASSERT_GT(cubeImpulse, 1e-4) << "the blob never hit the cube";

  auto source = withBed(blob());
  mpm::ParticleSet ahead0, later0;
  CoupledCheckpoint atAhead, atLater;
  for (long k = 1; k <= later; ++k) {
    source->step(dt);
    if (k == ahead || k == later) {
      (k == ahead ? atAhead : atLater) = captureCheckpoint(*source, 0, dt, {Quat::Identity()});
      source->mpm().getParticles(k == ahead ? ahead0 : later0);
    }
  }
  ASSERT_FALSE(atAhead.historyIndex.empty()) << "the blob does not rest on the bed";

  const mpm::MpmParams& prm = whole->mpm().params();
  auto started = withCube(withBed(fresh(prm)));
  mpm::WholeParticleSet particles(ahead0);
  startFromFlow(*started, particles, ahead, atAhead.time, dt, &atAhead, 2 * prm.dx);
  for (long k = ahead; k < end; ++k) started->step(dt);
  EXPECT_EQ(started->mpm().steps(), whole->mpm().steps());
  EXPECT_EQ(started->time(), whole->time());
  EXPECT_EQ(started->world.engine.position(1), whole->world.engine.position(1));
  EXPECT_EQ(started->world.engine.orientation(1).coeffs(), whole->world.engine.orientation(1).coeffs());
  EXPECT_EQ(started->world.engine.angularVelocity(1), whole->world.engine.angularVelocity(1));
  EXPECT_EQ(started->coupling.force(1), whole->coupling.force(1));
  EXPECT_EQ(started->coupling.frictionDissipation(), whole->coupling.frictionDissipation());
  EXPECT_EQ(started->coupling.impulse(0), whole->coupling.impulse(0));  // the bed's, kept from the source
  EXPECT_EQ(started->coupling.impulse(1), whole->coupling.impulse(1));
  EXPECT_EQ(started->contactStepLow().step, whole->contactStepLow().step);
  mpm::ParticleSet pa, pb;
  whole->mpm().getParticles(pa);
  started->mpm().getParticles(pb);
  mpm::agreement::expectBitIdentical(pa, pb);

  auto refused = [&](const char* what, long step, double time, const CoupledCheckpoint& c, mpm::ParticleSet& ps,
                     bool bedFixed) {
    auto w = withCube(withBed(fresh(prm)));
    if (!bedFixed) w->world.engine.setFixed(0, false);
    mpm::WholeParticleSet p(ps);
    try {
      startFromFlow(*w, p, step, time, dt, &c, 2 * prm.dx);
      ADD_FAILURE() << "started: " << what;
    } catch (const ParameterError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  refused("the flow had reached it", later, atLater.time, atLater, later0, true);
  refused("that run took other steps", ahead, atAhead.time + dt, atAhead, ahead0, true);
  refused("must be fixed", ahead, atAhead.time, atAhead, ahead0, false);
}

// A checkpoint file that is missing or not one is refused by name.
TEST(CoupledCheckpoint, BadFilesAreRefusedByName) {
  const std::string path = (std::filesystem::temp_directory_path() / "mpmsdem_test_bad_checkpoint.json").string();
  std::remove(path.c_str());
  try {
    readCheckpoint(path);
    ADD_FAILURE() << "a missing checkpoint was read";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("is missing"), std::string::npos) << e.what();
  }
  for (const char* text : {"{\"format\": \"other\"}", "{\"format\": \"mpmsdem-driver-coupled-1\"}", "[1, 2"}) {
    std::ofstream(path) << text;
    try {
      readCheckpoint(path);
      ADD_FAILURE() << "read " << text;
    } catch (const ParameterError& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
  }
  std::remove(path.c_str());
}

// The run's lowest contact step is the smallest coupledContactStep after any step, with the
// time it was reached: inf before the blob reaches the cube, then finite and never above the
// step of the first contact.
TEST(CoupledWorld, RecordsTheLowestContactStepOfTheRun) {
  int cube;
  auto world = blobAtCube(1.0, false, 1e4, &cube);
  CoupledWorld& w = *world;
  double low = std::numeric_limits<double>::infinity(), lowTime = 0, first = 0;
  for (int s = 0; s < 1500; ++s) {
    w.step(1e-5);
    const double c = coupledContactStep(w.world.engine, w.coupling);
    if (w.coupling.contactCount(cube) == 0 && low == std::numeric_limits<double>::infinity()) {
      ASSERT_EQ(w.contactStepLow().step, std::numeric_limits<double>::infinity()) << "step " << s;
      ASSERT_TRUE(std::isnan(w.contactStepLow().time));
    }
    if (c < low) {
      if (!std::isfinite(low)) first = c;
      low = c;
      lowTime = w.mpm().time();
    }
  }
  ASSERT_TRUE(std::isfinite(low));
  EXPECT_EQ(w.contactStepLow().step, low);
  EXPECT_EQ(w.contactStepLow().time, lowTime);
  EXPECT_LE(low, first);
  EXPECT_GT(lowTime, 0.0);
  EXPECT_LT(lowTime, 1500 * 1e-5);
}

#ifdef MPMSDEM_WITH_CGAL
// The stored table that builds without CGAL use is the hull CGAL builds today, and fromCore
// gives back its geometry and mass properties (a table written in the body frame stays there).
TEST(ShapeTable, StoredHullTableIsTheCgalHull) {
#if defined(__SANITIZE_ADDRESS__)  // gcc -fsanitize=address (make test-sanitize)
  // Measured 2026-11-29: the -O1 sanitizer build makes the same hull (volume, inertia and frame
  // pass) but numbers two of its vertices the other way round (vertices 0 and 1, 0.067 m apart,
  // and the face loops with them). The numbering pinned here is the optimised build's, which
  // wrote the stored table and which the driver-only build has to match.
  GTEST_SKIP() << "the vertex numbering is the optimised build's (make test runs it in the plain build)";
#endif
  const auto built = testShapes()[1];
  const auto stored = storedHull();
  ASSERT_EQ(built->vertices.size(), stored->vertices.size());
  ASSERT_EQ(built->faces.size(), stored->faces.size());
  for (std::size_t i = 0; i < built->vertices.size(); ++i)
    EXPECT_LE((built->vertices[i] - stored->vertices[i]).norm(), 1e-15) << i;
  for (std::size_t f = 0; f < built->faces.size(); ++f) EXPECT_EQ(built->faces[f].loop, stored->faces[f].loop) << f;
  EXPECT_NEAR(stored->volume, built->volume, 1e-14 * built->volume);
  EXPECT_LE((stored->inertiaPerDensity - built->inertiaPerDensity).norm(), 1e-12 * built->inertiaPerDensity.norm());
  EXPECT_LE(stored->framePosition.norm(), 1e-15);
  EXPECT_LE(stored->frameOrientation.angularDistance(Quat::Identity()), 1e-12);
}
#endif

// fromCore refuses tables that are not closed, consistently oriented solids, naming the entry.
TEST(ShapeTable, FromCoreRefusesBadTables) {
  const std::vector<Vec3> v{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  const std::vector<std::vector<int>> tet{{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  EXPECT_NO_THROW(SpheroPolyhedron::fromCore(v, tet, 0.1, true));
  auto refused = [&](const std::vector<std::vector<int>>& faces, const std::string& what, bool convex = true) {
    try {
      SpheroPolyhedron::fromCore(v, faces, 0.1, convex);
    } catch (const ParameterError& e) {
      return std::string(e.what()).find(what) != std::string::npos;
    }
    return false;
  };
  EXPECT_TRUE(refused({{0, 2, 1}, {0, 1, 3}, {0, 3, 2}}, "at least 4"));
  EXPECT_TRUE(refused({{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {0, 2, 3}}, "core.faces[3]"));      // side used twice
  EXPECT_TRUE(refused({{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}}, "positive"));           // inward
  EXPECT_TRUE(refused({{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 7}}, "vertex index 7"));
  EXPECT_THROW(SpheroPolyhedron::fromCore(v, tet, -0.1, true), ParameterError);
  // a mass from the table: a unit right tetrahedron's core has volume 1/6
  const auto s = SpheroPolyhedron::fromCore(v, tet, 1e-6, true);
  EXPECT_NEAR(s->volume, 1.0 / 6.0, 1e-5);
}

TEST(ShapeTable, ClosestPointMatchesShapeQuery) {
  const auto shapes = testShapes();
  sdem::ShapeTable table;
  for (const auto& s : shapes) table.add(*s);
  const auto view = table.view();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.12, 0.12);
  int kinds[3] = {0, 0, 0};
  for (int s = 0; s < 3; ++s)
    for (int k = 0; k < 3000; ++k) {
      const Vec3 p(u(rng), u(rng), u(rng));
      const auto ref = shapes[s]->closestPoint(p);
      const auto q = sdem::closestPointOnCore(view, s, mpmsdem::Vec3T<double>{p[0], p[1], p[2]});
      ASSERT_NEAR(q.distance, ref.distance, 1e-14) << "shape " << s;
      ASSERT_LE(sdem::coreDistanceLowerBound(view, s, mpmsdem::Vec3T<double>{p[0], p[1], p[2]}), ref.distance + 1e-14);
      ASSERT_EQ(q.featureKind, ref.featureKind) << "shape " << s;
      ASSERT_EQ(q.featureIndex, ref.featureIndex) << "shape " << s;
      for (int d = 0; d < 3; ++d) ASSERT_NEAR(q.closest[d], ref.closest[d], 1e-14);
      ++kinds[q.featureKind];
    }
  for (int k = 0; k < 3; ++k) EXPECT_GT(kinds[k], 100) << "feature kind " << k << " hardly sampled";
}

// The float instantiation (what the CUDA float backend runs) against double.
TEST(ShapeTable, FloatFormulasAgreeWithDouble) {
  const auto shapes = testShapes();
  sdem::ShapeTable table;
  for (const auto& s : shapes) table.add(*s);
  std::vector<float> vf(table.vertex.begin(), table.vertex.end()), nf(table.faceNormal.begin(), table.faceNormal.end()),
      of(table.faceOffset.begin(), table.faceOffset.end()), rf(table.sweepRadius.begin(), table.sweepRadius.end()),
      bf(table.boundingRadius.begin(), table.boundingRadius.end());
  const auto dv = table.view();
  sdem::ShapeTableView<float> fv{dv.numShapes,         vf.data(),           nf.data(),          of.data(),
                                 dv.faceLoopStart,     dv.loopVertex,       dv.loopEdge,        dv.shapeFaceStart,
                                 dv.shapeVertexStart,  dv.shapeEdgeStart,   rf.data(),          bf.data(),
                                 dv.convex};
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.12, 0.12);
  for (int s = 0; s < 3; ++s)
    for (int k = 0; k < 500; ++k) {
      const Vec3 p(u(rng), u(rng), u(rng));
      const auto d = sdem::closestPointOnCore(dv, s, mpmsdem::Vec3T<double>{p[0], p[1], p[2]});
      const auto f = sdem::closestPointOnCore(fv, s, mpmsdem::Vec3T<float>{float(p[0]), float(p[1]), float(p[2])});
      EXPECT_NEAR(f.distance, d.distance, 2e-6 * 0.12);
    }
  // the law: float within 1e-5 relative of double over the barrier's range
  const sdem::BarrierCoulombPhys<double> pd{1e4, 0.4, 0.3, 0.1, 0.1};
  const sdem::BarrierCoulombPhys<float> pf{1e4f, 0.4f, 0.3f, 0.1f, 0.1f};
  for (double x : {1e-3, 0.1, 0.5, 0.9}) {
    const double R = 0.008, delta = x * R;
    double xid[3] = {1e-5, 0, 0};
    float xif[3] = {1e-5f, 0, 0};
    const auto rd = sdem::barrierCoulomb(pd, R, delta, mpmsdem::Vec3T<double>{0, 0, 1}, mpmsdem::Vec3T<double>{0.1, 0.02, -0.3},
                                         0.01, 1e-5, xid);
    const auto rf2 = sdem::barrierCoulomb(pf, float(R), float(delta), mpmsdem::Vec3T<float>{0, 0, 1},
                                          mpmsdem::Vec3T<float>{0.1f, 0.02f, -0.3f}, 0.01f, 1e-5f, xif);
    EXPECT_NEAR(rf2.normalForce, rd.normalForce, 1e-5 * rd.normalForce) << "x = " << x;
    EXPECT_NEAR(rf2.kn, rd.kn, 1e-5 * rd.kn) << "x = " << x;
    EXPECT_NEAR(rf2.tangential.x, rd.tangential.x, 1e-5 * std::abs(rd.tangential.x) + 1e-12);
  }
}

// The particle loop's memo (the radius of the last V0 met, the face plane that last culled a
// point) gives exactly what a fresh memo per particle gives: the same forces, contacts,
// histories and approach bounds, to the last bit, over two steps (so histories are reused) of
// 36,000 points around three blocks (box, hull, non-convex L prism, turned) with two volumes.
TEST(CouplingKernels, LoopMemoGivesExactlyWhatAFreshMemoGives) {
  const auto shapes = testShapes();
  sdem::ShapeTable table;
  for (const auto& sh : shapes) table.add(*sh);
  const auto S = table.view();
  std::vector<BlockState<double>> blocks(3);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.4, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  for (int b = 0; b < 3; ++b) {
    BlockState<double>& k = blocks[b];
    for (int d = 0; d < 3; ++d) {
      k.pos[d] = (d == 0 ? 0.3 * b : 0.0);
      k.vel[d] = 0.1 * (d - 1);
      k.angVel[d] = 0.5 * d;
      for (int e = 0; e < 3; ++e) k.rot[3 * d + e] = R(d, e);
    }
    k.mass = 2.0;
    k.reach = S.boundingRadius[b];
    k.shape = b;
    k.phys = 0;
    k.fixed = b == 2;
  }
  const sdem::BarrierCoulombPhys<double> phys{1e4, 0.4, 0.3, 0.0, 0.1};
  const int binSlot[1] = {0}, binFirst[2] = {0, 3}, binBlocks[3] = {0, 1, 2};
  const BinGridView bins{{-1, -1, -1}, 0.5, {1, 1, 1}, binSlot, binFirst, binBlocks, 0.01};
  // A jittered lattice in seeding order (neighbours follow each other, as in a solver's
  // storage) of points whose centre stays clear of every core over both steps (else the step
  // fails), with random velocities and runs of equal volumes.
  auto clear = [&](const Vec3& xw) {
    for (const auto& k : blocks) {
      const Vec3 r = R.transpose() * (xw - Vec3(k.pos[0], k.pos[1], k.pos[2]));
      if (sdem::closestPointOnCore(S, k.shape, mpmsdem::Vec3T<double>{r[0], r[1], r[2]}).distance < 3e-3) return false;
    }
    return true;
  };
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> jitter(-2e-3, 2e-3), uv(-2, 2);
  std::vector<double> x0[3], v[3], mass, vol0;
  for (int i = 0; i < 90; ++i)
    for (int j = 0; j < 20; ++j)
      for (int k = 0; k < 20; ++k) {
        const Vec3 xp(-0.15 + 0.01 * i + jitter(rng), -0.1 + 0.01 * j + jitter(rng), -0.1 + 0.01 * k + jitter(rng));
        const Vec3 vp(uv(rng), uv(rng), uv(rng));
        if (!clear(xp) || !clear(xp + 1e-3 * vp)) continue;
        for (int d = 0; d < 3; ++d) {
          x0[d].push_back(xp[d]);
          v[d].push_back(vp[d]);
        }
        vol0.push_back(i % 2 ? 1e-6 / 8 : 1e-6);
        mass.push_back(1600 * vol0.back());
      }
  const int n = static_cast<int>(vol0.size()), slots = 4;
  struct Run {
    std::vector<double> force[3], xi;
    std::vector<long long> key;
    std::vector<unsigned> written;
    std::vector<double> contactForces;
    std::vector<double> approach;  // per particle and step
    int overflow = 0;
  };
  auto run = [&](bool shareMemo, Run& r) {
    std::vector<double> moved[3] = {x0[0], x0[1], x0[2]};
    for (int d = 0; d < 3; ++d) r.force[d].assign(n, 0.0);
    r.key.assign(slots * n, -1);
    r.written.assign(n, 0);
    r.xi.assign(3 * slots * n, 0.0);
    CouplingParticles<double> P;
    for (int d = 0; d < 3; ++d) {
      P.x[d] = x0[d].data();
      P.v[d] = v[d].data();
      P.force[d] = r.force[d].data();
    }
    P.mass = mass.data();
    P.vol0 = vol0.data();
    P.id = nullptr;
    auto sink = [&r](const MpContact<double>& c) {
      for (int d = 0; d < 3; ++d) r.contactForces.push_back(c.force[d]);
    };
    for (int step = 0; step < 2; ++step) {
      const HistoryView<double> H{r.key.data(), r.xi.data(), r.written.data(), static_cast<unsigned>(step + 1), slots};
      CouplingLoopMemo<double> shared;
      for (int p = 0; p < n; ++p) {
        CouplingLoopMemo<double> fresh;
        int bad = -1;
        double approach = std::numeric_limits<double>::infinity();
        ASSERT_EQ(coupleParticle(p, P, blocks.data(), S, &phys, bins, H, 2e-3, 0.5, sink, &bad, &r.overflow,
                                 &approach, shareMemo ? shared : fresh),
                  kCoupleOk);
        r.approach.push_back(approach);
      }
      if (shareMemo) EXPECT_GE(shared.cullBlock, 0) << "the face memo never culled";
      for (int p = 0; p < n; ++p)
        for (int d = 0; d < 3; ++d) moved[d][p] = x0[d][p] + 1e-3 * v[d][p];  // step 1 from moved points
      for (int d = 0; d < 3; ++d) P.x[d] = moved[d].data();
    }
  };
  Run a, b;
  run(true, a);
  run(false, b);
  ASSERT_GT(a.contactForces.size(), 3u * 200) << "too few contacts to test";
  EXPECT_GT(std::count_if(a.approach.begin(), a.approach.end(), [](double t) { return std::isfinite(t); }), 20)
      << "too few points closing on a block to test";
  EXPECT_EQ(a.contactForces, b.contactForces);
  for (int d = 0; d < 3; ++d) EXPECT_EQ(a.force[d], b.force[d]);
  EXPECT_EQ(a.key, b.key);
  EXPECT_EQ(a.written, b.written);
  EXPECT_EQ(a.xi, b.xi);
  EXPECT_EQ(a.approach, b.approach);
  EXPECT_EQ(a.overflow, b.overflow);
}

// A contact's tangential memory lasts only while the contact does: a point sliding on a fixed
// box builds its spring over consecutive steps (the third step's force differs from the
// first's); once it has left the box for a step, in the box's bins or in a bin without blocks,
// it comes back with a spring at rest: the first step's force to the last bit.
TEST(CouplingKernels, TangentialHistoryEndsWithTheContact) {
  sdem::ShapeTable table;
  table.add(*testShapes()[0]);
  const auto S = table.view();
  BlockState<double> box{};
  box.rot[0] = box.rot[4] = box.rot[8] = 1;
  box.mass = 1;
  box.reach = S.boundingRadius[0];
  box.fixed = 1;
  const sdem::BarrierCoulombPhys<double> phys{1e4, 0.5, 0.3, 0.0, 0.0};
  // Bins of 0.2 m along x from -0.2: the first two list the box, the third none.
  const int binSlot[3] = {0, 1, -1}, binFirst[3] = {0, 1, 2}, binBlocks[2] = {0, 0};
  const BinGridView bins{{-0.2, -0.2, -0.2}, 5.0, {3, 1, 1}, binSlot, binFirst, binBlocks, 0.01};
  const double vol0 = 1e-6, mass = 1.6e-3;
  const double rp = std::cbrt(3 * vol0 / (4 * M_PI));
  const double top = 1 - sdem::closestPointOnCore(S, 0, mpmsdem::Vec3T<double>{0, 0, 1}).distance;
  const double onTop = top + S.sweepRadius[0] + rp - 1e-3;  // 1 mm overlap
  const double vx = 0.05, dt = 1e-3;  // the spring gains about 0.1 N a step, below mu F_n = 1.4 N
  auto forcesAlong = [&](const std::vector<std::array<double, 3>>& path) {
    double x[3], v[3] = {vx, 0, 0}, f[3];
    std::vector<long long> key(2, -1);
    std::vector<double> xi(6, 0.0);
    std::vector<unsigned> written(1, 0);
    CouplingParticles<double> P;
    for (int d = 0; d < 3; ++d) {
      P.x[d] = &x[d];
      P.v[d] = &v[d];
      P.force[d] = &f[d];
    }
    P.mass = &mass;
    P.vol0 = &vol0;
    P.id = nullptr;
    std::vector<std::array<double, 3>> out;
    for (std::size_t step = 0; step < path.size(); ++step) {
      for (int d = 0; d < 3; ++d) {
        x[d] = path[step][d];
        f[d] = 0;
      }
      const HistoryView<double> H{key.data(), xi.data(), written.data(), static_cast<unsigned>(step + 1), 2};
      auto sink = [](const MpContact<double>&) {};
      int bad = -1, over = 0;
      double approach = std::numeric_limits<double>::infinity();
      CouplingLoopMemo<double> memo;
      EXPECT_EQ(coupleParticle(0, P, &box, S, &phys, bins, H, dt, 0.5, sink, &bad, &over, &approach, memo),
                kCoupleOk);
      out.push_back({f[0], f[1], f[2]});
    }
    return out;
  };
  const std::array<double, 3> a{0.0, 0.0, onTop}, b{vx * dt, 0.0, onTop};
  const auto kept = forcesAlong({a, b, a});
  ASSERT_GT(kept[0][2], 1.0) << "no contact";  // the box pushes the point up (2.8 N at 1 mm)
  ASSERT_LT(kept[0][0], 0.0) << "no tangential force";
  EXPECT_LT(kept[2][0], kept[0][0] - 1e-3 * std::abs(kept[0][0])) << "the spring did not build up";
  const std::array<double, 3> above{0.0, 0.0, onTop + 0.05}, farAway{0.3, 0.0, onTop};
  for (const auto& away : {above, farAway}) {
    const auto back = forcesAlong({a, b, away, a});
    EXPECT_EQ(back[2][0], 0.0);
    EXPECT_EQ(back[2][2], 0.0);
    for (int d = 0; d < 3; ++d) EXPECT_EQ(back[3][d], kept[0][d]) << "component " << d;
  }
}

// Zero gravity: a granular blob thrown at a free cube. The particles' forces sum to minus the
// block's at every step (Eqs 17-18), and the total momentum of particles + block is conserved.
TEST_P(MpSdemCouplingInPrecision, ImpulseBalanceAndMomentumConservation) {
  auto world = blobWorld(24, 1.0, backend(), precision());
  CoupledWorld& w = *world;
  const int cube = addCube(w, 0.02, 0.003, Vec3(0.125, 0.07, 0.07), 2000);
  w.coupling.setPair(0, pair(0.3));
  const Vec3 p0 = particleMomentum(w.mpm()) + w.world.engine.mass(cube) * w.world.engine.velocity(cube);
  const Vec3 v0 = w.world.engine.velocity(cube);
  const double dt = 1e-5;
  double maxForce = 0;
  Vec3 stepSum = Vec3::Zero();
  int steps = 0, contactSteps = 0;
  for (; steps < 4000; ++steps) {
    w.step(dt);
    if (w.coupling.contactCount(cube) > 0) ++contactSteps;
    maxForce = std::max(maxForce, w.coupling.force(cube).norm());
    stepSum += dt * w.coupling.force(cube);
    if (w.world.engine.velocity(cube).x() > 0.5) break;
  }
  ASSERT_GT(contactSteps, 50) << "the blob never hit the block";
  EXPECT_GT(w.world.engine.velocity(cube).x(), 0.1);
  // The impulse the coupling keeps is the flow's only action on the free cube: m (v1 - v0), both
  // summed in double step by step (a few ulps of |J| over the steps).
  const Vec3 J = w.coupling.impulse(cube), dp = w.world.engine.mass(cube) * (w.world.engine.velocity(cube) - v0);
  EXPECT_NEAR((J - stepSum).norm(), 0.0, 1e-12 * J.norm());
  EXPECT_NEAR((J - dp).norm(), 0.0, 1e-9 * J.norm()) << "J " << J.transpose() << " m dv " << dp.transpose();
  const Vec3 p1 = particleMomentum(w.mpm()) + w.world.engine.mass(cube) * w.world.engine.velocity(cube);
  // Float: each MPM step leaves every particle velocity with a rounding of at most about eps/2
  // of |v| <= 1 m/s, of the same sign for all in the worst case (the contact forces reach the
  // block in double): |dp| / |p0| <= steps eps / 2, 2.4e-4 over 4000 steps (measured 8e-7).
  // In double that is below the round-off of this check's own sums: 1e-9 there.
  const double tol = std::max(1e-9, steps * 0.5 * mpm::agreement::roundOff(precision()));
  std::printf("%s: momentum change %.3e of p0 after %d steps, tolerance %.2e\n", w.mpm().name().c_str(),
              (p1 - p0).norm() / p0.norm(), steps, tol);
  EXPECT_NEAR((p1 - p0).norm() / p0.norm(), 0.0, tol) << "p0 " << p0.transpose() << " p1 " << p1.transpose();
  EXPECT_GT(maxForce, 0.0);
}

// Impulse to the particles' force slots = - impulse to the block, step by step (round-off).
TEST_P(MpSdemCouplingInPrecision, ParticleForcesBalanceBlockForce) {
  auto prm = gridParams({20, 14, 14});
  mpm::ParticleSet ps;
  mpm::seedBox(prm, {0.04, 0.05, 0.05}, {0.08, 0.09, 0.09}, 8, ps);
  for (std::size_t p = 0; p < ps.size(); ++p) {
    ps.v[3 * p] = 1.5;
    ps.v[3 * p + 2] = 0.2 * (ps.x[3 * p + 1] - 0.07) / 0.02;
  }
  auto flow = solver(prm);
  flow->setParticles(ps);
  CoupledWorld w(std::move(flow));
  w.world.gravity = Vec3::Zero();
  const int cube = addCube(w, 0.02, 0.003, Vec3(0.12, 0.07, 0.07), 2000, true);
  w.coupling.setPair(0, pair(0.5));
  // A particle's force is the sum of its contacts' forces rounded to T, at most twice (history
  // slots 2), and the block takes each contact's force in double: the balance holds to
  // 2 eps of the sum of |force| in float; in double to the round-off of this check's sums.
  const double tol = std::max(1e-13, 2 * mpm::agreement::roundOff(precision()));
  int checked = 0;
  for (int s = 0; s < 3000 && checked < 200; ++s) {
    w.coupling.computeForces(w.mpm(), 1e-5);
    mpm::ParticleSet now;
    w.mpm().getParticles(now);
    Vec3 fp = Vec3::Zero();
    double scale = 0;
    for (std::size_t p = 0; p < now.size(); ++p)
      for (int d = 0; d < 3; ++d) {
        fp[d] += now.fext[3 * p + d];
        scale += std::abs(now.fext[3 * p + d]);
      }
    if (scale > 0) {
      EXPECT_NEAR((fp + w.coupling.force(cube)).norm(), 0.0, tol * scale);
      EXPECT_NEAR((w.coupling.faceForce(cube) + w.coupling.edgeForce(cube) - w.coupling.force(cube)).norm(), 0.0,
                  1e-13 * scale);
      ++checked;
    }
    w.mpm().step(1e-5);
  }
  EXPECT_GE(checked, 200);
}

// A cube set on a granular layer under gravity settles and the flow carries its weight.
TEST(MpSdemCoupling, BlockRestingOnGranularLayerCarriesItsWeight) {
  auto prm = gridParams({12, 12, 10});
  prm.gravity = {0, 0, -9.81};
  prm.walls[4].friction = 0.5;
  mpm::ParticleSet ps;
  const double top = 0.05;
  mpm::seedBox(prm, {0.02, 0.02, 0.02}, {0.10, 0.10, top}, 8, ps);
  auto solver = mpm::makeSolver(prm);
  solver->setParticles(ps);
  CoupledWorld w(std::move(solver));
  const double h = 0.02, R = 0.002;
  const double rp = std::cbrt(3 * ps.volume0[0] / (4 * M_PI));
  // the top particles sit a quarter cell below the layer's surface
  const int cube = addCube(w, h, R, Vec3(0.06, 0.06, top - 0.0025 + rp + h + 1e-4), 2500);
  w.coupling.setPair(0, pair(0.4, 0.5));
  const double dt = 1e-4;
  const double weight = w.world.engine.mass(cube) * 9.81;
  double sum = 0, zSettled = 0;
  int n = 0;
  for (int s = 0; s < 3000; ++s) {
    ASSERT_LE(dt, w.criticalTimeStep()) << "step " << s;
    w.step(dt);
    if (s == 2000) zSettled = w.world.engine.position(cube).z();
    if (s >= 2000) {
      sum += w.coupling.force(cube).z();
      ++n;
    }
  }
  EXPECT_NEAR(sum / n, weight, 0.02 * weight);
  // settled: over the last 0.1 s it sinks less than a tenth of a material point's radius
  // (the elastic layer still rings at ~1 mm/s and creeps slowly under the block)
  EXPECT_NEAR(w.world.engine.position(cube).z(), zSettled, 0.1 * rp);
  EXPECT_GT(w.coupling.contactCount(cube), 16);
}

TEST(MpSdemCoupling, BlockSumsDoNotDependOnThreadCount) {
  auto run = [](int threads) {
    omp_set_num_threads(threads);
    auto world = blobWorld(20, 1.5);
    CoupledWorld& w = *world;
    const int cube = addCube(w, 0.02, 0.003, Vec3(0.108, 0.07, 0.07), 2000);
    w.coupling.setPair(0, pair(0.5));
    Vec3 impulse = Vec3::Zero();
    for (int s = 0; s < 800; ++s) {
      w.step(1e-5);
      impulse += 1e-5 * w.coupling.force(cube);
    }
    return std::make_pair(w.world.engine.position(cube), impulse);
  };
  const int before = omp_get_max_threads();
  const auto a = run(1), b = run(2);
  omp_set_num_threads(before);
  EXPECT_EQ(a.first, b.first);
  EXPECT_EQ(a.second, b.second);
  EXPECT_GT(a.second.norm(), 0.0);
}

TEST(MpSdemCoupling, BadInputIsRefusedClearly) {
  auto prm = gridParams({20, 14, 14});
  mpm::ParticleSet ps;
  mpm::seedBox(prm, {0.04, 0.05, 0.05}, {0.10, 0.09, 0.09}, 8, ps);
  auto solver = mpm::makeSolver(prm);
  solver->setParticles(ps);
  CoupledWorld w(std::move(solver));
  const int cube = addCube(w, 0.02, 0.003, Vec3(0.07, 0.07, 0.07), 2000);  // inside the blob
  // no pair for the block's material
  try {
    w.step(1e-5);
    FAIL() << "a block without a coupling pair was accepted";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("coupling pair for SDEM material 0"), std::string::npos) << e.what();
  }
  w.coupling.setPair(0, pair());
  try {
    w.step(1e-5);
    FAIL() << "particles seeded inside a block were accepted";
  } catch (const RuntimeFailure& e) {
    EXPECT_NE(std::string(e.what()).find("reached the core of block " + std::to_string(100 + cube)), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(w.coupling.setHistorySlots(0), ParameterError);
  EXPECT_THROW(w.coupling.setDeviceListCapacity(0), ParameterError);
  sdem::BarrierPhys bad = pair();
  bad.friction = -1;
  EXPECT_THROW(w.coupling.setPair(0, bad), ParameterError);
  EXPECT_THROW(w.coupling.setPair(3, pair()), ParameterError);
}

// The bin table, changed in place as blocks move (the slots of the bins they left cleared, those
// they reach set), lists at every point what a table built afresh at the same poses lists: five
// cubes moved at random through the bins ahead of a blob for 30 steps, every bin checked.
TEST(MpSdemCoupling, BinTableChangedInPlaceIsTheFreshOne) {
  auto w = blobWorld(24, 0.0);
  std::vector<int> cubes;
  for (int k = 0; k < 5; ++k) cubes.push_back(addCube(*w, 0.02, 0.003, Vec3(0.13 + 0.02 * k, 0.07, 0.07), 2000));
  w->coupling.setPair(0, pair());
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> ux(0.12, 0.22), uyz(0.02, 0.12);
  int changed = 0;
  std::vector<std::vector<int>> last;
  for (int s = 0; s < 30; ++s) {
    for (int c : cubes)
      w->world.engine.setState(c, Vec3(ux(rng), uyz(rng), uyz(rng)), Quat::Identity(), Vec3::Zero(), Vec3::Zero());
    w->coupling.computeForces(w->mpm(), 1e-5);
    MpSdemCoupling fresh(w->world.engine);
    fresh.setPair(0, pair());
    fresh.computeForces(w->mpm(), 1e-5);
    ASSERT_EQ(fresh.binSize(), w->coupling.binSize());
    const double h = w->coupling.binSize();
    std::vector<std::vector<int>> now;
    int listed = 0;
    for (double x = 0.5 * h; x < 0.24; x += h)
      for (double y = 0.5 * h; y < 0.14; y += h)
        for (double z = 0.5 * h; z < 0.14; z += h) {
          now.push_back(w->coupling.binnedBlocks(Vec3(x, y, z)));
          EXPECT_EQ(now.back(), fresh.binnedBlocks(Vec3(x, y, z))) << "step " << s << " at " << x << ", " << y << ", " << z;
          EXPECT_TRUE(std::is_sorted(now.back().begin(), now.back().end()));
          listed += !now.back().empty();
        }
    for (int c : cubes) {
      const std::vector<int> at = w->coupling.binnedBlocks(w->world.engine.position(c));
      EXPECT_NE(std::find(at.begin(), at.end(), c), at.end()) << "cube " << c << " is not in its own bin";
    }
    EXPECT_GT(listed, 0);
    changed += now != last;
    last = now;
  }
  EXPECT_EQ(changed, 30) << "the table did not change every step";
}

// The device's bin table, changed in place as on the host (old slots cleared by a kernel, new
// ones set): five cubes moved at random along the blob's front for 30 steps find the contacts
// the CPU finds, block by block.
TEST(MpSdemCoupling, CudaBinTableFollowsMovingBlocks) {
  if (!mpm::cudaAvailable()) GTEST_SKIP() << "no CUDA device in this build/machine";
  auto cpu = blobWorld(24, 0.0), gpu = blobWorld(24, 0.0, mpm::Backend::Cuda);
  std::vector<int> cubes;
  for (int k = 0; k < 5; ++k) {
    cubes.push_back(addCube(*cpu, 0.02, 0.003, Vec3(0.1 + 0.025 * k, 0.07, 0.07), 2000));
    addCube(*gpu, 0.02, 0.003, Vec3(0.1 + 0.025 * k, 0.07, 0.07), 2000);
  }
  cpu->coupling.setPair(0, pair());
  gpu->coupling.setPair(0, pair());
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> ux(0.095, 0.2), uyz(0.03, 0.11);
  long touched = 0;
  for (int s = 0; s < 30; ++s) {
    for (int c : cubes) {
      const Vec3 at(ux(rng), uyz(rng), uyz(rng));
      cpu->world.engine.setState(c, at, Quat::Identity(), Vec3::Zero(), Vec3::Zero());
      gpu->world.engine.setState(c, at, Quat::Identity(), Vec3::Zero(), Vec3::Zero());
    }
    cpu->coupling.computeForces(cpu->mpm(), 1e-5);
    gpu->coupling.computeForces(gpu->mpm(), 1e-5);
    for (int c : cubes) {
      ASSERT_EQ(gpu->coupling.contactCount(c), cpu->coupling.contactCount(c)) << "step " << s << ", cube " << c;
      EXPECT_NEAR((gpu->coupling.force(c) - cpu->coupling.force(c)).norm(), 0.0, 1e-9 * cpu->coupling.force(c).norm() + 1e-15);
      touched += cpu->coupling.contactCount(c);
    }
  }
  EXPECT_GT(touched, 0) << "no cube ever touched the blob";
}

// The flow's step queued behind the contacts and run after the blocks' update (CUDA's order,
// here with a CPU solver that queues) gives the run of the plain order to the last bit: the
// blob presses a free cube against a fixed one, so the contacts, the block–block contact and
// the flow all act.
TEST(CoupledWorld, QueuedFlowStepGivesTheSameRunBitForBit) {
  auto run = [](bool queued) {
    auto w = blobWorld(24, 1.0, mpm::Backend::Cpu, mpm::Precision::Double, queued);
    addCube(*w, 0.02, 0.003, Vec3(0.115, 0.07, 0.07), 2000);
    addCube(*w, 0.02, 0.003, Vec3(0.1549, 0.07, 0.07), 2000, true);
    w->coupling.setPair(0, pair(0.3, 0.2));
    for (int s = 0; s < 1500; ++s) w->step(1e-5);
    return w;
  };
  auto plain = run(false), queued = run(true);
  const auto* q = dynamic_cast<const QueuedCpuSolver*>(&queued->mpm());
  ASSERT_NE(q, nullptr);
  EXPECT_EQ(q->launches, 1500);
  EXPECT_EQ(q->abandoned, 0);
  ASSERT_GT(plain->coupling.contactCount(0), 0) << "the blob does not press the cube";
  EXPECT_GT(plain->world.engine.contacts().size(), 0u) << "the cubes are not in contact";
  EXPECT_EQ(queued->mpm().steps(), 1500);
  EXPECT_EQ(queued->mpm().time(), plain->mpm().time());
  EXPECT_EQ(queued->world.engine.position(0), plain->world.engine.position(0));
  EXPECT_EQ(queued->world.engine.orientation(0).coeffs(), plain->world.engine.orientation(0).coeffs());
  EXPECT_EQ(queued->coupling.force(0), plain->coupling.force(0));
  mpm::ParticleSet a, b;
  plain->mpm().getParticles(a);
  queued->mpm().getParticles(b);
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.v, b.v);
  EXPECT_EQ(a.stress, b.stress);
}

// A coupling step that fails (particles seeded inside a block) abandons the flow's step queued
// behind it: the flow stays at the step's start, untouched, and takes a step of its own after.
class QueuedStepEveryBackend : public mpm::agreement::EveryBackend {};
INSTANTIATE_TEST_SUITE_P(Kinds, QueuedStepEveryBackend, ::testing::ValuesIn(mpm::agreement::everyKind()),
                         mpm::agreement::kindName);
TEST_P(QueuedStepEveryBackend, AFailedCouplingStepLeavesTheFlowAtItsStart) {
  for (bool wrap : {false, true}) {
    if (wrap && backend() != mpm::Backend::Cpu) continue;  // CUDA queues its own steps
    auto prm = gridParams({20, 14, 14});
    mpm::ParticleSet ps;
    mpm::seedBox(prm, {0.04, 0.05, 0.05}, {0.10, 0.09, 0.09}, 8, ps);
    for (std::size_t p = 0; p < ps.size(); ++p) ps.v[3 * p] = 0.5;
    std::unique_ptr<mpm::MpmSolver> solver = mpm::makeSolver(prm, backend(), precision());
    solver->setParticles(ps);
    mpm::ParticleSet before;
    solver->getParticles(before);
    if (wrap) solver = std::make_unique<QueuedCpuSolver>(std::move(solver));
    CoupledWorld w(std::move(solver));
    addCube(w, 0.02, 0.003, Vec3(0.07, 0.07, 0.07), 2000);  // inside the blob
    w.coupling.setPair(0, pair());
    EXPECT_EQ(w.mpm().queuesSteps(), wrap || backend() == mpm::Backend::Cuda) << w.mpm().name();
    EXPECT_THROW(w.step(1e-5), RuntimeFailure) << w.mpm().name();
    EXPECT_EQ(w.mpm().time(), 0.0) << w.mpm().name();
    EXPECT_EQ(w.mpm().steps(), 0) << w.mpm().name();
    mpm::ParticleSet after;
    w.mpm().getParticles(after);
    EXPECT_EQ(after.x, before.x) << w.mpm().name();
    EXPECT_EQ(after.v, before.v) << w.mpm().name();
    if (wrap) EXPECT_EQ(dynamic_cast<const QueuedCpuSolver&>(w.mpm()).abandoned, 1);
    w.mpm().step(1e-5);  // nothing left launched
    EXPECT_EQ(w.mpm().steps(), 1) << w.mpm().name();
    EXPECT_GT(w.mpm().time(), 0.0) << w.mpm().name();
  }
}

// The approach step of one material point closing on the upstream face of a fixed cube (outer
// face at x = 0.08 m, sweep radius 5 mm) at gap g, against the hand-derived bound: the step dt
// brings it to delta = v_n dt - g, and the next step must stay within sqrt(m R / (6 k_c delta f))
// (safety 1, R = R_p0 + R_b, f = max(1, 1 / (2 (1 + nu)))); inf for a point that does not
// reach the barrier within dt, recedes or slides along the face.
TEST(MpSdemCoupling, ParticleApproachStepIsTheHandDerivedBound) {
  const double dx = 0.01, rho = 1600, vol0 = dx * dx * dx / 8, Rb = 0.005;
  const double rp = std::cbrt(3 * vol0 / (4 * M_PI)), m = rho * vol0, R = rp + Rb;
  auto approach = [&](double gap, const Vec3& v, double kc, double dt, double poisson = 0.3) {
    mpm::ParticleSet ps;
    ps.x = {0.08 - rp - gap, 0.07, 0.07};
    ps.v = {v.x(), v.y(), v.z()};
    ps.stress.assign(6, 0.0);
    ps.mass = {m};
    ps.volume0 = {vol0};
    ps.J = {1.0};
    ps.gammaDotP = {0.0};
    ps.phase = {0};
    auto solver = mpm::makeSolver(gridParams({20, 14, 14}, dx));
    solver->setParticles(ps);
    CoupledWorld w(std::move(solver));
    addCube(w, 0.02, Rb, Vec3(0.1, 0.07, 0.07), 2000, true);
    sdem::BarrierPhys ph = pair();
    ph.barrierStiffness = kc;
    ph.poisson = poisson;
    w.coupling.setPair(0, ph);
    w.coupling.computeForces(w.mpm(), dt);
    EXPECT_EQ(w.coupling.totalContacts(), 0);
    EXPECT_EQ(w.coupling.particleCriticalStep(), std::numeric_limits<double>::infinity());
    return w.coupling.particleApproachStep();
  };
  const double inf = std::numeric_limits<double>::infinity();
  // 1e-3 s at 0.5 m/s closes 5e-4 m: 4.9e-4 m into the barrier
  EXPECT_NEAR(approach(1e-5, Vec3(0.5, 0, 0), 1e4, 1e-3), std::sqrt(m * R / (6 * 1e4 * 4.9e-4)), 1e-12);
  EXPECT_NEAR(approach(1e-4, Vec3(0.5, 0, 0), 1e7, 1e-3), std::sqrt(m * R / (6 * 1e7 * 4e-4)), 1e-14);
  // the normal speed counts, not the speed: 45 degrees off the normal
  EXPECT_NEAR(approach(1e-5, Vec3(0.5, 0.5, 0), 1e4, 1e-3), std::sqrt(m * R / (6 * 1e4 * 4.9e-4)), 1e-12);
  // K_t above k_n (nu < -1/2): the tangential spring sets the step
  EXPECT_NEAR(approach(1e-5, Vec3(0.5, 0, 0), 1e4, 1e-3, -0.8), std::sqrt(m * R / (6 * 1e4 * 4.9e-4 * 2.5)),
              1e-12);
  EXPECT_EQ(approach(1e-5, Vec3(-0.5, 0, 0), 1e4, 1e-3), inf);  // receding
  EXPECT_EQ(approach(1e-5, Vec3(0, 0.5, 0), 1e4, 1e-3), inf);   // sliding along the face
  // short of the barrier by 1e-5 m at the end of this step: it may arrive during the next one,
  // whose step is then bounded by the overlap it could reach by its end (firstContactStepBound):
  // dt <= (m R / (6 k_c vn))^(1/3), 3.78e-4 s here; with k_c 1e15 N/m 1.75e-7 s
  EXPECT_NEAR(approach(5.1e-4, Vec3(0.5, 0, 0), 1e4, 1e-3), std::cbrt(m * R / (6 * 1e4 * 0.5)), 1e-15);
  EXPECT_NEAR(approach(5.1e-4, Vec3(0.5, 0, 0), 1e15, 1e-3), std::cbrt(m * R / (6 * 1e15 * 0.5)), 1e-18);
  EXPECT_NEAR(approach(9.9e-4, Vec3(0.5, 0, 0), 1e4, 1e-3), std::cbrt(m * R / (6 * 1e4 * 0.5)), 1e-15);
  // beyond what this step and the next can close (2.01 x 5e-4 m): not examined
  EXPECT_EQ(approach(1.1e-3, Vec3(0.5, 0, 0), 1e4, 1e-3), inf);
}

// A granular blob thrown at 1 m/s at a fixed cube behind a stiff barrier (k_c 1e7 N/m), the
// step set by coupledAutoStep (factor 0.5) every step. A step's forces come from the contacts
// at its start, and the contact step of those is known only once the step has begun (the
// check of "dt": "auto" allows twice it). With the particles' approach step every step stays
// within the contact step it ran with; without it, the step in which the blob's face first
// pressed into the barrier overshot twice that.
TEST(MpSdemCoupling, ParticleApproachStepKeepsAStiffFirstTouchWithinTheStepCheck) {
  auto worstRatio = [](bool particleApproach, int* firstContactStep) {
    int cube;
    auto world = blobAtCube(1.0, true, 1e7, &cube);
    CoupledWorld& w = *world;
    double lastDt = 0, worst = 0;
    *firstContactStep = -1;
    for (int s = 0; s < 400; ++s) {
      const double pa = particleApproach ? w.coupling.particleApproachStep() : std::numeric_limits<double>::infinity();
      const double dt = coupledAutoStep(0.5, w.criticalTimeStep(), w.world.engine.approachTimeStep(), pa, lastDt);
      w.step(dt);
      lastDt = dt;
      if (*firstContactStep < 0 && w.coupling.contactCount(cube) > 0) *firstContactStep = s;
      worst = std::max(worst, dt / w.contactStep());
    }
    return worst;
  };
  int firstWith = -1, firstWithout = -1;
  const double with = worstRatio(true, &firstWith), without = worstRatio(false, &firstWithout);
  // measured: 1.004 with, 2.46 without (the first contacts at step 289 in both)
  ASSERT_GT(firstWith, 0);
  ASSERT_GT(firstWithout, 0);
  EXPECT_GT(with, 0.5);  // contacts did set the step
  EXPECT_LE(with, 1.05);
  EXPECT_GT(without, 2.0);
}

// A blob thrown at 2 m/s at a fixed cube behind a barrier of k_c 1e10 N/m, gravity off, the
// step set by coupledAutoStep (factor 0.9) every step. The step that brings a point into the
// barrier must already be short: the points that may arrive during the next step bound it
// (firstContactStepBound). Without that the step that first touched was a CFL step and the
// flow's kinetic energy grew about tenfold (measured with k_c 1e9 on a driver scene); with it
// the blob only loses energy: to friction, to the barrier's stored energy and to the flow.
TEST(MpSdemCoupling, StiffBarrierShortensTheStepBeforeTheFirstContact) {
  int cube;
  auto world = blobAtCube(2.0, true, 1e10, &cube);
  CoupledWorld& w = *world;
  auto kinetic = [&w] {
    mpm::ParticleSet ps;
    w.mpm().getParticles(ps);
    double e = 0;
    for (std::size_t p = 0; p < 3 * ps.size(); ++p) e += 0.5 * ps.mass[p / 3] * ps.v[p] * ps.v[p];
    return e;
  };
  const double e0 = kinetic();
  double lastDt = 0, highest = e0, stepBeforeContact = 0;
  int firstContact = -1;
  for (int s = 0; s < 3000 && w.time() < 0.03; ++s) {
    const double dt = coupledAutoStep(0.9, w.criticalTimeStep(), w.world.engine.approachTimeStep(),
                                      w.coupling.particleApproachStep(), lastDt);
    w.step(dt);
    lastDt = dt;
    if (firstContact < 0 && w.coupling.contactCount(cube) > 0) firstContact = s;
    if (firstContact < 0) stepBeforeContact = dt;
    highest = std::max(highest, kinetic());
  }
  ASSERT_GT(firstContact, 0) << "the blob never reached the cube";
  // the step before the first contact is at most the first-contact bound of the fastest point,
  // cbrt(m R / (6 k_c vn)) with m = 1600 dx^3/8, R = R_p0 + 0.003 m, vn = 2 m/s: 5.8e-7 s
  const double m = 1600 * 1e-6 / 8, R = std::cbrt(3 * 1e-6 / 8 / (4 * M_PI)) + 0.003;
  EXPECT_LE(stepBeforeContact, std::cbrt(m * R / (6 * 1e10 * 2.0)) * 1.000001);
  EXPECT_LE(highest, e0 * (1 + 1e-9)) << "the flow gained kinetic energy at the barrier";
}

// A block added between steps joins the coupling (its shape enters the table) and is hit.
TEST(MpSdemCoupling, BlockAddedMidRunIsCoupled) {
  auto world = blobWorld(24, 1.0);
  CoupledWorld& w = *world;
  addCube(w, 0.01, 0.002, Vec3(0.02 + 0.2, 0.07, 0.12), 2000, true);  // far away
  w.coupling.setPair(0, pair());
  for (int s = 0; s < 100; ++s) w.step(1e-5);
  EXPECT_EQ(w.coupling.totalContacts(), 0);
  const int cube = addCube(w, 0.02, 0.003, Vec3(0.125, 0.07, 0.07), 2000);
  int hit = 0;
  for (int s = 0; s < 3000 && !hit; ++s) {
    w.step(1e-5);
    hit = w.coupling.contactCount(cube);
  }
  EXPECT_GT(hit, 0);
  EXPECT_EQ(w.coupling.numBlocks(), 2);
}

// The CUDA coupling (float and double) against the CPU path on the same scene: a blob thrown
// at a free cube, 1500 steps; block trajectory and flow force within precision-scaled bounds.
TEST(MpSdemCoupling, CpuAndCudaAgree) {
  if (!mpm::cudaAvailable()) GTEST_SKIP() << "no CUDA device in this build/machine: CPU-vs-CUDA coupling check skipped";
  const BlobHit cpu = blobHitsCube(mpm::Backend::Cpu, mpm::Precision::Double);
  ASSERT_GT(cpu.impulse.norm(), 0.0) << "the blob never hit the cube";
  ASSERT_LT(cpu.minApproach, std::numeric_limits<double>::infinity());
  for (const auto& [prec, tol] : {std::make_pair(mpm::Precision::Double, 1e-9), std::make_pair(mpm::Precision::Float, 2e-3)}) {
    const BlobHit gpu = blobHitsCube(mpm::Backend::Cuda, prec);
    std::printf("cuda-%s against cpu-double: cube position %.3e m (bound %.1e), impulse %.3e of %.4g N s (bound %.1e)\n",
                ::testing::PrintToString(prec).c_str(), (gpu.position - cpu.position).norm(), tol * 0.1,
                (gpu.impulse - cpu.impulse).norm(), cpu.impulse.norm(), tol * cpu.impulse.norm() * 10);
    if (prec == mpm::Precision::Double)  // the device reduces it in float
      EXPECT_NEAR(gpu.minApproach / cpu.minApproach, 1.0, 1e-6);
    EXPECT_NEAR((gpu.position - cpu.position).norm(), 0.0, tol * 0.1) << "precision " << ::testing::PrintToString(prec);
    EXPECT_NEAR((gpu.impulse - cpu.impulse).norm(), 0.0, tol * cpu.impulse.norm() * 10) << "precision " << ::testing::PrintToString(prec);
    // The last step's contacts, read back from the device list: the CPU's, in its order.
    ASSERT_EQ(gpu.contacts.size(), cpu.contacts.size()) << "precision " << ::testing::PrintToString(prec);
    ASSERT_FALSE(cpu.contacts.empty());
    for (std::size_t i = 0; i < cpu.contacts.size(); ++i) {
      const MpContactRecord &g = gpu.contacts[i], &c = cpu.contacts[i];
      EXPECT_EQ(g.particle, c.particle) << i;
      EXPECT_EQ(g.block, c.block) << i;
      EXPECT_EQ(g.featureKind, c.featureKind) << i;
      EXPECT_NEAR((g.point - c.point).norm(), 0.0, tol * 0.1) << i;
      EXPECT_NEAR((g.force - c.force).norm(), 0.0, tol * 10 * c.force.norm() + 1e-12) << i;
    }
    // No sum on the device depends on thread timing: a second run gives the same bits.
    const BlobHit again = blobHitsCube(mpm::Backend::Cuda, prec);
    EXPECT_EQ(again.position, gpu.position) << "precision " << ::testing::PrintToString(prec);
    EXPECT_EQ(again.impulse, gpu.impulse) << "precision " << ::testing::PrintToString(prec);
  }
}

// Steps whose contacts overflow the device's contact list (a list of 4 at first, grown to
// twice a step's contacts each time it overflows): their block sums (the overflowing contacts
// added atomically, the listed ones after them) are the CPU's within the ordered sums' bound.
TEST(MpSdemCoupling, CudaStepsBeyondTheContactListAgreeWithTheCpu) {
  if (!mpm::cudaAvailable()) GTEST_SKIP() << "no CUDA device in this build/machine";
  const BlobHit cpu = blobHitsCube(mpm::Backend::Cpu, mpm::Precision::Double);
  const BlobHit gpu = blobHitsCube(mpm::Backend::Cuda, mpm::Precision::Double, 4);
  ASSERT_GT(cpu.contacts.size(), 8u) << "too few contacts to overflow a list of 4 twice";
  std::printf("cuda-double, contact list of 4 at first: cube position %.3e m, impulse %.3e of %.4g N s\n",
              (gpu.position - cpu.position).norm(), (gpu.impulse - cpu.impulse).norm(), cpu.impulse.norm());
  EXPECT_NEAR((gpu.position - cpu.position).norm(), 0.0, 1e-10);
  EXPECT_NEAR((gpu.impulse - cpu.impulse).norm(), 0.0, 1e-8 * cpu.impulse.norm());
}

// The coupling's stage timing (mpmsdem-run --device-stages): its parts add up to at most the
// coupled step's coupling stage, which they lie inside, and the contact loop, where the blob
// presses the cube, is part of them; on CUDA the device parts fit in the device call.
TEST(MpSdemCoupling, StageTimesFitInTheCouplingStage) {
  for (auto backend : {mpm::Backend::Cpu, mpm::Backend::Cuda}) {
    if (backend == mpm::Backend::Cuda && !mpm::cudaAvailable()) continue;
    int cube;
    auto world = blobAtCube(1.0, false, 1e4, &cube, backend, mpm::Precision::Double);
    CoupledWorld& w = *world;
    EXPECT_TRUE(w.coupling.stageSeconds().empty());  // timing off
    w.coupling.setStageTiming(true);
    for (int s = 0; s < 1500; ++s) w.step(1e-5);
    ASSERT_GT(w.coupling.totalContacts(), 0) << "the blob is not touching the cube";
    std::map<std::string, double> t;
    double host = 0;
    for (const auto& [name, sec] : w.coupling.stageSeconds()) {
      EXPECT_GE(sec, 0.0) << name;
      t[name] = sec;
      if (name.rfind("device_", 0) != 0) host += sec;
    }
    for (const char* name : {"force_buffer", "setup", "bins", "contacts"}) EXPECT_EQ(t.count(name), 1u) << name;
    const double stage = w.stageSeconds().coupling;
    std::printf("%s: coupling stage %.4f s; parts %.4f s: contacts %.4f s\n", w.mpm().name().c_str(), stage, host,
                t["contacts"]);
    EXPECT_LE(host, stage);
    EXPECT_GT(t["contacts"], 0.0);
    if (backend == mpm::Backend::Cuda) {
      for (const char* name : {"device_upload", "device_kernel", "device_sums", "device_host_wait"})
        EXPECT_EQ(t.count(name), 1u) << name;
      EXPECT_LE(t["device_host_wait"], t["contacts"]);
      EXPECT_GT(t["device_kernel"], 0.0);
    }
  }
}

// The records contacts() hands out are the contacts the block sums were made of.
TEST(MpSdemCoupling, ContactRecordsMakeTheBlockSums) {
  int cube;
  auto world = blobAtCube(1.0, false, 1e4, &cube, mpm::Backend::Cpu, mpm::Precision::Double);
  CoupledWorld& w = *world;
  EXPECT_TRUE(w.coupling.contacts().empty());  // no step yet
  for (int s = 0; s < 1500; ++s) w.step(1e-5);
  const auto rec = w.coupling.contacts();
  ASSERT_FALSE(rec.empty()) << "the blob is not touching the cube at the end";
  ASSERT_EQ(static_cast<int>(rec.size()), w.coupling.contactCount(cube));
  Vec3 f = Vec3::Zero(), tq = Vec3::Zero(), face = Vec3::Zero();
  int previous = -1;
  for (const MpContactRecord& r : rec) {
    EXPECT_EQ(r.block, cube);
    EXPECT_GT(r.particle, previous);  // by particle number (one block: one contact each)
    previous = r.particle;
    f += r.force;
    tq += (r.point - w.world.engine.position(cube)).cross(r.force);
    if (r.featureKind == sdem::kFeatureFace) face += r.force;
    EXPECT_NEAR(r.normal.norm(), 1.0, 1e-12);
    EXPECT_GT(r.normalForce, 0.0);
  }
  const double scale = w.coupling.force(cube).norm();
  EXPECT_NEAR((f - w.coupling.force(cube)).norm(), 0.0, 1e-12 * scale);
  EXPECT_NEAR((tq - w.coupling.torque(cube)).norm(), 0.0, 1e-12 * scale);
  EXPECT_NEAR((face - w.coupling.faceForce(cube)).norm(), 0.0, 1e-12 * scale);
  EXPECT_TRUE(w.coupling.contactsAvailable());
}

// The same scene as CpuAndCudaAgree, cpu-float against cpu-double. Float positions round
// x += v dt to ulp(x) <= eps x each step, with the same sign while v dt stays the same (a blob
// in free flight): the blob's front lags by up to n eps x / 2 after n steps (x ~ 0.1 m, n =
// 1440 steps to the contact: 9e-6 m), so the contact starts up to delay = n eps x / (2 v)
// later (0.9 dt at v = 1 m/s). Over the m = 1500 - n steps of contact the impulse grows about
// as (t - t_c)^2 and the cube's displacement as (t - t_c)^3: relative differences up to
// 2 delay / (m dt) and 3 delay / (m dt) (3 % and 4.5 %; measured 0.8 % and 1.2 %). The
// double run perturbed by 1e-8 m changes by 1e-6 only: the differences are float's.
TEST(MpSdemCoupling, CpuFloatAgreesWithCpuDouble) {
  const BlobHit d = blobHitsCube(mpm::Backend::Cpu, mpm::Precision::Double);
  const BlobHit f = blobHitsCube(mpm::Backend::Cpu, mpm::Precision::Float);
  ASSERT_GT(d.firstContact, 0) << "the blob never hit the cube";
  const double eps = mpm::agreement::roundOff(mpm::Precision::Float), dt = 1e-5, v = 1.0, x = 0.1;
  const double delay = d.firstContact * eps * x / (2 * v);
  const double contact = (1500 - d.firstContact) * dt;
  const double moved = d.position.x() - 0.115;
  std::printf("blob on cube, cpu-float vs cpu-double: first contact at step %d / %d; impulse %.6e / %.6e N s; cube moved %.4e / %.4e m\n",
              f.firstContact, d.firstContact, f.impulse.x(), d.impulse.x(), f.position.x() - 0.115, moved);
  EXPECT_NEAR(f.firstContact, d.firstContact, 1);
  EXPECT_NEAR(f.impulse.x(), d.impulse.x(), 2 * delay / contact * d.impulse.x());
  EXPECT_NEAR(f.position.x() - 0.115, moved, 3 * delay / contact * moved);
  // head-on and centred: no sideways impulse or motion in either, to round-off of the forces
  EXPECT_NEAR(f.impulse.tail<2>().norm(), 0.0, 10 * eps * d.impulse.x());
  EXPECT_NEAR((f.position - d.position).tail<2>().norm(), 0.0, 10 * eps * x);
  EXPECT_GT(moved, 0.0);
}
