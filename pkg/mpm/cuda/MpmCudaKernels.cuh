// CUDA kernels of one MPM step: thin wrappers that call the shared stage functions.
#pragma once
#include "mpm/DiagnosticsKernels.hpp"
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
  // Blocks of the colour in the whole grid: its list's capacity.
  __host__ __device__ int colourCapacity(int colour) const { return count(colour, 0) * count(colour, 1) * count(colour, 2); }
  // Where the colour's list starts in the array of all colours' lists.
  __host__ __device__ int colourStart(int colour) const {
    int s = 0;
    for (int c = 0; c < colour; ++c) s += colourCapacity(c);
    return s;
  }
};

// The step's occupied blocks and active tiles (MpmKernelsCommon.hpp, forTilesOfBlock), built on
// the device from the sorted keys: each colour's occupied blocks in its part of `blocks` (from
// BlockGrid::colourStart), their numbers in count[colour]; the active tiles in `tiles`, their
// number in count[8], each listed by the first occupied block to mark it (tileMark), so that no
// pass visits the tiles of the whole box. Lists fill in no fixed order: blocks of one colour
// share no node and a tile's nodes are updated independently, so no result depends on it. An
// occupied block b's particles are the sorted places [start[b], end[b]) (the entries of other
// blocks are stale).
struct ActiveLists {
  int* blocks;
  int* tiles;
  int* count;
  int* tileMark;  // 1 for the listed tiles, 0 elsewhere (forgetListsKernel clears them)
  int* start;
  int* end;
};
constexpr int kTilesCount = 8;  // count[] index of the active tiles

// The grid's node columns as the kernels that store and check them see them (GridConst::column).
struct ColumnMap {
  int* column;  // the stored column of each (i, j), -1 where none
  int nodes[3];
};

// The first sorted particle of each block lists the block under its colour and its tiles not
// listed yet; the first and last give the block's range. A tile whose node columns are not all
// stored sets *missing (the step then writes nothing: MpmCuda::step).
__global__ inline void occupiedBlocksKernel(int n, const unsigned long long* key, int shift, BlockGrid bg,
                                            ActiveLists a, ColumnMap cm, unsigned int* missing) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  const int b = static_cast<int>((key[i] >> shift) / kBlockCells);
  if (i == n - 1 || static_cast<int>((key[i + 1] >> shift) / kBlockCells) != b) a.end[b] = i + 1;
  if (i > 0 && static_cast<int>((key[i - 1] >> shift) / kBlockCells) == b) return;
  a.start[b] = i;
  int c[3];
  blockCoordsOf(b, bg.blocks, c);
  const int colour = blockColourOf(c);
  a.blocks[bg.colourStart(colour) + atomicAdd(&a.count[colour], 1)] = b;
  forTilesOfBlock(c, bg.blocks, [&](int t) {
    if (atomicExch(&a.tileMark[t], 1) != 0) return;  // listed by another block
    a.tiles[atomicAdd(&a.count[kTilesCount], 1)] = t;
    if (!tileColumnsStored(t, bg.blocks, cm.nodes, cm.column)) *missing = 1u;
  });
}

// f(node) for every node of the active tiles, a thread per node over the whole launch; a node
// whose column is not stored is left out (a step whose tiles' columns were not all stored
// writes nothing to them and fails: MpmCuda::step).
template <typename F>
__device__ void forActiveTileNodes(const ActiveLists& a, const int tilesPerAxis[3], const int nodes[3],
                                   const int* column, F&& f) {
  // (64-bit: a flow over most of a kilometre at 0.5 m lists 6e7 tiles)
  const long long total = static_cast<long long>(kBlockCells) * a.count[kTilesCount];
  for (long long i = blockIdx.x * blockDim.x + threadIdx.x; i < total; i += gridDim.x * blockDim.x) {
    const int node = tileNodeOf(a.tiles[i / kBlockCells], static_cast<int>(i % kBlockCells), tilesPerAxis, nodes);
    if (node >= 0 && (!column || column[node / nodes[2]] >= 0)) f(node);
  }
}

