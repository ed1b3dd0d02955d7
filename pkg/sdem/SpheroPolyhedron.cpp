// SpheroPolyhedron factories, body frame, point queries (see SpheroPolyhedron.hpp).
// CGAL (convex hull, linear program) is used in this file only, and only by the factories that
// take points or a convex mesh: a build without CGAL (MPMSDEM_WITH_CGAL unset: the driver-only
// build for machines without it) keeps box, fromCore and non-convex meshes.
#include "sdem/SpheroPolyhedron.hpp"

#ifdef MPMSDEM_WITH_CGAL
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Gmpzf.h>
#include <CGAL/QP_functions.h>
#include <CGAL/QP_models.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>
#endif

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "common/Error.hpp"
#include "input/MeshReader.hpp"
#include "sdem/MassProperties.hpp"

namespace mpmsdem {
namespace sdem {
namespace {

constexpr Real kPi = 3.14159265358979323846;
// Two face normals closer than this (1 - cos of the angle) are one plane (~1.4e-5 rad).
constexpr Real kCoplanarCos = 1e-10;
// Points closer than this fraction of the shape size are merged / counted as coplanar.
constexpr Real kRelTol = 1e-9;

std::string num(Real x) {
  std::ostringstream os;
  os.precision(10);
  os << x;
  return os.str();
}

void checkRadiusPositive(Real R) {
  if (!(R > 0) || !std::isfinite(R))
    throwParameter("sweepRadius", R, "m", "finite and > 0 (and below half the thinnest dimension of the shape)");
}

Real shapeSize(const std::vector<Vec3>& pts) {
  Vec3 lo = pts[0], hi = pts[0];
  for (const Vec3& p : pts) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return (hi - lo).norm();
}

// Edges between non-coplanar faces, per-face side -> edge map, vertex -> edges.
void buildTopology(SpheroPolyhedron& s) {
  s.edges.clear();
  s.faceEdges.assign(s.faces.size(), {});
  s.vertexEdges.assign(s.vertices.size(), {});
  std::map<std::pair<int, int>, std::pair<int, int>> side;  // directed (a,b) -> (face, loop position)
  for (size_t f = 0; f < s.faces.size(); ++f) {
    const auto& loop = s.faces[f].loop;
    s.faceEdges[f].assign(loop.size(), -1);
    for (size_t i = 0; i < loop.size(); ++i)
      side[{loop[i], loop[(i + 1) % loop.size()]}] = {static_cast<int>(f), static_cast<int>(i)};
  }
  for (const auto& kv : side) {
    const int a = kv.first.first, b = kv.first.second;
    if (a > b) continue;
    const auto twin = side.find({b, a});
    if (twin == side.end()) throw RuntimeFailure("SpheroPolyhedron: core surface is not closed");
    const int f0 = kv.second.first, f1 = twin->second.first;
    const Vec3& n0 = s.faces[f0].normal;
    const Vec3& n1 = s.faces[f1].normal;
    if (1.0 - n0.dot(n1) < kCoplanarCos) continue;  // flat diagonal
    CoreEdge e{a, b, f0, f1, n0.cross(n1).dot(s.vertices[b] - s.vertices[a]) > 0};
    const int id = static_cast<int>(s.edges.size());
    s.edges.push_back(e);
    s.faceEdges[f0][kv.second.second] = id;
    s.faceEdges[f1][twin->second.second] = id;
    s.vertexEdges[a].push_back(id);
    s.vertexEdges[b].push_back(id);
  }
}

// Topology, mass properties, body frame (centroid + principal axes), bounding radius.
void finalize(SpheroPolyhedron& s) {
  buildTopology(s);
  // Integrate about the vertex mean (avoids cancellation when the input is far off-centre).
  Vec3 ref = Vec3::Zero();
  for (const Vec3& v : s.vertices) ref += v / static_cast<Real>(s.vertices.size());
  for (Vec3& v : s.vertices) v -= ref;
  for (Vec3& v : s.outerVertices) v -= ref;
  for (CoreFace& f : s.faces) f.offset -= f.normal.dot(ref);
  const Moments m = roundedBodyMoments(s);
  const Vec3 c = m.m1 / m.m0;
  const Mat3 I = inertiaAbout(m, c);
  Mat3 Q = Mat3::Identity();
  const Real off = std::max({std::abs(I(0, 1)), std::abs(I(0, 2)), std::abs(I(1, 2))});
  if (off > 1e-12 * I.trace()) {
    Eigen::SelfAdjointEigenSolver<Mat3> eig(I);
    Q = eig.eigenvectors();
    for (int k = 0; k < 2; ++k) {  // sign convention: largest component of axes 0 and 1 positive
      Eigen::Index big;
      Q.col(k).cwiseAbs().maxCoeff(&big);
      if (Q(big, k) < 0) Q.col(k) *= -1;
    }
    Q.col(2) = Q.col(0).cross(Q.col(1));  // right-handed
  }
  for (Vec3& v : s.vertices) v = Q.transpose() * (v - c);
  for (Vec3& v : s.outerVertices) v = Q.transpose() * (v - c);
  for (CoreFace& f : s.faces) {
    f.offset -= f.normal.dot(c);
    f.normal = Q.transpose() * f.normal;
  }
  s.volume = m.m0;
  s.inertiaPerDensity = (Q.transpose() * I * Q).diagonal();
  s.framePosition = ref + c;
  s.frameOrientation = Quat(Q).normalized();
  Real rmax = 0;
  for (const Vec3& v : s.vertices) rmax = std::max(rmax, v.norm());
  s.boundingRadius = rmax + s.sweepRadius;
}

#ifdef MPMSDEM_WITH_CGAL
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using CgalPoint = Kernel::Point_3;
using CgalMesh = CGAL::Surface_mesh<CgalPoint>;

// Faces (convex polygons) of the convex hull of pts, coplanar hull triangles merged.
// Holds the hull vertices and triangles, and the merged polygon loops (indices into
// vertices, counter-clockwise from outside) with their planes.
//
// The result is canonical: it depends on the set of points only, not on their order nor on
// how CGAL's hull happens to number its vertices and triangulate planar faces (its quickhull
// keys maps by handle addresses, so two runs on the same points can number the hull
// differently). Vertices are the loop corners in lexicographic order of (x, y, z), each loop
// starts at its smallest index, loops are sorted, and planes and triangles are derived from
// the loops alone. Shapes built from the same points are then bit-identical, so runs repeat.
struct Hull {
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> triangles;  // fan of each loop from its first corner
  std::vector<std::vector<int>> loops;
  std::vector<Vec3> normals;
  std::vector<Real> offsets;
};

void requireSolid(const std::vector<Vec3>& pts) {
  if (pts.size() < 4)
    throwParameter("points", std::to_string(pts.size()) + " points", "", "at least 4 points, not all coplanar");
  for (const Vec3& p : pts)
    if (!p.allFinite()) throwParameter("points", "a non-finite coordinate", "", "finite coordinates");
  const Real tol = kRelTol * shapeSize(pts);
  size_t i1 = 0, i2 = 0;
  Real best = 0;
  for (size_t i = 0; i < pts.size(); ++i)
    if ((pts[i] - pts[0]).norm() > best) best = (pts[i] - pts[0]).norm(), i1 = i;
  const Vec3 u = (pts[i1] - pts[0]).normalized();
  best = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    const Real d = (pts[i] - pts[0]).cross(u).norm();
    if (d > best) best = d, i2 = i;
  }
  const Vec3 n = u.cross(pts[i2] - pts[0]).normalized();
  Real height = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    const Real d = std::abs((pts[i] - pts[0]).dot(n));
    height = std::max(height, d);
  }
  if (!(height > tol) || !(best > tol))
    throwParameter("points", "a degenerate set (all points collinear or coplanar)", "",
                   "at least 4 points, not all coplanar");
}

bool lexLess(const Vec3& a, const Vec3& b) {
  if (a.x() != b.x()) return a.x() < b.x();
  if (a.y() != b.y()) return a.y() < b.y();
  return a.z() < b.z();
}

Hull convexHullFaces(const std::vector<Vec3>& pts) {
  std::vector<CgalPoint> cp;
  cp.reserve(pts.size());
  for (const Vec3& p : pts) cp.emplace_back(p.x(), p.y(), p.z());
  CgalMesh sm;
  CGAL::convex_hull_3(cp.begin(), cp.end(), sm);
  // Hull vertices renumbered in lexicographic order, triangles rotated to start at their
  // smallest index and sorted: the grouping below then visits them in a canonical order.
  std::vector<Vec3> hv;
  std::map<CgalMesh::Vertex_index, int> cgalId;
  for (auto v : sm.vertices()) {
    cgalId[v] = static_cast<int>(hv.size());
    const CgalPoint& p = sm.point(v);
    hv.emplace_back(p.x(), p.y(), p.z());
  }
  std::vector<int> order(hv.size()), rank(hv.size());
  for (size_t i = 0; i < hv.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return lexLess(hv[a], hv[b]); });
  std::vector<Vec3> verts(hv.size());
  for (size_t i = 0; i < order.size(); ++i) {
    rank[order[i]] = static_cast<int>(i);
    verts[i] = hv[order[i]];
  }
  std::vector<std::array<int, 3>> tris;
  for (auto f : sm.faces()) {
    std::array<int, 3> t{};
    int k = 0;
    for (auto v : CGAL::vertices_around_face(sm.halfedge(f), sm)) t[k++] = rank[cgalId[v]];
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    tris.push_back(t);
  }
  std::sort(tris.begin(), tris.end());
  const Real tol = kRelTol * shapeSize(verts);
  // Flood-fill groups of edge-adjacent triangles lying in one plane.
  std::map<std::pair<int, int>, int> triOfSide;
  for (size_t t = 0; t < tris.size(); ++t)
    for (int k = 0; k < 3; ++k) triOfSide[{tris[t][k], tris[t][(k + 1) % 3]}] = static_cast<int>(t);
  std::vector<int> group(tris.size(), -1);
  auto triNormal = [&](int t) {
    const auto& T = tris[t];
    return Vec3((verts[T[1]] - verts[T[0]]).cross(verts[T[2]] - verts[T[0]]));
  };
  std::vector<std::vector<int>> loops;
  for (size_t seed = 0; seed < tris.size(); ++seed) {
    if (group[seed] >= 0) continue;
    const int g = static_cast<int>(loops.size());
    const Vec3 n = triNormal(static_cast<int>(seed)).normalized();
    const Real d = n.dot(verts[tris[seed][0]]);
    std::vector<int> stack{static_cast<int>(seed)}, members;
    group[seed] = g;
    while (!stack.empty()) {
      const int t = stack.back();
      stack.pop_back();
      members.push_back(t);
      for (int k = 0; k < 3; ++k) {
        const auto it = triOfSide.find({tris[t][(k + 1) % 3], tris[t][k]});
        if (it == triOfSide.end() || group[it->second] >= 0) continue;
        bool inPlane = true;
        for (int c = 0; c < 3; ++c) inPlane = inPlane && std::abs(n.dot(verts[tris[it->second][c]]) - d) < tol;
        if (inPlane) {
          group[it->second] = g;
          stack.push_back(it->second);
        }
      }
    }
    // Boundary of the group: sides whose twin is outside the group, chained into a loop.
    std::map<int, int> next;
    for (int t : members)
      for (int k = 0; k < 3; ++k) {
        const int a = tris[t][k], b = tris[t][(k + 1) % 3];
        if (group[triOfSide.at({b, a})] != g) next[a] = b;
      }
    std::vector<int> loop{next.begin()->first};
    while (true) {
      const int nx = next.at(loop.back());
      if (nx == loop.front()) break;
      loop.push_back(nx);
    }
    // Drop corners where the boundary goes straight on (points inside a hull edge).
    std::vector<int> clean;
    for (size_t i = 0; i < loop.size(); ++i) {
      const Vec3& pr = verts[loop[(i + loop.size() - 1) % loop.size()]];
      const Vec3& p = verts[loop[i]];
      const Vec3& nx = verts[loop[(i + 1) % loop.size()]];
      if ((p - pr).normalized().cross((nx - p).normalized()).norm() > 1e-9) clean.push_back(loop[i]);
    }
    std::rotate(clean.begin(), std::min_element(clean.begin(), clean.end()), clean.end());
    loops.push_back(clean);
  }
  std::sort(loops.begin(), loops.end());
  // Keep the loop corners only (a hull vertex inside a face or an edge is no corner),
  // renumbered in the same (lexicographic) order.
  std::vector<int> keep(verts.size(), -1);
  for (const auto& loop : loops)
    for (int v : loop) keep[v] = 0;
  Hull h;
  for (size_t v = 0; v < verts.size(); ++v)
    if (keep[v] == 0) {
      keep[v] = static_cast<int>(h.vertices.size());
      h.vertices.push_back(verts[v]);
    }
  for (auto& loop : loops) {
    for (int& v : loop) v = keep[v];
    Vec3 areaNormal = Vec3::Zero();
    for (size_t i = 1; i + 1 < loop.size(); ++i) {
      const Vec3& o = h.vertices[loop[0]];
      areaNormal += (h.vertices[loop[i]] - o).cross(h.vertices[loop[i + 1]] - o);
      h.triangles.push_back({loop[0], loop[i], loop[i + 1]});
    }
    const Vec3 fn = areaNormal.normalized();
    Real off = 0;
    for (int v : loop) off += fn.dot(h.vertices[v]);
    h.normals.push_back(fn);
    h.offsets.push_back(off / loop.size());
  }
  h.loops = std::move(loops);
  return h;
}

