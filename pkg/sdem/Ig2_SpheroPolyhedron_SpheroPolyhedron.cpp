#include "sdem/Ig2_SpheroPolyhedron_SpheroPolyhedron.hpp"

#include <algorithm>
#include <cmath>

namespace mpmsdem {
namespace sdem {

void PosedSpheroPolyhedron::update(const SpheroPolyhedron& s, const Vec3& p, const Quat& q) {
  shape = &s;
  pos = p;
  ori = q.normalized();
  const Mat3 rot = ori.toRotationMatrix();
  const size_t nv = s.vertices.size(), nf = s.faces.size(), ne = s.edges.size();
  vertices.resize(nv);
  coreLo = Vec3::Constant(INFINITY);
  coreHi = Vec3::Constant(-INFINITY);
  for (size_t i = 0; i < nv; ++i) {
    vertices[i] = pos + rot * s.vertices[i];
    coreLo = coreLo.cwiseMin(vertices[i]);
    coreHi = coreHi.cwiseMax(vertices[i]);
  }
  faceNormals.resize(nf);
  faceOffsets.resize(nf);
  faceLo.resize(nf);
  faceHi.resize(nf);
  for (size_t f = 0; f < nf; ++f) {
    const CoreFace& F = s.faces[f];
    faceNormals[f] = rot * F.normal;
    faceOffsets[f] = F.offset + faceNormals[f].dot(pos);
    Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
    for (int v : F.loop) {
      lo = lo.cwiseMin(vertices[v]);
      hi = hi.cwiseMax(vertices[v]);
    }
    faceLo[f] = lo;
    faceHi[f] = hi;
  }
  edgeDir.resize(ne);
  edgeLength.resize(ne);
  edgeIn0.resize(ne);
  edgeIn1.resize(ne);
  for (size_t e = 0; e < ne; ++e) {
    const CoreEdge& E = s.edges[e];
    const Vec3 d = vertices[E.v1] - vertices[E.v0];
    edgeLength[e] = d.norm();
    edgeDir[e] = d / edgeLength[e];
    // f0 runs v0 -> v1 counter-clockwise seen from outside: its interior is on the left,
    // n0 x t; f1 runs v1 -> v0, its interior is n1 x (-t) = t x n1.
    edgeIn0[e] = faceNormals[E.f0].cross(edgeDir[e]).normalized();
    edgeIn1[e] = edgeDir[e].cross(faceNormals[E.f1]).normalized();
  }
}

namespace {

bool boxesOverlap(const Vec3& lo1, const Vec3& hi1, const Vec3& lo2, const Vec3& hi2) {
  return (lo1.array() <= hi2.array()).all() && (lo2.array() <= hi1.array()).all();
}

bool pointInBox(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
}

// Everything one pair's enumeration needs.
struct PairContext {
  const PosedSpheroPolyhedron& A;
  const PosedSpheroPolyhedron& B;
  Real cutoff;  // R_A + R_B
  Real tol;     // length tolerance
  std::vector<SdemGeom>& out;
  size_t first;  // index of this pair's first contact in out
};

// Unit direction of edge `e` leaving vertex `v`.
Vec3 edgeFrom(const PosedSpheroPolyhedron& P, int e, int v) {
  return P.shape->edges[e].v0 == v ? P.edgeDir[e] : Vec3(-P.edgeDir[e]);
}

// Normal cone of vertex v of P: `sep` (from v towards the other body) must not point into P
// along any incident edge by more than tol.
bool vertexCone(const PosedSpheroPolyhedron& P, int v, const Vec3& sep, Real tol) {
  for (int e : P.shape->vertexEdges[v])
    if (sep.dot(edgeFrom(P, e, v)) > tol) return false;
  return true;
}

// Normal cone of edge e of P: convex, and `sep` (from the edge towards the other body) not
// pointing into either adjacent face by more than tol.
bool edgeCone(const PosedSpheroPolyhedron& P, int e, const Vec3& sep, Real tol) {
  if (!P.shape->edges[e].convex) return false;
  return sep.dot(P.edgeIn0[e]) <= tol && sep.dot(P.edgeIn1[e]) <= tol;
}

// Does vertex v of P belong to a face whose normal is nearly anti-parallel to n?
bool inPatch(const PosedSpheroPolyhedron& P, int v, const Vec3& n) {
  for (int e : P.shape->vertexEdges[v]) {
    const CoreEdge& E = P.shape->edges[e];
    if (P.faceNormals[E.f0].dot(n) <= -Ig2_SpheroPolyhedron_SpheroPolyhedron::patchCosine ||
        P.faceNormals[E.f1].dot(n) <= -Ig2_SpheroPolyhedron_SpheroPolyhedron::patchCosine)
      return true;
  }
  return false;
}

// If edge ea of A and edge eb of B bound two faces, one of each, that are nearly anti-parallel
// (a contact patch), return in `na` the outward normal of A's face: the patch direction.
bool patchNormal(const PosedSpheroPolyhedron& A, int ea, const PosedSpheroPolyhedron& B, int eb, Vec3& na) {
  const CoreEdge &EA = A.shape->edges[ea], &EB = B.shape->edges[eb];
  for (int fa : {EA.f0, EA.f1})
    for (int fb : {EB.f0, EB.f1})
      if (A.faceNormals[fa].dot(B.faceNormals[fb]) <= -Ig2_SpheroPolyhedron_SpheroPolyhedron::patchCosine) {
        na = A.faceNormals[fa];
        return true;
      }
  return false;
}

// Append a contact given the two core points, merging it into an equal one of this pair.
void emit(PairContext& c, FeatureKind ka, int ia, FeatureKind kb, int ib, const Vec3& pa, const Vec3& pb,
          Real d) {
  const Real mergeTol = 4 * c.tol;
  for (size_t k = c.first; k < c.out.size(); ++k)
    if ((c.out[k].pointA - pa).norm() <= mergeTol && (c.out[k].pointB - pb).norm() <= mergeTol) return;
  SdemGeom g;
  g.kindA = ka;
  g.indexA = ia;
  g.kindB = kb;
  g.indexB = ib;
  g.pointA = pa;
  g.pointB = pb;
  g.normal = (pb - pa) / d;
  g.distance = d;
  g.overlap = c.cutoff - d;
  const Real RA = c.A.shape->sweepRadius, RB = c.B.shape->sweepRadius;
  // sphere surfaces: pa + RA n (A's) and pb - RB n (B's); midway between them
  g.contactPoint = 0.5 * (pa + RA * g.normal + pb - RB * g.normal);
  c.out.push_back(g);
}

// Vertex v of P against face f of Q. pIsA: P is body A.
void vertexFace(PairContext& c, const PosedSpheroPolyhedron& P, int v, const PosedSpheroPolyhedron& Q, int f,
                bool pIsA) {
  const Vec3& x = P.vertices[v];
  const Vec3& nf = Q.faceNormals[f];
  const Real s = nf.dot(x) - Q.faceOffsets[f];
  if (s <= 0 || s >= c.cutoff) return;
  const Vec3 q = x - s * nf;
  const std::vector<int>& loop = Q.shape->faces[f].loop;
  const size_t m = loop.size();
  for (size_t k = 0; k < m; ++k) {
    const Vec3& a = Q.vertices[loop[k]];
    const Vec3& b = Q.vertices[loop[(k + 1) % m]];
    const Vec3 inward = nf.cross(b - a);
    if ((q - a).dot(inward) < -c.tol * inward.norm()) return;
  }
  const Vec3 sep = q - x;  // from the vertex towards Q
  if (!inPatch(P, v, nf) && !vertexCone(P, v, sep, c.tol)) return;
  if (pIsA)
    emit(c, FeatureKind::Vertex, v, FeatureKind::Face, f, x, q, s);
  else
    emit(c, FeatureKind::Face, f, FeatureKind::Vertex, v, q, x, s);
}

// Crossing of two edges bounding a contact patch (see patchNormal): the points of the two
// edges that coincide when projected along the patch normal na. This is a corner of the
// clipped intersection polygon of the two faces; it meets the patch's vertex–face corners
// continuously when it reaches an edge end, whatever the small tilt between the faces (the
// closest points of the two edge lines would drift away from the corner instead).
bool patchCrossing(PairContext& c, int ea, int eb, const Vec3& na) {
  const PosedSpheroPolyhedron &A = c.A, &B = c.B;
  const Vec3& p0 = A.vertices[A.shape->edges[ea].v0];
  const Vec3& q0 = B.vertices[B.shape->edges[eb].v0];
  const Vec3 &ta = A.edgeDir[ea], &tb = B.edgeDir[eb];
  const Real La = A.edgeLength[ea], Lb = B.edgeLength[eb];
  const Real den = ta.cross(tb).dot(na);
  // parallel in the patch plane: the ends' vertex–face corners carry the contact
  if (std::abs(den) * c.cutoff <= c.tol) return true;
  const Vec3 r = q0 - p0;
  const Real s = r.cross(tb).dot(na) / den;
  const Real t = r.cross(ta).dot(na) / den;
  if (s < -c.tol || s > La + c.tol || t < -c.tol || t > Lb + c.tol) return true;
  const Vec3 pa = p0 + std::clamp(s, Real(0), La) * ta, pb = q0 + std::clamp(t, Real(0), Lb) * tb;
  const Vec3 sep = pb - pa;
  if (sep.dot(na) <= 0) return false;  // B behind A's face: not this patch, try the general rule
  const Real d = sep.norm();
  if (d < c.cutoff) emit(c, FeatureKind::Edge, ea, FeatureKind::Edge, eb, pa, pb, d);
  return true;
}

void edgeEdge(PairContext& c, int ea, int eb) {
  const PosedSpheroPolyhedron &A = c.A, &B = c.B;
  const Vec3& p0 = A.vertices[A.shape->edges[ea].v0];
  const Vec3& q0 = B.vertices[B.shape->edges[eb].v0];
  const Vec3 &ta = A.edgeDir[ea], &tb = B.edgeDir[eb];
  const Real La = A.edgeLength[ea], Lb = B.edgeLength[eb];
  // cheap cull: bounding spheres of the two segments
  const Vec3 mid = (p0 + 0.5 * La * ta) - (q0 + 0.5 * Lb * tb);
  const Real reach = 0.5 * (La + Lb) + c.cutoff;
  if (mid.squaredNorm() >= reach * reach) return;
  if (!A.shape->edges[ea].convex || !B.shape->edges[eb].convex) return;
  Vec3 na;
  if (patchNormal(A, ea, B, eb, na) && patchCrossing(c, ea, eb, na)) return;
  // Parallel within tolerance: the contact is carried by the endpoints' vertex pairs, whose
  // cone tests then pass within tol. sin(angle) * cutoff <= tol keeps both rules consistent.
  const Real sin2 = ta.cross(tb).squaredNorm();
  if (sin2 * c.cutoff * c.cutoff <= c.tol * c.tol) return;
  const Vec3 r = q0 - p0;
  const Real cosab = ta.dot(tb), da = ta.dot(r), db = tb.dot(r);
  Real s = (da - cosab * db) / sin2;
  Real t = (cosab * da - db) / sin2;
  if (s < -c.tol || s > La + c.tol || t < -c.tol || t > Lb + c.tol) return;
  s = std::clamp(s, Real(0), La);
  t = std::clamp(t, Real(0), Lb);
  const Vec3 pa = p0 + s * ta, pb = q0 + t * tb;
  const Vec3 sep = pb - pa;
  const Real d = sep.norm();
  if (d <= 0 || d >= c.cutoff) return;
  if (!edgeCone(A, ea, sep, c.tol) || !edgeCone(B, eb, -sep, c.tol)) return;
  emit(c, FeatureKind::Edge, ea, FeatureKind::Edge, eb, pa, pb, d);
}

// Vertex v of P against edge e of Q.
void vertexEdge(PairContext& c, const PosedSpheroPolyhedron& P, int v, const PosedSpheroPolyhedron& Q, int e,
                bool pIsA) {
  const Vec3& x = P.vertices[v];
  const Vec3& q0 = Q.vertices[Q.shape->edges[e].v0];
  const Vec3& t = Q.edgeDir[e];
  const Real L = Q.edgeLength[e];
  Real u = (x - q0).dot(t);
  if (u < -c.tol || u > L + c.tol) return;
  u = std::clamp(u, Real(0), L);
  const Vec3 q = q0 + u * t;
  const Vec3 sep = q - x;  // from the vertex towards Q
  const Real d = sep.norm();
  if (d <= 0 || d >= c.cutoff) return;
  if (!vertexCone(P, v, sep, c.tol) || !edgeCone(Q, e, -sep, c.tol)) return;
  if (pIsA)
    emit(c, FeatureKind::Vertex, v, FeatureKind::Edge, e, x, q, d);
  else
    emit(c, FeatureKind::Edge, e, FeatureKind::Vertex, v, q, x, d);
}

void vertexVertex(PairContext& c, int va, int vb) {
  const Vec3& xa = c.A.vertices[va];
  const Vec3& xb = c.B.vertices[vb];
  const Vec3 sep = xb - xa;
  const Real d = sep.norm();
  if (d <= 0 || d >= c.cutoff) return;
  if (!vertexCone(c.A, va, sep, c.tol) || !vertexCone(c.B, vb, -sep, c.tol)) return;
  emit(c, FeatureKind::Vertex, va, FeatureKind::Vertex, vb, xa, xb, d);
}

// Features of P that may take part in a contact: those touching box [lo, hi].
struct Selection {
  std::vector<int> v, e, f;
  void build(const PosedSpheroPolyhedron& P, const Vec3& lo, const Vec3& hi) {
    v.clear();
    e.clear();
    f.clear();
    // a vertex with no incident ridge or valley lies inside a flat region: the faces around
    // it carry its contacts
    for (int i = 0; i < static_cast<int>(P.vertices.size()); ++i)
      if (!P.shape->vertexEdges[i].empty() && pointInBox(P.vertices[i], lo, hi)) v.push_back(i);
    for (int i = 0; i < static_cast<int>(P.edgeDir.size()); ++i) {
      const CoreEdge& E = P.shape->edges[i];
      if (!E.convex) continue;
      const Vec3& a = P.vertices[E.v0];
      const Vec3& b = P.vertices[E.v1];
      if (boxesOverlap(a.cwiseMin(b), a.cwiseMax(b), lo, hi)) e.push_back(i);
    }
    for (int i = 0; i < static_cast<int>(P.faceNormals.size()); ++i)
      if (boxesOverlap(P.faceLo[i], P.faceHi[i], lo, hi)) f.push_back(i);
  }
};

// Is any selected vertex of P strictly inside Q's (convex) core?
bool vertexInside(const PosedSpheroPolyhedron& P, const std::vector<int>& sel, const PosedSpheroPolyhedron& Q) {
  if (!Q.shape->convex) return false;
  for (int v : sel) {
    bool inside = true;
    for (size_t f = 0; f < Q.faceNormals.size() && inside; ++f)
      inside = Q.faceNormals[f].dot(P.vertices[v]) - Q.faceOffsets[f] < 0;
    if (inside) return true;
  }
  return false;
}

}  // namespace

Real Ig2_SpheroPolyhedron_SpheroPolyhedron::tolerance(const PosedSpheroPolyhedron& A,
                                                      const PosedSpheroPolyhedron& B) {
  return 1e-9 * std::max(A.shape->boundingRadius, B.shape->boundingRadius);
}

bool Ig2_SpheroPolyhedron_SpheroPolyhedron::go(const PosedSpheroPolyhedron& A, const PosedSpheroPolyhedron& B,
                                               std::vector<SdemGeom>& out) {
  const Real cutoff = A.shape->sweepRadius + B.shape->sweepRadius;
  const Real tol = tolerance(A, B);
  // A core point in contact lies in A's core box and within `cutoff` of B's core box.
  const Vec3 margin = Vec3::Constant(cutoff), slack = Vec3::Constant(tol);
  const Vec3 loA = A.coreLo.cwiseMax(B.coreLo - margin) - slack;
  const Vec3 hiA = A.coreHi.cwiseMin(B.coreHi + margin) + slack;
  if ((loA.array() > hiA.array()).any()) return true;
  const Vec3 loB = B.coreLo.cwiseMax(A.coreLo - margin) - slack;
  const Vec3 hiB = B.coreHi.cwiseMin(A.coreHi + margin) + slack;
  if ((loB.array() > hiB.array()).any()) return true;

  thread_local Selection sa, sb;
  sa.build(A, loA, hiA);
  sb.build(B, loB, hiB);
  if (vertexInside(A, sa.v, B) || vertexInside(B, sb.v, A)) return false;

  PairContext c{A, B, cutoff, tol, out, out.size()};
  for (int v : sa.v)
    for (int f : sb.f) vertexFace(c, A, v, B, f, true);
  for (int v : sb.v)
    for (int f : sa.f) vertexFace(c, B, v, A, f, false);
  for (int ea : sa.e)
    for (int eb : sb.e) edgeEdge(c, ea, eb);
  for (int v : sa.v)
    for (int e : sb.e) vertexEdge(c, A, v, B, e, true);
  for (int v : sb.v)
    for (int e : sa.e) vertexEdge(c, B, v, A, e, false);
  for (int va : sa.v)
    for (int vb : sb.v) vertexVertex(c, va, vb);
  return true;
}

}  // namespace sdem
}  // namespace mpmsdem
