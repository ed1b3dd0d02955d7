// The CUDA backend's P2G gathers (MpmCudaKernels.cuh, p2gBaseKernel): particles sorted by block of
// stencil bases, base and number; the particles of each base summed in that order into its 27
// nodes (p2gBasePrepare, p2gBaseNodeAdd), then each node of the block's 5x5x5 tile summing the
// bases that reach it in base order (p2gBaseTileSum); the blocks of one parity colour at a time.
// Here the same shared functions run that algorithm on the host, against the per-particle scatter
// (p2gParticle) and against the CPU backend's grid.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>
#include <random>
#include <vector>

#include "mpm/MpmKernelsCommon.hpp"
#include "mpm/MpmSolver.hpp"

using namespace mpmsdem;
using namespace mpmsdem::mpm;

namespace {

// Particles stored by slot, with the number of each slot.
struct Slots {
  std::vector<double> x[3], v[3], s[6], f[3], J, mass, vol0;
  std::vector<int> id;
  ParticleIn<double> in() const {
    ParticleIn<double> p;
    for (int d = 0; d < 3; ++d) {
      p.x[d] = x[d].data();
      p.v[d] = v[d].data();
      p.fext[d] = f[d].data();
    }
    for (int k = 0; k < 6; ++k) p.s[k] = s[k].data();
    p.J = J.data();
    p.mass = mass.data();
    p.vol0 = vol0.data();
    p.id = id.data();
    return p;
  }
  // The same particles in the slots `perm` gives: slot q holds this set's slot perm[q].
  Slots permuted(const std::vector<int>& perm) const {
    Slots o;
    auto move = [&perm](const std::vector<double>& a, std::vector<double>& b) {
      b.resize(a.size());
      for (std::size_t q = 0; q < a.size(); ++q) b[q] = a[perm[q]];
    };
    for (int d = 0; d < 3; ++d) move(x[d], o.x[d]), move(v[d], o.v[d]), move(f[d], o.f[d]);
    for (int k = 0; k < 6; ++k) move(s[k], o.s[k]);
    move(J, o.J), move(mass, o.mass), move(vol0, o.vol0);
    o.id.resize(id.size());
    for (std::size_t q = 0; q < id.size(); ++q) o.id[q] = id[perm[q]];
    return o;
  }
};

// A grid whose cell counts are not multiples of 3 (blocks cut by the far faces).
MpmParams tileScene() {
  MpmParams prm;
  prm.dx = 0.01;
  prm.cells = {13, 11, 10};
  prm.origin = {0, 0, 0};
  return prm;
}

// n particles spread over the admissible box, clustered so that blocks hold from none to dozens,
// with random mass, velocity, stress, J, volume and external force.
Slots randomParticles(const GridConst<double>& g, int n) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  Slots p;
  for (int d = 0; d < 3; ++d) {
    p.x[d].resize(n), p.v[d].resize(n), p.f[d].resize(n);
  }
  for (int k = 0; k < 6; ++k) p.s[k].resize(n);
  p.J.resize(n), p.mass.resize(n), p.vol0.resize(n), p.id.resize(n);
  for (int i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) {
      const double t = i % 3 == 0 ? u(rng) : 0.3 + 0.4 * u(rng) * u(rng);
      p.x[d][i] = g.lo[d] + t * (g.hi[d] - g.lo[d]);
      p.v[d][i] = 2 * u(rng) - 1;
      p.f[d][i] = 1e-3 * (2 * u(rng) - 1);
    }
    for (int k = 0; k < 6; ++k) p.s[k][i] = 1e3 * (2 * u(rng) - 1);
    p.J[i] = 0.9 + 0.2 * u(rng);
    p.vol0[i] = (0.5 + u(rng)) * 1.25e-7;
    p.mass[i] = 1800 * p.vol0[i];
    p.id[i] = i;
  }
  return p;
}

constexpr double kDt = 5e-5;  // [s], below the stable step of the default material at dx 0.01 m

// The grid after P2G by the per-particle scatter, slot by slot.
std::vector<double> scatterGrid(const GridConst<double>& g, const Slots& p) {
  const int nodes = g.nodes[0] * g.nodes[1] * g.nodes[2];
  std::vector<double> grid(static_cast<std::size_t>(kNodeValues) * nodes, 0.0);
  const ParticleIn<double> in = p.in();
  auto add = [&grid](int node, const double* r) {
    for (int c = 0; c < kNodeValues; ++c) grid[kNodeValues * node + c] += r[c];
  };
  for (int q = 0; q < static_cast<int>(p.id.size()); ++q) p2gParticle(q, in, g, kDt, add);
  return grid;
}