// Core faces from a hull (its vertices are all loop corners).
void coreFromHull(SpheroPolyhedron& s, const Hull& h) {
  s.vertices = h.vertices;
  s.faces.clear();
  for (size_t f = 0; f < h.loops.size(); ++f) {
    CoreFace face;
    face.loop = h.loops[f];
    face.normal = h.normals[f];
    face.offset = h.offsets[f];
    s.faces.push_back(face);
  }
}

// Largest ball inside {x : n_i.x <= d_i} (linear program, exact arithmetic): centre, radius.
std::pair<Vec3, Real> chebyshevCentre(const std::vector<Vec3>& n, const std::vector<Real>& d) {
  CGAL::Quadratic_program<double> lp(CGAL::SMALLER, false, 0, false, 0);
  for (int j = 0; j < 3; ++j) lp.set_l(j, false);
  lp.set_l(3, true, 0.0);
  for (size_t i = 0; i < n.size(); ++i) {
    for (int j = 0; j < 3; ++j) lp.set_a(j, static_cast<int>(i), n[i][j]);
    lp.set_a(3, static_cast<int>(i), 1.0);
    lp.set_b(static_cast<int>(i), d[i]);
  }
  lp.set_c(3, -1.0);
  const auto sol = CGAL::solve_linear_program(lp, CGAL::Gmpzf());
  if (!sol.is_optimal()) throw RuntimeFailure("SpheroPolyhedron: inradius linear program failed");
  Vec3 x;
  Real r = 0;
  int j = 0;
  for (auto it = sol.variable_values_begin(); it != sol.variable_values_end(); ++it, ++j) {
    const Real val = CGAL::to_double(*it);
    if (j < 3) x[j] = val; else r = val;
  }
  return {x, r};
}

