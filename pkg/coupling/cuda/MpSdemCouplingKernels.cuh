// CUDA kernel of the MP–SDEM coupling: a thin wrapper over the shared coupleParticle().
#pragma once
#include "coupling/CouplingKernelsCommon.hpp"

namespace mpmsdem {
namespace coupling {
namespace cudak {

// Device-side step flags: the first failing particle (packed with its block), the smallest
// particle step and approach bounds as float bits (non-negative floats order like their bits),
// and the contacts of the step (entries the contact list was asked for).
struct CouplingFlags {
  unsigned long long bad;       // (particle << 32) | block, or all ones
  unsigned int minStepBits;
  unsigned int minApproachBits;
  unsigned long long overflow;
  unsigned int contacts;
};

struct AtomicAdd {
  __device__ __forceinline__ void operator()(double* slot, double value) const { atomicAdd(slot, value); }
};

// The step's contacts for the block sums in a fixed order: each contact's share (blockShare)
// at the place an atomic counter gives it, with a sort key that orders the contacts by block,
// particle number and the particle's own contact order (the order the CPU backend adds them in,
// block by block).
struct ContactList {
  double* share;            // kBlockSums per entry
  unsigned long long* key;  // block << (numberBits + 8) | number << 8 | j
  int* entry;               // the entry's own place (the sort's values)
  double* record;           // kContactValues per entry (contactRecord), or null: not recorded
  unsigned int capacity;
  int numberBits;
};

// A place in the contact list: one atomic add per group of lanes that reach it together (the
// whole flow's contacts with the bed would otherwise queue on one counter).
__device__ __forceinline__ unsigned int listPlace(unsigned int* counter) {
  const unsigned int mask = __activemask();
  const int lane = threadIdx.x & 31;
  const int leader = __ffs(mask) - 1;
  unsigned int first = 0u;
  if (lane == leader) first = atomicAdd(counter, static_cast<unsigned int>(__popc(mask)));
  first = __shfl_sync(mask, first, leader);
  return first + static_cast<unsigned int>(__popc(mask & ((1u << lane) - 1u)));
}

template <typename T>
struct DeviceSink {
  const BlockState<T>* blocks;
  double* sums;
  CouplingFlags* flags;
  ContactList list;
  unsigned int j = 0;  // contacts of this particle so far
  // A contact past the list's end adds its share atomically (a step that overflows the list
  // then adds the listed shares too: listedSharesKernel); the listed ones are summed in order
  // (blockSumsKernel). Atomics for every contact would queue a step's thousands of contacts
  // with the bed on the same 16 sums.
  __device__ void operator()(const MpContact<T>& c) {
    const BlockState<T>& b = blocks[c.block];
    const unsigned int i = listPlace(&flags->contacts);
    if (i >= list.capacity) addBlockShare(c, b, sums, AtomicAdd{});
    if (i < list.capacity) {
      blockShare(c, b, list.share + static_cast<std::size_t>(kBlockSums) * i);
      list.key[i] = (static_cast<unsigned long long>(c.block) << (list.numberBits + 8)) |
                    (static_cast<unsigned long long>(c.particle) << 8) | (j < 255u ? j : 255u);
      list.entry[i] = static_cast<int>(i);
      if (list.record) {
        double* r = list.record + static_cast<std::size_t>(kContactValues) * i;
        contactRecord(c, r);
        r[kRecOrder] = j;
      }
    }
    ++j;
    const float bound = static_cast<float>(particleStepBound(c));
    if (bound == bound) atomicMin(&flags->minStepBits, __float_as_uint(bound));
  }
};

// Block b's sums from its sorted contacts: thread t adds contacts t, t + kSumThreads, ... in
// turn, then a fixed tree adds the threads' sums. The order depends on the contacts alone, not
// on thread timing.
constexpr int kSumThreads = 128;
static __global__ void __launch_bounds__(kSumThreads)
    blockSumsKernel(const double* share, const int* sortedEntry, const int* start, const int* end, double* sums) {
  __shared__ double part[kBlockSums][kSumThreads];
  const int b = blockIdx.x, t = threadIdx.x;
  double acc[kBlockSums] = {};
  for (int q = start[b] + t; q < end[b]; q += kSumThreads) {
    const double* s = share + static_cast<std::size_t>(kBlockSums) * sortedEntry[q];
    for (int k = 0; k < kBlockSums; ++k) acc[k] += s[k];
  }
  for (int k = 0; k < kBlockSums; ++k) part[k][t] = acc[k];
  __syncthreads();
  for (int half = kSumThreads / 2; half > 0; half >>= 1) {
    if (t < half)
      for (int k = 0; k < kBlockSums; ++k) part[k][t] += part[k][t + half];
    __syncthreads();
  }
  if (t < kBlockSums) sums[static_cast<std::size_t>(kBlockSums) * b + t] = part[t][0];
}

// The shares of the listed contacts added atomically to the block sums, in a step whose
// contacts overflowed the list (the others were added so in coupleKernel).
static __global__ void listedSharesKernel(unsigned int count, const double* share, const unsigned long long* key,
                                          int blockShift, double* sums) {
  const unsigned int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= count) return;
  const double* s = share + static_cast<std::size_t>(kBlockSums) * i;
  double* dst = sums + static_cast<std::size_t>(kBlockSums) * (key[i] >> blockShift);
  for (int k = 0; k < kBlockSums; ++k)
    if (s[k] != 0.0) atomicAdd(dst + k, s[k]);
}

template <typename T>
__global__ void coupleKernel(int n, CouplingParticles<T> P, const BlockState<T>* blocks,
                             sdem::ShapeTableView<T> shapes, const sdem::BarrierCoulombPhys<T>* phys,
                             BinGridView bins, HistoryView<T> hist, T dt, T safety, double* sums,
                             CouplingFlags* flags, ContactList list) {
  const int p = blockIdx.x * blockDim.x + threadIdx.x;
  if (p >= n) return;
  DeviceSink<T> sink{blocks, sums, flags, list};
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