// At a step's end: the node columns near the step's active tiles (columnNearTile) that are not
// stored yet get the next places of the column pool (*used of them taken), each once: the first
// thread to reach a column takes it (-2 while it draws its place). Places past the pool's
// capacity are given too; the host grows the pool to *used before any kernel reads the map, or,
// where it cannot, takes those places back (unstoreColumnsPastKernel).
__global__ inline void storeColumnsNearKernel(ActiveLists a, BlockGrid bg, ColumnMap cm, unsigned int* used) {
  const long long total = static_cast<long long>(kColumnsNearTile) * a.count[kTilesCount];
  for (long long i = blockIdx.x * blockDim.x + threadIdx.x; i < total; i += gridDim.x * blockDim.x) {
    const int c = columnNearTile(a.tiles[i / kColumnsNearTile], static_cast<int>(i % kColumnsNearTile), bg.blocks,
                                 cm.nodes);
    if (c < 0 || cm.column[c] != -1 || atomicCAS(&cm.column[c], -1, -2) != -1) continue;  // stored, or taken now
    cm.column[c] = static_cast<int>(atomicAdd(used, 1u));
  }
}

// The columns given places at or past `capacity` (a pool that could not grow) unstored again.
__global__ inline void unstoreColumnsPastKernel(int columns, int capacity, int* column) {
  for (int c = blockIdx.x * blockDim.x + threadIdx.x; c < columns; c += gridDim.x * blockDim.x)
    if (column[c] >= capacity) column[c] = -1;
}

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

// P2G of one block of bases, with the whole CUDA block, in three rows (o0 = 0, 1, 2 of the bases
// (o0, o1, o2)): warp 3 o1 + o2 sums the particles of base (row, o1, o2), prepared kBaseChunk at a
// time into shared memory, into that base's 27 nodes, a lane per node; then thread m of the
// first 125 adds to tile node m (m = 25 n0 + 5 n1 + n2) the sums of the row's bases that reach
// it (p2gBaseTileSum). Its tile node's sums in acc; false (and acc untouched) for a block with no
// particle. Every thread of the CUDA block calls it (it holds barriers).
constexpr int kBaseWarps = 9;
constexpr int kBaseThreads = 32 * kBaseWarps;
constexpr int kTileNodes = kBlockNodes * kBlockNodes * kBlockNodes;
template <typename T>
constexpr int kBaseChunk = sizeof(T) == 8 ? 16 : 32;  // double: the shared arrays within 48 kB
template <typename T>
struct P2GShared {
  int range[kBlockCells][2];
  P2GBaseParticle<T> stage[kBaseWarps][kBaseChunk<T>];
  T part[kBaseWarps][kBlockCells][kNodeVNew + 3];
};
template <typename T>
__device__ bool p2gBlockTile(int block, const ActiveLists& lists, const unsigned long long* key, int shift,
                             ParticleIn<T> in, const int* sorted, GridConst<T> g, T dt, P2GShared<T>& sh,
                             T acc[kNodeVNew + 3]) {
  const int t = threadIdx.x, warp = t / 32, lane = t % 32;
  const int n0 = t / (kBlockNodes * kBlockNodes), n1 = (t / kBlockNodes) % kBlockNodes, n2 = t % kBlockNodes;
  __syncthreads();  // the previous block's ranges and sums have been read
  if (t < kBlockCells) {  // base t's particles in the block's range of the sorted keys
    const unsigned long long cell = static_cast<unsigned long long>(kBlockCells) * block + t;
    const int hi = lists.end[block];
    sh.range[t][0] = firstKeyAtLeast(key, lists.start[block], hi, shift, cell);
    sh.range[t][1] = firstKeyAtLeast(key, sh.range[t][0], hi, shift, cell + 1);
  }
  if (!__syncthreads_or(t < kBlockCells && sh.range[t][0] < sh.range[t][1])) return false;
  for (int row = 0; row < 3; ++row) {
    const int q0 = sh.range[9 * row + warp][0], q1 = sh.range[9 * row + warp][1];
    T mine[kNodeVNew + 3] = {};
    for (int q = q0; q < q1; q += kBaseChunk<T>) {
      const int m = min(kBaseChunk<T>, q1 - q);
      __syncwarp();  // the previous chunk has been read
      if (lane < m) p2gBasePrepare(sorted[q + lane], in, g, dt, sh.stage[warp][lane]);
      __syncwarp();
      if (lane < kBlockCells)
        for (int j = 0; j < m; ++j) p2gBaseNodeAdd(sh.stage[warp][j], lane / 9, (lane / 3) % 3, lane % 3, mine);
    }
    if (lane < kBlockCells)
      for (int c = 0; c < kNodeVNew + 3; ++c) sh.part[warp][lane][c] = mine[c];
    __syncthreads();
    if (t < kTileNodes)
      p2gBaseTileSum(row, n0, n1, n2, [&](int o1, int o2, int m) -> const T* { return sh.part[3 * o1 + o2][m]; },
                     acc);
    __syncthreads();  // the row's sums have been read
  }
  return true;
}

