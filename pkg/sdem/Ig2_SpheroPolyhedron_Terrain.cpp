#include "sdem/Ig2_SpheroPolyhedron_Terrain.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "common/Error.hpp"

namespace mpmsdem {
namespace sdem {

namespace {

// The upward unit normal of the terrain triangle (a, b, c).
Vec3 upwardNormal(const Vec3& a, const Vec3& b, const Vec3& c) {
  Vec3 n = (b - a).cross(c - a);
  if (n.z() < 0) n = -n;
  return n.normalized();
}

// The unit direction from the line of edge (a, u) into the triangle with third vertex c.
Vec3 intoTriangle(const Vec3& a, const Vec3& u, const Vec3& c) {
  const Vec3 w = c - a;
  return (w - w.dot(u) * u).normalized();
}

// The raster indices [first, last] whose nodes lie within `reach` of [lo, hi] along one axis
// (first > last: none).
void nodeRange(Real lo, Real hi, Real reach, Real origin, Real spacing, int n, int& first, int& last) {
  const Real a = std::floor((lo - reach - origin) / spacing), b = std::ceil((hi + reach - origin) / spacing);
  first = static_cast<int>(std::clamp(a, Real(0), Real(n)));
  last = static_cast<int>(std::clamp(b, Real(-1), Real(n - 1)));
}

}  // namespace

void Ig2_SpheroPolyhedron_Terrain::setTerrain(const mpmsdem::TerrainSpec& t) {
  if (3.0 * t.nx * t.ny > 2147483647.0)
    throwParameter("terrain.heights", std::to_string(t.nx) + " x " + std::to_string(t.ny) + " nodes", "",
                   "fewer than 2^31 / 3 nodes under blocks (their terrain edges are named in 32 bits)");
  spec_ = t;
  const int nx = t.nx, ny = t.ny;
  Real zmax = 0;
  for (double h : t.heights) zmax = std::max(zmax, std::abs(h));
  const Real tol = 1e-9 * (t.spacing + zmax);
  auto z = [&](int i, int j) { return t.heights[static_cast<std::size_t>(node(i, j))]; };
  convex_.assign(t.heights.size(), 0);
  crest_.assign(t.heights.size(), 0);
  // Edge d at (i, j) is convex when the third vertex of one of its triangles lies below the plane
  // of the other, the lower triangle of cell (i, j) (z00 + fx (z10 - z00) + fy (z01 - z00))
  // extended to it; the raster's border edges have one triangle and are not.
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j) {
      std::uint8_t bits = 0;
      if (i + 1 < nx && j >= 1 && j + 1 < ny && z(i + 1, j - 1) < z(i + 1, j) - z(i, j + 1) + z(i, j) - tol) {
        bits |= 1;  // (i, j)-(i+1, j), against (i+1, j-1) of the upper triangle of cell (i, j-1)
        crest_[node(i, j)] = crest_[node(i + 1, j)] = 1;
      }
      if (j + 1 < ny && i >= 1 && i + 1 < nx && z(i - 1, j + 1) < z(i, j + 1) - z(i + 1, j) + z(i, j) - tol) {
        bits |= 2;  // (i, j)-(i, j+1), against (i-1, j+1) of the upper triangle of cell (i-1, j)
        crest_[node(i, j)] = crest_[node(i, j + 1)] = 1;
      }
      if (i + 1 < nx && j + 1 < ny && z(i + 1, j + 1) < z(i + 1, j) + z(i, j + 1) - z(i, j) - tol) {
        bits |= 4;  // the diagonal (i+1, j)-(i, j+1), against (i+1, j+1) of the upper triangle
        crest_[node(i + 1, j)] = crest_[node(i, j + 1)] = 1;
      }
      convex_[node(i, j)] = bits;
    }
}

Vec3 Ig2_SpheroPolyhedron_Terrain::nodePoint(int i, int j) const {
  return Vec3(spec_.x0 + i * spec_.spacing, spec_.y0 + j * spec_.spacing, spec_.heights[node(i, j)]);
}

void Ig2_SpheroPolyhedron_Terrain::edgePoints(int i, int j, int dir, Vec3& a, Vec3& b, Vec3& c1, Vec3& c2) const {
  if (dir == 0) {
    a = nodePoint(i, j), b = nodePoint(i + 1, j), c1 = nodePoint(i, j + 1), c2 = nodePoint(i + 1, j - 1);
  } else if (dir == 1) {
    a = nodePoint(i, j), b = nodePoint(i, j + 1), c1 = nodePoint(i + 1, j), c2 = nodePoint(i - 1, j + 1);
  } else {
    a = nodePoint(i + 1, j), b = nodePoint(i, j + 1), c1 = nodePoint(i, j), c2 = nodePoint(i + 1, j + 1);
  }
}

template <typename Emit>
void Ig2_SpheroPolyhedron_Terrain::wallContacts(int v, const Vec3& p, const Vec3& under, Real R, Emit& emit) const {
  struct Wall {
    Real d;
    int key;
    Vec3 n;
  };
  std::vector<Wall> found;  // empty, and unallocated, away from walls
  const Real s = spec_.spacing, edge = 1e-9;
  int i0, i1, j0, j1;
  nodeRange(p.x(), p.x(), R, spec_.x0, s, spec_.nx - 1, i0, i1);  // cells: their lower-left nodes
  nodeRange(p.y(), p.y(), R, spec_.y0, s, spec_.ny - 1, j0, j1);
  for (int i = i0; i <= i1; ++i)
    for (int j = j0; j <= j1; ++j)
      for (int t = 0; t < 2; ++t) {
        const Vec3 a = t == 0 ? nodePoint(i, j) : nodePoint(i + 1, j + 1);
        const Vec3 n = upwardNormal(a, nodePoint(i + 1, j), nodePoint(i, j + 1));
        if (n.dot(under) >= wallCosine) continue;  // the surface under the vertex, continued
        const Real d = n.dot(p - a);
        if (!(d > 0) || d >= R) continue;  // behind the triangle's plane: another slope's side
        const Vec3 q = p - d * n;
        const Real fx = (q.x() - spec_.x0) / s - i, fy = (q.y() - spec_.y0) / s - j;
        const bool inside = t == 0 ? fx >= -edge && fy >= -edge && fx + fy <= 1 + edge
                                   : fx <= 1 + edge && fy <= 1 + edge && fx + fy >= 1 - edge;
        if (!inside) continue;
        found.push_back(Wall{d, 2 * node(i, j) + t, n});
      }
  // Nearest first; a wall nearly parallel to one kept is the same slope's next triangle.
  std::sort(found.begin(), found.end(),
            [](const Wall& x, const Wall& y) { return x.d < y.d || (x.d == y.d && x.key < y.key); });
  std::vector<Vec3> kept;
  for (const Wall& w : found) {
    if (std::any_of(kept.begin(), kept.end(), [&](const Vec3& n) { return n.dot(w.n) >= wallCosine; })) continue;
    kept.push_back(w.n);
    emit(FeatureKind::Vertex, v, FeatureKind::Face, w.key, p, p - w.d * w.n, -w.n, w.d);
  }
}

bool Ig2_SpheroPolyhedron_Terrain::go(const PosedSpheroPolyhedron& P, std::vector<SdemGeom>& out,
                                      std::string& what) const {
  const SpheroPolyhedron& S = *P.shape;
  const Real R = S.sweepRadius;
  const Real tol = 1e-9 * std::max(S.boundingRadius, spec_.spacing);
  const std::size_t first = out.size();
  auto emit = [&](FeatureKind ka, int ia, FeatureKind kb, int ib, const Vec3& pa, const Vec3& pb, const Vec3& normal,
                  Real d) {
    for (std::size_t k = first; k < out.size(); ++k)
      if ((out[k].pointA - pa).norm() <= 4 * tol && (out[k].pointB - pb).norm() <= 4 * tol) return;
    out.push_back(SdemGeom::of(ka, ia, kb, ib, pa, pb, normal, d, R, 0));
  };
  auto where = [](const Vec3& p) {
    std::ostringstream os;
    os << "(" << p.x() << ", " << p.y() << ", " << p.z() << ") m";
    return os.str();
  };

  const mpmsdem::TerrainView<Real> view = mpmsdem::terrainViewOf(spec_, spec_.heights.data());  // (a copy's own heights)
  std::vector<char> touching(P.vertices.size(), 0);
  for (std::size_t v = 0; v < P.vertices.size(); ++v) {
    const Vec3& p = P.vertices[v];
    Real gx, gy;
    const Real h = mpmsdem::terrainHeight(view, p.x(), p.y(), gx, gy);
    const Real s = std::sqrt(1 + gx * gx + gy * gy);
    const Real d = (p.z() - h) / s;
    if (!(d > 0)) {
      std::ostringstream os;
      os << "core vertex " << v << " at " << where(p) << " is at or below the terrain (height " << h << " m there)";
      what = os.str();
      return false;
    }
    const Vec3 n(-gx / s, -gy / s, 1 / s);  // the terrain's upward normal
    if (d < R) {
      emit(FeatureKind::Vertex, static_cast<int>(v), FeatureKind::Face, -1, p, p - d * n, -n, d);
      touching[v] = 1;
    }
    wallContacts(static_cast<int>(v), p, n, R, emit);
  }

  int i0, i1, j0, j1;
  nodeRange(P.coreLo.x(), P.coreHi.x(), R, spec_.x0, spec_.spacing, spec_.nx, i0, i1);
  nodeRange(P.coreLo.y(), P.coreHi.y(), R, spec_.y0, spec_.spacing, spec_.ny, j0, j1);
  const Real low = P.coreLo.z() - R;  // terrain below this cannot reach the core
  const Quat toBody = P.ori.conjugate();
  for (int i = i0; i <= i1; ++i)
    for (int j = j0; j <= j1; ++j) {
      if (!crest_[node(i, j)]) continue;
      const Vec3 p = nodePoint(i, j);
      if (p.z() < low) continue;
      const SpheroPolyhedron::PointQuery q = S.closestPoint(toBody * (p - P.pos));
      if (q.distance >= R) continue;
      if (!(q.distance > 0)) {
        what = "terrain crest node (" + std::to_string(i) + ", " + std::to_string(j) + ") at " + where(p) +
               " is in the core";
        return false;
      }
      if (q.featureKind == 2 && touching[q.featureIndex]) continue;  // the vertex's own contact holds it
      const Vec3 pa = P.pos + P.ori * q.closest;
      emit(FeatureKind::Face, -1, FeatureKind::Vertex, node(i, j), pa, p, (p - pa) / q.distance, q.distance);
    }

  // Edges from the nodes one before the range too: they reach into it.
  for (int i = std::max(i0 - 1, 0); i <= i1; ++i)
    for (int j = std::max(j0 - 1, 0); j <= j1; ++j)
      for (int dir = 0; dir < 3; ++dir) {
        if (!((convex_[node(i, j)] >> dir) & 1)) continue;
        Vec3 a, b, c1, c2;
        edgePoints(i, j, dir, a, b, c1, c2);
        if (std::max(a.z(), b.z()) < low) continue;
        const Real L = (b - a).norm();
        const Vec3 u = (b - a) / L;
        const int key = 3 * node(i, j) + dir;
        if (S.convex) {  // a ridge through the core, between its features, stops the run too
          Real t0 = 0, t1 = L;
          for (std::size_t f = 0; f < P.faceNormals.size() && t0 < t1; ++f) {
            const Real s0 = P.faceNormals[f].dot(a) - P.faceOffsets[f], rate = P.faceNormals[f].dot(u);
            if (std::abs(rate) <= 0) {
              if (s0 >= -tol) t1 = t0;
            } else if (rate > 0) {
              t1 = std::min(t1, (-tol - s0) / rate);
            } else {
              t0 = std::max(t0, (-tol - s0) / rate);
            }
          }
          if (t0 < t1) {
            what = "terrain ridge edge " + std::to_string(key) + " from " + where(a) + " to " + where(b) +
                   " passes through the core";
            return false;
          }
        }
        const Vec3 N[2] = {upwardNormal(a, b, c1), upwardNormal(a, b, c2)};
        const Vec3 w[2] = {intoTriangle(a, u, c1), intoTriangle(a, u, c2)};
        for (std::size_t e = 0; e < S.edges.size(); ++e) {
          const CoreEdge& E = S.edges[e];
          if (!E.convex) continue;
          const Vec3& p0 = P.vertices[E.v0];
          const Vec3& ta = P.edgeDir[e];
          const Real La = P.edgeLength[e];
          const Vec3 mid = (p0 + 0.5 * La * ta) - 0.5 * (a + b);
          const Real reach = 0.5 * (La + L) + R;
          if (mid.squaredNorm() >= reach * reach) continue;
          const EdgeSegment core{p0, ta, La}, ridge{a, u, L};
          Vec3 pa, pb;
          // A face at the core edge nearly flat on a triangle at the terrain edge: their crossing
          // seen along the face's normal na (a corner of the contact patch).
          bool patch = false;
          Vec3 na;
          for (int fa : {E.f0, E.f1})
            for (const Vec3& Nk : N)
              if (!patch && P.faceNormals[fa].dot(Nk) <= -Ig2_SpheroPolyhedron_SpheroPolyhedron::patchCosine) {
                patch = true;
                na = P.faceNormals[fa];
              }
          if (patch) {
            // parallel in the patch plane, or no crossing: the ends' pairs carry it
            if (!crossingAlong(core, ridge, na, R, tol, pa, pb)) continue;
            const Vec3 sep = pb - pa;
            if (sep.dot(na) > 0) {
              const Real d = sep.norm();
              if (d < R) emit(FeatureKind::Edge, static_cast<int>(e), FeatureKind::Edge, key, pa, pb, sep / d, d);
              continue;
            }
          }
          if (!closestOfSegments(core, ridge, R, tol, pa, pb)) continue;  // parallel: the ends' pairs carry it
          const Vec3 sep = pb - pa;
          const Real d = sep.norm();
          if (d >= R) continue;
          if (!(d > 0)) {
            what = "terrain ridge edge " + std::to_string(key) + " from " + where(a) + " to " + where(b) +
                   " meets core edge " + std::to_string(e);
            return false;
          }
          if (sep.dot(P.edgeIn0[e]) > tol || sep.dot(P.edgeIn1[e]) > tol) continue;  // the core edge's cone
          if (-sep.dot(w[0]) > tol || -sep.dot(w[1]) > tol) continue;                // the terrain edge's
          emit(FeatureKind::Edge, static_cast<int>(e), FeatureKind::Edge, key, pa, pb, sep / d, d);
        }
      }
  return true;
}

}  // namespace sdem
}  // namespace mpmsdem
