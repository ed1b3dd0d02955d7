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

// Edge e of P as a segment.
EdgeSegment segmentOf(const PosedSpheroPolyhedron& P, int e) {
  return {P.vertices[P.shape->edges[e].v0], P.edgeDir[e], P.edgeLength[e]};
}

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
  c.out.push_back(SdemGeom::of(ka, ia, kb, ib, pa, pb, (pb - pa) / d, d, c.A.shape->sweepRadius,
                               c.B.shape->sweepRadius));
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
  // parallel in the patch plane: the ends' vertex–face corners carry the contact
  Vec3 pa, pb;
  if (!crossingAlong(segmentOf(A, ea), segmentOf(B, eb), na, c.cutoff, c.tol, pa, pb)) return true;
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
  Vec3 pa, pb;
  if (!closestOfSegments(segmentOf(A, ea), segmentOf(B, eb), c.cutoff, c.tol, pa, pb)) return;
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

// ---- interpenetration of the cores. Cores whose interiors overlap by more than tol must be
// reported: their features meet from behind, no contact rule accepts them, and the bodies
// would pass through each other with no force. A vertex of one core inside the other is not
// enough to find them: equal cubes created coincident, or overlapping with aligned faces,
// have none.

// Largest and smallest projection of P's core on axis n.
Real maxAlong(const PosedSpheroPolyhedron& P, const Vec3& n) {
  Real m = -INFINITY;
  for (const Vec3& x : P.vertices) m = std::max(m, n.dot(x));
  return m;
}
Real minAlong(const PosedSpheroPolyhedron& P, const Vec3& n) {
  Real m = INFINITY;
  for (const Vec3& x : P.vertices) m = std::min(m, n.dot(x));
  return m;
}

// Does every vertex of Q lie in front of face f of P, or less than tol behind its plane?
bool faceSeparates(const PosedSpheroPolyhedron& P, int f, const PosedSpheroPolyhedron& Q, Real tol) {
  const Vec3& n = P.faceNormals[f];
  const Real limit = P.faceOffsets[f] - tol;
  for (const Vec3& x : Q.vertices)
    if (n.dot(x) <= limit) return false;
  return true;
}

// Separating-axis test of two convex cores, on the faces of their Minkowski difference:
// the face normals of A, those of B, and the cross products of the edge pairs whose arcs
// on the Gauss map cross (Gregorius, GDC 2013). The cores interpenetrate when the
// separation along every one of these axes is below -tol. `hint`: a first axis to try
// (a contact normal from A to B, which separates a pair in contact), or zero.
bool convexCoresInterpenetrate(const PosedSpheroPolyhedron& A, const PosedSpheroPolyhedron& B, Real tol,
                               const Vec3& hint) {
  if (hint.squaredNorm() > 0 && minAlong(B, hint) - maxAlong(A, hint) > -tol) return false;
  for (int f = 0; f < static_cast<int>(A.faceNormals.size()); ++f)
    if (faceSeparates(A, f, B, tol)) return false;
  for (int f = 0; f < static_cast<int>(B.faceNormals.size()); ++f)
    if (faceSeparates(B, f, A, tol)) return false;
  const auto& EA = A.shape->edges;
  const auto& EB = B.shape->edges;
  for (size_t ea = 0; ea < EA.size(); ++ea) {
    const Vec3& a = A.faceNormals[EA[ea].f0];
    const Vec3& b = A.faceNormals[EA[ea].f1];
    const Vec3 u = a.cross(b);  // normal of the great circle through a and b
    for (size_t eb = 0; eb < EB.size(); ++eb) {
      // arc of B's edge on the Gauss map of -B: from c = -n0 to d = -n1
      const Vec3 c = -B.faceNormals[EB[eb].f0];
      const Vec3 d = -B.faceNormals[EB[eb].f1];
      const Real cu = c.dot(u), du = d.dot(u);
      if (cu * du >= 0) continue;
      const Vec3 w = c.cross(d);
      const Real aw = a.dot(w), bw = b.dot(w);
      if (aw * bw >= 0 || cu * bw <= 0) continue;
      // The arcs cross at +-n: A's support along n is edge ea, B's support along -n is eb.
      Vec3 n = A.edgeDir[ea].cross(B.edgeDir[eb]);
      const Real len = n.norm();
      if (!(len > 0)) continue;  // parallel edges: the face normals above cover them
      n /= len;
      if (n.dot(a + b) < 0) n = -n;
      const Real sep = len > 1e-6
                           ? n.dot(B.vertices[EB[eb].v0] - A.vertices[EA[ea].v0])
                           : minAlong(B, n) - maxAlong(A, n);  // n not accurate enough for the shortcut
      if (sep > -tol) return false;
    }
  }
  return true;
}

