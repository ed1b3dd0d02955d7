// CPU backend of the MPM solver: double precision, OpenMP.
//
// P2G without races: each step the particles are binned (counting sort, O(N)) into blocks
// of 3x3x3 stencil-base cells. A particle whose stencil base lies in block b touches nodes
// 3b .. 3b+4 per axis, so two blocks whose indices differ by 2 or more along some axis share
// no node. The blocks are split into 8 colours by index parity; the blocks of one colour are
// scattered in parallel, the colours one after another. The summation order is fixed, so
// the result does not depend on the thread count.
//
// The mutable particle state is double-buffered: a step reads buffer `cur_` and writes the
// other one, and only swaps when every particle passed the NaN/blow-up check. After a
// RuntimeFailure, getParticles() returns the state at the start of the failed step.
#pragma once
#include <cstdint>
#include <vector>

#include "mpm/MpmKernelsCommon.hpp"
#include "mpm/MpmSolver.hpp"

namespace mpmsdem {
namespace mpm {

class MpmCpu : public MpmSolver {
 public:
  // params must have been validated (makeSolver does it).
  explicit MpmCpu(const MpmParams& params);

  std::string name() const override { return "cpu-double"; }
  const MpmParams& params() const override { return params_; }
  void setParticles(const ParticleSet& particles) override;
  void getParticles(ParticleSet& out) override;
  std::size_t numParticles() const override { return n_; }
  void setExternalForces(const std::vector<double>& f) override;
  ParticleView openForceBuffer() override;
  void step(double dt) override;
  double stableTimeStep() override;
  std::size_t memoryBytes() const override;

 private:
  struct State {
    std::vector<double> x[3], v[3], s[6], J, gdp;
    std::vector<std::uint8_t> phase;
    void resize(std::size_t n);
  };
  ParticleIn<double> input() const;
  ParticleOut<double> output();
  void scatter(double dt, const ParticleIn<double>& in);

  MpmParams params_;
  GridConst<double> grid_{};
  ConstitutiveConst<double> mat_{};
  double maxSpeedAllowed_;
  std::size_t n_ = 0;
  int nNodes_;
  State state_[2];
  int cur_ = 0;
  std::vector<double> mass_, vol0_;
  std::vector<double> fext_[3];
  bool hasFext_ = false;
  std::vector<double> nodes_;  // kGridComponents * nNodes_
  double maxSpeed_ = 0;        // largest particle speed of the current state [m/s]
  // P2G colouring
  int blocks_[3];
  std::vector<int> colourBlocks_[8];  // block ids of each colour
  std::vector<int> blockStart_;       // counting-sort offsets, size nBlocks + 1
  std::vector<int> order_;            // particle ids sorted by block
  std::vector<int> blockOf_;          // block id of each particle
};

}  // namespace mpm
}  // namespace mpmsdem