std::shared_ptr<SpheroPolyhedron> convexFromPoints(const std::vector<Vec3>& points, Real R, const char* what) {
  requireSolid(points);
  checkRadiusPositive(R);
  const Hull outer = convexHullFaces(points);
  // Thickness limits: min width over face normals, and the inradius (the core is empty beyond it).
  Real minWidth = std::numeric_limits<Real>::infinity();
  for (size_t f = 0; f < outer.normals.size(); ++f) {
    Real lo = std::numeric_limits<Real>::infinity();
    for (const Vec3& v : outer.vertices) lo = std::min(lo, outer.normals[f].dot(v));
    minWidth = std::min(minWidth, outer.offsets[f] - lo);
  }
  const auto [centre, inradius] = chebyshevCentre(outer.normals, outer.offsets);
  const Real limit = std::min(0.5 * minWidth, inradius);
  if (R >= limit * (1 - 1e-9))
    throwParameter("sweepRadius", R, "m",
                   std::string("in (0, ") + num(limit) + ") m so that the " + what +
                       " shrunk by R keeps a volume (limit = min(inradius " + num(inradius) +
                       " m, half the min width over face normals " + num(0.5 * minWidth) + " m))");
  // Core = intersection of the half-spaces n.x <= d - R, by polar duality about the Chebyshev
  // centre x0 (strictly inside, margin inradius - R): each facet {m.y = h} of the hull of the
  // dual points n/(d - R - n.x0) is a core vertex x0 + m/h.
  std::vector<Vec3> dual;
  for (size_t f = 0; f < outer.normals.size(); ++f)
    dual.push_back(outer.normals[f] / (outer.offsets[f] - R - outer.normals[f].dot(centre)));
  const Hull dualHull = convexHullFaces(dual);
  // Facets of the dual hull are already merged when coplanar (a vertex where more than three
  // planes meet); nearly coincident results are merged again below, then re-hulled.
  const Real tol = kRelTol * shapeSize(outer.vertices);
  std::vector<Vec3> corePts;
  for (size_t f = 0; f < dualHull.normals.size(); ++f) {
    const Vec3 q = centre + dualHull.normals[f] / dualHull.offsets[f];
    bool dup = false;
    for (const Vec3& e : corePts) dup = dup || (e - q).norm() < tol;
    if (!dup) corePts.push_back(q);
  }
  auto s = std::make_shared<SpheroPolyhedron>();
  s->sweepRadius = R;
  s->convex = true;
  coreFromHull(*s, convexHullFaces(corePts));
  // Polish to round-off: each core face takes the shifted outer plane it comes from, each core
  // vertex becomes the least-squares intersection of the planes of its faces. A vertex whose
  // planes are nearly dependent (it would move by more than the merge tolerance) keeps its
  // position from the dual construction.
  for (CoreFace& f : s->faces) {
    size_t best = 0;
    for (size_t g = 1; g < outer.normals.size(); ++g)
      if (outer.normals[g].dot(f.normal) > outer.normals[best].dot(f.normal)) best = g;
    if (1 - outer.normals[best].dot(f.normal) > kCoplanarCos) continue;
    f.normal = outer.normals[best];
    f.offset = outer.offsets[best] - R;
  }
  std::vector<Mat3> A(s->vertices.size(), Mat3::Zero());
  std::vector<Vec3> b(s->vertices.size(), Vec3::Zero());
  for (const CoreFace& f : s->faces)
    for (int v : f.loop) {
      A[v] += f.normal * f.normal.transpose();
      b[v] += f.offset * f.normal;
    }
  for (size_t v = 0; v < s->vertices.size(); ++v) {
    const Vec3 x = s->vertices[v] + A[v].ldlt().solve(b[v] - A[v] * s->vertices[v]);
    if ((x - s->vertices[v]).norm() < tol) s->vertices[v] = x;
  }
  s->outerVertices = outer.vertices;
  s->outerTriangles = outer.triangles;
  finalize(*s);
  return s;
}

