// The three stages of one explicit MPM step (paper §2.1, Fig 1) written once as
// __host__ __device__ functions: the CPU loops (MpmCpu.cpp) and the CUDA kernels
// (cuda/MpmCudaKernels.cuh) call exactly these, in double or float.
//
// Grid layout: one record of kNodeValues values per node. Node (i, j, k) has the index
// n = (i * nodes[1] + j) * nodes[2] + k; its record is n itself in the dense layout, or, where
// a backend stores only the node columns its particles reach (GridConst::column), the k-th of
// its column's nodes[2] consecutive records; its value c at grid[kNodeValues * record + c]. A node's
// values share a cache line and two SIMD registers (double; one in float), so P2G adds and G2P
// reads a node with whole-register operations.
// After P2G: c = 0..2 momentum of the particle velocities (sum w m v), 3 mass, 4..6 that
// momentum plus dt times the internal and external particle forces, 7 zero.
// After the grid update: 0..2 old velocity, 3 mass, 4..6 new velocity (gravity, grid hooks and
// walls applied), 7 zero.
#pragma once
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>

#include "common/Error.hpp"

#include "mpm/BSpline.hpp"
#include "mpm/Constitutive.hpp"
#include "mpm/GridBoundary.hpp"
#include "common/MathHD.hpp"
#include "mpm/MpmTypes.hpp"
#include "mpm/TerrainBoundary.hpp"