// The grid after P2G by the CUDA backend's algorithm, run serially.
std::vector<double> gatherGrid(const GridConst<double>& g, const Slots& p) {
  const int nb[3] = {blocksAlong(g.cells[0]), blocksAlong(g.cells[1]), blocksAlong(g.cells[2])};
  const int n = static_cast<int>(p.id.size());
  const ParticleIn<double> in = p.in();
  // sort by (block and base, number), as binKernel's keys and the radix sort do
  std::vector<long long> key(n);
  for (int q = 0; q < n; ++q) {
    double gc[3];
    gridCoordinate(in, q, g, gc);
    key[q] = (static_cast<long long>(blockCellOf(gc, nb)) << 32) | p.id[q];
  }
  std::vector<int> sorted(n);
  std::iota(sorted.begin(), sorted.end(), 0);
  std::sort(sorted.begin(), sorted.end(), [&key](int a, int b) { return key[a] < key[b]; });
  const int nodes = g.nodes[0] * g.nodes[1] * g.nodes[2];
  std::vector<double> grid(static_cast<std::size_t>(kNodeValues) * nodes, 0.0);
  // the blocks of one colour at a time; in a block, base by base (warps in a row of bases), then
  // each tile node from the sums of the bases that reach it, row by row
  for (int colour = 0; colour < 8; ++colour)
    for (int b0 = colour >> 2; b0 < nb[0]; b0 += 2)
      for (int b1 = (colour >> 1) & 1; b1 < nb[1]; b1 += 2)
        for (int b2 = colour & 1; b2 < nb[2]; b2 += 2) {
          const long long first = kBlockCells * ((static_cast<long long>(b0) * nb[1] + b1) * nb[2] + b2);
          double part[kBlockCells][kBlockCells][kNodeVNew + 3] = {};  // [base][its node][value]
          for (int q : sorted) {
            const long long cell = (key[q] >> 32) - first;
            if (cell < 0 || cell >= kBlockCells) continue;
            P2GBaseParticle<double> a;
            p2gBasePrepare(q, in, g, kDt, a);
            for (int m = 0; m < kBlockCells; ++m) p2gBaseNodeAdd(a, m / 9, (m / 3) % 3, m % 3, part[cell][m]);
          }
          for (int n0 = 0; n0 < kBlockNodes; ++n0)
            for (int n1 = 0; n1 < kBlockNodes; ++n1)
              for (int n2 = 0; n2 < kBlockNodes; ++n2) {
                const int g0 = 3 * b0 + n0, g1 = 3 * b1 + n1, g2 = 3 * b2 + n2;
                if (g0 >= g.nodes[0] || g1 >= g.nodes[1] || g2 >= g.nodes[2]) continue;
                double acc[kNodeVNew + 3] = {};
                for (int row = 0; row < 3; ++row)
                  p2gBaseTileSum(
                      row, n0, n1, n2,
                      [&](int o1, int o2, int m) -> const double* { return part[9 * row + 3 * o1 + o2][m]; }, acc);
                double* r = grid.data() + kNodeValues * ((g0 * g.nodes[1] + g1) * g.nodes[2] + g2);
                for (int v = 0; v < kNodeVNew + 3; ++v) r[v] += acc[v];
              }
        }
  return grid;
}

// Records the node masses a step's P2G left (a grid hook sees them unchanged).
class MassRecorder : public GridHook {
 public:
  std::vector<double> mass;
  void apply(const GridView& v) override {
    const int nodes = v.nodes[0] * v.nodes[1] * v.nodes[2];
    mass.assign(nodes, 0.0);  // a node that is not stored is empty
    for (int i = 0; i < nodes; ++i)
      if (const long r = v.record(i); r >= 0) mass[i] = static_cast<const double*>(v.mass)[v.stride * r];
  }
};

}  // namespace