#else
// Without CGAL there is no hull: convex shapes come as core tables (SpheroPolyhedron::fromCore),
// which a build with CGAL writes (the driver's scene files).
std::shared_ptr<SpheroPolyhedron> convexFromPoints(const std::vector<Vec3>&, Real, const char* what) {
  throw ParameterError(std::string(what) + ": this build has no CGAL (a driver-only build), which convex hulls and "
                       "convex meshes need: give the block as a core table (\"core\" in a scene file; "
                       "mpmsdem.driver.writeScene writes them from a YADE script), or use a box");
}
#endif  // MPMSDEM_WITH_CGAL

// Signed distance along -n from point c to the first triangle of the mesh hit by the ray.
Real rayThickness(const Vec3& c, const Vec3& dir, const std::vector<Vec3>& V,
                  const std::vector<std::array<int, 3>>& T, size_t skip) {
  Real best = std::numeric_limits<Real>::infinity();
  for (size_t t = 0; t < T.size(); ++t) {
    if (t == skip) continue;
    const Vec3 &a = V[T[t][0]], &b = V[T[t][1]], &cc = V[T[t][2]];
    const Vec3 e1 = b - a, e2 = cc - a;
    const Vec3 p = dir.cross(e2);
    const Real det = e1.dot(p);
    if (std::abs(det) < 1e-300) continue;
    const Vec3 s = c - a;
    const Real u = s.dot(p) / det;
    if (u < 0 || u > 1) continue;
    const Vec3 q = s.cross(e1);
    const Real v = dir.dot(q) / det;
    if (v < 0 || u + v > 1) continue;
    const Real dist = e2.dot(q) / det;
    if (dist > 0) best = std::min(best, dist);
  }
  return best;
}

}  // namespace

