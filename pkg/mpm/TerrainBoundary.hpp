// The terrain as a boundary of the flow (common/Terrain.hpp: the surface): on every grid node at
// or below the surface the velocity into the terrain, along its upward normal, is removed, with
// Coulomb friction on what remains as for the box walls (mpm/GridBoundary.hpp, Appendix A
// corrected); material points carried below the surface are lifted back onto it. The same
// functions run in the CPU loops and the CUDA kernels.
#pragma once
#include "common/MathHD.hpp"
#include "common/Terrain.hpp"

namespace mpmsdem {
namespace mpm {

// The terrain on the new velocity v of a grid node at p [m]: nothing above the surface; at or
// below it the component of v into the terrain (along the upward unit normal n) is removed and
// the tangential part is held by the friction: no-slip, or Coulomb (Eq A.4 with |v_n|): if
// |v_t| <= mu |v_n| then v_t = 0, else v_t -= mu |v_n| v_t / |v_t|. A flat terrain does to a node
// exactly what the -z wall (applyWall) does.
template <typename T>
MPM_HD_INLINE void applyTerrain(Vec3T<T>& v, const Vec3T<T>& p, const TerrainView<T>& t) {
  T gx, gy;
  const T h = terrainHeight(t, p.x, p.y, gx, gy);
  if (p.z > h) return;
  const T s = hdSqrt(T(1) + gx * gx + gy * gy);
  const Vec3T<T> n{-gx / s, -gy / s, T(1) / s};
  T vn = dot(v, n);
  T removed = T(0);
  if (vn < T(0)) {
    removed = -vn;
    vn = T(0);
  }
  const Vec3T<T> along = vn * n;
  Vec3T<T> vt = v - dot(v, n) * n;
  if (t.friction < T(0)) {
    v = along;
    return;
  }
  if (t.friction > T(0) && removed > T(0)) {
    const T st = hdSqrt(dot(vt, vt));
    const T cap = t.friction * removed;
    const T f = st <= cap ? T(0) : T(1) - cap / st;
    vt = f * vt;
  }
  v = along + vt;
}

// A material point carried below the surface is put back onto it (vertically: the height field is
// a function of x and y). x, y, z: its position [m], z changed in place.
template <typename T>
MPM_HD_INLINE void liftAboveTerrain(T x, T y, T& z, const TerrainView<T>& t) {
  T gx, gy;
  const T h = terrainHeight(t, x, y, gx, gy);
  z = z < h ? h : z;
}

}  // namespace mpm
}  // namespace mpmsdem
