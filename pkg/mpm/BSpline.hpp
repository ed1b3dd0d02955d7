// Quadratic B-spline shape functions of the paper's Eq 2 and their gradients, and the
// 3x3x3 node stencil of one material point. Shared by CPU and CUDA code.
#pragma once
#include "common/MathHD.hpp"

namespace mpmsdem {
namespace mpm {

// Eq 2: w(r) for the distance r between a point and a node in units of dx.
template <typename T>
MPM_HD_INLINE T bsplineWeight(T r) {
  const T a = r < T(0) ? -r : r;
  if (a < T(0.5)) return T(0.75) - a * a;
  if (a < T(1.5)) return T(0.5) * (T(1.5) - a) * (T(1.5) - a);
  return T(0);
}

// dw/dr of Eq 2 (units of 1/dx when r is in units of dx).
template <typename T>
MPM_HD_INLINE T bsplineDerivative(T r) {
  const T a = r < T(0) ? -r : r;
  const T sgn = r < T(0) ? T(-1) : T(1);
  if (a < T(0.5)) return T(-2) * r;
  if (a < T(1.5)) return -sgn * (T(1.5) - a);
  return T(0);
}

// The 27 nodes that carry weight for a point at grid coordinate g = (x - origin)/dx:
// nodes base[d] + k, k = 0..2, with separable weights w[d][k] and derivatives
// dw[d][k] (with respect to the grid coordinate; divide by dx for physical gradients).
template <typename T>
struct Stencil {
  int base[3];
  T w[3][3];
  T dw[3][3];

  MPM_HD_INLINE void compute(const T g[3]) {
    for (int d = 0; d < 3; ++d) {
      const T b = hdFloor(g[d] - T(0.5));
      base[d] = static_cast<int>(b);
      const T f = g[d] - b;  // in [0.5, 1.5): distance to node base
      for (int k = 0; k < 3; ++k) axis(f, k, w[d][k], dw[d][k]);
    }
  }
  // Weight and derivative along one axis of node base + k for a point at distance f from node
  // base: Eq 2 in closed form at distances f, f - 1, f - 2; dw is d/dg of w(g - node).
  MPM_HD_INLINE static void axis(T f, int k, T& wk, T& dwk) {
    if (k == 0) {
      const T a0 = T(1.5) - f;
      wk = T(0.5) * a0 * a0;
      dwk = -a0;
    } else if (k == 1) {
      const T a1 = f - T(1);
      wk = T(0.75) - a1 * a1;
      dwk = T(-2) * a1;
    } else {
      const T a2 = f - T(0.5);
      wk = T(0.5) * a2 * a2;
      dwk = a2;
    }
  }
  // Weight of node (i, j, k) of the stencil.
  MPM_HD_INLINE T weight(int i, int j, int k) const { return w[0][i] * w[1][j] * w[2][k]; }
  // Physical gradient of the weight of node (i, j, k) [1/m].
  MPM_HD_INLINE Vec3T<T> gradient(int i, int j, int k, T invDx) const {
    return {invDx * dw[0][i] * w[1][j] * w[2][k], invDx * w[0][i] * dw[1][j] * w[2][k],
            invDx * w[0][i] * w[1][j] * dw[2][k]};
  }
};

}  // namespace mpm
}  // namespace mpmsdem
