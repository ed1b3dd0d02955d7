// CUDA kernel of the MP–SDEM coupling: a thin wrapper over the shared coupleParticle().
#pragma once
#include "coupling/CouplingKernelsCommon.hpp"

namespace mpmsdem {
namespace coupling {
namespace cudak {

// Device-side step flags: the first failing particle (packed with its block) and the
// smallest particle step and approach bounds as float bits (non-negative floats order like
// their bits).
struct CouplingFlags {
  unsigned long long bad;       // (particle << 32) | block, or all ones
  unsigned int minStepBits;
  unsigned int minApproachBits;
  unsigned long long overflow;
};

struct AtomicAdd {
  __device__ __forceinline__ void operator()(double* slot, double value) const { atomicAdd(slot, value); }
};

template <typename T>
struct DeviceSink {
  const BlockState<T>* blocks;
  double* sums;
  CouplingFlags* flags;
  __device__ void operator()(const MpContact<T>& c) const {
    addBlockShare(c, blocks[c.block], sums, AtomicAdd{});
    const float bound = static_cast<float>(particleStepBound(c));
    if (bound == bound) atomicMin(&flags->minStepBits, __float_as_uint(bound));
  }
};

template <typename T>
__global__ void coupleKernel(int n, CouplingParticles<T> P, const BlockState<T>* blocks,
                             sdem::ShapeTableView<T> shapes, const sdem::BarrierCoulombPhys<T>* phys,
                             BinGridView bins, HistoryView<T> hist, T dt, T safety, double* sums,
                             CouplingFlags* flags) {
  const int p = blockIdx.x * blockDim.x + threadIdx.x;
  if (p >= n) return;
  DeviceSink<T> sink{blocks, sums, flags};
  int badBlock = -1, overflow = 0;
  T approach = T(INFINITY);
  CouplingLoopMemo<T> memo;
  if (coupleParticle(p, P, blocks, shapes, phys, bins, hist, dt, safety, sink, &badBlock, &overflow, &approach,
                     memo) != kCoupleOk)
    atomicMin(&flags->bad,
              (static_cast<unsigned long long>(particleNumber(P, p)) << 32) | static_cast<unsigned int>(badBlock));
  if (overflow) atomicAdd(&flags->overflow, static_cast<unsigned long long>(overflow));
  if (approach < T(INFINITY)) atomicMin(&flags->minApproachBits, __float_as_uint(static_cast<float>(approach)));
}

}  // namespace cudak
}  // namespace coupling
}  // namespace mpmsdem