namespace mpmsdem {
namespace mpm {

constexpr int kNodeValues = 8;
constexpr int kNodeMass = 3;   // the mass in a node's record
constexpr int kNodeVNew = 4;   // the new velocity (3 values) in a node's record

// Grid geometry and per-run constants.
template <typename T>
struct GridConst {
  T origin[3];      // lower corner [m]
  T dx, invDx;      // spacing [m] and its inverse
  int cells[3];     // cells per axis
  int nodes[3];     // cells + 1
  T gravity[3];     // [m/s^2]
  T wallFriction[6];
  T massEps;        // nodes with mass <= massEps are treated as empty [kg]
  T lo[3], hi[3];   // admissible particle box (kWallLayer cells inside the faces) [m]
  TerrainView<T> terrain;  // its heights in the backend's memory, set by the backend; null z: none
  // Where each column of nodes (i, j) is stored: its nodes k = 0 .. nodes[2] - 1 are the records
  // column[i * nodes[1] + j] * nodes[2] + k. Null: the dense layout (column i * nodes[1] + j). A
  // backend that allocates the columns as its particles reach them sets it, so that the grid's
  // memory follows the flow and not the box.
  const int* column;
};

// The record of node (i, j, k), and of the node with index `node` (see the layout above). Node
// indices are ints (a grid has fewer than 2^31 nodes); records, and the value offsets
// kNodeValues * record, are 64-bit, so that the grid's size is bounded by the memory of the
// nodes it stores and not by 2^31 values.
template <typename T>
MPM_HD_INLINE long nodeRecordAt(const GridConst<T>& g, int i, int j, int k) {
  const int c = i * g.nodes[1] + j;
  return static_cast<long>(g.column ? g.column[c] : c) * g.nodes[2] + k;
}
template <typename T>
MPM_HD_INLINE long nodeRecord(const GridConst<T>& g, int node) {
  if (!g.column) return node;
  const int c = node / g.nodes[2];
  return static_cast<long>(g.column[c]) * g.nodes[2] + (node - c * g.nodes[2]);
}

// Per-step constants.
template <typename T>
struct StepConst {
  T dt;         // [s]
  T alpha;      // FLIP fraction, Eq 4
  T maxSpeed;   // blow-up threshold on |v_p| [m/s]
  ConstitutiveConst<T> mat;
};

// Particle state read by a step (SoA, one array per component), indexed by storage slot; id[slot]
// is the particle number (a backend that keeps the particles in their own order has id null:
// slot and number are the same).
template <typename T>
struct ParticleIn {
  const T* x[3];
  const T* v[3];
  const T* s[6];
  const T* J;
  const T* mass;
  const T* vol0;
  const T* fext[3];  // all null when no external forces are set for this step
  const int* id;
};

// Particle state written by a step.
template <typename T>
struct ParticleOut {
  T* x[3];
  T* v[3];
  T* s[6];
  T* J;
  T* gdp;
  std::uint8_t* phase;
};

template <typename T>
MPM_HD_INLINE void gridCoordinate(const ParticleIn<T>& P, int p, const GridConst<T>& g, T out[3]) {
  for (int d = 0; d < 3; ++d) out[d] = (P.x[d][p] - g.origin[d]) * g.invDx;
}

// What P2G needs of one particle: its stencil and the coefficients of its share of each node's
// values, r = w C_w + (grad w) . (C_x, C_y, C_z) (see p2gStencil).
template <typename T>
struct P2GParticle {
  Stencil<T> st;
  T cw[kNodeValues], cx[kNodeValues], cy[kNodeValues], cz[kNodeValues];
};

template <typename T>
MPM_HD_INLINE void p2gPrepare(int p, const ParticleIn<T>& P, const GridConst<T>& g, T dt, P2GParticle<T>& a) {
  T gc[3];
  gridCoordinate(P, p, g, gc);
  a.st.compute(gc);
  const T m = P.mass[p];
  const T vol = P.J[p] * P.vol0[p];
  T s[6];
  for (int k = 0; k < 6; ++k) s[k] = -dt * vol * g.invDx * P.s[k][p];  // -dt V sigma / dx
  for (int d = 0; d < 3; ++d) {
    a.cw[d] = m * P.v[d][p];
    a.cw[kNodeVNew + d] = a.cw[d] + (P.fext[0] ? dt * P.fext[d][p] : T(0));
  }
  a.cw[kNodeMass] = m;
  a.cw[7] = T(0);
  for (int c = 0; c < kNodeValues; ++c) a.cx[c] = a.cy[c] = a.cz[c] = T(0);
  // (-dt V sigma) . grad w, sigma symmetric in Voigt order xx yy zz yz xz xy
  T* ix = a.cx + kNodeVNew;
  T* iy = a.cy + kNodeVNew;
  T* iz = a.cz + kNodeVNew;
  ix[0] = s[0], iy[0] = s[5], iz[0] = s[4];
  ix[1] = s[5], iy[1] = s[1], iz[1] = s[3];
  ix[2] = s[4], iy[2] = s[3], iz[2] = s[2];
}

// P2G of a prepared particle: calls add(i, j, k, r) for the 27 nodes a.st.base + (i, j, k) with
// r[c] the particle's share of node value c (r[7] = 0): mass w m, momentum w m v, and momentum
// plus the impulse dt (w f_ext - V_p sigma grad w), V_p = J V0 (Eq 14), from the coefficients
// and the separable weights factored per (i, j) row, so that a row of 3 nodes costs two
// multiply-adds per value.
template <typename T, typename Scatter>
MPM_HD_INLINE void p2gStencil(const P2GParticle<T>& a, Scatter& add) {
  const Stencil<T>& st = a.st;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const T wij = st.w[0][i] * st.w[1][j];
      const T xij = st.dw[0][i] * st.w[1][j];
      const T yij = st.w[0][i] * st.dw[1][j];
      T row[kNodeValues], rowZ[kNodeValues];
      MPM_SIMD
      for (int c = 0; c < kNodeValues; ++c) {
        row[c] = wij * a.cw[c] + xij * a.cx[c] + yij * a.cy[c];
        rowZ[c] = wij * a.cz[c];
      }
      for (int k = 0; k < 3; ++k) {
        T r[kNodeValues];
        MPM_SIMD
        for (int c = 0; c < kNodeValues; ++c) r[c] = st.w[2][k] * row[c] + st.dw[2][k] * rowZ[c];
        add(i, j, k, r);
      }
    }
}

// P2G of particle p into the flat grid: calls add(node, r) for its 27 nodes by index (see
// p2gStencil).
template <typename T, typename Scatter>
MPM_HD_INLINE void p2gParticle(int p, const ParticleIn<T>& P, const GridConst<T>& g, T dt, Scatter& add) {
  P2GParticle<T> a;
  p2gPrepare(p, P, g, dt, a);
  auto toNode = [&](int i, int j, int k, const T* r) {
    add(((a.st.base[0] + i) * g.nodes[1] + (a.st.base[1] + j)) * g.nodes[2] + (a.st.base[2] + k), r);
  };
  p2gStencil(a, toNode);
}

// ---------------------------------------------------------------- P2G by blocks of bases
// Both backends sum P2G by blocks of 3x3x3 stencil-base cells: a particle whose base lies in
// block b reaches nodes 3b .. 3b + 4 per axis (the block's 5x5x5 tile), so blocks whose indices
// differ by 2 or more along some axis share no node; a block's tile is added to the grid with
// the blocks of one parity colour at a time. The CPU scatters a block's particles, in the order
// (base, number), into a private copy of its tile. CUDA gathers: the particles of one base (in
// number order) into that base's 27 nodes (p2gBaseNodeAdd, one thread per node), then each tile
// node adds the sums of the bases that reach it in base order (p2gBaseTileSum). Either way a
// node's sum does not depend on thread timing or on the order the particles are stored in.
constexpr int kBlockCells = 27;  // stencil bases per block
constexpr int kBlockNodes = 5;   // nodes per axis of a block's tile

// Blocks along an axis of `cells` cells (stencil bases run up to cells - 1).
MPM_HD_INLINE int blocksAlong(int cells) { return cells / 3 + 1; }

// kBlockCells b + c for a point at grid coordinate gc: b its block in a grid of nb blocks per
// axis, c = 9 o0 + 3 o1 + o2 the place (o0, o1, o2) of its stencil base (Stencil::compute's
// floor) in the block.
template <typename T>
MPM_HD_INLINE int blockCellOf(const T gc[3], const int nb[3]) {
  int b[3], c = 0;
  for (int d = 0; d < 3; ++d) {
    const int base = static_cast<int>(hdFloor(gc[d] - T(0.5)));  // >= 1 inside the admissible box
    b[d] = base / 3;
    c = 3 * c + base % 3;
  }
  return kBlockCells * ((b[0] * nb[1] + b[1]) * nb[2] + b[2]) + c;
}

// Block (or tile) b's coordinates in a grid of n per axis.
MPM_HD_INLINE void blockCoordsOf(int b, const int n[3], int c[3]) {
  c[2] = b % n[2];
  c[1] = (b / n[2]) % n[1];
  c[0] = b / (n[2] * n[1]);
}

// Parity colour of the block at coordinates c: 4 (c0 % 2) + 2 (c1 % 2) + c2 % 2.
MPM_HD_INLINE int blockColourOf(const int c[3]) { return (c[0] & 1) * 4 + (c[1] & 1) * 2 + (c[2] & 1); }

// Grid work follows the occupied blocks on both backends: the nodes are grouped in tiles of
// 3x3x3 (tile t holds nodes 3t .. 3t + 2 per axis; a grid has as many tiles per axis as blocks),
// and the particles of block b reach tiles b and b + 1 per axis. A step zeroes, updates and
// wall-corrects only the tiles next to occupied blocks (the active tiles); every other node is
// zero at every stage, as a sweep of the whole grid would leave it (an empty node's update
// writes zeros). f(tile) for the tiles the particles of the block at coordinates c reach.
template <typename F>
MPM_HD_INLINE void forTilesOfBlock(const int c[3], const int n[3], F&& f) {
  for (int t0 = c[0]; t0 <= c[0] + 1 && t0 < n[0]; ++t0)
    for (int t1 = c[1]; t1 <= c[1] + 1 && t1 < n[1]; ++t1)
      for (int t2 = c[2]; t2 <= c[2] + 1 && t2 < n[2]; ++t2) f((t0 * n[1] + t1) * n[2] + t2);
}

// Node k (0..26: 9 i + 3 j + l, its place in the tile) of tile t, in a grid of n tiles and
// `nodes` nodes per axis: its index, or -1 past the grid's far faces.
MPM_HD_INLINE int tileNodeOf(int t, int k, const int n[3], const int nodes[3]) {
  int c[3];
  blockCoordsOf(t, n, c);
  const int a = 3 * c[0] + k / 9, b = 3 * c[1] + (k / 3) % 3, d = 3 * c[2] + k % 3;
  if (a >= nodes[0] || b >= nodes[1] || d >= nodes[2]) return -1;
  return (a * nodes[1] + b) * nodes[2] + d;
}

// Which node columns a backend stores (GridConst::column). The CPU stores the columns of each
// step's active tiles as its binning finds them. CUDA learns the active tiles on the device only,
// so at each step's end it stores the columns near them (columnNearTile): the next step's
// particles have moved less than a cell, so their blocks are at most one block from this step's,
// and the tiles those reach lie within one tile of this step's active tiles, along x and y (a
// column is the grid's whole height). The next step then finds its columns stored without a
// host round trip; tileColumnsStored checks it.
constexpr int kColumnsNearTile = 81;  // 9 tiles' (x, y) columns of 3 x 3 node columns each

// Node column r (0 .. kColumnsNearTile - 1) near tile t in a grid of n tiles and `nodes` nodes
// per axis: column (i, j) of the tile (r / 27 - 1, (r / 9) % 3 - 1) tiles from t along x and y,
// its node column (r % 9) / 3, r % 3 in that tile. Its index i nodes[1] + j, or -1 outside the grid.
MPM_HD_INLINE int columnNearTile(int t, int r, const int n[3], const int nodes[3]) {
  int c[3];
  blockCoordsOf(t, n, c);
  const int k = r % 9;
  const int i = 3 * (c[0] + r / 27 - 1) + k / 3, j = 3 * (c[1] + (r / 9) % 3 - 1) + k % 3;
  if (i < 0 || j < 0 || i >= nodes[0] || j >= nodes[1]) return -1;
  return i * nodes[1] + j;
}

// Whether every node column of tile t is stored (column[] >= 0).
MPM_HD_INLINE bool tileColumnsStored(int t, const int n[3], const int nodes[3], const int* column) {
  for (int k = 0; k < 9; ++k) {
    const int c = columnNearTile(t, 36 + k, n, nodes);  // 36: the tile itself
    if (c >= 0 && column[c] < 0) return false;
  }
  return true;
}

// The first place q in [lo, hi) of ascending keys whose bits from `shift` up are >= value, or hi:
// where a value's run of keys starts (CUDA finds the stencil bases' particles in a block's range
// of the sorted keys so, instead of keeping a range for every cell of the grid).
MPM_HD_INLINE int firstKeyAtLeast(const unsigned long long* key, int lo, int hi, int shift, unsigned long long value) {
  while (lo < hi) {
    const int mid = lo + (hi - lo) / 2;
    if ((key[mid] >> shift) < value)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo;
}

// A particle as the gather of its base keeps it: its offset from the base node per axis (the f of
// Stencil::compute) and P2GParticle's coefficients without those that are always zero (cx, cy,
// cz are non-zero only for the new momentum, values kNodeVNew..+2).
template <typename T>
struct P2GBaseParticle {
  T f[3];
  T cw[kNodeVNew + 3];
  T cx[3], cy[3], cz[3];
};

template <typename T>
MPM_HD_INLINE void p2gBasePrepare(int p, const ParticleIn<T>& P, const GridConst<T>& g, T dt, P2GBaseParticle<T>& t) {
  P2GParticle<T> a;
  p2gPrepare(p, P, g, dt, a);
  T gc[3];
  gridCoordinate(P, p, g, gc);
  for (int d = 0; d < 3; ++d) t.f[d] = gc[d] - static_cast<T>(a.st.base[d]);
  for (int c = 0; c < kNodeVNew + 3; ++c) t.cw[c] = a.cw[c];
  for (int d = 0; d < 3; ++d) {
    t.cx[d] = a.cx[kNodeVNew + d];
    t.cy[d] = a.cy[kNodeVNew + d];
    t.cz[d] = a.cz[kNodeVNew + d];
  }
}

// Adds a prepared particle's share of node base + (i, j, k) to acc[0..6]: p2gStencil's values,
// with the products by zero coefficients left out (they add exact zeros there).
template <typename T>
MPM_HD_INLINE void p2gBaseNodeAdd(const P2GBaseParticle<T>& a, int i, int j, int k, T acc[kNodeVNew + 3]) {
  T w[3], dw[3];
  const int idx[3] = {i, j, k};
  for (int d = 0; d < 3; ++d) Stencil<T>::axis(a.f[d], idx[d], w[d], dw[d]);
  const T wij = w[0] * w[1];
  const T xij = dw[0] * w[1];
  const T yij = w[0] * dw[1];
  for (int c = 0; c < kNodeVNew; ++c) acc[c] += w[2] * (wij * a.cw[c]);
  for (int d = 0; d < 3; ++d) {
    const T row = wij * a.cw[kNodeVNew + d] + xij * a.cx[d] + yij * a.cy[d];
    acc[kNodeVNew + d] += w[2] * row + dw[2] * (wij * a.cz[d]);
  }
}

// Adds to acc the sums of tile node (n0, n1, n2) (0..4 per axis) from the bases (o0, o1, o2) of
// one o0 = row that reach it, in (o1, o2) order: part(o1, o2, m) is the sum of base (row, o1, o2)
// at its node m = 9 i + 3 j + k.
template <typename T, typename Part>
MPM_HD_INLINE void p2gBaseTileSum(int row, int n0, int n1, int n2, const Part& part, T acc[kNodeVNew + 3]) {
  const int i = n0 - row;
  if (i < 0 || i > 2) return;
  for (int o1 = 0; o1 < 3; ++o1) {
    const int j = n1 - o1;
    if (j < 0 || j > 2) continue;
    for (int o2 = 0; o2 < 3; ++o2) {
      const int k = n2 - o2;
      if (k < 0 || k > 2) continue;
      const T* s = part(o1, o2, 9 * i + 3 * j + k);
      for (int c = 0; c < kNodeVNew + 3; ++c) acc[c] += s[c];
    }
  }
}

// The tiles that reach node gn (grid coordinates) in a grid of nb blocks per axis: block b per
// axis holds nodes 3b .. 3b + 4, so gn lies in the tiles of b = gn/3 and, when gn % 3 <= 1, of
// b - 1; the up to 8 blocks have 8 different parity colours. For each colour: slotOf(block) of
// its block (-1: none, or the block holds no tile this step) in slot[colour], and the node's
// place in that block's tile (25 n0 + 5 n1 + n2) in local[colour]. Adding the tiles in colour
// order from zero makes the same additions in the same order as adding each colour's tiles to
// the grid one colour after another.
template <typename SlotOf>
MPM_HD_INLINE void tilesOfNode(const int gn[3], const int nb[3], const SlotOf& slotOf, int slot[8], int local[8]) {
  for (int k = 0; k < 8; ++k) slot[k] = -1;
  for (int k = 0; k < 8; ++k) {
    int b[3], m = 0;
    bool inside = true;
    for (int d = 0; d < 3; ++d) {
      b[d] = gn[d] / 3 - ((k >> (2 - d)) & 1);
      const int o = gn[d] - 3 * b[d];
      inside = inside && b[d] >= 0 && b[d] < nb[d] && o < kBlockNodes;
      m = kBlockNodes * m + o;
    }
    if (!inside) continue;
    const int s = slotOf((b[0] * nb[1] + b[1]) * nb[2] + b[2]);
    if (s < 0) continue;
    slot[blockColourOf(b)] = s;
    local[blockColourOf(b)] = m;
  }
}

// Grid velocities of one node (Eq 3): v_old = p/m, v_new = (p + dt f)/m + dt g; an empty node
// is zeroed (mass included, so grid hooks see it at rest).
template <typename T>
MPM_HD_INLINE void gridNodeVelocity(int node, T* grid, const GridConst<T>& g, T dt) {
  T* r = grid + kNodeValues * nodeRecord(g, node);
  const T m = r[kNodeMass];
  if (!(m > g.massEps)) {
    for (int c = 0; c < kNodeValues; ++c) r[c] = T(0);
    return;
  }
  const T inv = T(1) / m;
  for (int d = 0; d < 3; ++d) {
    r[d] *= inv;
    r[kNodeVNew + d] = r[kNodeVNew + d] * inv + dt * g.gravity[d];
  }
}

// The terrain, then the walls, on the new velocity of one node.
template <typename T>
MPM_HD_INLINE void gridNodeWalls(int node, T* grid, const GridConst<T>& g) {
  int idx[3];
  idx[2] = node % g.nodes[2];
  const int q = node / g.nodes[2];
  idx[1] = q % g.nodes[1];
  idx[0] = q / g.nodes[1];
  T* r = grid + kNodeValues * nodeRecord(g, node) + kNodeVNew;
  Vec3T<T> vn{r[0], r[1], r[2]};
  if (g.terrain.z) {
    const Vec3T<T> p{g.origin[0] + T(idx[0]) * g.dx, g.origin[1] + T(idx[1]) * g.dx, g.origin[2] + T(idx[2]) * g.dx};
    applyTerrain(vn, p, g.terrain);
  }
  applyWalls(vn, idx, g.cells, g.wallFriction);
  for (int d = 0; d < 3; ++d) r[d] = vn[d];
}

// Grid update of one node without grid hooks: velocities, then walls. A solver with hooks
// runs the two halves as separate passes with the hooks between them; the values are the
// same (each half stores and reloads T).
template <typename T>
MPM_HD_INLINE void gridNodeUpdate(int node, T* grid, const GridConst<T>& g, T dt) {
  gridNodeVelocity(node, grid, g, dt);
  gridNodeWalls(node, grid, g);
}

// Admissible volume ratio J = V/V0 of a material point. A granular material changes its
// volume by tens of per cent at most (random loose to dense packing, or the elastic strain
// p/K under any pressure the flows of interest reach); J below kMinJ (crushed to 1/1000 of its
// volume, denser than the solid grains) or above kMaxJ (torn to 1000 x its volume) only comes
// from a numerical failure, e.g. a step too large for the loading, that would otherwise run
// on with flattened particles. The bounds are 1000 x beyond anything physical so that no
// sound run stops.
constexpr double kMinJ = 1e-3;
constexpr double kMaxJ = 1e3;

// Result of the G2P of one particle.
template <typename T>
struct G2PResult {
  bool ok;    // false: non-finite state, |v| above StepConst::maxSpeed, or J outside [kMinJ, kMaxJ]
  T speed;    // |v_p| after the step [m/s]
};

// What the G2P update of one particle reads, gathered by g2pGather as kG2PValues values at
// a[c * stride], c one of the offsets below: the grid sums over the particle's stencil, sum
// w (v_new - v_old) (3 values), sum w v_new (3) and the velocity gradient L = sum v_new (x)
// grad w [1/s] (9, row-major); then the particle's state at the start of the step. The stride
// lets a CPU loop keep the values of several particles side by side, so that g2pUpdate runs on
// them as one vector loop that reads each value of consecutive particles from consecutive
// addresses.
enum : int {
  kG2PDv = 0,
  kG2PVPic = 3,
  kG2PL = 6,
  kG2PX = 15,
  kG2PV = 18,
  kG2PSigma = 21,
  kG2PJ = 27,
  kG2PMass = 28,
  kG2PVol0 = 29,
  kG2PValues = 30
};

// The G2P grid sums of `count` (1..G) particles ps[] that share one stencil base, one lane per
// particle, so that one vector instruction serves G particles (the CPU step's groups of a
// stencil base; g2pGather is the group of one). A node's values are the same for the whole
// group, so each is read once and broadcast. Every lane runs the same instructions, so a
// particle's sums do not depend on the other members of its group or on its lane; lanes of
// missing particles repeat the last one and are not written.
template <int G, typename T>
MPM_HD_INLINE void g2pGatherGroup(const int* ps, int count, const ParticleIn<T>& P, const T* grid,
                                  const GridConst<T>& g, T* a, int stride) {
  T wx[3][G], dwx[3][G], wy[3][G], dwy[3][G], wz[3][G], dwz[3][G];
  int base[3] = {0, 0, 0};
  for (int l = 0; l < G; ++l) {
    T gc[3];
    gridCoordinate(P, ps[l < count ? l : count - 1], g, gc);
    Stencil<T> st;
    st.compute(gc);
    if (l == 0)
      for (int d = 0; d < 3; ++d) base[d] = st.base[d];
    for (int k = 0; k < 3; ++k) {
      wx[k][l] = st.w[0][k], dwx[k][l] = st.dw[0][k];
      wy[k][l] = st.w[1][k], dwy[k][l] = st.dw[1][k];
      wz[k][l] = st.w[2][k], dwz[k][l] = st.dw[2][k];
    }
  }
  // Sums over the stencil of w (v_new - v_old), w v_new and the gradient components times
  // v_new, per component d and particle l, factored per (i, j) row like P2G.
  T sd[3][G], sw[3][G], sx[3][G], sy[3][G], sz[3][G];
  for (int d = 0; d < 3; ++d) {
    MPM_SIMD
    for (int l = 0; l < G; ++l) sd[d][l] = sw[d][l] = sx[d][l] = sy[d][l] = sz[d][l] = T(0);
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const T* row = grid + kNodeValues * nodeRecordAt(g, base[0] + i, base[1] + j, base[2]);
      T ad[3][G], an[3][G], bn[3][G];
      for (int d = 0; d < 3; ++d) {
        MPM_SIMD
        for (int l = 0; l < G; ++l) ad[d][l] = an[d][l] = bn[d][l] = T(0);
      }
      for (int k = 0; k < 3; ++k) {
        const T* r = row + kNodeValues * k;
        for (int d = 0; d < 3; ++d) {
          const T vn = r[kNodeVNew + d], dv = vn - r[d];
          MPM_SIMD
          for (int l = 0; l < G; ++l) {
            ad[d][l] += wz[k][l] * dv;
            an[d][l] += wz[k][l] * vn;
            bn[d][l] += dwz[k][l] * vn;
          }
        }
      }
      for (int d = 0; d < 3; ++d) {
        MPM_SIMD
        for (int l = 0; l < G; ++l) {
          const T wij = wx[i][l] * wy[j][l];
          const T xij = dwx[i][l] * wy[j][l];
          const T yij = wx[i][l] * dwy[j][l];
          sd[d][l] += wij * ad[d][l];
          sw[d][l] += wij * an[d][l];
          sx[d][l] += xij * an[d][l];
          sy[d][l] += yij * an[d][l];
          sz[d][l] += wij * bn[d][l];
        }
      }
    }
  for (int l = 0; l < count; ++l) {
    const int p = ps[l];
    T* al = a + l;
    for (int d = 0; d < 3; ++d) {
      al[(kG2PDv + d) * stride] = sd[d][l];
      al[(kG2PVPic + d) * stride] = sw[d][l];
      al[(kG2PL + 3 * d) * stride] = g.invDx * sx[d][l];
      al[(kG2PL + 3 * d + 1) * stride] = g.invDx * sy[d][l];
      al[(kG2PL + 3 * d + 2) * stride] = g.invDx * sz[d][l];
      al[(kG2PX + d) * stride] = P.x[d][p];
      al[(kG2PV + d) * stride] = P.v[d][p];
    }
    for (int k = 0; k < 6; ++k) al[(kG2PSigma + k) * stride] = P.s[k][p];
    al[kG2PJ * stride] = P.J[p];
    al[kG2PMass * stride] = P.mass[p];
    al[kG2PVol0 * stride] = P.vol0[p];
  }
}

// The G2P grid sums and state of particle p at a[c * stride] (kG2PValues values).
template <typename T>
MPM_HD_INLINE void g2pGather(int p, const ParticleIn<T>& P, const T* grid, const GridConst<T>& g, T* a,
                             int stride) {
  g2pGatherGroup<1>(&p, 1, P, grid, g, a, stride);
}

// The update of one particle from the values g2pGather collected (Eq 4 and Appendix B): writes
// its new state to slot q of Q (a CPU step that keeps the particles sorted by grid block writes
// them in their new order, elsewhere q is the slot read), except the phase, which it gives back
// with the speed |v| [m/s]; returns false for a non-finite state, |v| above StepConst::maxSpeed,
// or J outside [kMinJ, kMaxJ]. Velocity v = alpha (v + sum w dv) + (1 - alpha) sum w v_new;
// position x += dt sum w v_new (clamped to the admissible box); J *= det(I + dt L); rho = m /
// (J V0); stress update. Every branch is a select (the checks combine with &, an inverted point
// keeps its old stress) and the byte-wide phase is left to the caller, so that the CPU step
// updates several particles per vector instruction.
template <typename T>
MPM_HD_INLINE bool g2pUpdate(const T* a, int stride, int q, const ParticleOut<T>& Q, const GridConst<T>& g,
                             const StepConst<T>& sc, T& speed, int& phase) {
  Mat3T<T> L;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) L.m[r][c] = a[(kG2PL + 3 * r + c) * stride];
  const T dt = sc.dt;
  Vec3T<T> v{T(0), T(0), T(0)};
  bool ok = true;
  for (int d = 0; d < 3; ++d) {
    const T vPic = a[(kG2PVPic + d) * stride];
    v[d] = sc.alpha * (a[(kG2PV + d) * stride] + a[(kG2PDv + d) * stride]) + (T(1) - sc.alpha) * vPic;
    T x = a[(kG2PX + d) * stride] + dt * vPic;
    ok = ok & hdIsFinite(x) & hdIsFinite(v[d]);
    const T lo = g.lo[d], hi = g.hi[d];
    x = x < lo ? lo : (x > hi ? hi : x);
    Q.x[d][q] = x;
    Q.v[d][q] = v[d];
  }
  Mat3T<T> F;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) F.m[r][c] = (r == c ? T(1) : T(0)) + dt * L.m[r][c];
  const T J = a[kG2PJ * stride] * F.det();
  Q.J[q] = J;
  speed = hdSqrt(dot(v, v));
  Sym6T<T> sig;
  for (int k = 0; k < 6; ++k) sig.s[k] = a[(kG2PSigma + k) * stride];
  // An inverted point (J <= 0) fails the step; it keeps its stress for the error report.
  const bool inverted = !(J > T(0));
  T gdp;
  {
    const T rho = a[kG2PMass * stride] / (J * a[kG2PVol0 * stride]);
    Sym6T<T> sigNew = sig;
    T gdpNew;
    const std::uint8_t phaseNew = updateStress(sigNew, L, dt, rho, sc.mat, gdpNew);
    for (int k = 0; k < 6; ++k) sig.s[k] = inverted ? sig.s[k] : sigNew.s[k];
    gdp = inverted ? T(0) : gdpNew;
    phase = inverted ? int(kPhaseGasified) : int(phaseNew);
  }
  for (int k = 0; k < 6; ++k) {
    Q.s[k][q] = sig.s[k];
    ok = ok & hdIsFinite(sig.s[k]);
  }
  Q.gdp[q] = gdp;
  ok = ok & !inverted & hdIsFinite(J) & (J >= T(kMinJ)) & (J <= T(kMaxJ)) & (speed <= sc.maxSpeed);
  return ok;
}

