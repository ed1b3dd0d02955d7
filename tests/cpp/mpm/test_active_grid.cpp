// The active grid of both backends (MpmKernelsCommon.hpp, forTilesOfBlock; MpmCpu, MpmCuda):
// grid work only in the tiles next to occupied blocks. Nodes a flow has left must read as
// empty, empty space around a flow must change nothing, and updating the active tiles alone
// must give the whole grid's update.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numeric>
#include <random>
#include <set>
#include <vector>

#include "mpm/MpmKernelsCommon.hpp"
#include "mpm/MpmSolver.hpp"
#include "mpm/Seeding.hpp"
#ifdef MPMSDEM_WITH_CUDA
#include <cuda_runtime.h>
#endif

#include "AgreementHelpers.hpp"
#include "GranularColumn.hpp"

using namespace mpmsdem;
using namespace mpmsdem::mpm;

namespace {

// Values every `stride` from `src` (a grid view's array, on the host or the device) for `nodes`
// nodes, as host doubles.
template <typename T>
std::vector<double> readStrided(const void* src, std::size_t nodes, int stride, bool device) {
  const std::size_t span = (nodes - 1) * stride + 1;
  std::vector<T> raw(span);
  if (device) {
#ifdef MPMSDEM_WITH_CUDA
    EXPECT_EQ(cudaMemcpy(raw.data(), src, span * sizeof(T), cudaMemcpyDeviceToHost), cudaSuccess);
#else
    ADD_FAILURE() << "a device view in a build without CUDA";
#endif
  } else {
    std::copy(static_cast<const T*>(src), static_cast<const T*>(src) + span, raw.begin());
  }
  std::vector<double> out(nodes);
  for (std::size_t i = 0; i < nodes; ++i) out[i] = static_cast<double>(raw[i * stride]);
  return out;
}

// Sums the node mass over the whole grid (every stored node record) and counts nodes that are
// empty but moving.
struct WholeGridProbe : GridHook {
  double mass = 0;
  long movingEmpty = 0;
  void apply(const GridView& g) override {
    const std::size_t nodes = static_cast<std::size_t>(g.storedNodes);
    auto read = [&](const void* a) {
      return g.precision == Precision::Float ? readStrided<float>(a, nodes, g.stride, g.device)
                                             : readStrided<double>(a, nodes, g.stride, g.device);
    };
    const std::vector<double> m = read(g.mass);
    const std::vector<double> v[3] = {read(g.v[0]), read(g.v[1]), read(g.v[2])};
    mass = 0;
    movingEmpty = 0;
    for (std::size_t i = 0; i < m.size(); ++i) {
      mass += m[i];
      for (int d = 0; d < 3; ++d)
        if (m[i] == 0 && v[d][i] != 0) ++movingEmpty;
    }
  }
};

}  // namespace

class ActiveGridEveryBackend : public agreement::EveryBackend {};
INSTANTIATE_TEST_SUITE_P(Kinds, ActiveGridEveryBackend, ::testing::ValuesIn(agreement::everyKind()),
                         agreement::kindName);

TEST_P(ActiveGridEveryBackend, TranslatingBlobLeavesNoMassBehind) {
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

  auto s = solver(prm);
  s->setParticles(ps);
  auto probe = std::make_shared<WholeGridProbe>();
  s->addGridHook(probe);
  const double dt = 5e-4;
  const int steps = 400;  // 0.3 m along x, 0.2 m along z: 30 and 20 cells
  // 1e-12 in double; the same number of round-offs in float
  const double tol = 4500 * agreement::roundOff(precision());
  for (int n = 0; n < steps; ++n) {
    s->step(dt);
    ASSERT_NEAR(probe->mass, M, tol * M) << "step " << n + 1;
    ASSERT_EQ(probe->movingEmpty, 0) << "step " << n + 1;
  }
  ParticleSet end;
  s->getParticles(end);
  const double t = steps * dt;
  for (std::size_t p = 0; p < end.size(); ++p)
    for (int d = 0; d < 3; ++d) {
      ASSERT_NEAR(end.x[3 * p + d], start.x[3 * p + d] + vel[d] * t, tol) << "particle " << p << " axis " << d;
      ASSERT_NEAR(end.v[3 * p + d], vel[d], tol) << "particle " << p << " axis " << d;
    }
}

