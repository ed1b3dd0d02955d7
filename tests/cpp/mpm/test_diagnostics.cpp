// Flow probes (the paper's free-flow tests, §3.2.3 and §5): the depth and velocity a probe reads
// from a particle state, and the arrival, h_f and v_f it reports over a run, against values
// worked out by hand.
#include <gtest/gtest.h>

#include <cmath>

#include "mpm/Diagnostics.hpp"
#include "mpm/MpmSolver.hpp"
#include "mpm/MpmTypes.hpp"
#include "mpm/Seeding.hpp"

#include "GranularColumn.hpp"

using namespace mpmsdem;
using namespace mpmsdem::mpm;

namespace {

// Points (x, z, mass, v_x), at y = 0, at rest across y and z.
ParticleSet points(const std::vector<std::array<double, 4>>& rows) {
  ParticleSet p;
  for (const auto& r : rows) {
    p.x.insert(p.x.end(), {r[0], 0.0, r[1]});
    p.v.insert(p.v.end(), {r[3], 0.0, 0.0});
    p.stress.insert(p.stress.end(), 6, 0.0);
    p.mass.push_back(r[2]);
    p.volume0.push_back(1e-6);
    p.J.push_back(1);
    p.phase.push_back(0);
  }
  return p;
}

}  // namespace

TEST(FlowProbe, ReadsTheHighestPointAndTheMassWeightedVelocityAtTheStation) {
  // Two points within 0.1 m of x = 1 (one exactly on the edge), two outside it.
  const ParticleSet p =
      points({{0.9, 0.30, 1.0, 2.0}, {1.05, 0.50, 3.0, 4.0}, {1.2, 9.0, 5.0, 7.0}, {0.7, 8.0, 1.0, 1.0}});
  WholeParticleSet all(p);
  FlowProbeSpec near{1.0, 0.1, 0.1, 2, 0.05}, strict = near, empty = near;
  strict.minPoints = 3;
  empty.x = 3.0;
  const Diagnostics d = diagnose(all, {0, 0, -9.81}, {near, strict, empty});
  ASSERT_EQ(d.probes.size(), 3u);
  EXPECT_EQ(d.probes[0].points, 2);
  EXPECT_NEAR(d.probes[0].depth, 0.50 - 0.1, 1e-15);                    // highest point above the bed
  EXPECT_NEAR(d.probes[0].velocity, (1 * 2.0 + 3 * 4.0) / 4.0, 1e-15);  // 3.5 m/s
  // fewer points than min_points: the front has not arrived, nothing is read
  EXPECT_EQ(d.probes[1].points, 2);
  EXPECT_EQ(d.probes[1].depth, 0.0);
  EXPECT_EQ(d.probes[1].velocity, 0.0);
  EXPECT_EQ(d.probes[2].points, 0);
  // the whole-set diagnostics do not change with the probes
  const Diagnostics plain = diagnose(all, {0, 0, -9.81});
  EXPECT_EQ(plain.kineticEnergy, d.kineticEnergy);
  EXPECT_TRUE(plain.probes.empty());
}

TEST(FlowProbe, RecordGivesTheArrivalAndTheMeansOverTheWindow) {
  FlowProbeRecord r({0.5, 0.01, 0.0, 4, 0.05});
  auto at = [](double depth, double velocity, long points) { return ProbeSample{depth, velocity, points}; };
  r.add(0.00, at(0, 0, 0));
  r.add(0.10, at(0, 0, 3));  // below min_points: not arrived
  EXPECT_FALSE(r.arrival());
  r.add(0.20, at(0.04, 1.0, 5));
  r.add(0.23, at(0.06, 2.0, 9));
  r.add(0.24, at(0, 0, 2));       // the front thinned out within the window: not averaged
  r.add(0.25, at(0.05, 3.0, 9));  // exactly arrival + window: averaged
  EXPECT_FALSE(r.complete());
  r.add(0.2500001, at(9, 9, 9));  // past the window: complete, not averaged
  EXPECT_TRUE(r.complete());
  r.add(0.30, at(9, 9, 9));
  ASSERT_TRUE(r.arrival());
  EXPECT_EQ(*r.arrival(), 0.20);
  EXPECT_NEAR(r.depth(), (0.04 + 0.06 + 0.05) / 3, 1e-15);
  EXPECT_NEAR(r.velocity(), 2.0, 1e-15);
  EXPECT_EQ(r.records(), 8);
}

