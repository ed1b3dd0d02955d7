// Wall boundary conditions on grid nodes (paper Appendix A, corrected as in docs/physics.md).
// The grid domain is a box with six walls (index 0..5 = -x,+x,-y,+y,-z,+z). A wall acts on
// the nodes of its layer: node index <= kWallLayer on the low side of an axis, >=
// cells - kWallLayer on the high side. Material points are kept at least kWallLayer cells
// inside each face, so the walls effectively sit kWallLayer*dx inside the domain box.
#pragma once
#include "common/MathHD.hpp"

namespace mpmsdem {
namespace mpm {

// Thickness of each wall's node layer and of the margin kept free of material points [cells].
constexpr int kWallLayer = 2;

// Apply one wall to a node velocity. axis 0..2; outwardSign = -1 for the low wall, +1 for
// the high wall; mu: wall friction (< 0 no-slip, 0 free slip, > 0 Coulomb).
// Only the inward normal component (toward the wall, i.e. out of the material) is removed,
// so material may separate from a wall. Coulomb (Eq A.4 with the |v_n| the paper drops):
// if |v_t| <= mu |v_n| then v_t = 0, else v_t -= mu |v_n| v_t/|v_t|, where |v_n| is the
// removed component; a separating node (no normal component removed) keeps v_t.
// No-slip: v_t = 0 on every node of the layer, inward normal removed.
template <typename T>
MPM_HD_INLINE void applyWall(Vec3T<T>& v, int axis, T outwardSign, T mu) {
  const T vn = v[axis] * outwardSign;  // > 0: moving into the wall
  T removed = T(0);
  if (vn > T(0)) {
    removed = vn;
    v[axis] = T(0);
  }
  const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
  if (mu < T(0)) {
    v[a1] = T(0);
    v[a2] = T(0);
    return;
  }
  if (mu == T(0) || removed == T(0)) return;
  const T vt = hdSqrt(v[a1] * v[a1] + v[a2] * v[a2]);
  const T cap = mu * removed;
  if (vt <= cap) {
    v[a1] = T(0);
    v[a2] = T(0);
  } else {
    const T f = T(1) - cap / vt;
    v[a1] *= f;
    v[a2] *= f;
  }
}

// Apply all walls whose layer contains node (i[0], i[1], i[2]) of a grid with `cells` cells
// per axis; friction[6] in wall order -x,+x,-y,+y,-z,+z.
template <typename T>
MPM_HD_INLINE void applyWalls(Vec3T<T>& v, const int i[3], const int cells[3], const T friction[6]) {
  for (int a = 0; a < 3; ++a) {
    if (i[a] <= kWallLayer) applyWall(v, a, T(-1), friction[2 * a]);
    if (i[a] >= cells[a] - kWallLayer) applyWall(v, a, T(1), friction[2 * a + 1]);
  }
}

// The nodes a gate (mpm/Gate.hpp) acts on in one step: the x layers i0..i1 (every j) and,
// in them, the z layers k0..nodes[2]-1. Set on the host each step from the gate's position
// and edge height; empty when i1 < i0 or k0 >= nodes[2].
struct GateBand {
  int i0, i1, k0;
  int nodes[3];
};

MPM_HD_INLINE int gateBandSize(const GateBand& b) {
  if (b.i1 < b.i0 || b.k0 >= b.nodes[2]) return 0;
  return (b.i1 - b.i0 + 1) * b.nodes[1] * (b.nodes[2] - b.k0);
}

// Flat grid index of the t-th node of the band, 0 <= t < gateBandSize(b).
MPM_HD_INLINE int gateBandNode(int t, const GateBand& b) {
  const int nk = b.nodes[2] - b.k0;
  const int k = b.k0 + t % nk;
  const int r = t / nk;
  const int j = r % b.nodes[1];
  const int i = b.i0 + r / b.nodes[1];
  return (i * b.nodes[1] + j) * b.nodes[2] + k;
}

// The record of the node with index `node` in a grid of nz nodes along z stored by node columns
// (GridConst::column, GridView::column; null: the dense layout, the node's index), or -1 where
// its column is not stored (no material point has reached it: its nodes are empty). The step's
// own loops, which reach stored columns only, use nodeRecord (MpmKernelsCommon.hpp).
MPM_HD_INLINE long storedNodeRecord(const int* column, int nz, long node) {
  if (!column) return node;
  const long c = node / nz;
  return column[c] < 0 ? -1 : static_cast<long>(column[c]) * nz + (node - c * nz);
}

// The gate on one node of the band, whose values are element `element` of the grid view's arrays
// (its record times GridView::stride): a wall facing -x (the velocity component into the gate,
// +x, removed; Coulomb friction mu as for the walls). Returns the impulse the gate gives the
// node's material this step, m (v_after - v_before) [N s].
template <typename T>
MPM_HD_INLINE Vec3T<T> applyGateNode(long element, const T* mass, T* vx, T* vy, T* vz, T mu) {
  const Vec3T<T> before{vx[element], vy[element], vz[element]};
  Vec3T<T> v = before;
  applyWall(v, 0, T(1), mu);
  vx[element] = v.x;
  vy[element] = v.y;
  vz[element] = v.z;
  return mass[element] * (v - before);
}

}  // namespace mpm
}  // namespace mpmsdem
