// Both backends store their particles sorted by grid block (MpmCpu, "Storage order"; MpmCuda):
// a particle keeps its number through every reordering, the results are those of number order
// (so two runs, and a run restarted from its particles by number, give the same bits), and what
// a coupling reads and writes through the particle view lands on the right particle.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>
#include <vector>

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

MpmParams columnScene(ParticleSet& ps, bool keepLastGoodState = true) {
  MpmParams prm = testing_scenes::granularColumnParams(0.01, {30, 5, 20}, 2e5);
  prm.keepLastGoodState = keepLastGoodState;
  seedBox(prm, {0.02, 0.02, 0.02}, {0.08, 0.03, 0.14}, {2, 1, 2}, ps);
  // Points of unequal size (the same density): a particle's mass and volume must travel with it
  // when the solver reorders the particles.
  for (std::size_t i = 0; i < ps.size(); ++i) {
    const double f = 1 + 0.05 * static_cast<double>(i % 7);
    ps.mass[i] *= f;
    ps.volume0[i] *= f;
  }
  return prm;
}

constexpr double kDt = 2e-4;  // [s]

// A solver of `prm` in `precision` started from `start` and stepped `steps` times by kDt; its
// particles at the end in `end`.
std::unique_ptr<MpmSolver> run(const MpmParams& prm, const ParticleSet& start, int steps, ParticleSet& end,
                               Precision precision = Precision::Double, Backend backend = Backend::Cpu) {
  auto s = makeSolver(prm, backend, precision);
  s->setParticles(start);
  for (int n = 0; n < steps; ++n) s->step(kDt);
  s->getParticles(end);
  return s;
}

// Largest distance a particle moved along x from `start` to `end` [m].
double largestTravel(const ParticleSet& start, const ParticleSet& end) {
  double travel = 0;
  for (std::size_t p = 0; p < start.size(); ++p) travel = std::max(travel, end.x[3 * p] - start.x[3 * p]);
  return travel;
}

// The particle number of each slot of a view, on the host.
std::vector<int> slotNumbers(const ParticleView& v) {
  std::vector<int> id(v.n);
  if (!v.id) {
    std::iota(id.begin(), id.end(), 0);
  } else if (v.device) {
#ifdef MPMSDEM_WITH_CUDA
    EXPECT_EQ(cudaMemcpy(id.data(), v.id, v.n * sizeof(int), cudaMemcpyDeviceToHost), cudaSuccess);
#else
    ADD_FAILURE() << "a device view in a build without CUDA";
#endif
  } else {
    std::copy(v.id, v.id + v.n, id.begin());
  }
  return id;
}

// Slots whose particle number is not the slot itself; fails unless id is a permutation.
long reordered(const ParticleView& v) {
  const std::vector<int> id = slotNumbers(v);
  std::vector<int> seen(v.n, 0);
  long moved = 0;
  for (std::size_t q = 0; q < v.n; ++q) {
    const int k = id[q];
    EXPECT_TRUE(k >= 0 && static_cast<std::size_t>(k) < v.n && !seen[k]) << "slot " << q << " holds number " << k;
    if (k >= 0 && static_cast<std::size_t>(k) < v.n) seen[k] = 1;
    moved += k != static_cast<int>(q);
  }
  return moved;
}

}  // namespace

class StorageOrderEveryBackend : public agreement::EveryBackend {};
INSTANTIATE_TEST_SUITE_P(Kinds, StorageOrderEveryBackend, ::testing::ValuesIn(agreement::everyKind()),
                         agreement::kindName);