// Is any selected vertex of P inside Q's convex core by more than tol?
bool vertexInside(const PosedSpheroPolyhedron& P, const std::vector<int>& sel, const PosedSpheroPolyhedron& Q,
                  Real tol) {
  if (!Q.shape->convex) return false;
  for (int v : sel) {
    bool inside = true;
    for (size_t f = 0; f < Q.faceNormals.size() && inside; ++f)
      inside = Q.faceNormals[f].dot(P.vertices[v]) - Q.faceOffsets[f] < -tol;
    if (inside) return true;
  }
  return false;
}

// Is x inside face polygon f of P (convex, in its plane) by more than tol from every side?
bool insidePolygon(const PosedSpheroPolyhedron& P, int f, const Vec3& x, Real tol) {
  const std::vector<int>& loop = P.shape->faces[f].loop;
  const Vec3& n = P.faceNormals[f];
  for (size_t k = 0; k < loop.size(); ++k) {
    const Vec3& a = P.vertices[loop[k]];
    const Vec3& b = P.vertices[loop[(k + 1) % loop.size()]];
    const Vec3 inward = n.cross(b - a);
    if ((x - a).dot(inward) <= tol * inward.norm()) return false;
  }
  return true;
}

// Does a side of a selected face of P (ridges, valleys and flat diagonals alike) pass through
// the interior of a selected face of Q, its ends more than tol on either side of the plane?
// Then part of P's surface, hence of P, lies inside Q.
bool sideThroughFace(const PosedSpheroPolyhedron& P, const std::vector<int>& pf, const PosedSpheroPolyhedron& Q,
                     const std::vector<int>& qf, Real tol) {
  for (int f : pf) {
    const std::vector<int>& loop = P.shape->faces[f].loop;
    for (size_t k = 0; k < loop.size(); ++k) {
      const int i0 = loop[k], i1 = loop[(k + 1) % loop.size()];
      if (i0 > i1) continue;  // each side once (the neighbour face runs it the other way)
      const Vec3& p0 = P.vertices[i0];
      const Vec3& p1 = P.vertices[i1];
      const Vec3 lo = p0.cwiseMin(p1), hi = p0.cwiseMax(p1);
      for (int g : qf) {
        if (!boxesOverlap(lo, hi, Q.faceLo[g], Q.faceHi[g])) continue;
        const Real s0 = Q.faceNormals[g].dot(p0) - Q.faceOffsets[g];
        const Real s1 = Q.faceNormals[g].dot(p1) - Q.faceOffsets[g];
        if (!((s0 < -tol && s1 > tol) || (s0 > tol && s1 < -tol))) continue;
        if (insidePolygon(Q, g, p0 + (s0 / (s0 - s1)) * (p1 - p0), tol)) return true;
      }
    }
  }
  return false;
}

// Projection interval of face polygon f of P on the in-plane direction t.
void polygonInterval(const PosedSpheroPolyhedron& P, int f, const Vec3& t, Real& lo, Real& hi) {
  lo = INFINITY;
  hi = -INFINITY;
  for (int v : P.shape->faces[f].loop) {
    const Real x = t.dot(P.vertices[v]);
    lo = std::min(lo, x);
    hi = std::max(hi, x);
  }
}

