// CUDA kernels of one MPM step: thin wrappers that call the shared stage functions.
#pragma once
#include "mpm/MpmKernelsCommon.hpp"

namespace mpmsdem {
namespace mpm {
namespace cudak {

// P2G scatter into the grid with atomics (the zero eighth value is skipped).
template <typename T>
struct AtomicScatter {
  T* grid;
  __device__ __forceinline__ void operator()(int node, const T* r) const {
    T* n = grid + kNodeValues * node;
    for (int c = 0; c < kNodeValues - 1; ++c) atomicAdd(n + c, r[c]);
  }
};

template <typename T>
__global__ void p2gKernel(int n, ParticleIn<T> in, GridConst<T> g, T dt, T* grid) {
  const int p = blockIdx.x * blockDim.x + threadIdx.x;
  if (p >= n) return;
  AtomicScatter<T> add{grid};
  p2gParticle(p, in, g, dt, add);
}

template <typename T>
__global__ void gridKernel(int nNodes, T* grid, GridConst<T> g, T dt) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= nNodes) return;
  gridNodeUpdate(i, grid, g, dt);
}

// The grid update in two halves, with the grid hooks launched between them.
template <typename T>
__global__ void gridVelocityKernel(int nNodes, T* grid, GridConst<T> g, T dt) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= nNodes) return;
  gridNodeVelocity(i, grid, g, dt);
}

template <typename T>
__global__ void gridWallsKernel(int nNodes, T* grid, GridConst<T> g) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= nNodes) return;
  gridNodeWalls(i, grid, g);
}

// flags[0]: smallest failing particle index (atomicMin); flags[1]: float bits of the largest
// speed (atomicMax; non-negative floats order like their bit patterns).
// Largest value over the warp; every lane calls it (inactive lanes must pass 0 via the
// caller, which keeps the whole warp alive).
__device__ __forceinline__ unsigned int warpMaxU32(unsigned int v) {
  for (int off = 16; off > 0; off >>= 1) {
    const unsigned int o = __shfl_xor_sync(0xffffffffu, v, off);
    v = o > v ? o : v;
  }
  return v;
}

// Sum over the warp, delivered to lane 0; every lane calls it.
__device__ __forceinline__ double warpSum(double v) {
  for (int off = 16; off > 0; off >>= 1) v += __shfl_down_sync(0xffffffffu, v, off);
  return v;
}

// The gate on the `count` nodes of its band; one thread per node, the impulse summed per warp
// and added to impulse[0..2] (blockDim is a multiple of 32, so whole warps reach the sums).
template <typename T>
__global__ void gateKernel(GateBand b, int count, int stride, const T* mass, T* vx, T* vy, T* vz, T mu, double* impulse) {
  const int t = blockIdx.x * blockDim.x + threadIdx.x;
  double p[3] = {0.0, 0.0, 0.0};
  if (t < count) {
    const Vec3T<T> d = applyGateNode(stride * gateBandNode(t, b), mass, vx, vy, vz, mu);
    for (int c = 0; c < 3; ++c) p[c] = static_cast<double>(d[c]);
  }
  for (int c = 0; c < 3; ++c) {
    const double s = warpSum(p[c]);
    if ((threadIdx.x & 31u) == 0u && s != 0.0) atomicAdd(impulse + c, s);
  }
}

template <typename T>
__global__ void g2pKernel(int n, ParticleIn<T> in, ParticleOut<T> out, const T* grid, GridConst<T> g,
                          StepConst<T> sc, int* firstBad, unsigned int* maxSpeedBits) {
  const int p = blockIdx.x * blockDim.x + threadIdx.x;
  unsigned int bits = 0u;
  if (p < n) {
    const G2PResult<T> r = g2pParticle(p, in, p, out, grid, g, sc);
    if (!r.ok) atomicMin(firstBad, p);
    const float s = static_cast<float>(r.speed);
    bits = s == s ? __float_as_uint(s) : 0u;  // NaN speeds are reported via firstBad
  }
  // One atomic per warp (blockDim is a multiple of 32, so whole warps reach this point).
  const unsigned int warpMax = warpMaxU32(bits);
  if ((threadIdx.x & 31u) == 0u && warpMax > 0u) atomicMax(maxSpeedBits, warpMax);
}

}  // namespace cudak
}  // namespace mpm
}  // namespace mpmsdem