std::shared_ptr<SpheroPolyhedron> SpheroPolyhedron::box(const Vec3& halfExtents, Real R) {
  if (!halfExtents.allFinite() || !(halfExtents.minCoeff() > 0))
    throwParameter("halfExtents", halfExtents.transpose(), "m", "three finite values > 0");
  checkRadiusPositive(R);
  if (R >= halfExtents.minCoeff())
    throwParameter("sweepRadius", R, "m",
                   "in (0, " + num(halfExtents.minCoeff()) + ") m: below half the thinnest dimension of the box");
  auto s = std::make_shared<SpheroPolyhedron>();
  s->sweepRadius = R;
  s->convex = true;
  const Vec3 c = halfExtents - Vec3::Constant(R);
  // Vertex i has coordinate k positive when bit k of i is set.
  for (int i = 0; i < 8; ++i) {
    s->vertices.emplace_back((i & 1 ? 1 : -1) * c.x(), (i & 2 ? 1 : -1) * c.y(), (i & 4 ? 1 : -1) * c.z());
    s->outerVertices.emplace_back((i & 1 ? 1 : -1) * halfExtents.x(), (i & 2 ? 1 : -1) * halfExtents.y(),
                                  (i & 4 ? 1 : -1) * halfExtents.z());
  }
  const int loops[6][4] = {{1, 3, 7, 5}, {0, 4, 6, 2}, {2, 6, 7, 3}, {0, 1, 5, 4}, {4, 5, 7, 6}, {0, 2, 3, 1}};
  for (int f = 0; f < 6; ++f) {
    const int axis = f / 2;
    const Real sign = (f % 2 == 0) ? 1.0 : -1.0;
    CoreFace face;
    face.loop.assign(loops[f], loops[f] + 4);
    face.normal = Vec3::Zero();
    face.normal[axis] = sign;
    face.offset = c[axis];
    s->faces.push_back(face);
    s->outerTriangles.push_back({loops[f][0], loops[f][1], loops[f][2]});
    s->outerTriangles.push_back({loops[f][0], loops[f][2], loops[f][3]});
  }
  finalize(*s);
  return s;
}