// Two coplanar faces with the same outward normal whose polygons overlap by more than tol:
// just behind the common area both bodies are solid. (Opposite normals are a touching contact.)
bool coplanarFacesOverlap(const PosedSpheroPolyhedron& A, const std::vector<int>& af, const PosedSpheroPolyhedron& B,
                          const std::vector<int>& bf, Real tol) {
  for (int fa : af)
    for (int fb : bf) {
      const Vec3& n = A.faceNormals[fa];
      if (1 - n.dot(B.faceNormals[fb]) > 1e-12 || std::abs(A.faceOffsets[fa] - B.faceOffsets[fb]) > tol) continue;
      if (!boxesOverlap(A.faceLo[fa], A.faceHi[fa], B.faceLo[fb], B.faceHi[fb])) continue;
      // 2D separating axes: the in-plane normals of both polygons' sides
      bool overlap = true;
      for (int pass = 0; pass < 2 && overlap; ++pass) {
        const PosedSpheroPolyhedron& P = pass == 0 ? A : B;
        const int f = pass == 0 ? fa : fb;
        const std::vector<int>& loop = P.shape->faces[f].loop;
        for (size_t k = 0; k < loop.size() && overlap; ++k) {
          const Vec3 t = n.cross(P.vertices[loop[(k + 1) % loop.size()]] - P.vertices[loop[k]]).normalized();
          Real la, ha, lb, hb;
          polygonInterval(A, fa, t, la, ha);
          polygonInterval(B, fb, t, lb, hb);
          overlap = std::min(ha, hb) - std::max(la, lb) > tol;
        }
      }
      if (overlap) return true;
    }
  return false;
}

// Distance from x to the core surface of P.
Real surfaceDistance(const PosedSpheroPolyhedron& P, const Vec3& x) {
  Real best = INFINITY;
  for (size_t f = 0; f < P.faceNormals.size(); ++f) {
    const Real s = P.faceNormals[f].dot(x) - P.faceOffsets[f];
    if (std::abs(s) >= best) continue;
    if (insidePolygon(P, static_cast<int>(f), x - s * P.faceNormals[f], 0)) {
      best = std::abs(s);
      continue;
    }
    const std::vector<int>& loop = P.shape->faces[f].loop;
    for (size_t k = 0; k < loop.size(); ++k) {
      const Vec3& a = P.vertices[loop[k]];
      const Vec3 ab = P.vertices[loop[(k + 1) % loop.size()]] - a;
      const Real t = std::clamp((x - a).dot(ab) / ab.squaredNorm(), Real(0), Real(1));
      best = std::min(best, (x - a - t * ab).norm());
    }
  }
  return best;
}

// P entirely inside Q (possible only when P's core box lies in Q's): the first vertex of P
// farther than tol from Q's surface tells on which side P lies. Called only when the
// surfaces do not cross, so all of P is on one side.
bool coreInside(const PosedSpheroPolyhedron& P, const PosedSpheroPolyhedron& Q, Real tol) {
  if ((P.coreLo.array() < Q.coreLo.array() - tol).any() || (P.coreHi.array() > Q.coreHi.array() + tol).any())
    return false;
  for (const Vec3& x : P.vertices) {
    if (surfaceDistance(Q, x) <= tol) continue;
    return Q.shape->closestPoint(Q.ori.conjugate() * (x - Q.pos)).distance == 0;
  }
  return false;
}

// Interpenetration of cores when one at least is not convex (no separating-axis theorem).
// Interiors overlap by more than tol only if a vertex lies inside a convex core, the surfaces
// cross (a face side through a face), coincide over an area with the same outward normal,
// or one core contains the other.
bool coresInterpenetrateGeneral(const PosedSpheroPolyhedron& A, const Selection& sa, const PosedSpheroPolyhedron& B,
                                 const Selection& sb, Real tol) {
  return vertexInside(A, sa.v, B, tol) || vertexInside(B, sb.v, A, tol) || sideThroughFace(A, sa.f, B, sb.f, tol) ||
         sideThroughFace(B, sb.f, A, sa.f, tol) || coplanarFacesOverlap(A, sa.f, B, sb.f, tol) ||
         coreInside(A, B, tol) || coreInside(B, A, tol);
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
  // Interiors can overlap only where the core boxes overlap by more than tol.
  const bool boxesMeet = (A.coreHi.cwiseMin(B.coreHi) - A.coreLo.cwiseMax(B.coreLo)).minCoeff() > tol;
  const bool convexPair = A.shape->convex && B.shape->convex;
  if (boxesMeet && !convexPair && coresInterpenetrateGeneral(A, sa, B, sb, tol)) return false;

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
  if (boxesMeet && convexPair) {
    // The normal of the closest contact separates two convex cores in contact: tried first.
    Vec3 hint = Vec3::Zero();
    Real dmin = INFINITY;
    for (size_t k = c.first; k < out.size(); ++k)
      if (out[k].distance < dmin) dmin = out[k].distance, hint = out[k].normal;
    if (convexCoresInterpenetrate(A, B, tol, hint)) {
      out.resize(c.first);
      return false;
    }
  }
  return true;
}

}  // namespace sdem
}  // namespace mpmsdem
