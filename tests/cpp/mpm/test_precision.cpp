// The CPU backend in float (cpu-float) against double (cpu-double): float arrays behind the
// views, memory, and agreement of the two on the same scenes within bounds scaled by the
// float round-off.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "mpm/MpmKernelsCommon.hpp"
#include "mpm/MpmSolver.hpp"
#include "mpm/Seeding.hpp"

#include "AgreementHelpers.hpp"
#include "GranularColumn.hpp"

using namespace mpmsdem;
using namespace mpmsdem::mpm;

namespace {

// Quasi-2D glass-bead column (one cell thick) on a rough base, free-slip elsewhere; rho_c half
// the bulk density keeps it away from the discontinuous gasification switch, where two runs
// that differ by round-off would part by a whole stress.
MpmParams columnParams(std::array<int, 3> cells) {
  MpmParams p = testing_scenes::granularColumnParams(0.01, cells, 2e5);
  p.material.criticalDensity = 0.5 * p.material.density;
  return p;
}

double kineticEnergy(const ParticleSet& ps) {
  double e = 0;
  for (std::size_t p = 0; p < ps.size(); ++p)
    e += 0.5 * ps.mass[p] * (ps.v[3 * p] * ps.v[3 * p] + ps.v[3 * p + 1] * ps.v[3 * p + 1] + ps.v[3 * p + 2] * ps.v[3 * p + 2]);
  return e;
}

// 99th percentile of x: the front, robust to a single point.
double front(const ParticleSet& ps) {
  std::vector<double> xs;
  for (std::size_t p = 0; p < ps.size(); ++p) xs.push_back(ps.x[3 * p]);
  std::sort(xs.begin(), xs.end());
  return xs[static_cast<std::size_t>(0.99 * (xs.size() - 1))];
}

bool isFloat(double v) { return static_cast<double>(static_cast<float>(v)) == v; }

// Records the precision of the grid it was shown and the node mass it sums.
struct GridProbe : GridHook {
  Precision precision = Precision::Double;
  double mass = 0;
  long stored = 0;  // node records behind the view
  void apply(const GridView& g) override {
    precision = g.precision;
    stored = g.storedNodes;
    const float* m = static_cast<const float*>(g.mass);
    mass = 0;
    for (long i = 0; i < g.storedNodes; ++i) mass += m[i * g.stride];
  }
};

}  // namespace

TEST(CpuFloat, HoldsFloatArraysBehindItsViews) {
  MpmParams prm = columnParams({10, 5, 12});
  ParticleSet ps;
  seedBox(prm, {0.02, 0.02, 0.02}, {0.06, 0.03, 0.08}, {2, 1, 2}, ps);
  auto f = makeSolver(prm, Backend::Cpu, Precision::Float);
  auto d = makeSolver(prm, Backend::Cpu, Precision::Double);
  EXPECT_EQ(f->name(), "cpu-float");
  EXPECT_EQ(d->name(), "cpu-double");
  f->setParticles(ps);
  d->setParticles(ps);
  // the state is stored in float: every value read back is a float, the double solver's the input
  ParticleSet a, b;
  f->getParticles(a);
  d->getParticles(b);
  EXPECT_TRUE(std::all_of(a.x.begin(), a.x.end(), isFloat));
  EXPECT_TRUE(std::all_of(a.mass.begin(), a.mass.end(), isFloat));
  EXPECT_FALSE(std::all_of(ps.x.begin(), ps.x.end(), isFloat));  // so the check above means something
  EXPECT_TRUE(b.x == ps.x);

  const ParticleView v = f->openForceBuffer();
  EXPECT_EQ(v.precision, Precision::Float);
  EXPECT_FALSE(v.device);
  ASSERT_EQ(v.n, ps.size());
  for (std::size_t p = 0; p < v.n; ++p) {
    EXPECT_EQ(static_cast<const float*>(v.x[2])[p], static_cast<float>(ps.x[3 * p + 2]));
    EXPECT_EQ(static_cast<const float*>(v.mass)[p], static_cast<float>(ps.mass[p]));
    EXPECT_EQ(static_cast<float*>(v.force[0])[p], 0.0f);
  }
  static_cast<float*>(v.force[0])[0] = 1.5f;  // read back as the particle's external force
  f->getParticles(a);
  EXPECT_EQ(a.fext[0], 1.5);

  auto probe = std::make_shared<GridProbe>();
  f->addGridHook(probe);
  f->step(0.5 * f->stableTimeStep());
  EXPECT_EQ(probe->precision, Precision::Float);
  const double M = std::accumulate(a.mass.begin(), a.mass.end(), 0.0);
  // the grid's mass is the particles' (B-spline weights sum to one); each node's is a float sum
  // of at most 27 x 4 shares (4 points per cell), within 27 x 4 x eps/2 = 6.4e-6 of it
  EXPECT_NEAR(probe->mass, M, 27 * 4 * 0.5 * agreement::roundOff(Precision::Float) * M);
}

