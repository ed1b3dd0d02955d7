// CUDA kernels of one MPM step: thin wrappers that call the shared stage functions.
#pragma once
#include "mpm/MpmKernelsCommon.hpp"

namespace mpmsdem {
namespace mpm {
namespace cudak {

// The grid's blocks of stencil bases (blockCellOf) and their eight parity colours: colour
// (px, py, pz) = 4 px + 2 py + pz holds the blocks with b[d] % 2 == p_d, count(colour, d) of them
// along axis d.
struct BlockGrid {
  int blocks[3];
  __host__ __device__ int count(int colour, int d) const {
    const int parity = (colour >> (2 - d)) & 1;
    return (blocks[d] - parity + 1) / 2;
  }
  __device__ void colourBlock(int colour, int i, int b[3]) const {
    for (int d = 2; d >= 0; --d) {
      const int m = count(colour, d);
      b[d] = 2 * (i % m) + ((colour >> (2 - d)) & 1);
      i /= m;
    }
  }
};

// What a particle carries from slot to slot besides its state.
template <typename T>
struct MovedWith {
  T* mass;
  T* vol0;
  int* id;
};

// Sort key of the particle in slot s: its block and base (blockCellOf) above its number, so
// that sorting by key orders the particles as the CPU backend bins them.
template <typename T>
__global__ void binKernel(int n, ParticleIn<T> in, GridConst<T> g, BlockGrid bg, int numberBits,
                          unsigned long long* key, int* slot) {
  const int s = blockIdx.x * blockDim.x + threadIdx.x;
  if (s >= n) return;
  T gc[3];
  gridCoordinate(in, s, g, gc);
  key[s] = (static_cast<unsigned long long>(blockCellOf(gc, bg.blocks)) << numberBits) |
           static_cast<unsigned int>(in.id[s]);
  slot[s] = s;
}

// P2G of the blocks of one parity colour, one CUDA block per block of bases, in three rows
// (o0 = 0, 1, 2 of the bases (o0, o1, o2)): warp 3 o1 + o2 sums the particles of base
// (row, o1, o2), prepared kBaseChunk at a time into shared memory, into that base's 27 nodes, a
// lane per node; then thread m of the first 125 adds to tile node m the sums of the row's bases
// that reach it (p2gBaseTileSum). After the third row it adds its node's sum to the grid. Blocks
// of one colour share no node, so the adds need no atomics; the colours run one launch after
// another.
constexpr int kBaseWarps = 9;
constexpr int kBaseThreads = 32 * kBaseWarps;
template <typename T>
constexpr int kBaseChunk = sizeof(T) == 8 ? 16 : 32;  // double: the shared arrays within 48 kB
template <typename T>
__global__ void __launch_bounds__(kBaseThreads)
    p2gBaseKernel(BlockGrid bg, int colour, ParticleIn<T> in, const int* sorted, const int* start, const int* end,
                  GridConst<T> g, T dt, T* grid) {
  int b[3];
  bg.colourBlock(colour, blockIdx.x, b);
  const int first = kBlockCells * ((b[0] * bg.blocks[1] + b[1]) * bg.blocks[2] + b[2]);
  const int t = threadIdx.x, warp = t / 32, lane = t % 32;
  __shared__ int range[kBlockCells][2];
  if (t < kBlockCells) {
    range[t][0] = start[first + t];
    range[t][1] = end[first + t];
  }
  if (!__syncthreads_or(t < kBlockCells && range[t][0] < range[t][1])) return;
  __shared__ P2GBaseParticle<T> stage[kBaseWarps][kBaseChunk<T>];
  __shared__ T part[kBaseWarps][kBlockCells][kNodeVNew + 3];
  constexpr int kTile = kBlockNodes * kBlockNodes * kBlockNodes;
  const int n0 = t / (kBlockNodes * kBlockNodes), n1 = (t / kBlockNodes) % kBlockNodes, n2 = t % kBlockNodes;
  T acc[kNodeVNew + 3] = {};
  for (int row = 0; row < 3; ++row) {
    const int q0 = range[9 * row + warp][0], q1 = range[9 * row + warp][1];
    T mine[kNodeVNew + 3] = {};
    for (int q = q0; q < q1; q += kBaseChunk<T>) {
      const int m = min(kBaseChunk<T>, q1 - q);
      __syncwarp();  // the previous chunk has been read
      if (lane < m) p2gBasePrepare(sorted[q + lane], in, g, dt, stage[warp][lane]);
      __syncwarp();
      if (lane < kBlockCells)
        for (int j = 0; j < m; ++j) p2gBaseNodeAdd(stage[warp][j], lane / 9, (lane / 3) % 3, lane % 3, mine);
    }
    if (lane < kBlockCells)
      for (int c = 0; c < kNodeVNew + 3; ++c) part[warp][lane][c] = mine[c];
    __syncthreads();
    if (t < kTile)
      p2gBaseTileSum(row, n0, n1, n2, [&](int o1, int o2, int m) -> const T* { return part[3 * o1 + o2][m]; }, acc);
    __syncthreads();  // the row's sums have been read
  }
  const int g0 = 3 * b[0] + n0, g1 = 3 * b[1] + n1, g2 = 3 * b[2] + n2;
  if (t < kTile && g0 < g.nodes[0] && g1 < g.nodes[1] && g2 < g.nodes[2]) {
    T* r = grid + kNodeValues * ((g0 * g.nodes[1] + g1) * g.nodes[2] + g2);
    for (int c = 0; c < kNodeVNew + 3; ++c) r[c] += acc[c];
  }
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

// G2P of the particle at sorted place s (slot sorted[s] of the state read) into slot s of the
// state written, which then holds the particles in sorted order; mass, volume0 and number move
// with them. firstBad: the smallest (number << 32 | slot) of a failing particle (atomicMin);
// maxSpeedBits: float bits of the largest speed (atomicMax; non-negative floats order like
// their bit patterns).
template <typename T>
__global__ void g2pKernel(int n, ParticleIn<T> in, ParticleOut<T> out, MovedWith<T> moved, const int* sorted,
                          const T* grid, GridConst<T> g, StepConst<T> sc, unsigned long long* firstBad,
                          unsigned int* maxSpeedBits) {
  const int s = blockIdx.x * blockDim.x + threadIdx.x;
  unsigned int bits = 0u;
  if (s < n) {
    const int p = sorted[s];
    const G2PResult<T> r = g2pParticle(p, in, s, out, grid, g, sc);
    moved.mass[s] = in.mass[p];
    moved.vol0[s] = in.vol0[p];
    moved.id[s] = in.id[p];
    if (!r.ok)
      atomicMin(firstBad, (static_cast<unsigned long long>(in.id[p]) << 32) | static_cast<unsigned int>(s));
    const float sp = static_cast<float>(r.speed);
    bits = sp == sp ? __float_as_uint(sp) : 0u;  // NaN speeds are reported via firstBad
  }
  // One atomic per warp (blockDim is a multiple of 32, so whole warps reach this point).
  const unsigned int warpMax = warpMaxU32(bits);
  if ((threadIdx.x & 31u) == 0u && warpMax > 0u) atomicMax(maxSpeedBits, warpMax);
}

// Outputs read the particles by number while they are stored by block: slotOf[number] is the
// slot of each particle, and a slice [first, first + count) is gathered through it on the device,
// so that a slice costs its own size to bring to the host.
__global__ inline void slotOfKernel(int n, const int* __restrict__ id, int* __restrict__ slotOf) {
  const int q = blockIdx.x * blockDim.x + threadIdx.x;
  if (q < n) slotOf[id[q]] = q;
}

template <typename U>
__global__ void gatherByNumberKernel(int count, int first, const int* __restrict__ slotOf, const U* __restrict__ src,
                                     U* __restrict__ dst) {
  const int k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k < count) dst[k] = src[slotOf[first + k]];
}

}  // namespace cudak
}  // namespace mpm
}  // namespace mpmsdem
