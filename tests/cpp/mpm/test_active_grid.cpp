// The CPU backend's active grid (MpmCpu): grid work only in the tiles next to occupied blocks.
// Nodes a flow has left must read as empty, and empty space around a flow must change nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>

#include "mpm/MpmSolver.hpp"
#include "mpm/Seeding.hpp"

#include "GranularColumn.hpp"

using namespace mpmsdem;
using namespace mpmsdem::mpm;

namespace {

// Sums the node mass over the whole grid and counts nodes that are empty but moving.
struct WholeGridProbe : GridHook {
  double mass = 0;
  long movingEmpty = 0;
  void apply(const GridView& g) override {
    const double* m = static_cast<const double*>(g.mass);
    mass = 0;
    movingEmpty = 0;
    for (int i = 0; i < g.nodes[0] * g.nodes[1] * g.nodes[2]; ++i) {
      const int e = i * g.stride;
      mass += m[e];
      for (int d = 0; d < 3; ++d)
        if (m[e] == 0 && static_cast<const double*>(g.v[d])[e] != 0) ++movingEmpty;
    }
  }
};

}  // namespace

TEST(ActiveGrid, TranslatingBlobLeavesNoMassBehind) {
  // Zero gravity, a stress-free blob moving at a uniform velocity across 30 cells diagonally:
  // a uniform velocity field has no strain rate, so the blob translates rigidly. Each step the
  // whole grid must hold exactly the particles' mass (the B-spline weights sum to one); a node
  // the blob has left and that kept its old values would add to it.
  MpmParams prm = testing_scenes::granularColumnParams(0.01, {48, 8, 40}, 1e4);  // soft: a large step is stable
  prm.gravity = {0, 0, 0};
  prm.walls[4].friction = 0;
  ParticleSet ps;
  seedBox(prm, {0.03, 0.03, 0.03}, {0.09, 0.05, 0.08}, {2, 2, 2}, ps);
  const std::array<double, 3> vel{1.5, 0, 1.0};
  for (std::size_t p = 0; p < ps.size(); ++p)
    for (int d = 0; d < 3; ++d) ps.v[3 * p + d] = vel[d];
  const ParticleSet start = ps;
  const double M = std::accumulate(ps.mass.begin(), ps.mass.end(), 0.0);

  auto s = makeSolver(prm, Backend::Cpu, Precision::Double);
  s->setParticles(ps);
  auto probe = std::make_shared<WholeGridProbe>();
  s->addGridHook(probe);
  const double dt = 5e-4;
  const int steps = 400;  // 0.3 m along x, 0.2 m along z: 30 and 20 cells
  for (int n = 0; n < steps; ++n) {
    s->step(dt);
    ASSERT_NEAR(probe->mass, M, 1e-12 * M) << "step " << n + 1;
    ASSERT_EQ(probe->movingEmpty, 0) << "step " << n + 1;
  }
  ParticleSet end;
  s->getParticles(end);
  const double t = steps * dt;
  for (std::size_t p = 0; p < end.size(); ++p)
    for (int d = 0; d < 3; ++d) {
      ASSERT_NEAR(end.x[3 * p + d], start.x[3 * p + d] + vel[d] * t, 1e-12) << "particle " << p << " axis " << d;
      ASSERT_NEAR(end.v[3 * p + d], vel[d], 1e-12) << "particle " << p << " axis " << d;
    }
}

TEST(ActiveGrid, EmptySpaceAroundAFlowChangesNothing) {
  // The same collapsing column in its own box and in a box four times as long and twice as
  // high (same origin, so the same node positions): the flow never reaches the far walls, so
  // the two runs must agree bit for bit.
  auto run = [](std::array<int, 3> cells) {
    MpmParams prm = testing_scenes::granularColumnParams(0.01, cells, 2e5);
    ParticleSet ps;
    seedBox(prm, {0.02, 0.02, 0.02}, {0.08, 0.03, 0.14}, {2, 1, 2}, ps);
    auto s = makeSolver(prm, Backend::Cpu, Precision::Double);
    s->setParticles(ps);
    for (int n = 0; n < 1000; ++n) s->step(2e-4);
    ParticleSet out;
    s->getParticles(out);
    return out;
  };
  const ParticleSet snug = run({30, 5, 20});
  const ParticleSet wide = run({120, 5, 40});
  ASSERT_EQ(snug.size(), wide.size());
  double maxTravel = 0;
  for (std::size_t p = 0; p < snug.size(); ++p) maxTravel = std::max(maxTravel, snug.x[3 * p] - 0.08);
  EXPECT_GT(maxTravel, 0.01);    // the column did collapse and run out
  EXPECT_LT(maxTravel, 0.24);    // without reaching the snug box's far wall (0.28 m less 2 wall cells)
  EXPECT_TRUE(snug.x == wide.x);
  EXPECT_TRUE(snug.v == wide.v);
  EXPECT_TRUE(snug.stress == wide.stress);
}