// G2P and stress update of the particle in slot p of P into slot q of Q: g2pGather, then
// g2pUpdate.
template <typename T>
MPM_HD_INLINE G2PResult<T> g2pParticle(int p, const ParticleIn<T>& P, int q, const ParticleOut<T>& Q,
                                       const T* grid, const GridConst<T>& g, const StepConst<T>& sc) {
  T a[kG2PValues];
  g2pGather(p, P, grid, g, a, 1);
  G2PResult<T> r;
  int phase;
  r.ok = g2pUpdate(a, 1, q, Q, g, sc, r.speed, phase);
  if (g.terrain.z) liftAboveTerrain(Q.x[0][q], Q.x[1][q], Q.x[2][q], g.terrain);
  Q.phase[q] = static_cast<std::uint8_t>(phase);
  return r;
}


// ------------------------------------------------------------------ host-side set-up
// (plain host functions shared by both backends; no device code below)

// Elastic P-wave speed sqrt((lambda + 2G)/rho_0) [m/s].
inline double pWaveSpeed(const GranularMaterial& m) {
  const double E = m.youngModulus, nu = m.poissonRatio;
  const double lambda = E * nu / ((1 + nu) * (1 - 2 * nu));
  const double G = E / (2 * (1 + nu));
  return std::sqrt((lambda + 2 * G) / m.density);
}

