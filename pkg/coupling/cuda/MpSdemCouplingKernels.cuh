// CUDA kernels of the material points' coupling with SDEM blocks and with LevelSet bodies: thin
// wrappers over the shared coupleParticle() and coupleParticleLevelSets().
#pragma once

#include "coupling/CouplingKernelsCommon.hpp"
#include "coupling/LevelSetKernelsCommon.hpp"
#include "mpm/MpmKernelsCommon.hpp"

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

// The step's contacts for the block sums in a fixed order: each contact's share at the place an
// atomic counter gives it, with its block and particle number (key) and its place among the
// particle's own contacts (entry, the order the CPU backend adds them in), and each particle's
// count of contacts by number. A scan of the counts then gives every contact a place that
// depends on the contacts alone (placeKernel), in particle-number order; a stable sort of those
// places by block alone (blockKeysKernel, then a radix sort of a few bits) gives each block its
// contacts in that order, side by side, and each block adds them (blockSumsKernel): the sums of a
// sort by block, number and contact order, without sorting the whole keys and with the count
// left on the device.
struct ContactList {
  double* share;            // kBlockSums per entry
  unsigned long long* key;  // block << numberBits | number
  int* entry;               // the contact's place among its particle's contacts
  int* count;               // per particle number: its contacts this step
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
  // then adds the listed shares too: blockSumsKernel); the listed ones are summed in order.
  // Atomics for every contact would queue a step's thousands of contacts with the bed on the
  // same 16 sums.
  __device__ void operator()(const MpContact<T>& c) {
    const BlockState<T>& b = blocks[c.block];
    const unsigned int i = listPlace(&flags->contacts);
    if (i >= list.capacity) addBlockShare(c, b, sums, AtomicAdd{});
    if (i < list.capacity) {
      blockShare(c, b, list.share + static_cast<std::size_t>(kBlockSums) * i);
      list.key[i] = (static_cast<unsigned long long>(c.block) << list.numberBits) |
                    static_cast<unsigned long long>(c.particle);
      list.entry[i] = static_cast<int>(j);
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

// The slots of the bin table (BinGridView): bin slotBins[s] gets slot s, or -1 when clearing.
static __global__ void binSlotsKernel(int numSlots, const int* slotBins, bool clear, int* slot) {
  for (int s = blockIdx.x * blockDim.x + threadIdx.x; s < numSlots; s += gridDim.x * blockDim.x)
    slot[slotBins[s]] = clear ? -1 : s;
}

// The listed contacts in particle-number order: contact i of particle `number`, its entry-th,
// goes to order[first[number] + entry], where first is the exclusive scan of the particles'
// counts. Nothing in a step that overflowed the list (its sums are atomic).
static __global__ void placeKernel(const CouplingFlags* flags, unsigned int capacity, const unsigned long long* key,
                                   const int* entry, const int* first, int numberBits, int* order) {
  const unsigned int count = flags->contacts;
  if (count > capacity) return;
  const unsigned long long numberMask = (1ull << numberBits) - 1ull;
  for (unsigned int i = blockIdx.x * blockDim.x + threadIdx.x; i < count; i += gridDim.x * blockDim.x)
    order[first[key[i] & numberMask] + entry[i]] = static_cast<int>(i);
}

// The block of each place of the particle-number order (the key's bits from numberBits up), for
// the stable sort by block; the places past the step's contacts get numBlocks, after every block.
// In a step that overflowed the list, the listed shares are added to their blocks' sums
// atomically instead, in one pass (the contacts past the list were added so in coupleKernel).
static __global__ void blockKeysKernel(const CouplingFlags* flags, unsigned int capacity, const unsigned long long* key,
                                       const int* order, int numberBits, unsigned long long numBlocks,
                                       unsigned long long* blockKey, const double* share, double* sums) {
  const unsigned int count = flags->contacts;
  for (unsigned int i = blockIdx.x * blockDim.x + threadIdx.x; i < capacity; i += gridDim.x * blockDim.x) {
    if (count <= capacity) {
      blockKey[i] = i < count ? key[order[i]] >> numberBits : numBlocks;
      continue;
    }
    const double* s = share + static_cast<std::size_t>(kBlockSums) * i;
    double* dst = sums + static_cast<std::size_t>(kBlockSums) * (key[i] >> numberBits);
    for (int k = 0; k < kBlockSums; ++k)
      if (s[k] != 0.0) atomicAdd(dst + k, s[k]);
  }
}

// Block b's sums from its contacts in particle-number order (byBlock: the listed contacts
// sorted stably by block, blockKey their blocks), in `chunks` equal runs of them: CUDA block
// b * chunks + c takes run c, whose r-th contact goes to thread r mod kSumThreads, which adds its
// contacts in turn; a fixed tree adds the threads' sums into partial[b * chunks + c], and
// blockTotalsKernel adds a block's runs in their order. The order depends on the contacts alone,
// not on thread timing; the runs spread a block with thousands of contacts (a flume's bed) over
// the device. Nothing in a step that overflowed the list (its sums are atomic: blockKeysKernel).
constexpr int kSumThreads = 128;
static __global__ void __launch_bounds__(kSumThreads)
    blockSumsKernel(const CouplingFlags* flags, unsigned int capacity, const double* share,
                    const unsigned long long* blockKey, const int* byBlock, int chunks, double* partial) {
  const unsigned long long b = blockIdx.x / chunks;
  const long long c = blockIdx.x % chunks;
  const int t = threadIdx.x;
  const unsigned int count = flags->contacts;
  if (count > capacity) return;
  __shared__ double part[kBlockSums][kSumThreads];
  const int listed = static_cast<int>(count);  // the places past them hold numBlocks
  const int first = mpm::firstKeyAtLeast(blockKey, 0, listed, 0, b);
  const long long length = mpm::firstKeyAtLeast(blockKey, first, listed, 0, b + 1) - first;
  const int lo = first + static_cast<int>(length * c / chunks);
  const int hi = first + static_cast<int>(length * (c + 1) / chunks);
  double acc[kBlockSums] = {};
  for (int i = lo + t; i < hi; i += kSumThreads) {
    const double* s = share + static_cast<std::size_t>(kBlockSums) * byBlock[i];
    for (int k = 0; k < kBlockSums; ++k) acc[k] += s[k];
  }
  for (int k = 0; k < kBlockSums; ++k) part[k][t] = acc[k];
  __syncthreads();
  for (int half = kSumThreads / 2; half > 0; half >>= 1) {
    if (t < half)
      for (int k = 0; k < kBlockSums; ++k) part[k][t] += part[k][t + half];
    __syncthreads();
  }
  if (t < kBlockSums) partial[static_cast<std::size_t>(kBlockSums) * blockIdx.x + t] = part[t][0];
}

// sums[b][k]: block b's runs (blockSumsKernel) added in their order.
static __global__ void blockTotalsKernel(const CouplingFlags* flags, unsigned int capacity, int numBlocks, int chunks,
                                         const double* partial, double* sums) {
  if (flags->contacts > capacity) return;
  const int n = numBlocks * kBlockSums;
  for (int i = blockIdx.x * blockDim.x + threadIdx.x; i < n; i += gridDim.x * blockDim.x) {
    const int b = i / kBlockSums, k = i % kBlockSums;
    const double* p = partial + static_cast<std::size_t>(kBlockSums) * b * chunks + k;
    double s = p[0];
    for (int c = 1; c < chunks; ++c) s += p[static_cast<std::size_t>(kBlockSums) * c];
    sums[i] = s;
  }
}

// What one particle's thread couples it with: SDEM blocks through the bins, or every LevelSet
// body (their bounding spheres tested in turn, as the CPU loop does).
template <typename T>
struct BlockBodies {
  sdem::ShapeTableView<T> shapes;
  BinGridView bins;
  __device__ int operator()(int p, const CouplingParticles<T>& P, const BlockState<T>* blocks,
                            const sdem::BarrierCoulombPhys<T>* phys, const HistoryView<T>& hist, T dt, T safety,
                            DeviceSink<T>& sink, int* bad, int* overflow, T* approach, CouplingLoopMemo<T>& memo) const {
    return coupleParticle(p, P, blocks, shapes, phys, bins, hist, dt, safety, sink, bad, overflow, approach, memo);
  }
};

template <typename T>
struct LevelSetBodies {
  const LevelSetGridView<T>* grids;
  int numBodies;
  T watch;
  __device__ int operator()(int p, const CouplingParticles<T>& P, const BlockState<T>* blocks,
                            const sdem::BarrierCoulombPhys<T>* phys, const HistoryView<T>& hist, T dt, T safety,
                            DeviceSink<T>& sink, int* bad, int* overflow, T* approach, CouplingLoopMemo<T>& memo) const {
    return coupleParticleLevelSets(p, P, blocks, numBodies, grids, phys, hist, dt, safety, watch, sink, bad, overflow,
                                   approach, memo);
  }
};

template <typename T, typename Bodies>
__global__ void coupleKernel(int n, CouplingParticles<T> P, const BlockState<T>* blocks, Bodies bodies,
                             const sdem::BarrierCoulombPhys<T>* phys, HistoryView<T> hist, T dt, T safety,
                             double* sums, CouplingFlags* flags, ContactList list) {
  const int p = blockIdx.x * blockDim.x + threadIdx.x;
  if (p >= n) return;
  DeviceSink<T> sink{blocks, sums, flags, list};
  int badBlock = -1, overflow = 0;
  T approach = T(INFINITY);
  CouplingLoopMemo<T> memo;
  const int status = bodies(p, P, blocks, phys, hist, dt, safety, sink, &badBlock, &overflow, &approach, memo);
  list.count[particleNumber(P, p)] = static_cast<int>(sink.j);
  if (status != kCoupleOk)
    atomicMin(&flags->bad,
              (static_cast<unsigned long long>(particleNumber(P, p)) << 32) | static_cast<unsigned int>(badBlock));
  if (overflow) atomicAdd(&flags->overflow, static_cast<unsigned long long>(overflow));
  if (approach < T(INFINITY)) atomicMin(&flags->minApproachBits, __float_as_uint(static_cast<float>(approach)));
}

}  // namespace cudak
}  // namespace coupling
}  // namespace mpmsdem