TEST_P(ActiveGridEveryBackend, EmptySpaceAroundAFlowChangesNothing) {
  // The same collapsing column in its own box and in a box four times as long and twice as
  // high (same origin, so the same node positions): the flow never reaches the far walls, so
  // the two runs must agree bit for bit.
  auto run = [this](std::array<int, 3> cells) {
    MpmParams prm = testing_scenes::granularColumnParams(0.01, cells, 2e5);
    ParticleSet ps;
    seedBox(prm, {0.02, 0.02, 0.02}, {0.08, 0.03, 0.14}, {2, 1, 2}, ps);
    auto s = solver(prm);
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

TEST_P(ActiveGridEveryBackend, ANewParticleSetRunsAsInAFreshSolver) {
  // A solver that has stepped one flow, then is given another that overlaps some of its tiles and
  // node columns (a restore, a YADE script replacing the points): the grid, the lists of occupied
  // blocks and active tiles and the stored columns the first left behind must change nothing:
  // the second flow runs as in a solver that never saw the first, to the bit.
  MpmParams prm = testing_scenes::granularColumnParams(0.01, {60, 8, 24}, 2e5);
  ParticleSet a, b;
  seedBox(prm, {0.02, 0.02, 0.02}, {0.08, 0.05, 0.14}, {2, 2, 2}, a);
  seedBox(prm, {0.06, 0.02, 0.02}, {0.14, 0.05, 0.10}, {2, 2, 2}, b);
  auto used = solver(prm);
  used->setParticles(a);
  for (int n = 0; n < 300; ++n) used->step(2e-4);
  used->setParticles(b);
  auto fresh = solver(prm);
  fresh->setParticles(b);
  for (int n = 0; n < 300; ++n) {
    used->step(2e-4);
    fresh->step(2e-4);
  }
  ParticleSet u, f;
  used->getParticles(u);
  fresh->getParticles(f);
  double travel = 0;
  for (std::size_t p = 0; p < f.size(); ++p) travel = std::max(travel, f.x[3 * p] - 0.14);
  EXPECT_GT(travel, 0.005);  // the second flow moved into ground the first had left
  EXPECT_TRUE(u.x == f.x);
  EXPECT_TRUE(u.v == f.v);
  EXPECT_TRUE(u.stress == f.stress);
}

namespace {

// The collapsing column of EmptySpaceAroundAFlowChangesNothing in a grid of `cells`, `steps`
// steps on `backend` in double: its particles at the end and the solver's memory then.
ParticleSet collapseIn(std::array<int, 3> cells, int steps, std::size_t& bytes, Backend backend) {
  MpmParams prm = testing_scenes::granularColumnParams(0.01, cells, 2e5);
  ParticleSet ps;
  seedBox(prm, {0.02, 0.02, 0.02}, {0.08, 0.03, 0.14}, {2, 1, 2}, ps);
  auto s = makeSolver(prm, backend, Precision::Double);
  s->setParticles(ps);
  for (int n = 0; n < steps; ++n) s->step(2e-4);
  bytes = s->memoryBytes();
  ParticleSet out;
  s->getParticles(out);
  return out;
}

// That collapse in its own box (30 cells long) and in a grid of `cells`: the same particles to the
// bit. The two solvers' memory in snugBytes and farBytes.
void expectTheCollapseOfItsOwnBox(Backend backend, std::array<int, 3> cells, int steps, std::size_t& snugBytes,
                                  std::size_t& farBytes) {
  const ParticleSet snug = collapseIn({30, 5, 20}, steps, snugBytes, backend);
  const ParticleSet far = collapseIn(cells, steps, farBytes, backend);
  EXPECT_TRUE(snug.x == far.x);
  EXPECT_TRUE(snug.v == far.v);
  EXPECT_TRUE(snug.stress == far.stress);
}

}  // namespace

TEST(CpuGrid, StoresTheNodeColumnsTheFlowReachedNotTheBox) {
  // The collapsing column of EmptySpaceAroundAFlowChangesNothing in its own box (30 cells long)
  // and in one 100 times as long (3000 cells: a dense grid of 3001 x 6 x 21 nodes would be
  // 24 MB in double). The runs agree bit for bit, and the long box's solver holds exactly its
  // larger index arrays more (an int per node column for the column map, two ints per block of
  // 3 x 3 x 3 cells for the binning, a byte per tile), not its grid: both store the node
  // columns the flow reached, in the same order.
  std::size_t snugBytes = 0, longBytes = 0;
  expectTheCollapseOfItsOwnBox(Backend::Cpu, {3000, 5, 20}, 1000, snugBytes, longBytes);
  auto indexBytes = [](int cellsX) {
    const std::size_t blocks = static_cast<std::size_t>(blocksAlong(cellsX)) * blocksAlong(5) * blocksAlong(20);
    const std::size_t tiles = blocks;  // as many tiles per axis as blocks
    return 4 * static_cast<std::size_t>(cellsX + 1) * 6 + 8 * blocks + tiles;
  };
  EXPECT_EQ(longBytes - snugBytes, indexBytes(3000) - indexBytes(30));
  EXPECT_LT(longBytes, 2 * snugBytes);
}

TEST(CpuGrid, RunsAGridWhoseDenseValuesPassTwoToThe31) {
  // The collapsing column above in a box 22 km long (2.2e6 cells at 1 cm, 2.8e8 nodes): its
  // dense grid would hold 2.2e9 values, beyond an int offset (and 18 GB in double), and was
  // refused. It runs, holding what the flow reached plus the box's index arrays, and moves the
  // column as its own box does, to the bit.
  const std::array<int, 3> huge = {2200000, 5, 20};
  EXPECT_GT(double(kNodeValues) * (huge[0] + 1) * (huge[1] + 1) * (huge[2] + 1), 2147483647.0);
  std::size_t snugBytes = 0, hugeBytes = 0;
  expectTheCollapseOfItsOwnBox(Backend::Cpu, huge, 300, snugBytes, hugeBytes);
  EXPECT_LT(hugeBytes, std::size_t(250) << 20);  // index arrays of 1.5e8 B, no dense grid
}

TEST(CpuGrid, NodeRecordsPastTwoToThe28AreAddressedIn64Bits) {
  // A stored column far down the column pool: its records' value offsets (8 a record) pass 2^31.
  GridConst<double> g{};
  g.nodes[0] = 2, g.nodes[1] = 2, g.nodes[2] = 401;
  const int column[4] = {0, -1, 1000000, 3};
  g.column = column;
  EXPECT_EQ(nodeRecordAt(g, 1, 0, 7), 401000007L);
  EXPECT_EQ(kNodeValues * nodeRecordAt(g, 1, 0, 400), 8L * 401000400L);
  EXPECT_EQ(kNodeValues * nodeRecord(g, 2 * 401 + 5), 8L * 401000005L);
  EXPECT_EQ(nodeRecordAt(g, 1, 1, 2), 3 * 401 + 2);
  g.column = nullptr;  // the dense layout: the node's own index
  EXPECT_EQ(nodeRecordAt(g, 1, 1, 2), (1 * 2 + 1) * 401 + 2);
}

namespace {

// The tiles the particles' blocks reach, found as the CUDA step finds them (forTilesOfBlock of
// each particle's block).
std::set<int> tilesReached(const ParticleSet& ps, const GridConst<double>& g, const int nb[3]) {
  std::set<int> tiles;
  for (std::size_t p = 0; p < ps.size(); ++p) {
    double gc[3];
    for (int d = 0; d < 3; ++d) gc[d] = (ps.x[3 * p + d] - g.origin[d]) * g.invDx;
    int c[3];
    blockCoordsOf(blockCellOf(gc, nb) / kBlockCells, nb, c);
    forTilesOfBlock(c, nb, [&tiles](int t) { tiles.insert(t); });
  }
  return tiles;
}

}  // namespace

TEST(ColumnsNearTiles, AreTheNineTilesAroundAlongXAndY) {
  // r = 0 .. 80 names each node column of the 3 x 3 tiles around a tile once (and none along z:
  // a column is the grid's whole height); at the grid's edges, those outside are -1.
  const int nb[3] = {5, 4, 3}, nodes[3] = {13, 11, 8};  // 12 x 10 x 7 cells
  std::set<int> seen;
  const int inner = (2 * nb[1] + 1) * nb[2] + 1;  // tile (2, 1, 1)
  for (int r = 0; r < kColumnsNearTile; ++r) {
    const int c = columnNearTile(inner, r, nb, nodes);
    ASSERT_GE(c, 0) << r;
    const int i = c / nodes[1], j = c % nodes[1];
    EXPECT_GE(i, 3) << r;  // tiles 1 .. 3 along x: node columns 3 .. 11
    EXPECT_LE(i, 11) << r;
    EXPECT_GE(j, 0) << r;  // tiles 0 .. 2 along y: node columns 0 .. 8
    EXPECT_LE(j, 8) << r;
    seen.insert(c);
  }
  EXPECT_EQ(seen.size(), 81u);
  int inside = 0;  // tile (4, 3, 0): the far corner, nodes 12 and 9 .. 10 its own
  for (int r = 0; r < kColumnsNearTile; ++r) inside += columnNearTile((4 * nb[1] + 3) * nb[2], r, nb, nodes) >= 0;
  EXPECT_EQ(inside, 4 * 5);  // node columns 9 .. 12 along x, 6 .. 10 along y
}

TEST(ColumnsNearTiles, ATileWithAColumnNotStoredIsFound) {
  const int nb[3] = {3, 3, 2}, nodes[3] = {8, 7, 5};
  std::vector<int> column(nodes[0] * nodes[1], -1);
  const int tile = (1 * nb[1] + 2) * nb[2] + 1;  // node columns 3 .. 5 along x, 6 along y (the last)
  EXPECT_FALSE(tileColumnsStored(tile, nb, nodes, column.data()));
  for (int i = 3; i <= 5; ++i) column[i * nodes[1] + 6] = i;
  EXPECT_TRUE(tileColumnsStored(tile, nb, nodes, column.data()));
  column[4 * nodes[1] + 6] = -1;
  EXPECT_FALSE(tileColumnsStored(tile, nb, nodes, column.data()));
  column[4 * nodes[1] + 6] = 0;
  column[4 * nodes[1] + 5] = -1;  // another tile's column
  EXPECT_TRUE(tileColumnsStored(tile, nb, nodes, column.data()));
}

TEST(ColumnsNearTiles, HoldEveryColumnTheNextStepReachesInACollapse) {
  // The CUDA backend stores at each step's end the columns near that step's tiles and checks at
  // the next step that its tiles' columns are stored. A column collapsing in a box 4 times its
  // runout, stepped at the stable step (the points move up to a few tenths of a cell a step),
  // on the CPU: at every step, the columns the tiles reach lie in those stored so far, and what
  // is stored follows the flow (a fraction of the box). Also printed: how far a point moved in a step.
  MpmParams prm = testing_scenes::granularColumnParams(0.01, {120, 30, 20}, 1e4);  // soft: a long stable step
  ParticleSet ps;
  seedBox(prm, {0.02, 0.02, 0.02}, {0.08, 0.05, 0.14}, {2, 2, 2}, ps);
  for (std::size_t p = 0; p < ps.size(); ++p) ps.v[3 * p] = 1.0, ps.v[3 * p + 1] = 0.5;  // thrown along x and y
  const GridConst<double> g = makeGridConst<double>(prm, 0.0);
  const int nb[3] = {blocksAlong(prm.cells[0]), blocksAlong(prm.cells[1]), blocksAlong(prm.cells[2])};
  auto s = makeSolver(prm, Backend::Cpu, Precision::Double);
  s->setParticles(ps);
  std::vector<int> column(static_cast<std::size_t>(g.nodes[0]) * g.nodes[1], -1);
  int stored = 0;
  auto storeNear = [&](const ParticleSet& now) {
    for (int t : tilesReached(now, g, nb))
      for (int r = 0; r < kColumnsNearTile; ++r)
        if (const int c = columnNearTile(t, r, nb, g.nodes); c >= 0 && column[c] < 0) column[c] = stored++;
  };
  storeNear(ps);  // as setParticles does
  double maxStep = 0, front0 = 0, front = 0;
  for (std::size_t p = 0; p < ps.size(); ++p) front0 = std::max(front0, ps.x[3 * p]);
  ParticleSet before = ps, after;
  for (int n = 0; n < 600; ++n, before = after) {
    s->step(0.9 * s->stableTimeStep());
    s->getParticles(after);
    for (std::size_t p = 0; p < after.size(); ++p)
      maxStep = std::max(maxStep,
                         std::hypot(after.x[3 * p] - before.x[3 * p], after.x[3 * p + 1] - before.x[3 * p + 1]));
    storeNear(before);  // the step's end: near the tiles the step's particles started in
    for (int t : tilesReached(after, g, nb))  // the check the CUDA step makes of each tile it lists
      ASSERT_TRUE(tileColumnsStored(t, nb, g.nodes, column.data())) << "step " << n + 1 << " tile " << t;
    if (n == 599)
      for (std::size_t p = 0; p < after.size(); ++p) front = std::max(front, after.x[3 * p]);
  }
  EXPECT_GT(front - front0, 0.05);           // the column ran out 5 cells and more
  EXPECT_GT(maxStep, 0.05 * prm.dx);         // the points crossed cells, up to a tenth of one a step
  EXPECT_LT(maxStep, prm.dx);                // within the stable step's bound
  EXPECT_LT(stored, static_cast<int>(column.size()) / 2);  // the stored columns follow the flow
  std::printf("collapse: front %.4f m further, largest step %.3f dx, %d of %zu columns stored\n", front - front0,
              maxStep / prm.dx, stored, column.size());
}

TEST(SortedKeys, FirstKeyAtLeastIsWhereAValuesRunStarts) {
  // Ascending keys (a value above 12 bits of number, as the particles' sort keys): for every value
  // and sub-range, the first place at or above it is the linear scan's.
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> value(0, 40), number(0, 4095);
  std::vector<unsigned long long> key(300);
  for (auto& k : key) k = (static_cast<unsigned long long>(value(rng)) << 12) | number(rng);
  std::sort(key.begin(), key.end());
  for (int lo : {0, 17, 150})
    for (int hi : {lo, lo + 1, 200, 300})
      for (unsigned long long v = 0; v <= 42; ++v) {
        int scan = lo;
        while (scan < hi && (key[scan] >> 12) < v) ++scan;
        ASSERT_EQ(firstKeyAtLeast(key.data(), lo, hi, 12, v), scan) << lo << " " << hi << " " << v;
      }
}

TEST(CudaGrid, StoresTheNodeColumnsTheFlowReachedNotTheBox) {
  // CpuGrid.StoresTheNodeColumnsTheFlowReachedNotTheBox on CUDA: the collapsing column in its box
  // and in one 100 times as long (a dense grid of 24 MB in double) agree bit for bit; the long
  // box's solver holds its index arrays and the node columns near the flow, a sixth of the
  // dense grid.
  if (!cudaAvailable()) GTEST_SKIP() << "no CUDA device in this build/machine";
  std::size_t snugBytes = 0, longBytes = 0;
  expectTheCollapseOfItsOwnBox(Backend::Cuda, {3000, 5, 20}, 1000, snugBytes, longBytes);
  // the long box: 0.4 MB of index arrays, 2 MB of P2G tile scratch (a tile per particle, 288),
  // the columns near the flow (at most the snug box's 186 and half again: 0.4 MB), 0.1 MB of points
  EXPECT_GT(longBytes, snugBytes);
  EXPECT_LT(longBytes, std::size_t(4) << 20);
}

TEST(CudaGrid, RunsAGridWhoseDenseValuesPassTwoToThe31) {
  // CpuGrid.RunsAGridWhoseDenseValuesPassTwoToThe31 on CUDA: the collapsing column in a box 22 km
  // long (a dense grid of 18 GB in double) moves as in its own box, to the bit, in its index arrays
  // (an int per node column, six ints per block: 3.0e8 bytes) and the columns near the flow.
  if (!cudaAvailable()) GTEST_SKIP() << "no CUDA device in this build/machine";
  std::size_t snugBytes = 0, hugeBytes = 0;
  expectTheCollapseOfItsOwnBox(Backend::Cuda, {2200000, 5, 20}, 300, snugBytes, hugeBytes);
  EXPECT_LT(hugeBytes, std::size_t(350) << 20);
}

TEST(CudaGrid, AFlowReachingMoreColumnsThanTheDeviceHoldsIsRefusedWithItsStateKept) {
  // A blob sliding across a tall grid (3001 nodes a column: 192 kB of records in double) with
  // the device filled but for 8 MB: when the column pool has to grow, the step is refused with
  // what the flow needs, the particles are those of the step's start, and once the memory is
  // given back the run goes on as one that was never refused, to the bit.
  if (!cudaAvailable()) GTEST_SKIP() << "no CUDA device in this build/machine";
#ifdef MPMSDEM_WITH_CUDA
  MpmParams prm = testing_scenes::granularColumnParams(0.01, {60, 40, 3000}, 1e4);
  prm.gravity = {0, 0, 0};
  ParticleSet ps;
  seedBox(prm, {0.03, 0.03, 0.03}, {0.09, 0.07, 0.08}, {2, 2, 2}, ps);
  for (std::size_t p = 0; p < ps.size(); ++p) ps.v[3 * p] = 1.5, ps.v[3 * p + 1] = 1.0;
  const double dt = 5e-4;  // 0.075 cells a step along x
  auto refused = makeSolver(prm, Backend::Cuda, Precision::Double);
  auto unbroken = makeSolver(prm, Backend::Cuda, Precision::Double);
  refused->setParticles(ps);
  unbroken->setParticles(ps);
  std::size_t freeBytes = 0, total = 0;
  ASSERT_EQ(cudaMemGetInfo(&freeBytes, &total), cudaSuccess);
  void* hog = nullptr;
  for (std::size_t leave = std::size_t(8) << 20; !hog && leave < freeBytes; leave *= 2)
    if (cudaMalloc(&hog, freeBytes - leave) != cudaSuccess) {
      hog = nullptr;
      cudaGetLastError();
    }
  ASSERT_NE(hog, nullptr);
  int failedAt = -1;
  ParticleSet before, after;
  for (int n = 0; n < 600 && failedAt < 0; ++n) {
    refused->getParticles(before);
    try {
      refused->step(dt);
    } catch (const RuntimeFailure& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("node columns"), std::string::npos) << msg;
      EXPECT_NE(msg.find("did not fit on the device"), std::string::npos) << msg;
      failedAt = n;
    }
  }
  ASSERT_GE(failedAt, 1) << "the pool had to grow within 600 steps (45 cells along x)";
  refused->getParticles(after);
  EXPECT_TRUE(after.x == before.x);
  EXPECT_TRUE(after.v == before.v);
  EXPECT_EQ(refused->steps(), failedAt);
  ASSERT_EQ(cudaFree(hog), cudaSuccess);
  for (int n = 0; n < failedAt + 100; ++n) unbroken->step(dt);
  for (int n = failedAt; n < failedAt + 100; ++n) refused->step(dt);
  ParticleSet a, b;
  refused->getParticles(a);
  unbroken->getParticles(b);
  EXPECT_TRUE(a.x == b.x);
  EXPECT_TRUE(a.v == b.v);
  EXPECT_TRUE(a.stress == b.stress);
#endif
}

TEST(ActiveTiles, TilesPartitionTheGridNodes) {
  // Grids whose node counts are and are not multiples of 3: over all tiles, tileNodeOf names
  // every node exactly once, and as many tiles per axis as blocks of stencil bases.
  for (const std::array<int, 3> cells : {std::array<int, 3>{13, 11, 10}, {8, 5, 2}, {3, 3, 3}, {1, 7, 4}}) {
    const int nb[3] = {blocksAlong(cells[0]), blocksAlong(cells[1]), blocksAlong(cells[2])};
    const int nodes[3] = {cells[0] + 1, cells[1] + 1, cells[2] + 1};
    std::vector<int> seen(static_cast<std::size_t>(nodes[0]) * nodes[1] * nodes[2], 0);
    for (int d = 0; d < 3; ++d) EXPECT_EQ(nb[d], (nodes[d] + 2) / 3);  // tiles of 3 nodes cover the axis
    for (int t = 0; t < nb[0] * nb[1] * nb[2]; ++t) {
      int c[3];
      blockCoordsOf(t, nb, c);
      EXPECT_EQ((c[0] * nb[1] + c[1]) * nb[2] + c[2], t);
      for (int k = 0; k < kBlockCells; ++k) {
        const int node = tileNodeOf(t, k, nb, nodes);
        if (node < 0) continue;
        ASSERT_LT(node, static_cast<int>(seen.size()));
        const int i = node / (nodes[1] * nodes[2]), j = (node / nodes[2]) % nodes[1], l = node % nodes[2];
        EXPECT_EQ(i / 3, c[0]);
        EXPECT_EQ(j / 3, c[1]);
        EXPECT_EQ(l / 3, c[2]);
        ++seen[node];
      }
    }
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), static_cast<long>(seen.size()));
  }
}