TEST(P2GTiles, TheGatherSumsWhatTheScatterSums) {
  // 3000 particles, blocks from empty to ~60 particles: every node value of the gather equals the
  // scatter's to round-off (the two sum in different orders), mass and momentum included.
  const MpmParams prm = tileScene();
  const GridConst<double> g = makeGridConst<double>(prm, 0.0);
  const Slots p = randomParticles(g, 3000);
  const std::vector<double> a = scatterGrid(g, p), b = gatherGrid(g, p);
  ASSERT_EQ(a.size(), b.size());
  double scale[kNodeValues] = {}, totalA[kNodeValues] = {}, totalB[kNodeValues] = {};
  for (std::size_t i = 0; i < a.size(); ++i) {
    scale[i % kNodeValues] = std::max(scale[i % kNodeValues], std::abs(a[i]));
    totalA[i % kNodeValues] += a[i];
    totalB[i % kNodeValues] += b[i];
  }
  for (int c = 0; c < kNodeVNew + 3; ++c) ASSERT_GT(scale[c], 0) << "value " << c;
  long touched = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_NEAR(b[i], a[i], 64 * 2.2e-16 * scale[i % kNodeValues])
        << "node " << i / kNodeValues << " value " << i % kNodeValues;
    touched += i % kNodeValues == kNodeMass && a[i] > 0;
  }
  EXPECT_GT(touched, 600);  // most of the 14 x 12 x 11 nodes
  double mass = 0;
  for (double m : p.mass) mass += m;
  EXPECT_NEAR(totalB[kNodeMass], mass,
              1e-13 * mass);  // the weights of a particle sum to 1
  for (int d = 0; d < 3; ++d) {
    double momentum = 0;
    for (std::size_t q = 0; q < p.mass.size(); ++q) momentum += p.mass[q] * p.v[d][q];
    EXPECT_NEAR(totalB[d], momentum, 1e-12 * mass);
  }
  EXPECT_EQ(b[kNodeValues * 5 + 7], 0.0);  // the pad value stays zero
}

TEST(P2GTiles, TheGatherDoesNotDependOnTheStorageOrder) {
  // The same particles in reversed and shuffled slots (numbers kept): the same bits.
  const MpmParams prm = tileScene();
  const GridConst<double> g = makeGridConst<double>(prm, 0.0);
  const Slots p = randomParticles(g, 3000);
  const std::vector<double> ref = gatherGrid(g, p);
  std::vector<int> perm(p.id.size());
  std::iota(perm.rbegin(), perm.rend(), 0);
  EXPECT_TRUE(gatherGrid(g, p.permuted(perm)) == ref);
  std::shuffle(perm.begin(), perm.end(), std::mt19937(3));
  EXPECT_TRUE(gatherGrid(g, p.permuted(perm)) == ref);
  EXPECT_FALSE(scatterGrid(g, p.permuted(perm)) == scatterGrid(g, p)) << "the scatter's order should matter";
}

TEST(P2GTiles, TheGatherGivesTheCpuBackendsNodeMasses) {
  // The CPU backend scatters a block's particles into a private tile in the order (base, number),
  // the gather sums them base by base and then the bases: node masses agree to the round-off of a
  // sum of a few hundred positive shares (< 1e-12 of the node's mass).
  const MpmParams prm = tileScene();
  const GridConst<double> g = makeGridConst<double>(prm, 0.0);
  const Slots p = randomParticles(g, 3000);
  ParticleSet ps;
  const std::size_t n = p.id.size();
  ps.x.resize(3 * n), ps.v.resize(3 * n), ps.stress.resize(6 * n);
  ps.J.resize(n), ps.mass.resize(n), ps.volume0.resize(n);
  for (std::size_t q = 0; q < p.id.size(); ++q) {
    for (int d = 0; d < 3; ++d) {
      ps.x[3 * q + d] = p.x[d][q];
      ps.v[3 * q + d] = p.v[d][q];
    }
    for (int k = 0; k < 6; ++k) ps.stress[6 * q + k] = p.s[k][q];
    ps.J[q] = p.J[q];
    ps.mass[q] = p.mass[q];
    ps.volume0[q] = p.vol0[q];
  }
  auto solver = makeSolver(prm);
  auto rec = std::make_shared<MassRecorder>();
  solver->addGridHook(rec);
  solver->setParticles(ps);
  solver->step(kDt);
  const std::vector<double> b = gatherGrid(g, p);
  ASSERT_EQ(rec->mass.size() * kNodeValues, b.size());
  // The grid update empties nodes of mass <= 1e-12 times the mean particle mass.
  const double empty = 1e-12 * std::accumulate(p.mass.begin(), p.mass.end(), 0.0) / static_cast<double>(n);
  long compared = 0;
  for (std::size_t i = 0; i < rec->mass.size(); ++i) {
    const double m = b[kNodeValues * i + kNodeMass];
    ASSERT_NEAR(rec->mass[i], m > empty ? m : 0.0, 1e-12 * m) << "node " << i;
    compared += m > empty;
  }
  EXPECT_GT(compared, 600);
}

