// SDEM geometry and contact law written once as __host__ __device__ functions over plain
// arrays, so that the CPU paths (block–block Law2, MP–block coupling) and the CUDA coupling
// kernels evaluate the same formulas in double or float.
//
// Shapes live in a flat table (ShapeTable.hpp builds it on the host from SpheroPolyhedron;
// CGAL is used only while building the shapes): core vertices, faces (outward unit normal,
// plane offset, vertex loop, and for each loop side the core edge it lies on or -1 for a flat
// diagonal between coplanar triangles), and per shape its sweep radius and convexity. Vertex
// and edge indices stored in the loops are table-global; queries report them shape-local.
#pragma once
#include <cstdint>

#include "common/MathHD.hpp"

namespace mpmsdem {
namespace sdem {

using mpmsdem::Vec3T;

template <typename T>
MPM_HD_INLINE Vec3T<T> cross(const Vec3T<T>& a, const Vec3T<T>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <typename T>
MPM_HD_INLINE T norm(const Vec3T<T>& a) {
  return mpmsdem::hdSqrt(mpmsdem::dot(a, a));
}

// Flat shape table (views into arrays owned by the host ShapeTable or by device buffers).
template <typename T>
struct ShapeTableView {
  int numShapes;
  const T* vertex;          // 3 per core vertex, body frame [m]
  const T* faceNormal;      // 3 per face, unit outward normal
  const T* faceOffset;      // per face: normal . x on the face plane [m]
  const int* faceLoopStart; // per face, start of its loop in loopVertex/loopEdge (numFaces + 1 entries)
  const int* loopVertex;    // table-global vertex index of each loop corner (counter-clockwise from outside)
  const int* loopEdge;      // table-global edge index of the side loop[i] -> loop[i+1], or -1
  const int* shapeFaceStart;    // per shape, first face (numShapes + 1 entries)
  const int* shapeVertexStart;  // per shape, first vertex (numShapes + 1 entries)
  const int* shapeEdgeStart;    // per shape, first edge (numShapes + 1 entries)
  const T* sweepRadius;         // R per shape [m]
  const T* boundingRadius;      // per shape: max |vertex| + R [m]
  const std::uint8_t* convex;   // per shape: 1 when the core is convex
};

// Feature kinds, numbered as SpheroPolyhedron::PointQuery::featureKind and FeatureKind.
constexpr int kFeatureFace = 0;
constexpr int kFeatureEdge = 1;
constexpr int kFeatureVertex = 2;

template <typename T>
struct CoreQuery {
  T distance;          // distance from the point to the core, 0 inside [m]
  Vec3T<T> closest;    // closest core point, body frame [m] (the point itself when inside)
  int featureKind;     // kFeatureFace / kFeatureEdge / kFeatureVertex of the nearest surface feature
  int featureIndex;    // shape-local index of that feature
};

// Closest point of shape s's core to point p (body frame): every face offers its interior
// projection, or else the nearest point of its boundary (a vertex, or an edge unless the side
// is a flat diagonal). Ties within 1e-12 of the shape size go to the lower kind
// number (face, then edge, then vertex), so a point over a face interior is a face contact.
// Inside the core (half-spaces for convex cores, winding number otherwise) the distance is 0.
// Outside a convex core only the faces whose plane p is in front of are searched: the nearest
// point's normal cone holds p - q, so one face through q has (p - q) . n > 0, and that is p's
// distance to its plane. Cost: linear in the number of face corners of the shape (of the faces
// facing p for a convex core outside).
template <typename T>
MPM_HD_INLINE CoreQuery<T> closestPointOnCore(const ShapeTableView<T>& S, int s, const Vec3T<T>& p) {
  CoreQuery<T> best{T(0), p, kFeatureFace, -1};
  T bestD2 = T(-1);
  const T br = S.boundingRadius[s];
  const T tieTol = T(1e-24) * br * br;
  const int v0 = S.shapeVertexStart[s], e0 = S.shapeEdgeStart[s], f0 = S.shapeFaceStart[s];
  auto offer = [&](const Vec3T<T>& q, int kind, int index) {
    const Vec3T<T> d = p - q;
    const T d2 = mpmsdem::dot(d, d);
    if (bestD2 < T(0) || d2 < bestD2 - tieTol || (d2 <= bestD2 + tieTol && kind < best.featureKind)) {
      bestD2 = (bestD2 < T(0) || d2 < bestD2) ? d2 : bestD2;
      best.closest = q;
      best.featureKind = kind;
      best.featureIndex = index;
    }
  };
  auto vertexAt = [&](int v) { return Vec3T<T>{S.vertex[3 * v], S.vertex[3 * v + 1], S.vertex[3 * v + 2]}; };
  auto normalAt = [&](int f) { return Vec3T<T>{S.faceNormal[3 * f], S.faceNormal[3 * f + 1], S.faceNormal[3 * f + 2]}; };
  // Offer face f's interior projection of p, or the nearest point of its boundary; height is
  // p's signed distance to the face plane.
  auto searchFace = [&](int f, T height) {
    const Vec3T<T> n = normalAt(f);
    const int l0 = S.faceLoopStart[f], l1 = S.faceLoopStart[f + 1], m = l1 - l0;
    const Vec3T<T> q = p - height * n;
    bool inside = true;
    for (int i = 0; i < m && inside; ++i) {
      const Vec3T<T> a = vertexAt(S.loopVertex[l0 + i]);
      const Vec3T<T> b = vertexAt(S.loopVertex[l0 + (i + 1) % m]);
      inside = mpmsdem::dot(cross(b - a, q - a), n) >= T(0);
    }
    if (inside) {
      offer(q, kFeatureFace, f - f0);
      return;
    }
    for (int i = 0; i < m; ++i) {
      const int ia = S.loopVertex[l0 + i], ib = S.loopVertex[l0 + (i + 1) % m];
      const Vec3T<T> a = vertexAt(ia), b = vertexAt(ib);
      const Vec3T<T> ab = b - a;
      const T t = mpmsdem::dot(p - a, ab) / mpmsdem::dot(ab, ab);
      if (t <= T(0))
        offer(a, kFeatureVertex, ia - v0);
      else if (t >= T(1))
        offer(b, kFeatureVertex, ib - v0);
      else if (S.loopEdge[l0 + i] >= 0)
        offer(a + t * ab, kFeatureEdge, S.loopEdge[l0 + i] - e0);
    }
  };
  const int f1 = S.shapeFaceStart[s + 1];
  const bool convex = S.convex[s] != 0;
  bool facing = false;  // p is in front of a face plane of the convex core, so outside it
  if (convex)
    for (int f = f0; f < f1; ++f) {
      const T height = mpmsdem::dot(normalAt(f), p) - S.faceOffset[f];
      if (height > T(0)) {
        facing = true;
        searchFace(f, height);
      }
    }
  if (!facing)
    for (int f = f0; f < f1; ++f) searchFace(f, mpmsdem::dot(normalAt(f), p) - S.faceOffset[f]);
  best.distance = mpmsdem::hdSqrt(bestD2 < T(0) ? T(0) : bestD2);
  bool inside;
  if (convex) {
    inside = !facing;
  } else {  // winding number: sum of the solid angles of the (fan-triangulated) faces seen from p
    T omega = T(0);
    for (int f = f0; f < f1; ++f) {
      const int l0 = S.faceLoopStart[f], l1 = S.faceLoopStart[f + 1];
      for (int i = l0 + 1; i + 1 < l1; ++i) {
        const Vec3T<T> a = vertexAt(S.loopVertex[l0]) - p, b = vertexAt(S.loopVertex[i]) - p,
                       c = vertexAt(S.loopVertex[i + 1]) - p;
        const T la = norm(a), lb = norm(b), lc = norm(c);
        omega += T(2) * mpmsdem::hdAtan2(mpmsdem::dot(a, cross(b, c)),
                                la * lb * lc + mpmsdem::dot(a, b) * lc + mpmsdem::dot(b, c) * la + mpmsdem::dot(c, a) * lb);
      }
    }
    inside = omega > T(2 * 3.14159265358979323846);
  }
  if (inside) {
    best.distance = T(0);
    best.closest = p;
  }
  return best;
}

// Signed distance of p (body frame) to the plane of table face f [m]: > 0 in front of it.
template <typename T>
MPM_HD_INLINE T facePlaneDistance(const ShapeTableView<T>& S, int f, const Vec3T<T>& p) {
  return S.faceNormal[3 * f] * p.x + S.faceNormal[3 * f + 1] * p.y + S.faceNormal[3 * f + 2] * p.z - S.faceOffset[f];
}

// Lower bound of the distance from p (body frame) to shape s's core: the largest signed
// distance of p to a face plane, exact outside a convex core along a face normal. Cheaper than
// closestPointOnCore (one dot product per face), so it culls points out of reach first. For
// a non-convex core it returns 0 (no bound). *face (when given) is the table index of the face
// that gives the bound, -1 when the bound is 0.
template <typename T>
MPM_HD_INLINE T coreDistanceLowerBound(const ShapeTableView<T>& S, int s, const Vec3T<T>& p, int* face = nullptr) {
  T best = T(0);
  int bestFace = -1;
  if (S.convex[s])
    for (int f = S.shapeFaceStart[s]; f < S.shapeFaceStart[s + 1]; ++f) {
      const T d = facePlaneDistance(S, f, p);
      if (d > best) {
        best = d;
        bestFace = f;
      }
    }
  if (face) *face = bestFace;
  return best;
}

// ------------------------------------------------------------------ barrier normal law (Eq 10)
// Read as a force: F_n = -db/dd of b(d) = -k_c (d - R)^2 ln(d/R) on the core gap d = R - delta,
// F_n(delta) = -k_c delta [2 ln((R - delta)/R) - R/(R - delta) + 1]. With x = delta/R the
// bracket is written with log1p(-x) and -x/(1-x), free of cancellation near first touch.
template <typename T>
MPM_HD_INLINE T barrierForce(T kc, T R, T delta) {
  if (!(delta > T(0))) return T(0);
  const T x = delta / R;
  return -kc * delta * (T(2) * mpmsdem::hdLog1p(-x) - x / (T(1) - x));
}
// Tangent stiffness k_n = dF_n/ddelta [N/m].
template <typename T>
MPM_HD_INLINE T barrierStiffness(T kc, T R, T delta) {
  if (!(delta > T(0))) return T(0);
  const T x = delta / R;
  return -kc * (T(2) * mpmsdem::hdLog1p(-x) - T(3) * x / (T(1) - x) - x / ((T(1) - x) * (T(1) - x)));
}
// Barrier potential b(R - delta) [J]; F_n = db/ddelta.
template <typename T>
MPM_HD_INLINE T barrierPotential(T kc, T R, T delta) {
  if (!(delta > T(0))) return T(0);
  return -kc * delta * delta * mpmsdem::hdLog1p(-delta / R);
}

// Pair parameters of the law (YADE's IPhys role), plain values for device use.
template <typename T>
struct BarrierCoulombPhys {
  T kc;        // barrier stiffness k_c [N/m]
  T mu;        // Coulomb friction [-]
  T nu;        // Poisson ratio in K_t = k_n / (2 (1 + nu)) [-]
  T zetaN;     // normal damping, fraction of critical [-]
  T zetaT;     // tangential damping, fraction of critical [-]
};

template <typename T>
struct BarrierCoulombResult {
  T normalForce;          // F_n >= 0 along n [N]
  Vec3T<T> tangential;    // F_t [N], perpendicular to n
  T kn, kt;               // tangent normal stiffness, tangential stiffness [N/m]
  T barrierEnergy;        // b(d) [J]
  T springEnergy;         // |F_el|^2 / (2 K_t) after the step [J]
  T frictionWork;         // slip work of this step [J]
  T dampingWork;          // dashpot work of this step [J]
  bool sliding;
};

// Rotate the tangential history h (the elastic tangential force) into the plane perpendicular
// to the unit normal n, keeping its length (Eq 9).
template <typename T>
MPM_HD_INLINE void rotateTangentialHistory(T h[3], const Vec3T<T>& n) {
  const Vec3T<T> x{h[0], h[1], h[2]};
  const T len = norm(x);
  if (len == T(0)) return;
  const Vec3T<T> proj = x - mpmsdem::dot(x, n) * n;
  const T plen = norm(proj);
  const T scale = plen > T(1e-12) * len ? len / plen : T(0);
  h[0] = proj.x * scale;
  h[1] = proj.y * scale;
  h[2] = proj.z * scale;
}

// Barrier normal force (Eq 10) with an optional dashpot, clamped at >= 0, and the incremental
// Coulomb tangential spring (Eqs 9, 11). The history is the elastic tangential force F_el [N],
// not a displacement: K_t follows the steep barrier stiffness k_n(delta), so F_t = -K_t xi with
// a stored xi would jump whenever delta changes under a held xi, a force change with no
// tangential motion that creates energy (a block ratchets down an incline it should stick on).
// Updating the force by K_t(delta) v_t dt (hypoelastic) leaves F_el untouched while nothing
// slides. Each step F_el is rotated into the tangent plane, F_el -= K_t v_t dt; above mu F_n it
// is rescaled to the cap (slip, dashpot off), else the dashpot -c_t v_t is added and the total
// capped at mu F_n. Forces act on the body whose velocity relative to the other is relVel
// (n points from the other body towards it). meff [kg] sets the dashpots. The caller checks
// 0 < delta < R.
template <typename T>
MPM_HD_INLINE BarrierCoulombResult<T> barrierCoulomb(const BarrierCoulombPhys<T>& ph, T R, T delta,
                                                     const Vec3T<T>& n, const Vec3T<T>& relVel, T meff, T dt,
                                                     T fEl[3]) {
  BarrierCoulombResult<T> r;
  r.kn = barrierStiffness(ph.kc, R, delta);
  r.kt = r.kn / (T(2) * (T(1) + ph.nu));
  r.barrierEnergy = barrierPotential(ph.kc, R, delta);
  const T vn = mpmsdem::dot(relVel, n);
  const T cn = T(2) * ph.zetaN * mpmsdem::hdSqrt(meff * r.kn);
  const T fElastic = barrierForce(ph.kc, R, delta);
  const T fn = fElastic - cn * vn;
  r.normalForce = fn > T(0) ? fn : T(0);
  r.dampingWork = (r.normalForce - fElastic) * -vn * dt;
  const Vec3T<T> vt = relVel - vn * n;
  // Rotation keeps |F_el|: turning the contact plane does no work on the spring.
  rotateTangentialHistory(fEl, n);
  for (int d = 0; d < 3; ++d) fEl[d] -= r.kt * vt[d] * dt;
  const Vec3T<T> fSpring{fEl[0], fEl[1], fEl[2]};
  const T cap = ph.mu * r.normalForce;
  const T fSpringNorm = norm(fSpring);
  r.frictionWork = T(0);
  if (fSpringNorm > cap) {
    r.sliding = true;
    const T ratio = fSpringNorm > T(0) ? cap / fSpringNorm : T(0);
    // The part of the trial increment beyond the cap is slip: (|F_trial| - cap) / K_t of
    // distance at the cap force.
    r.frictionWork = r.kt > T(0) ? cap * (fSpringNorm - cap) / r.kt : T(0);
    for (int d = 0; d < 3; ++d) fEl[d] *= ratio;
    r.tangential = Vec3T<T>{fEl[0], fEl[1], fEl[2]};
  } else {
    r.sliding = false;
    const T ct = T(2) * ph.zetaT * mpmsdem::hdSqrt(meff * r.kt);
    Vec3T<T> ft = fSpring - ct * vt;
    const T ftNorm = norm(ft);
    if (ftNorm > cap) ft = (cap / ftNorm) * ft;
    r.tangential = ft;
    r.dampingWork += -mpmsdem::dot(ft - fSpring, vt) * dt;
  }
  const T f2 = fEl[0] * fEl[0] + fEl[1] * fEl[1] + fEl[2] * fEl[2];
  r.springEnergy = r.kt > T(0) ? f2 / (T(2) * r.kt) : T(0);
  return r;
}

}  // namespace sdem
}  // namespace mpmsdem