template <typename T>
inline ConstitutiveConst<T> makeConstitutiveConst(const GranularMaterial& m) {
  const double E = m.youngModulus, nu = m.poissonRatio;
  ConstitutiveConst<T> c;
  c.lambda = static_cast<T>(E * nu / ((1 + nu) * (1 - 2 * nu)));
  c.G = static_cast<T>(E / (2 * (1 + nu)));
  c.muS = static_cast<T>(m.muS);
  c.mu2 = static_cast<T>(m.mu2);
  c.xi = static_cast<T>(m.I0 / (m.grainDiameter * std::sqrt(m.solidDensity)));
  c.rhoC = static_cast<T>(m.criticalDensity > 0 ? m.criticalDensity : m.density);
  return c;
}

// massEps: nodal mass below which a node counts as empty [kg].
template <typename T>
inline GridConst<T> makeGridConst(const MpmParams& prm, double massEps) {
  GridConst<T> g;
  g.column = nullptr;
  g.dx = static_cast<T>(prm.dx);
  g.invDx = static_cast<T>(1.0 / prm.dx);
  for (int d = 0; d < 3; ++d) {
    g.origin[d] = static_cast<T>(prm.origin[d]);
    g.cells[d] = prm.cells[d];
    g.nodes[d] = prm.cells[d] + 1;
    g.gravity[d] = static_cast<T>(prm.gravity[d]);
    // Rounded inward: a particle held at a bound in float must still pass setParticles'
    // check in double when its state is loaded again (a restart from a float run).
    const double lo = prm.origin[d] + kWallLayer * prm.dx, hi = prm.origin[d] + (prm.cells[d] - kWallLayer) * prm.dx;
    g.lo[d] = static_cast<T>(lo);
    g.hi[d] = static_cast<T>(hi);
    if (static_cast<double>(g.lo[d]) < lo) g.lo[d] = std::nextafter(g.lo[d], static_cast<T>(hi));
    if (static_cast<double>(g.hi[d]) > hi) g.hi[d] = std::nextafter(g.hi[d], static_cast<T>(lo));
  }
  for (int w = 0; w < 6; ++w) g.wallFriction[w] = static_cast<T>(prm.walls[w].friction);
  g.massEps = static_cast<T>(massEps);
  if (prm.terrain.enabled()) g.terrain = terrainViewOf<T>(prm.terrain, nullptr);  // z: the backend's copy
  return g;
}

