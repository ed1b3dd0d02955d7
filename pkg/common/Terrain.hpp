// A terrain: a height field z(x, y) in the grid frame, given on a raster and read between its
// nodes linearly on the two triangles of each raster cell (split along the diagonal from node
// (i+1, j) to node (i, j+1)): continuous heights, a plane per triangle, so that the surface is a
// triangle mesh a contact search can use as it is. Outside the raster the edge heights continue
// flat. The flow (mpm/TerrainBoundary.hpp) and the blocks (sdem/Ig2_SpheroPolyhedron_Terrain.hpp)
// read the same surface through these functions, in CPU loops and CUDA kernels.
//
// The raster's own frame: node (i, j), 0 <= i < nx, 0 <= j < ny, at (x0 + i s, y0 + j s) in the
// grid frame, height z[i * ny + j]. A scene that reads a georeferenced raster places its corner in
// the grid frame (mpmsdem.terrain keeps the georeference for the outputs).
#pragma once
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "common/Error.hpp"
#include "common/MathHD.hpp"

namespace mpmsdem {

// A terrain described on the host: heights z(x, y) in the grid frame on a raster of
// nx x ny nodes, node (i, j) at (x0 + i spacing, y0 + j spacing) with height heights[i * ny + j],
// linear on the two triangles of each raster cell and continued flat outside. The flow cannot enter it (grid nodes at or
// below the surface lose their velocity into it, Coulomb friction on the rest) and points are kept
// on or above it. Use it with gravity along -z (a real slope, not a rotated one). Range checks:
// validate(), which the scene reader, makeSolver and the SDEM engine call.
struct TerrainSpec {
  std::vector<double> heights;  // [m], nx * ny finite values; empty: no terrain (the default)
  int nx = 0, ny = 0;           // raster nodes along x and y, >= 2 each
  double x0 = 0, y0 = 0;        // position of node (0, 0) in the grid frame [m], finite
  double spacing = 0;           // raster spacing [m], > 0 and finite
  double friction = 0;          // flow–terrain friction [-], finite: < 0 no-slip, 0 free slip, > 0 Coulomb
  bool enabled() const { return !heights.empty(); }
  // ParameterError naming "terrain.<field>" for a field out of its range (nothing to check
  // without a terrain).
  void validate() const {
    if (!enabled()) return;
    if (nx < 2) throwParameter("terrain.nx", nx, "", ">= 2 raster nodes along x");
    if (ny < 2) throwParameter("terrain.ny", ny, "", ">= 2 raster nodes along y");
    if (double(nx) * ny > 2147483647.0 || heights.size() != std::size_t(nx) * std::size_t(ny))
      throwParameter("terrain.heights", std::to_string(heights.size()) + " values", "",
                     "nx * ny = " + std::to_string(nx) + " x " + std::to_string(ny) + " values (< 2^31)");
    if (!(spacing > 0) || !std::isfinite(spacing)) throwParameter("terrain.spacing", spacing, "m", "finite and > 0");
    if (!std::isfinite(x0)) throwParameter("terrain.x0", x0, "m", "finite");
    if (!std::isfinite(y0)) throwParameter("terrain.y0", y0, "m", "finite");
    if (!std::isfinite(friction))
      throwParameter("terrain.friction", friction, "", "finite (< 0 no-slip, 0 free slip, > 0 Coulomb)");
    for (std::size_t k = 0; k < heights.size(); ++k)
      if (!std::isfinite(heights[k]))
        throwParameter("terrain.heights[" + std::to_string(k) + "] (node i " + std::to_string(k / ny) + ", j " +
                           std::to_string(k % ny) + ")",
                       heights[k], "m", "finite (fill the raster's no-data nodes first)");
  }
};

template <typename T>
struct TerrainView {
  const T* z = nullptr;  // heights [m], nx * ny; null: no terrain
  int nx = 0, ny = 0;    // raster nodes along x and y (>= 2 each)
  T x0 = T(0), y0 = T(0);  // node (0, 0) [m]
  T invSpacing = T(0);   // 1 / raster spacing [1/m]
  T friction = T(0);     // flow–terrain friction: < 0 no-slip, 0 free slip, > 0 Coulomb
};

// The view of a terrain description (TerrainSpec: nx, ny, x0, y0, spacing, friction) over
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

}  // namespace mpmsdem