TEST_P(StorageOrderEveryBackend, TwoRunsAndARestartByParticleNumberGiveTheSameBits) {
  // A collapsing column: 600 steps in one run, the same again, and 300 + 300 with the state
  // handed over through getParticles/setParticles (by particle number: the new solver starts
  // with slot = number, where the first one had its particles in block order). The flow mixes
  // the particles across blocks, so the storage orders of the runs differ; the results must not
  // (on CUDA: no atomic sum whose order changes from run to run).
  ParticleSet ps;
  const MpmParams prm = columnScene(ps);
  ParticleSet endA, endB, half, endC;
  run(prm, ps, 600, endA, precision(), backend());
  run(prm, ps, 600, endB, precision(), backend());
  auto b = run(prm, ps, 300, half, precision(), backend());
  EXPECT_GT(reordered(b->openForceBuffer()), static_cast<long>(ps.size() / 10));  // stored in an order of its own
  auto c = solver(prm);
  c->setParticles(half);
  EXPECT_EQ(reordered(c->openForceBuffer()), 0);
  for (int n = 0; n < 300; ++n) c->step(kDt);
  c->getParticles(endC);

  EXPECT_GT(largestTravel(ps, endA), 0.02);  // the column did collapse
  agreement::expectBitIdentical(endA, endB);
  agreement::expectBitIdentical(endA, endC);
  for (std::size_t p = 0; p < ps.size(); ++p)
    ASSERT_EQ(endA.mass[p], precision() == Precision::Float ? double(float(ps.mass[p])) : ps.mass[p]) << p;
}

// With a second copy of the particles (G2P writes them in block order) and with one (G2P
// updates them in place, and they are sorted every few steps).
class StorageOrderCopies : public ::testing::TestWithParam<bool> {};
INSTANTIATE_TEST_SUITE_P(KeepLastGoodState, StorageOrderCopies, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& i) { return i.param ? "TwoCopies" : "OneCopy"; });

TEST_P(StorageOrderCopies, ForcesReachTheParticleTheyWereMeantFor) {
  // After the collapse reordered the particles: a force written into the view's slot of particle
  // k, and a force given by number to setExternalForces, both come back as particle k's; the
  // view's position of that slot is particle k's; and the force pushes particle k (against a
  // twin run without it), while particles whose stencils do not reach k's nodes are unchanged.
  ParticleSet ps;
  const MpmParams prm = columnScene(ps, GetParam());
  ParticleSet now;
  auto s = run(prm, ps, 300, now);
  auto twin = makeSolver(prm);
  twin->setParticles(now);

  ParticleView view = s->openForceBuffer();
  ASSERT_GT(reordered(view), 0);
  const int k = static_cast<int>(ps.size() / 3);
  const int slot = static_cast<int>(std::find(view.id, view.id + view.n, k) - view.id);
  ASSERT_NE(slot, k);
  EXPECT_EQ(static_cast<const double*>(view.x[0])[slot], now.x[3 * k]);
  EXPECT_EQ(static_cast<const double*>(view.v[2])[slot], now.v[3 * k + 2]);
  EXPECT_EQ(static_cast<const double*>(view.mass)[slot], ps.mass[k]);
  EXPECT_EQ(static_cast<const double*>(view.volume0)[slot], ps.volume0[k]);
  static_cast<double*>(view.force[2])[slot] = 0.25;
  ParticleSet got;
  s->getParticles(got);
  for (std::size_t p = 0; p < got.size(); ++p)
    for (int d = 0; d < 3; ++d) ASSERT_EQ(got.fext[3 * p + d], p == static_cast<std::size_t>(k) && d == 2 ? 0.25 : 0.0);

  std::vector<double> f(3 * ps.size(), 0.0);
  f[3 * k] = -0.05;  // [N], against the flow
  s->setExternalForces(f);
  s->getParticles(got);
  EXPECT_TRUE(got.fext == f);
  s->step(kDt);
  twin->step(kDt);
  ParticleSet pushed, free;
  s->getParticles(pushed);
  twin->getParticles(free);
  // impulse f dt spread over the nodes around k: particle k slows by a share of f dt / m_k
  const double dv = pushed.v[3 * k] - free.v[3 * k];
  EXPECT_LT(dv, 0);
  EXPECT_GT(dv, -0.05 * kDt / ps.mass[k]);
  long far = 0;
  for (std::size_t p = 0; p < ps.size(); ++p) {
    double reach = 0;
    for (int d = 0; d < 3; ++d) reach = std::max(reach, std::abs(now.x[3 * p + d] - now.x[3 * k + d]));
    if (reach <= 3 * prm.dx) continue;
    ++far;
    for (int d = 0; d < 3; ++d) ASSERT_EQ(pushed.v[3 * p + d], free.v[3 * p + d]) << "particle " << p;
  }
  EXPECT_GT(far, static_cast<long>(ps.size() / 2));
}