// The CUDA backend's one-launch P2G for small grids (p2gTilesKernel, p2gTileSumsKernel): every
// occupied block's tile summed apart, then each node adding the tiles that reach it
// (tilesOfNode) in colour order from zero. In a grid of 4 x 3 x 5 blocks with about half of them
// occupied and random tiles of widely spread magnitudes (so that any other order of the additions
// changes bits), every node equals, bit for bit, the grid that adding the tiles colour by colour
// (p2gBaseKernel's launches) leaves; a node of a grid with every block occupied is reached by 8
// tiles inside, fewer at the faces.
TEST(P2GTiles, EachNodeAddingItsTilesInColourOrderIsTheColourLaunches) {
  const int cells[3] = {10, 7, 13};
  const int nb[3] = {blocksAlong(cells[0]), blocksAlong(cells[1]), blocksAlong(cells[2])};
  const int nodes[3] = {cells[0] + 1, cells[1] + 1, cells[2] + 1};
  ASSERT_EQ(nb[0] * nb[1] * nb[2], 60);
  constexpr int kTile = kBlockNodes * kBlockNodes * kBlockNodes, kV = kNodeVNew + 3;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0), e(-12.0, 12.0);
  const int nBlocks = nb[0] * nb[1] * nb[2];
  for (const bool every : {false, true}) {
    std::vector<int> slotOf(nBlocks, -1);
    std::vector<double> tiles;
    for (int b = 0; b < nBlocks; ++b)
      if (every || rng() % 2) {
        slotOf[b] = static_cast<int>(tiles.size() / (kTile * kV));
        for (int k = 0; k < kTile * kV; ++k) tiles.push_back(u(rng) * std::pow(10.0, e(rng)));
      }
    const std::size_t nNodes = static_cast<std::size_t>(nodes[0]) * nodes[1] * nodes[2];
    std::vector<double> byColour(nNodes * kV, 0.0);
    for (int colour = 0; colour < 8; ++colour)
      for (int b = 0; b < nBlocks; ++b) {
        int c[3];
        blockCoordsOf(b, nb, c);
        if (slotOf[b] < 0 || blockColourOf(c) != colour) continue;
        for (int t = 0; t < kTile; ++t) {
          const int g0 = 3 * c[0] + t / 25, g1 = 3 * c[1] + (t / 5) % 5, g2 = 3 * c[2] + t % 5;
          if (g0 >= nodes[0] || g1 >= nodes[1] || g2 >= nodes[2]) continue;
          for (int v = 0; v < kV; ++v)
            byColour[((static_cast<std::size_t>(g0) * nodes[1] + g1) * nodes[2] + g2) * kV + v] +=
                tiles[(static_cast<std::size_t>(slotOf[b]) * kTile + t) * kV + v];
        }
      }
    int most = 0, least = 8, differing = 0;
    for (int g0 = 0; g0 < nodes[0]; ++g0)
      for (int g1 = 0; g1 < nodes[1]; ++g1)
        for (int g2 = 0; g2 < nodes[2]; ++g2) {
          const int gn[3] = {g0, g1, g2};
          int slot[8], local[8];
          tilesOfNode(gn, nb, [&](int b) { return slotOf[b]; }, slot, local);
          double sum[kV] = {};
          int reached = 0;
          for (int colour = 0; colour < 8; ++colour) {
            if (slot[colour] < 0) continue;
            ++reached;
            for (int v = 0; v < kV; ++v) sum[v] += tiles[(static_cast<std::size_t>(slot[colour]) * kTile + local[colour]) * kV + v];
          }
          most = std::max(most, reached), least = std::min(least, reached);
          const std::size_t node = (static_cast<std::size_t>(g0) * nodes[1] + g1) * nodes[2] + g2;
          for (int v = 0; v < kV; ++v) differing += sum[v] != byColour[node * kV + v];
        }
    EXPECT_EQ(differing, 0) << (every ? "every block occupied" : "half the blocks occupied");
    if (every) {
      EXPECT_EQ(most, 8);
      EXPECT_EQ(least, 1);  // the corner node (0, 0, 0)
    }
  }
}