TEST(FlowProbe, ARecordThatNeverSeesTheFlowHasNoResult) {
  FlowProbeRecord r({0.5, 0.01, 0.0, 4, 0.0});
  for (int k = 0; k < 5; ++k) r.add(0.1 * k, ProbeSample{});
  EXPECT_FALSE(r.arrival());
  EXPECT_FALSE(r.complete());
  EXPECT_EQ(r.depth(), 0.0);
  EXPECT_EQ(r.velocity(), 0.0);
}

// The CUDA backend's reduction of the diagnostics on the device (MpmSolver::diagnosticSums)
// against the host's pass over the same particles read back in slices: maxima and counts
// equal, sums of positive terms within the round-off of another order of the same double terms
// (1e-12 relative; the probes' mean velocities 1e-12 of the largest speed), on a column 100
// steps into its collapse with two probes across the flow; two
// reductions give the same bits; more stations than the device carries fall back to slices.
TEST(Diagnostics, CudaReductionIsTheHostPassOverTheSameParticles) {
  if (!cudaAvailable()) GTEST_SKIP() << "no CUDA device in this build/machine: device diagnostics check skipped";
  const MpmParams prm = testing_scenes::granularColumnParams(0.01, {30, 12, 24}, 2e5);
  ParticleSet ps;
  seedBox(prm, {0.02, 0.02, 0.02}, {0.10, 0.10, 0.20}, {2, 2, 2}, ps);
  const std::array<double, 3> g = prm.gravity;
  const std::vector<FlowProbeSpec> probes = {{0.09, 0.01, 0.02, 1, 0.05}, {0.05, 0.005, 0.02, 1, 0.05}};
  for (auto prec : {Precision::Double, Precision::Float}) {
    auto s = makeSolver(prm, Backend::Cuda, prec);
    s->setParticles(ps);
    const double dt = 0.8 * s->stableTimeStep();
    for (int i = 0; i < 100; ++i) s->step(dt);
    SolverParticleSlices slices(*s, 1000);
    const Diagnostics host = diagnose(slices, g, probes);
    const Diagnostics dev = diagnose(*s, slices, g, probes);
    const Diagnostics again = diagnose(*s, slices, g, probes);
    std::printf("%s: kinetic %.6e J (host %.6e), front %.6f m, probes %ld and %ld points\n", s->name().c_str(),
                dev.kineticEnergy, host.kineticEnergy, dev.frontX, dev.probes[0].points, dev.probes[1].points);
    ASSERT_GT(host.kineticEnergy, 0.0);
    ASSERT_GT(host.probes[0].points, 0) << "no point at the first probe";
    auto near = [](double a, double b) { return std::abs(a - b) <= 1e-12 * std::abs(b); };
    EXPECT_TRUE(near(dev.kineticEnergy, host.kineticEnergy)) << dev.kineticEnergy << " vs " << host.kineticEnergy;
    EXPECT_TRUE(near(dev.potential, host.potential)) << dev.potential << " vs " << host.potential;
    for (int a = 0; a < 3; ++a) EXPECT_TRUE(near(dev.com[a], host.com[a])) << a;
    EXPECT_EQ(dev.frontX, host.frontX);
    EXPECT_EQ(dev.heightZ, host.heightZ);
    EXPECT_EQ(dev.maxSpeed, host.maxSpeed);
    EXPECT_EQ(dev.flowing, host.flowing);
    EXPECT_EQ(dev.gasified, host.gasified);
    for (std::size_t k = 0; k < probes.size(); ++k) {
      EXPECT_EQ(dev.probes[k].points, host.probes[k].points) << k;
      EXPECT_EQ(dev.probes[k].depth, host.probes[k].depth) << k;
      // a mean of velocities of either sign: its round-off is relative to the largest speed
      EXPECT_NEAR(dev.probes[k].velocity, host.probes[k].velocity, 1e-12 * host.maxSpeed) << k;
    }
    EXPECT_EQ(again.kineticEnergy, dev.kineticEnergy);
    EXPECT_EQ(again.potential, dev.potential);
    DiagnosticSums sums;
    std::vector<ProbeSums> probeSums;
    EXPECT_FALSE(s->diagnosticSums(g, std::vector<ProbeStation>(kMaxDeviceProbes + 1, {0.1, 0.01}), sums, probeSums));
  }
}