TEST(StorageOrder, OneCopyGivesTheSameRunToTheLastBitAndHoldsLessMemory) {
  // The collapsing column with keepLastGoodState on and off, in both precisions, 604 steps (the
  // one-copy run sorts its particles every 8 steps, and ends between two sorts):
  // every output equal to the last bit, and the memory differs by exactly the second copy
  // (14 state values, mass and volume0, the phase byte and the particle number per particle) less
  // the sort's buffer (one value per particle).
  for (const Precision prec : {Precision::Double, Precision::Float}) {
    ParticleSet ps;
    const MpmParams two = columnScene(ps, true), one = columnScene(ps, false);
    ParticleSet endA, endB;
    auto a = run(two, ps, 604, endA, prec);
    auto b = run(one, ps, 604, endB, prec);
    const std::size_t value = prec == Precision::Double ? 8 : 4;
    EXPECT_EQ(a->memoryBytes() - b->memoryBytes(), ps.size() * (15 * value + 1 + sizeof(int)));
    EXPECT_GT(reordered(b->openForceBuffer()), static_cast<long>(ps.size() / 10));
    EXPECT_GT(largestTravel(ps, endB), 0.02);
    agreement::expectBitIdentical(endA, endB);
  }
}

// An output reads the particles in slices by number (MpmSolver::getParticles(out, first,
// count)): each slice is exactly its range of the whole set, with the particles stored in an
// order of their own, on every backend and precision and (CPU) with one or two copies; steps in between make
// the next slices read the particles in their new slots; a slice outside the set is refused by name.
TEST_P(StorageOrderEveryBackend, SlicesByNumberAreTheWholeSetsRanges) {
  for (const bool keep : {true, false}) {
    ParticleSet ps, whole, slice;
    const MpmParams prm = columnScene(ps, keep);
    auto s = run(prm, ps, 30, whole, precision(), backend());
    ASSERT_GT(reordered(s->openForceBuffer()), static_cast<long>(ps.size() / 10));
    for (int pass = 0; pass < 2; ++pass) {
      s->getParticles(whole);
      const std::size_t n = whole.size(), size = 97;  // not a divisor of n: a short last slice
      ASSERT_NE(n % size, 0u);
      for (std::size_t first = 0; first < n; first += size) {
        const std::size_t count = std::min(size, n - first);
        s->getParticles(slice, first, count);
        ASSERT_EQ(slice.size(), count);
        agreement::expectRangeOf(slice, whole, first);
      }
      const std::vector<int> order = slotNumbers(s->openForceBuffer());
      for (int k = 0; k < 200; ++k) s->step(kDt);
      ASSERT_FALSE(order == slotNumbers(s->openForceBuffer())) << "the particles kept their slots";
    }
    EXPECT_THROW(s->getParticles(slice, ps.size() - 2, 3), ParameterError);
  }
}

// Loading slice by slice: forces that first appear in a later slice are loaded (the slices
// before held zeros), and a non-finite one is refused by its index.
TEST(StorageOrder, ForcesFirstGivenInALaterSliceAreLoaded) {
  ParticleSet ps;
  const MpmParams prm = columnScene(ps);
  class InSlices : public ParticleSlices {
   public:
    explicit InSlices(const ParticleSet& set) : set_(set) {}
    std::size_t size() const override { return set_.size(); }
    std::size_t sliceSize() const override { return 97; }
    const ParticleSet& slice(std::size_t first, std::size_t count) override {
      copyParticleRange(set_, first, count, buf_);
      return buf_;
    }

   private:
    const ParticleSet& set_;
    ParticleSet buf_;
  };
  const std::size_t k = ps.size() - 3;
  ASSERT_GT(k, 2 * 97u);
  ps.fext[3 * k + 2] = 0.25;
  auto s = makeSolver(prm);
  InSlices slices(ps);
  s->setParticles(slices);
  ParticleSet got;
  s->getParticles(got);
  EXPECT_TRUE(got.fext == ps.fext);
  ps.fext[3 * k] = std::nan("");
  try {
    s->setParticles(slices);
    ADD_FAILURE() << "a NaN force was loaded";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("externalForces[" + std::to_string(3 * k) + "]"), std::string::npos)
        << e.what();
  }
}