// Blow-up threshold on particle speeds: 1e3 times the elastic wave speed [m/s].
inline double blowUpSpeed(const MpmParams& prm) { return 1e3 * pWaveSpeed(prm.material); }

// Checks of validateParticles on particles [first, first + ps.size()) of a set (messages name
// particle first + p), adding their masses to massSum in order.
inline void validateParticleSlice(const MpmParams& prm, const ParticleSet& ps, std::size_t first, double& massSum) {
  const std::size_t n = ps.size();
  ps.validateSizes(true);
  auto id = [first](std::size_t p) { return "[" + std::to_string(first + p) + "]"; };
  for (std::size_t p = 0; p < n; ++p) {
    if (!(ps.mass[p] > 0) || !std::isfinite(ps.mass[p])) throwParameter("mass" + id(p), ps.mass[p], "kg", "finite and > 0");
    if (!(ps.volume0[p] > 0) || !std::isfinite(ps.volume0[p]))
      throwParameter("volume0" + id(p), ps.volume0[p], "m^3", "finite and > 0");
    if (!(ps.J[p] > 0) || !std::isfinite(ps.J[p])) throwParameter("J" + id(p), ps.J[p], "", "finite and > 0");
    for (int d = 0; d < 3; ++d) {
      const double lo = prm.origin[d] + kWallLayer * prm.dx, hi = prm.origin[d] + (prm.cells[d] - kWallLayer) * prm.dx;
      const double x = ps.x[3 * p + d];
      if (!(x >= lo && x <= hi)) {
        std::ostringstream os;
        os << "in [" << lo << ", " << hi << "] m (the grid box less its " << kWallLayer << "-cell wall layers)";
        throwParameter("particle x" + id(p) + "[" + std::to_string(d) + "]", x, "m", os.str());
      }
      if (!std::isfinite(ps.v[3 * p + d])) throwParameter("v" + id(p), ps.v[3 * p + d], "m/s", "finite");
    }
    for (int k = 0; k < 6; ++k)
      if (!std::isfinite(ps.stress[6 * p + k])) throwParameter("stress" + id(p), ps.stress[6 * p + k], "Pa", "finite");
    massSum += ps.mass[p];
  }
}