// P2G of the blocks of one parity colour: each adds its tile to the grid. Blocks of one colour
// share no node, so the adds need no atomics; the colours run one launch after another. The
// launch is bounded (p2gLaunch), not one CUDA block per block of the colour: the occupied ones
// are known on the device only, and a long or wide grid has hundreds of thousands of empty
// blocks per colour, each a CUDA block that would start only to return. Each CUDA block takes
// occupied blocks blockIdx.x, blockIdx.x + gridDim.x, ... in turn. Nothing is written in a step
// whose tiles' columns are not all stored (*missing).
template <typename T>
__global__ void __launch_bounds__(kBaseThreads)
    p2gBaseKernel(BlockGrid bg, int colour, ActiveLists lists, ParticleIn<T> in, const int* sorted,
                  const unsigned long long* key, int shift, GridConst<T> g, T dt, T* grid,
                  const unsigned int* missing) {
  __shared__ P2GShared<T> sh;
  if (*missing) return;
  const int t = threadIdx.x;
  const int n0 = t / (kBlockNodes * kBlockNodes), n1 = (t / kBlockNodes) % kBlockNodes, n2 = t % kBlockNodes;
  const int occupied = lists.count[colour];
  for (int q = blockIdx.x; q < occupied; q += gridDim.x) {
    const int block = lists.blocks[bg.colourStart(colour) + q];
    T acc[kNodeVNew + 3] = {};
    if (!p2gBlockTile(block, lists, key, shift, in, sorted, g, dt, sh, acc)) continue;
    int b[3];
    blockCoordsOf(block, bg.blocks, b);
    const int g0 = 3 * b[0] + n0, g1 = 3 * b[1] + n1, g2 = 3 * b[2] + n2;
    if (t < kTileNodes && g0 < g.nodes[0] && g1 < g.nodes[1] && g2 < g.nodes[2]) {
      T* r = grid + kNodeValues * nodeRecordAt(g, g0, g1, g2);
      for (int c = 0; c < kNodeVNew + 3; ++c) r[c] += acc[c];
    }
  }
}

// The same P2G for a grid small enough to keep every occupied block's tile apart (p2gTileSums
// then adds them): all colours' occupied blocks in one launch, their tiles' sums into
// scratch[place] (kTileNodes x (kNodeVNew + 3) values, place = the block's rank among the
// step's occupied blocks, colour by colour), the place in slotOf[block]. A thin flow's colour
// launches hold a few dozen blocks each and wait for one another; this one fills the device.
template <typename T>
__global__ void __launch_bounds__(kBaseThreads)
    p2gTilesKernel(BlockGrid bg, ActiveLists lists, ParticleIn<T> in, const int* sorted,
                   const unsigned long long* key, int shift, GridConst<T> g, T dt, T* scratch, int* slotOf) {
  __shared__ P2GShared<T> sh;
  const int t = threadIdx.x;
  int total = 0;
  for (int colour = 0; colour < 8; ++colour) total += lists.count[colour];
  for (int q = blockIdx.x; q < total; q += gridDim.x) {
    int colour = 0, rank = q;
    while (rank >= lists.count[colour]) rank -= lists.count[colour++];
    const int block = lists.blocks[bg.colourStart(colour) + rank];
    T acc[kNodeVNew + 3] = {};
    p2gBlockTile(block, lists, key, shift, in, sorted, g, dt, sh, acc);
    if (t < kTileNodes) {
      T* s = scratch + (static_cast<std::size_t>(q) * kTileNodes + t) * (kNodeVNew + 3);
      for (int c = 0; c < kNodeVNew + 3; ++c) s[c] = acc[c];
    }
    if (t == 0) slotOf[block] = q;
  }
}