TEST(CpuFloat, HalvesEveryArrayOfT) {
  // Every particle and grid array is T, the particle numbers and the binning arrays int: the
  // double solver holds exactly 4 bytes more per value, 32 values per particle (16 twice: 14
  // state values, mass and volume0) and 8 per grid node (7 and a pad), and 3 per particle more once a force buffer is
  // opened.
  // The grid holds the node columns the particles have reached (both solvers the same ones):
  // points at x 0.0225 .. 0.0975 m have stencil bases 1 .. 9, in blocks 0 .. 3 of 3 bases, whose
  // tiles 0 .. 4 cover nodes 0 .. 14 along x (of 21), every y (6) and z (23).
  MpmParams prm = columnParams({20, 5, 22});
  ParticleSet ps;
  seedBox(prm, {0.02, 0.02, 0.02}, {0.10, 0.03, 0.18}, {2, 1, 2}, ps);
  auto f = makeSolver(prm, Backend::Cpu, Precision::Float);
  auto d = makeSolver(prm, Backend::Cpu, Precision::Double);
  f->setParticles(ps);
  d->setParticles(ps);
  auto fp = std::make_shared<GridProbe>(), dp = std::make_shared<GridProbe>();
  f->addGridHook(fp);
  d->addGridHook(dp);
  const double dt = 0.5 * d->stableTimeStep();
  f->step(dt);
  d->step(dt);
  ASSERT_EQ(fp->stored, dp->stored);
  EXPECT_EQ(dp->stored, 15 * 6 * 23);
  const std::size_t n = ps.size(), nodes = static_cast<std::size_t>(dp->stored);
  EXPECT_EQ(d->memoryBytes() - f->memoryBytes(), 4 * (32 * n + 8 * nodes));
  f->openForceBuffer();
  d->openForceBuffer();
  EXPECT_EQ(d->memoryBytes() - f->memoryBytes(), 4 * (35 * n + 8 * nodes));
  // and what float holds per particle: 32 floats, 2 phase bytes, 8 number bytes, 8 binning bytes
  // and 3 forces,
  // besides the grid's 8 floats per node, its column map (an int per column of nodes, 21 x 6)
  // and the block lists of the P2G colouring (two to four ints per block of 3 x 3 x 3 cells)
  const double blocks = (20 / 3 + 1) * (5 / 3 + 1) * (22 / 3 + 1);
  const double perParticle = (f->memoryBytes() - 8.0 * 4 * nodes) / n;
  EXPECT_GE(perParticle, 32 * 4 + 2 + 8 + 8 + 12);
  EXPECT_LE(perParticle, 32 * 4 + 2 + 8 + 8 + 12 + (4 * 4 * blocks + 4 * 21 * 6) / n);
}

TEST(CpuFloat, AgreesWithDoubleOnACollapsingColumn) {
  // A 0.08 m x 0.16 m column released on a rough base, n = 200 and 1000 steps (0.02 s: the
  // collapse under way; 0.11 s: the front near its final runout).
  // Bounds, with eps = 1.2e-7 the float unit round-off (measured differences in brackets):
  //  - stresses: each step adds a float rounding of the stress increment, and these do not
  //    average out (the elastic update integrates them): |d sigma| <= 2 n eps max|sigma|
  //    (measured 0.2 to 0.3 n eps);
  //  - positions: x += dt v rounds to eps x each step, in random directions, plus the velocity
  //    differences integrated: |dx| <= 5 sqrt(n) eps L with L = 0.2 m the column's extent
  //    (measured 0.4 sqrt(n) eps L); the front (99th percentile of x) within the same;
  //  - kinetic energy: relative difference <= n eps (measured 0.01 n eps).
  const double eps = agreement::roundOff(Precision::Float), L = 0.2;
  MpmParams prm = columnParams({20, 5, 22});
  ParticleSet ps;
  seedBox(prm, {0.02, 0.02, 0.02}, {0.10, 0.03, 0.18}, {2, 1, 2}, ps);
  double frontMoved = 0;
  for (int n : {200, 1000}) {
    auto d = makeSolver(prm, Backend::Cpu, Precision::Double);
    auto f = makeSolver(prm, Backend::Cpu, Precision::Float);
    d->setParticles(ps);
    const double dt = 0.5 * d->stableTimeStep();  // margin for the speeds the collapse reaches
    ParticleSet a, b;
    agreement::runPair(*d, *f, ps, dt, n, a, b);
    const agreement::Agreement r = agreement::compare(a, b);
    const double ka = kineticEnergy(a), kb = kineticEnergy(b);
    std::printf("cpu-float vs cpu-double, %d steps: |dx| %.2e m, |dsigma| %.2e of %.0f Pa, KE %.6e / %.6e J, front %.6f / %.6f m\n",
                n, r.position, r.stress, r.stressScale, ka, kb, front(a), front(b));
    EXPECT_LT(r.stress, 2 * n * eps * r.stressScale) << n << " steps";
    EXPECT_LT(r.position, 5 * std::sqrt(double(n)) * eps * L) << n << " steps";
    EXPECT_NEAR(front(b), front(a), 5 * std::sqrt(double(n)) * eps * L) << n << " steps";
    EXPECT_NEAR(kb, ka, n * eps * ka) << n << " steps";
    EXPECT_GT(r.stressScale, 1000.0);  // the column carries its weight
    frontMoved = front(a) - 0.10;
  }
  EXPECT_GT(frontMoved, 0.02);  // and it did collapse: the front ran out by more than 2 cells
}
