// CUDA backend of the MPM solver (host control class). The kernels are in
// MpmCudaKernels.cuh and call the same __host__ __device__ stage functions as the CPU
// backend (MpmKernelsCommon.hpp). T = float or double, picked at run time by makeSolver.
//
// Device memory (T = float, N particles, G grid nodes): particle state double-buffered
// (x, v, stress, J, gammaDotP: 14 values, phase 1 byte, twice) plus mass and volume0
// = 122 bytes/particle, + 12 bytes/particle once external forces are set, + kNodeValues (8)
// values per grid node (32 bytes; at 8 particles per cell 4 bytes/particle for a fully filled
// grid). Particles are stored by number (no reordering: slot = number).
// Double-buffering makes a failed step leave the previous state intact at no bandwidth cost.
// P2G scatters with atomicAdd.
#pragma once
#include <cstdint>
#include <memory>

#include "mpm/MpmKernelsCommon.hpp"
#include "mpm/MpmSolver.hpp"

namespace mpmsdem {
namespace mpm {

template <typename T>
class MpmCuda : public MpmSolver {
 public:
  explicit MpmCuda(const MpmParams& params);  // params must have been validated
  ~MpmCuda() override;
  MpmCuda(const MpmCuda&) = delete;
  MpmCuda& operator=(const MpmCuda&) = delete;

  std::string name() const override;
  const MpmParams& params() const override { return params_; }
  void setParticles(const ParticleSet& particles) override;
  using MpmSolver::setParticles;  // slices gathered into a whole set
  void getParticles(ParticleSet& out) override;
  void getParticles(ParticleSet& out, std::size_t first, std::size_t count) override;
  std::size_t numParticles() const override { return n_; }
  void setExternalForces(const std::vector<double>& f) override;
  ParticleView openForceBuffer() override;
  void step(double dt) override;
  double stableTimeStep() override;
  std::size_t memoryBytes() const override;

 private:
  struct DeviceState {
    T* x[3] = {};
    T* v[3] = {};
    T* s[6] = {};
    T* J = nullptr;
    T* gdp = nullptr;
    std::uint8_t* phase = nullptr;
  };
  struct StepFlags {
    int firstBad;                // smallest failing particle index, or N
    unsigned int maxSpeedBits;   // float bits of the largest particle speed (>= 0, so ordered as uint)
  };
  void freeParticles();
  void loadParticles(const ParticleSet& ps);  // allocates and fills the particle arrays for ps
  ParticleIn<T> input() const;
  ParticleOut<T> output() const;

  MpmParams params_;
  GridConst<T> grid_{};
  ConstitutiveConst<T> mat_{};
  double maxSpeedAllowed_;
  int nNodes_;
  std::size_t n_ = 0;
  DeviceState state_[2];
  int cur_ = 0;
  T* mass_ = nullptr;
  T* vol0_ = nullptr;
  T* fext_[3] = {};
  bool hasFext_ = false;
  T* nodes_ = nullptr;
  StepFlags* flags_ = nullptr;
  double maxSpeed_ = 0;
  std::size_t bytes_ = 0;
};

// Build a CUDA solver in the given precision (params validated by the caller).
std::unique_ptr<MpmSolver> makeCudaSolver(const MpmParams& params, Precision precision);
// True when the CUDA runtime finds at least one device.
bool cudaDevicePresent();

}  // namespace mpm
}  // namespace mpmsdem