TEST(ActiveTiles, UpdatingTheActiveTilesIsUpdatingTheWholeGrid) {
  // Particles clustered in part of a grid: the occupied blocks and their tiles as the CUDA step
  // finds them (the first particle of each block in key order marks forTilesOfBlock), then the
  // P2G grid updated on those tiles' nodes only and on every node: the same bits (an empty node's
  // update writes zeros), and every node reached by a particle's stencil lies in a marked tile.
  MpmParams prm;
  prm.dx = 0.01;
  prm.cells = {80, 7, 14};
  prm.origin = {0, 0, 0};
  const GridConst<double> g = makeGridConst<double>(prm, 0.0);
  const int nb[3] = {blocksAlong(prm.cells[0]), blocksAlong(prm.cells[1]), blocksAlong(prm.cells[2])};
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  const int n = 500;
  std::vector<double> x[3], v[3], s[6], J(n, 1.0), mass(n, 2e-4), vol0(n, 1.25e-7);
  std::vector<int> id(n);
  for (int d = 0; d < 3; ++d) x[d].resize(n), v[d].resize(n);
  for (int k = 0; k < 6; ++k) s[k].assign(n, 0.0);
  for (int p = 0; p < n; ++p) {
    const double lo[3] = {0.05, 0.02, 0.02}, span[3] = {0.12, 0.03, 0.06};  // a corner of the box
    for (int d = 0; d < 3; ++d) {
      x[d][p] = lo[d] + span[d] * u(rng);
      v[d][p] = 2 * u(rng) - 1;
    }
    s[0][p] = -1e3 * u(rng);
    id[p] = p;
  }
  ParticleIn<double> in{};
  for (int d = 0; d < 3; ++d) in.x[d] = x[d].data(), in.v[d] = v[d].data();
  for (int k = 0; k < 6; ++k) in.s[k] = s[k].data();
  in.J = J.data(), in.mass = mass.data(), in.vol0 = vol0.data(), in.id = id.data();

  std::vector<long long> key(n);
  for (int p = 0; p < n; ++p) {
    double gc[3];
    gridCoordinate(in, p, g, gc);
    key[p] = blockCellOf(gc, nb);
  }
  std::sort(key.begin(), key.end());
  std::set<int> tiles;
  std::set<int> occupied;
  for (int i = 0; i < n; ++i) {
    const int b = static_cast<int>(key[i] / kBlockCells);
    if (i > 0 && key[i - 1] / kBlockCells == b) continue;
    occupied.insert(b);
    int c[3];
    blockCoordsOf(b, nb, c);
    forTilesOfBlock(c, nb, [&tiles](int t) { tiles.insert(t); });
  }
  const int nTiles = nb[0] * nb[1] * nb[2];
  ASSERT_GT(static_cast<int>(tiles.size()), 8);
  ASSERT_LT(static_cast<int>(tiles.size()), nTiles / 3);  // the point: most of the grid is idle

  const int nNodes = g.nodes[0] * g.nodes[1] * g.nodes[2];
  std::vector<double> grid(static_cast<std::size_t>(kNodeValues) * nNodes, 0.0);
  std::vector<char> reached(nNodes, 0);
  auto add = [&grid, &reached](int node, const double* r) {
    reached[node] = 1;
    for (int c = 0; c < kNodeValues; ++c) grid[kNodeValues * node + c] += r[c];
  };
  for (int p = 0; p < n; ++p) p2gParticle(p, in, g, 5e-5, add);
  std::vector<char> active(nNodes, 0);
  for (int t : tiles)
    for (int k = 0; k < kBlockCells; ++k) {
      const int node = tileNodeOf(t, k, nb, g.nodes);
      if (node >= 0) active[node] = 1;
    }
  for (int i = 0; i < nNodes; ++i) ASSERT_TRUE(!reached[i] || active[i]) << "node " << i;
  std::vector<double> whole = grid, tilesOnly = grid;
  for (int i = 0; i < nNodes; ++i) gridNodeUpdate(i, whole.data(), g, 5e-5);
  for (int i = 0; i < nNodes; ++i)
    if (active[i]) gridNodeUpdate(i, tilesOnly.data(), g, 5e-5);
  EXPECT_TRUE(whole == tilesOnly);
  double moving = 0;
  for (int i = 0; i < nNodes; ++i) moving += std::abs(whole[kNodeValues * i + kNodeVNew]);
  EXPECT_GT(moving, 0.1);  // the update did something
  // every colour's blocks are two apart along some axis from one another: their tiles of 5x5x5
  // nodes share none (P2G adds a colour's tiles without atomics)
  for (int a : occupied)
    for (int b : occupied) {
      if (a >= b) continue;
      int ca[3], cb[3];
      blockCoordsOf(a, nb, ca);
      blockCoordsOf(b, nb, cb);
      if (blockColourOf(ca) != blockColourOf(cb)) continue;
      bool apart = false;
      for (int d = 0; d < 3; ++d) apart = apart || std::abs(ca[d] - cb[d]) >= 2;
      EXPECT_TRUE(apart) << a << " " << b;
    }
}
