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

// The range [start[b], end[b]) of block b in the sorted keys (left as zeros for empty blocks);
// static: this header is included by more than one translation unit.
static __global__ void blockRangesKernel(int n, const unsigned long long* key, int numberBits, int* start, int* end) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  auto blockOf = [&](int q) { return static_cast<int>((key[q] >> numberBits) / kBlockCells); };
  const int b = blockOf(i);
  if (i == 0 || blockOf(i - 1) != b) start[b] = i;
  if (i == n - 1 || blockOf(i + 1) != b) end[b] = i + 1;
}

// P2G of the blocks of one parity colour, one CUDA block per block of bases: kTileSplit
// threads per node of its 5x5x5 tile. The block's particles are prepared kTileChunk at a time
// into shared memory; thread (node, part) sums its node's shares of the chunk's particles
// part, part + kTileSplit, ... in sorted order, and the parts are added in a fixed order
// (p2gTileCombine) before the node's sum goes to the grid. Blocks of one colour share no node,
// so the adds need no atomics; the colours run one launch after another.
constexpr int kTileNodes = kBlockNodes * kBlockNodes * kBlockNodes;
constexpr int kTileRow = 128;  // threads per part: the tile's nodes and 3 idle
constexpr int kTileThreads = kTileRow * kTileSplit;
constexpr int kTileChunk = 64;
static_assert(kTileChunk % kTileSplit == 0, "a chunk must keep the parts' particles those of the whole block");
template <typename T>
__global__ void __launch_bounds__(kTileThreads)
    p2gTileKernel(BlockGrid bg, int colour, ParticleIn<T> in, const int* sorted, const int* start, const int* end,
                  GridConst<T> g, T dt, T* grid) {
  int b[3];
  bg.colourBlock(colour, blockIdx.x, b);
  const int blk = (b[0] * bg.blocks[1] + b[1]) * bg.blocks[2] + b[2];
  const int q0 = start[blk], q1 = end[blk];
  if (q0 >= q1) return;
  __shared__ P2GTileParticle<T> chunk[kTileChunk];
  __shared__ T parts[kTileSplit - 1][kTileNodes][kNodeVNew + 3];
  const int t = threadIdx.x, node = t % kTileRow, part = t / kTileRow;
  const int n0 = 3 * b[0] + node / (kBlockNodes * kBlockNodes), n1 = 3 * b[1] + (node / kBlockNodes) % kBlockNodes,
            n2 = 3 * b[2] + node % kBlockNodes;
  T acc[kNodeVNew + 3] = {};
  for (int q = q0; q < q1; q += kTileChunk) {
    const int m = min(kTileChunk, q1 - q);
    __syncthreads();  // the previous chunk has been read
    if (t < m) p2gTilePrepare(sorted[q + t], in, g, dt, chunk[t]);
    __syncthreads();
    if (node < kTileNodes)
      for (int j = part; j < m; j += kTileSplit) p2gTileNodeAdd(chunk[j], n0, n1, n2, acc);
  }
  if (part > 0 && node < kTileNodes)
    for (int c = 0; c < kNodeVNew + 3; ++c) parts[part - 1][node][c] = acc[c];
  __syncthreads();
  if (part == 0 && node < kTileNodes && n0 < g.nodes[0] && n1 < g.nodes[1] && n2 < g.nodes[2]) {
    T* r = grid + kNodeValues * ((n0 * g.nodes[1] + n1) * g.nodes[2] + n2);
    for (int c = 0; c < kNodeVNew + 3; ++c) r[c] += p2gTileCombine(acc[c], parts[0][node][c], parts[1][node][c], parts[2][node][c]);
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

}  // namespace cudak
}  // namespace mpm
}  // namespace mpmsdem