std::shared_ptr<SpheroPolyhedron> SpheroPolyhedron::fromCore(const std::vector<Vec3>& vertices,
                                                             const std::vector<std::vector<int>>& faces, Real R,
                                                             bool convex, const std::vector<Vec3>& outerVertices,
                                                             const std::vector<std::array<int, 3>>& outerTriangles) {
  checkRadiusPositive(R);
  const int nv = static_cast<int>(vertices.size());
  if (nv < 4) throwParameter("core.vertices", std::to_string(nv) + " vertices", "", "at least 4");
  if (faces.size() < 4) throwParameter("core.faces", std::to_string(faces.size()) + " faces", "", "at least 4");
  for (const Vec3& v : vertices)
    if (!v.allFinite()) throwParameter("core.vertices", "a non-finite coordinate", "", "finite coordinates");
  const Real tol = kRelTol * shapeSize(vertices);
  auto s = std::make_shared<SpheroPolyhedron>();
  s->sweepRadius = R;
  s->convex = convex;
  s->vertices = vertices;
  std::map<std::pair<int, int>, int> sideFace;
  Real volume6 = 0;
  for (size_t f = 0; f < faces.size(); ++f) {
    const std::vector<int>& loop = faces[f];
    const std::string name = "core.faces[" + std::to_string(f) + "]";
    if (loop.size() < 3) throwParameter(name, std::to_string(loop.size()) + " corners", "", "at least 3");
    for (int v : loop)
      if (v < 0 || v >= nv) throwParameter(name, "vertex index " + std::to_string(v), "", "in [0, " + std::to_string(nv) + ")");
    // Newell's normal: exact for planar loops, and defined for any corner order.
    Vec3 area = Vec3::Zero();
    for (size_t i = 0; i < loop.size(); ++i) area += vertices[loop[i]].cross(vertices[loop[(i + 1) % loop.size()]]);
    if (!(area.norm() > tol * tol)) throwParameter(name, "a face of zero area", "", "faces of non-zero area");
    CoreFace face;
    face.loop = loop;
    face.normal = area.normalized();
    face.offset = 0;
    for (int v : loop) face.offset += face.normal.dot(vertices[v]) / static_cast<Real>(loop.size());
    for (int v : loop)
      if (std::abs(face.normal.dot(vertices[v]) - face.offset) > tol)
        throwParameter(name, "corner " + std::to_string(v) + " off the face's plane by " +
                                 num(std::abs(face.normal.dot(vertices[v]) - face.offset)) + " m",
                       "", "planar faces");
    for (size_t i = 0; i < loop.size(); ++i) {
      const int a = loop[i], b = loop[(i + 1) % loop.size()];
      if (!sideFace.emplace(std::make_pair(a, b), static_cast<int>(f)).second)
        throwParameter(name, "side (" + std::to_string(a) + ", " + std::to_string(b) + ")", "",
                       "each side in two faces, traversed in opposite directions (consistent orientation)");
      if (i >= 1 && i + 1 < loop.size())  // fan triangle (0, i, i+1): signed volume x 6
        volume6 += vertices[loop[0]].dot(vertices[loop[i]].cross(vertices[loop[i + 1]]));
    }
    s->faces.push_back(face);
  }
  for (const auto& kv : sideFace)
    if (!sideFace.count({kv.first.second, kv.first.first}))
      throwParameter("core.faces", "side (" + std::to_string(kv.first.first) + ", " + std::to_string(kv.first.second) +
                                       ") in one face only", "", "a closed surface");
  if (!(volume6 > 0))
    throwParameter("core.faces", "enclosed volume " + num(volume6 / 6) + " m^3", "",
                   "positive: loops counter-clockwise seen from outside");
  if (convex)
    for (size_t f = 0; f < s->faces.size(); ++f)
      for (int v = 0; v < nv; ++v)
        if (s->faces[f].normal.dot(vertices[v]) > s->faces[f].offset + tol)
          throwParameter("core.convex", "true", "",
                         "false for this core: vertex " + std::to_string(v) + " lies outside the plane of face " +
                             std::to_string(f));
  if (outerVertices.empty() != outerTriangles.empty())
    throwParameter("outer", "vertices without triangles or triangles without vertices", "", "both or neither");
  if (!outerVertices.empty()) {
    for (const auto& t : outerTriangles)
      for (int v : t)
        if (v < 0 || v >= static_cast<int>(outerVertices.size()))
          throwParameter("outer.triangles", "vertex index " + std::to_string(v), "",
                         "in [0, " + std::to_string(outerVertices.size()) + ")");
    s->outerVertices = outerVertices;
    s->outerTriangles = outerTriangles;
  } else {
    s->outerVertices = vertices;
    for (const CoreFace& f : s->faces)
      for (size_t i = 1; i + 1 < f.loop.size(); ++i) s->outerTriangles.push_back({f.loop[0], f.loop[i], f.loop[i + 1]});
  }
  finalize(*s);
  return s;
}

std::shared_ptr<SpheroPolyhedron> SpheroPolyhedron::convexHull(const std::vector<Vec3>& points, Real R) {
  return convexFromPoints(points, R, "convex hull");
}

