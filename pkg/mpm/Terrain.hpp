// A terrain under the flow: a height field z(x, y) in the grid frame, given on a raster and read
// between its nodes linearly on the two triangles of each raster cell (split along the diagonal
// from node (i+1, j) to node (i, j+1)): continuous heights, a plane per triangle, so that the
// surface is a triangle mesh a contact search can use as it is. It is a boundary of the flow: on every grid node at or below the surface
// the velocity into the terrain, along its upward normal, is removed, with Coulomb friction on
// what remains as for the box walls (mpm/GridBoundary.hpp, Appendix A corrected); material points
// carried below the surface are lifted back onto it. Outside the raster the edge heights continue
// flat. The same functions run in the CPU loops and the CUDA kernels.
//
// The raster's own frame: node (i, j), 0 <= i < nx, 0 <= j < ny, at (x0 + i s, y0 + j s) in the
// grid frame, height z[i * ny + j]. A scene that reads a georeferenced raster places its corner in
// the grid frame (mpmsdem.terrain keeps the georeference for the outputs).
#pragma once
#include "mpm/MathHD.hpp"

namespace mpmsdem {
namespace mpm {

template <typename T>
struct TerrainView {
  const T* z = nullptr;  // heights [m], nx * ny; null: no terrain
  int nx = 0, ny = 0;    // raster nodes along x and y (>= 2 each)
  T x0 = T(0), y0 = T(0);  // node (0, 0) [m]
  T invSpacing = T(0);   // 1 / raster spacing [1/m]
  T friction = T(0);     // flow–terrain friction: < 0 no-slip, 0 free slip, > 0 Coulomb
};

// The view of a terrain description (mpm::TerrainSpec: nx, ny, x0, y0, spacing, friction) over
// heights z in the backend's memory (null: set later). Host set-up.
template <typename T, typename Spec>
inline TerrainView<T> terrainViewOf(const Spec& s, const T* z) {
  TerrainView<T> v;
  v.z = z;
  v.nx = s.nx;
  v.ny = s.ny;
  v.x0 = static_cast<T>(s.x0);
  v.y0 = static_cast<T>(s.y0);
  v.invSpacing = static_cast<T>(1.0 / s.spacing);
  v.friction = static_cast<T>(s.friction);
  return v;
}

// One raster coordinate: the cell c (0 <= c <= n - 2) and the fraction f in [0, 1] within it of
// u (in raster spacings from node 0); inside reports whether u lies on the raster (the gradient
// along this axis is zero outside, where the edge heights continue flat).
template <typename T>
MPM_HD_INLINE void terrainAxis(T u, int n, int& c, T& f, bool& inside) {
  const T top = T(n - 1);
  inside = u >= T(0) && u <= top;
  const T uc = u < T(0) ? T(0) : (u > top ? top : u);
  c = static_cast<int>(uc);
  if (c > n - 2) c = n - 2;
  f = uc - T(c);
}

// Height of the surface at (x, y) [m] and its slopes dz/dx, dz/dy (those of the triangle the
// point is over; the lower one, fx + fy <= 1, on the diagonal).
template <typename T>
MPM_HD_INLINE T terrainHeight(const TerrainView<T>& t, T x, T y, T& dzdx, T& dzdy) {
  int i, j;
  T fx, fy;
  bool inX, inY;
  terrainAxis((x - t.x0) * t.invSpacing, t.nx, i, fx, inX);
  terrainAxis((y - t.y0) * t.invSpacing, t.ny, j, fy, inY);
  const T* r0 = t.z + i * t.ny + j;
  const T* r1 = r0 + t.ny;
  const T z00 = r0[0], z01 = r0[1], z10 = r1[0], z11 = r1[1];
  T h, sx, sy;
  if (fx + fy <= T(1)) {  // the triangle (i, j), (i+1, j), (i, j+1)
    sx = z10 - z00;
    sy = z01 - z00;
    h = z00 + fx * sx + fy * sy;
  } else {  // the triangle (i+1, j+1), (i, j+1), (i+1, j)
    sx = z11 - z01;
    sy = z11 - z10;
    h = z11 - (T(1) - fx) * sx - (T(1) - fy) * sy;
  }
  dzdx = inX ? sx * t.invSpacing : T(0);
  dzdy = inY ? sy * t.invSpacing : T(0);
  return h;
}

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