// Checks a particle set against the grid before it is handed to a backend: consistent array
// sizes, positive mass and volume, J > 0, finite values, every particle inside the admissible
// box [origin + kWallLayer dx, origin + (cells - kWallLayer) dx] per axis. Returns the mean
// particle mass (used for the empty-node threshold). Throws ParameterError naming the field.
inline double validateParticles(const MpmParams& prm, const ParticleSet& ps) {
  double sum = 0;
  validateParticleSlice(prm, ps, 0, sum);
  const std::size_t n = ps.size();
  return n ? sum / static_cast<double>(n) : 1.0;
}

// Checks the argument of MpmSolver::setExternalForces for n particles: 3 finite values [N] a
// particle.
inline void validateExternalForces(const std::vector<double>& f, std::size_t n) {
  if (f.size() != 3 * n) {
    std::ostringstream os;
    os << "3 x numParticles = " << 3 * n << " values";
    throwParameter("externalForces.size()", f.size(), "", os.str());
  }
  for (std::size_t i = 0; i < f.size(); ++i)
    if (!std::isfinite(f[i])) throwParameter("externalForces[" + std::to_string(i) + "]", f[i], "N", "finite");
}

// The message of a step that particle `number` stopped (non-finite state, a speed above
// maxSpeed, J outside [kMinJ, kMaxJ]) with its position x [m], velocity v [m/s] and J at the
// end of the step, and what became of the particle state (`state`, a sentence).
inline std::string badParticleMessage(long step, double time, const std::string& solver, long number,
                                      double maxSpeed, const double x[3], const double v[3], double J,
                                      const char* state) {
  std::ostringstream os;
  os << "MPM step " << step << " (t = " << time << " s, " << solver << "): particle " << number
     << " has a non-finite state, a speed above " << maxSpeed
     << " m/s (1e3 x P-wave speed) or a volume ratio J outside [" << kMinJ << ", " << kMaxJ
     << "] (crushed or torn apart: no granular material does that; a step too large for the loading?): x = ("
     << x[0] << ", " << x[1] << ", " << x[2] << ") m, v = (" << v[0] << ", " << v[1] << ", " << v[2]
     << ") m/s, J = " << J << ". " << state;
  return os.str();
}

}  // namespace mpm
}  // namespace mpmsdem