std::shared_ptr<SpheroPolyhedron> SpheroPolyhedron::mesh(const std::vector<Vec3>& inputVerts,
                                                         const std::vector<std::array<int, 3>>& inputTris, Real R) {
  checkRadiusPositive(R);
  if (inputTris.size() < 4)
    throwParameter("mesh", std::to_string(inputTris.size()) + " triangles", "", "a closed mesh of at least 4 triangles");
  for (size_t t = 0; t < inputTris.size(); ++t)
    for (int k = 0; k < 3; ++k)
      if (inputTris[t][k] < 0 || inputTris[t][k] >= static_cast<int>(inputVerts.size()))
        throwParameter("mesh", "triangle " + std::to_string(t) + " vertex index " + std::to_string(inputTris[t][k]), "",
                       "indices in [0, " + std::to_string(inputVerts.size()) + ")");
  // Drop vertices no triangle uses (they would enlarge the bounds); keep the input order.
  std::vector<int> remap(inputVerts.size(), -1), orig;  // input -> kept index, and back
  std::vector<Vec3> verts;
  std::vector<std::array<int, 3>> tris = inputTris;
  for (auto& t : tris)
    for (int& v : t) {
      if (remap[v] < 0) {
        remap[v] = static_cast<int>(verts.size());
        verts.push_back(inputVerts[v]);
        orig.push_back(v);
      }
      v = remap[v];
    }
  for (const Vec3& v : verts)
    if (!v.allFinite()) throwParameter("mesh", "a non-finite vertex coordinate", "", "finite coordinates");
  const Real size = shapeSize(verts);
  std::vector<Vec3> triN(tris.size());
  for (size_t t = 0; t < tris.size(); ++t) {
    const Vec3 a = verts[tris[t][1]] - verts[tris[t][0]], b = verts[tris[t][2]] - verts[tris[t][0]];
    const Vec3 n = a.cross(b);
    if (!(n.norm() > kRelTol * size * size))
      throwParameter("mesh", "triangle " + std::to_string(t) + " with zero area", "", "triangles of non-zero area");
    triN[t] = n.normalized();
  }
  // Closedness and orientation: each directed side once, each undirected edge in two triangles.
  std::map<std::pair<int, int>, int> sideTri;
  std::map<std::pair<int, int>, int> useCount;
  for (size_t t = 0; t < tris.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = tris[t][k], b = tris[t][(k + 1) % 3];
      ++useCount[{std::min(a, b), std::max(a, b)}];
      if (!sideTri.emplace(std::make_pair(a, b), static_cast<int>(t)).second)
        throwParameter("mesh", "edge (" + std::to_string(orig[a]) + ", " + std::to_string(orig[b]) + ")", "",
                       "shared by exactly two consistently oriented triangles (it is traversed twice in the same "
                       "direction: non-manifold or inconsistent orientation)");
    }
  for (const auto& kv : useCount)
    if (kv.second != 2)
      throwParameter("mesh", "edge (" + std::to_string(orig[kv.first.first]) + ", " + std::to_string(orig[kv.first.second]) + ")",
                     "", "shared by exactly two triangles (it is used by " + std::to_string(kv.second) +
                             (kv.second == 1 ? ": the mesh is open)" : ": non-manifold)"));
  // One body is one closed surface: several parts would otherwise pass every check above and
  // be replaced by the convex hull of them all (convex path) or give one rigid body made of
  // separate pieces. Parts are counted through shared vertices.
  {
    std::vector<int> parent(verts.size());
    for (size_t v = 0; v < verts.size(); ++v) parent[v] = static_cast<int>(v);
    auto root = [&](int v) {
      while (parent[v] != v) v = parent[v] = parent[parent[v]];
      return v;
    };
    for (const auto& t : tris)
      for (int k = 1; k < 3; ++k) parent[root(t[k])] = root(t[0]);
    size_t parts = 0;
    for (size_t v = 0; v < verts.size(); ++v) parts += root(static_cast<int>(v)) == static_cast<int>(v) ? 1 : 0;
    if (parts > 1)
      throwParameter("mesh", std::to_string(parts) + " disconnected components", "",
                     "one closed surface (split it into one body per part)");
  }
  Real vol = 0;
  for (const auto& t : tris) vol += verts[t[0]].dot(verts[t[1]].cross(verts[t[2]])) / 6.0;
  if (!(vol > 0))
    throwParameter("mesh", "enclosed volume " + num(vol) + " m^3", "",
                   "positive: triangles counter-clockwise seen from outside (this mesh is inward-oriented or flat)");
  // Convex mesh: every edge a ridge or flat.
  bool isConvex = true;
  for (const auto& kv : sideTri) {
    const int a = kv.first.first, b = kv.first.second;
    const Vec3& n0 = triN[kv.second];
    const Vec3& n1 = triN[sideTri.at({b, a})];
    if (1.0 - n0.dot(n1) < kCoplanarCos) continue;
    if (n0.cross(n1).dot((verts[b] - verts[a]).normalized()) <= 0) isConvex = false;
  }
  if (isConvex) return convexFromPoints(verts, R, "mesh");
  // Non-convex: erode each vertex so that each distinct incident face plane moves in by R.
  std::vector<std::vector<Vec3>> vertNormals(verts.size());
  for (size_t t = 0; t < tris.size(); ++t)
    for (int v : tris[t]) {
      bool known = false;
      for (const Vec3& n : vertNormals[v]) known = known || 1.0 - n.dot(triN[t]) < kCoplanarCos;
      if (!known) vertNormals[v].push_back(triN[t]);
    }
  auto s = std::make_shared<SpheroPolyhedron>();
  s->sweepRadius = R;
  s->convex = false;
  s->vertices = verts;
  for (size_t v = 0; v < verts.size(); ++v) {
    if (vertNormals[v].empty()) continue;
    Mat3 A = Mat3::Zero();
    Vec3 b = Vec3::Zero();
    for (const Vec3& n : vertNormals[v]) {
      A += n * n.transpose();
      b -= R * n;
    }
    Eigen::JacobiSVD<Mat3> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
    svd.setThreshold(1e-10);
    s->vertices[v] += svd.solve(b);
  }
  Real thinnest = std::numeric_limits<Real>::infinity();
  for (size_t t = 0; t < tris.size(); ++t) {
    const Vec3 c = (verts[tris[t][0]] + verts[tris[t][1]] + verts[tris[t][2]]) / 3.0;
    thinnest = std::min(thinnest, rayThickness(c, -triN[t], verts, tris, t));
  }
  if (R >= 0.5 * thinnest)
    throwParameter("sweepRadius", R, "m",
                   "in (0, " + num(0.5 * thinnest) + ") m: below half the thinnest wall of the mesh");
  for (size_t t = 0; t < tris.size(); ++t) {
    const Vec3 &a = s->vertices[tris[t][0]], &b = s->vertices[tris[t][1]], &c = s->vertices[tris[t][2]];
    const Vec3 n = (b - a).cross(c - a);
    if (!(n.dot(triN[t]) > 0))
      throwParameter("sweepRadius", R, "m",
                     "small enough that no eroded triangle flips (triangle " + std::to_string(t) + " does)");
    CoreFace f;
    f.loop = {tris[t][0], tris[t][1], tris[t][2]};
    f.normal = n.normalized();
    f.offset = f.normal.dot((a + b + c) / 3.0);
    s->faces.push_back(f);
  }
  s->outerVertices = verts;
  s->outerTriangles = tris;
  finalize(*s);
  return s;
}

