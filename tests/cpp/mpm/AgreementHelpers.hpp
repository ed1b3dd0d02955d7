// Agreement of two MPM runs of one scene (CPU against CUDA, float against double): the same
// particles stepped by two solvers, compared field by field against the field's own scale.
#pragma once
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "mpm/MpmSolver.hpp"

namespace mpmsdem {
namespace mpm {

// GoogleTest prints a Precision parameter by its name.
inline void PrintTo(Precision p, std::ostream* os) { *os << (p == Precision::Float ? "float" : "double"); }

namespace agreement {

// Unit round-off of a precision: the relative spacing of its numbers near 1.
inline double roundOff(Precision p) {
  return p == Precision::Float ? std::numeric_limits<float>::epsilon() : std::numeric_limits<double>::epsilon();
}

// A backend in a precision: the parameter of the physics suites that every backend must pass.
struct SolverKind {
  Backend backend;
  Precision precision;
};
inline void PrintTo(const SolverKind& k, std::ostream* os) {
  *os << (k.backend == Backend::Cuda ? "cuda_" : "cpu_") << ::testing::PrintToString(k.precision);
}
// Test name suffix of a kind: "cpu_double", "cuda_float".
inline std::string kindName(const ::testing::TestParamInfo<SolverKind>& info) {
  return ::testing::PrintToString(info.param);
}
// Both precisions on the CPU and, in a build with the CUDA backend, on CUDA: a machine
// without a GPU lists the CUDA cases as skipped (EveryBackend::SetUp).
inline std::vector<SolverKind> everyKind() {
  std::vector<SolverKind> k = {{Backend::Cpu, Precision::Double}, {Backend::Cpu, Precision::Float}};
#ifdef MPMSDEM_WITH_CUDA
  k.push_back({Backend::Cuda, Precision::Double});
  k.push_back({Backend::Cuda, Precision::Float});
#endif
  return k;
}
// Fixture base of those suites: precision() and backend() of the case, makeSolver for it.
class EveryBackend : public ::testing::TestWithParam<SolverKind> {
 protected:
  void SetUp() override {
    if (backend() == Backend::Cuda && !cudaAvailable()) GTEST_SKIP() << "no CUDA device on this machine";
  }
  Backend backend() const { return GetParam().backend; }
  Precision precision() const { return GetParam().precision; }
  std::unique_ptr<MpmSolver> solver(const MpmParams& prm) const { return makeSolver(prm, backend(), precision()); }
};

// `slice` is particles [first, first + slice.size()) of `whole`, every field to the last bit.
inline void expectRangeOf(const ParticleSet& slice, const ParticleSet& whole, std::size_t first) {
  const std::size_t count = slice.size();
  auto same = [&](const auto& a, const auto& b, std::size_t per, const char* name) {
    ASSERT_EQ(a.size(), per * count) << name;
    for (std::size_t k = 0; k < per * count; ++k)
      ASSERT_EQ(a[k], b[per * first + k]) << name << ", particle " << first + k / per;
  };
  same(slice.x, whole.x, 3, "x");
  same(slice.v, whole.v, 3, "v");
  same(slice.stress, whole.stress, 6, "stress");
  same(slice.mass, whole.mass, 1, "mass");
  same(slice.volume0, whole.volume0, 1, "volume0");
  same(slice.J, whole.J, 1, "J");
  same(slice.gammaDotP, whole.gammaDotP, 1, "gammaDotP");
  same(slice.fext, whole.fext, 3, "fext");
  same(slice.phase, whole.phase, 1, "phase");
}

// Largest differences between two states of the same particles (same order).
struct Agreement {
  double position = 0;     // max |x_a - x_b| [m]
  double velocity = 0;     // max |v_a - v_b| [m/s]
  double stress = 0;       // max |sigma_a - sigma_b| [Pa]
  double stressScale = 0;  // max |sigma_a| [Pa]
  double J = 0;            // max |J_a - J_b|
};

inline Agreement compare(const ParticleSet& a, const ParticleSet& b) {
  Agreement r;
  auto maxDiff = [](const std::vector<double>& u, const std::vector<double>& w) {
    double m = u.size() == w.size() ? 0.0 : std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < std::min(u.size(), w.size()); ++i) m = std::max(m, std::abs(u[i] - w[i]));
    return m;
  };
  r.position = maxDiff(a.x, b.x);
  r.velocity = maxDiff(a.v, b.v);
  r.stress = maxDiff(a.stress, b.stress);
  r.J = maxDiff(a.J, b.J);
  for (double s : a.stress) r.stressScale = std::max(r.stressScale, std::abs(s));
  return r;
}

// Steps `a` and `b` from the same particles `steps` times with dt; their final states.
inline void runPair(MpmSolver& a, MpmSolver& b, const ParticleSet& particles, double dt, int steps, ParticleSet& outA,
                    ParticleSet& outB) {
  a.setParticles(particles);
  b.setParticles(particles);
  for (int i = 0; i < steps; ++i) {
    a.step(dt);
    b.step(dt);
  }
  a.getParticles(outA);
  b.getParticles(outB);
}

// Positions within tol times the length scale of the domain [m], stresses within stressTol
// (default: tol) times the largest stress of the reference run `a` (which must carry stress:
// > minStress Pa).
inline void expectAgree(const ParticleSet& a, const ParticleSet& b, double tol, double length, double minStress,
                        const std::string& what, double stressTol = -1) {
  if (stressTol < 0) stressTol = tol;
  const Agreement r = compare(a, b);
  std::printf("%s against the reference: max |dx| = %.3e m (bound %.1e), max |dsigma| = %.3e Pa (bound %.1e)\n",
              what.c_str(), r.position, tol * length, r.stress, stressTol * r.stressScale);
  EXPECT_LT(r.position, tol * length) << what << ": positions";
  EXPECT_LT(r.stress, stressTol * r.stressScale) << what << ": stresses (scale " << r.stressScale << " Pa)";
  EXPECT_GT(r.stressScale, minStress) << what << ": the reference run carries no stress";
}

// The evolving state of two runs equal to the last bit (mass and volume0 are inputs).
inline void expectBitIdentical(const ParticleSet& a, const ParticleSet& b) {
  EXPECT_TRUE(a.x == b.x);
  EXPECT_TRUE(a.v == b.v);
  EXPECT_TRUE(a.stress == b.stress);
  EXPECT_TRUE(a.J == b.J);
  EXPECT_TRUE(a.gammaDotP == b.gammaDotP);
  EXPECT_TRUE(a.phase == b.phase);
}

}  // namespace agreement
}  // namespace mpm
}  // namespace mpmsdem