// Each active node's sum of the tiles that reach it (tilesOfNode), added in colour order from
// zero: the same additions, in the same order, as the colour launches of p2gBaseKernel make.
template <typename T>
__global__ void p2gTileSumsKernel(ActiveLists a, BlockGrid bg, const T* scratch, const int* slotOf, T* grid,
                                  GridConst<T> g) {
  forActiveTileNodes(a, bg.blocks, g.nodes, g.column, [=](int node) {
    const int gn[3] = {node / (g.nodes[1] * g.nodes[2]), (node / g.nodes[2]) % g.nodes[1], node % g.nodes[2]};
    int slot[8], local[8];
    tilesOfNode(gn, bg.blocks, [slotOf](int block) { return slotOf[block]; }, slot, local);
    T sum[kNodeVNew + 3] = {};
    for (int colour = 0; colour < 8; ++colour) {
      if (slot[colour] < 0) continue;
      const T* s = scratch + (static_cast<std::size_t>(slot[colour]) * kTileNodes + local[colour]) * (kNodeVNew + 3);
      for (int c = 0; c < kNodeVNew + 3; ++c) sum[c] += s[c];
    }
    T* r = grid + kNodeValues * nodeRecord(g, node);
    for (int c = 0; c < kNodeVNew + 3; ++c) r[c] = sum[c];
  });
}

// The grid update (gridKernel), or its two halves with the grid hooks launched between them,
// over the active tiles' nodes.
template <typename T>
__global__ void gridKernel(ActiveLists a, BlockGrid bg, T* grid, GridConst<T> g, T dt) {
  forActiveTileNodes(a, bg.blocks, g.nodes, g.column, [=](int node) { gridNodeUpdate(node, grid, g, dt); });
}

template <typename T>
__global__ void gridVelocityKernel(ActiveLists a, BlockGrid bg, T* grid, GridConst<T> g, T dt) {
  forActiveTileNodes(a, bg.blocks, g.nodes, g.column, [=](int node) { gridNodeVelocity(node, grid, g, dt); });
}

template <typename T>
__global__ void gridWallsKernel(ActiveLists a, BlockGrid bg, T* grid, GridConst<T> g) {
  forActiveTileNodes(a, bg.blocks, g.nodes, g.column, [=](int node) { gridNodeWalls(node, grid, g); });
}

// The last step's active tiles back to zero before P2G (every other node is zero).
template <typename T>
__global__ void clearTilesKernel(ActiveLists a, BlockGrid bg, T* grid, GridConst<T> g) {
  forActiveTileNodes(a, bg.blocks, g.nodes, g.column, [=](int node) {
    T* r = grid + kNodeValues * nodeRecord(g, node);
    for (int c = 0; c < kNodeValues; ++c) r[c] = T(0);
  });
}