std::shared_ptr<SpheroPolyhedron> SpheroPolyhedron::meshFile(const std::string& path, Real R, Real scale) {
  const io::TriangleMesh m = io::readMesh(path, scale);
  return mesh(m.vertices, m.triangles, R);
}

SpheroPolyhedron::PointQuery SpheroPolyhedron::closestPoint(const Vec3& p) const {
  PointQuery best{std::numeric_limits<Real>::infinity(), Vec3::Zero(), 0, -1};
  Real bestD2 = std::numeric_limits<Real>::infinity();
  const Real tieTol = 1e-24 * boundingRadius * boundingRadius;
  auto offer = [&](const Vec3& q, int kind, int index) {
    const Real d2 = (p - q).squaredNorm();
    if (d2 < bestD2 - tieTol || (d2 <= bestD2 + tieTol && kind < best.featureKind)) {
      bestD2 = std::min(d2, bestD2);
      best = {0, q, kind, index};
    }
  };
  for (size_t f = 0; f < faces.size(); ++f) {
    const CoreFace& face = faces[f];
    const size_t n = face.loop.size();
    const Vec3 q = p - (face.normal.dot(p) - face.offset) * face.normal;
    bool inside = true;
    for (size_t i = 0; i < n && inside; ++i) {
      const Vec3& a = vertices[face.loop[i]];
      const Vec3& b = vertices[face.loop[(i + 1) % n]];
      inside = (b - a).cross(q - a).dot(face.normal) >= 0;
    }
    if (inside) {
      offer(q, 0, static_cast<int>(f));
      continue;
    }
    for (size_t i = 0; i < n; ++i) {
      const int ia = face.loop[i], ib = face.loop[(i + 1) % n];
      const Vec3& a = vertices[ia];
      const Vec3& b = vertices[ib];
      const Real t = (p - a).dot(b - a) / (b - a).squaredNorm();
      if (t <= 0) {
        offer(a, 2, ia);
      } else if (t >= 1) {
        offer(b, 2, ib);
      } else if (faceEdges[f][i] >= 0) {
        offer(a + t * (b - a), 1, faceEdges[f][i]);
      }
    }
  }
  best.distance = std::sqrt(bestD2);
  // Inside the core: distance 0, closest point p itself, feature = nearest surface feature.
  bool inside;
  if (convex) {
    inside = true;
    for (const CoreFace& f : faces) inside = inside && f.normal.dot(p) <= f.offset;
  } else {  // winding number: sum of the solid angles of the faces seen from p
    Real omega = 0;
    for (const CoreFace& f : faces)
      for (size_t i = 1; i + 1 < f.loop.size(); ++i) {
        const Vec3 a = vertices[f.loop[0]] - p, b = vertices[f.loop[i]] - p, c = vertices[f.loop[i + 1]] - p;
        const Real la = a.norm(), lb = b.norm(), lc = c.norm();
        omega += 2 * std::atan2(a.dot(b.cross(c)), la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb);
      }
    inside = omega > 2 * kPi;
  }
  if (inside) {
    best.distance = 0;
    best.closest = p;
  }
  return best;
}

Real SpheroPolyhedron::coreMinWidth() const {
  Real w = std::numeric_limits<Real>::infinity();
  for (const CoreFace& f : faces) {
    Real lo = std::numeric_limits<Real>::infinity();
    for (const Vec3& v : vertices) lo = std::min(lo, f.normal.dot(v));
    w = std::min(w, f.offset - lo);
  }
  return w;
}

}  // namespace sdem
}  // namespace mpmsdem