// The last lists forgotten where they left marks: their occupied blocks' places in
// p2gTilesKernel's scratch (every other block's is -1 already) and their tiles' marks. Clearing
// the whole arrays each step would move 8 bytes a block of a long or wide grid.
__global__ inline void forgetListsKernel(ActiveLists a, BlockGrid bg, int* slotOf) {
  const int stride = gridDim.x * blockDim.x;
  for (int colour = 0; colour < 8; ++colour) {
    const int count = a.count[colour], base = bg.colourStart(colour);
    for (int i = blockIdx.x * blockDim.x + threadIdx.x; i < count; i += stride) slotOf[a.blocks[base + i]] = -1;
  }
  const int tiles = a.count[kTilesCount];
  for (int i = blockIdx.x * blockDim.x + threadIdx.x; i < tiles; i += stride) a.tileMark[a.tiles[i]] = 0;
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
__global__ void gateKernel(GateBand b, int count, int stride, const int* column, const T* mass, T* vx, T* vy, T* vz,
                           T mu, double* impulse) {
  const int t = blockIdx.x * blockDim.x + threadIdx.x;
  double p[3] = {0.0, 0.0, 0.0};
  const long r = t < count ? storedNodeRecord(column, b.nodes[2], gateBandNode(t, b)) : -1;
  if (r >= 0) {  // (a column no point has reached holds empty nodes and is not stored)
    const Vec3T<T> d = applyGateNode(stride * r, mass, vx, vy, vz, mu);
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
                          unsigned int* maxSpeedBits, const unsigned int* missing) {
  if (*missing) return;  // the whole launch: the step fails (MpmCuda::step)
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

// Whole-system diagnostics (DiagnosticsKernels.hpp) in a fixed order: thread t of the
// kDiagBlocks x kDiagThreads takes slots t, t + stride, ... in turn, a fixed tree adds each
// block's threads, and diagnosticsTotalKernel adds the blocks' results the same way, so that the
// sums depend on the slots' order alone (the step's sort gives it), not on thread timing.
constexpr int kDiagThreads = 64;
constexpr int kDiagBlocks = 256;

struct DiagnosticPartial {
  DiagnosticSums sums;
  ProbeSums probes[kMaxDeviceProbes];
};

struct DiagnosticInput {
  double gravity[3];
  ProbeStation probes[kMaxDeviceProbes];
  int numProbes;
};

__device__ __forceinline__ void emptyPartial(DiagnosticPartial& a) {
  a.sums = emptyDiagnosticSums();
  for (int k = 0; k < kMaxDeviceProbes; ++k) a.probes[k] = emptyProbeSums();
}

__device__ __forceinline__ void combinePartial(DiagnosticPartial& a, const DiagnosticPartial& b, int numProbes) {
  combineDiagnostics(a.sums, b.sums);
  for (int k = 0; k < numProbes; ++k) combineProbe(a.probes[k], b.probes[k]);
}

// Adds part[0..kDiagThreads) into part[0] by halves (a fixed tree).
__device__ __forceinline__ void treeSum(DiagnosticPartial* part, int numProbes) {
  const int t = threadIdx.x;
  for (int half = kDiagThreads / 2; half > 0; half >>= 1) {
    __syncthreads();
    if (t < half) combinePartial(part[t], part[t + half], numProbes);
  }
}

template <typename T>
__global__ void __launch_bounds__(kDiagThreads)
    diagnosticsKernel(int n, ParticleIn<T> in, const std::uint8_t* phase, DiagnosticInput d, DiagnosticPartial* partial) {
  __shared__ DiagnosticPartial part[kDiagThreads];
  const int t = threadIdx.x;
  DiagnosticPartial& acc = part[t];
  emptyPartial(acc);
  for (int p = blockIdx.x * kDiagThreads + t; p < n; p += kDiagBlocks * kDiagThreads) {
    const double x[3] = {static_cast<double>(in.x[0][p]), static_cast<double>(in.x[1][p]),
                         static_cast<double>(in.x[2][p])};
    const double v[3] = {static_cast<double>(in.v[0][p]), static_cast<double>(in.v[1][p]),
                         static_cast<double>(in.v[2][p])};
    const double m = static_cast<double>(in.mass[p]);
    addParticleDiagnostics(acc.sums, x, v, m, phase[p], d.gravity);
    for (int k = 0; k < d.numProbes; ++k) addProbeSample(acc.probes[k], d.probes[k], x, v[0], m);
  }
  treeSum(part, d.numProbes);
  if (t == 0) partial[blockIdx.x] = part[0];
}

// One block of kDiagThreads: the kDiagBlocks partial results into *total.
static __global__ void __launch_bounds__(kDiagThreads)
    diagnosticsTotalKernel(const DiagnosticPartial* partial, int numProbes, DiagnosticPartial* total) {
  __shared__ DiagnosticPartial part[kDiagThreads];
  const int t = threadIdx.x;
  emptyPartial(part[t]);
  for (int q = t; q < kDiagBlocks; q += kDiagThreads) combinePartial(part[t], partial[q], numProbes);
  treeSum(part, numProbes);
  if (t == 0) *total = part[0];
}

}  // namespace cudak
}  // namespace mpm
}  // namespace mpmsdem
