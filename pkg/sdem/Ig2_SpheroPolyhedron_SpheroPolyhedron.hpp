// Ig2_SpheroPolyhedron_SpheroPolyhedron: narrow-phase contact geometry between two
// sphero-polyhedra (paper §2.2, Fig 3, Eq 7; docs/physics.md).
//
// Core feature pairs are enumerated (vertex–face both ways, edge–edge, vertex–edge both
// ways, vertex–vertex); a pair is a contact when its core distance d < R_A + R_B and it
// passes the rules below, which make each geometric contact count once:
//  - vertex–face: the vertex lies strictly in front of the face and projects inside the
//    closed face polygon, and either the vertex belongs to a face of its own body that is
//    nearly anti-parallel to the other face (normals' dot product <= -patchCosine: the two
//    faces form a contact patch, whose corners are the vertices of the clipped intersection
//    polygon of the faces) or the contact normal lies in the vertex's normal cone;
//  - edge–edge: both closest points interior to their (closed) edges, edges not parallel,
//    both edges convex (valleys never carry a contact), and either each edge bounds a face
//    nearly anti-parallel to a face bounded by the other, facing it (a crossing of the two
//    faces' boundaries: a corner of their contact patch, kept while the faces tilt) or the
//    normal lies in both edges' normal cones;
//  - vertex–edge and vertex–vertex: the normal in the normal cones of both features.
// All these tests use a length tolerance tol = 1e-9 x the larger bounding radius, and
// contacts of one pair whose two core points both coincide within 4 tol are merged (the
// first enumerated survives: vertex–face, face–vertex, edge–edge, vertex–edge, edge–vertex,
// vertex–vertex). Two aligned equal cubes face to face give 4 contacts, a cube face-down on
// a slab 4 at any yaw, edge-down 2, corner-down 1.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "sdem/SpheroPolyhedron.hpp"

namespace mpmsdem {
namespace sdem {

// Kind of a core feature; numbering matches SpheroPolyhedron::PointQuery::featureKind.
enum class FeatureKind : std::int8_t { Face = 0, Edge = 1, Vertex = 2 };

// One contact between bodies A and B (world frame).
struct SdemGeom {
  FeatureKind kindA = FeatureKind::Vertex;  // feature of A's core carrying the contact
  FeatureKind kindB = FeatureKind::Face;    // feature of B's core
  int indexA = -1;                          // index of that feature in A's shape
  int indexB = -1;                          // index in B's shape
  Vec3 pointA = Vec3::Zero();               // closest point on A's core [m]
  Vec3 pointB = Vec3::Zero();               // closest point on B's core [m]
  Vec3 normal = Vec3::UnitX();              // unit normal from pointA to pointB
  Real distance = 0;                        // core distance d [m], 0 < d < R_A + R_B
  Real overlap = 0;                         // delta = R_A + R_B - d [m] (Eq 7)
  Vec3 contactPoint = Vec3::Zero();         // midway between the two sphere surfaces [m]

  // The contact of feature (ka, ia) of A with (kb, ib) of B at core points pa and pb, d apart
  // along the unit normal n (from A to B), for sweep radii RA and RB.
  static SdemGeom of(FeatureKind ka, int ia, FeatureKind kb, int ib, const Vec3& pa, const Vec3& pb, const Vec3& n,
                     Real d, Real RA, Real RB) {
    SdemGeom g;
    g.kindA = ka;
    g.indexA = ia;
    g.kindB = kb;
    g.indexB = ib;
    g.pointA = pa;
    g.pointB = pb;
    g.normal = n;
    g.distance = d;
    g.overlap = RA + RB - d;
    g.contactPoint = 0.5 * (pa + RA * n + pb - RB * n);  // sphere surfaces pa + RA n (A's), pb - RB n (B's)
    return g;
  }
};

// A core edge as a segment: from p0 along the unit direction t for length L [m].
struct EdgeSegment {
  Vec3 p0;
  Vec3 t;
  Real L;
};

// The points of segments a and b that coincide when seen along the unit direction na (a contact
// patch's normal), clamped to the segments. False when the two are parallel in the plane
// normal to na (|(ta x tb) . na| cutoff <= tol) or the crossing lies beyond either segment by
// more than tol.
inline bool crossingAlong(const EdgeSegment& a, const EdgeSegment& b, const Vec3& na, Real cutoff, Real tol, Vec3& pa,
                          Vec3& pb) {
  const Real den = a.t.cross(b.t).dot(na);
  if (std::abs(den) * cutoff <= tol) return false;
  const Vec3 r = b.p0 - a.p0;
  const Real s = r.cross(b.t).dot(na) / den;
  const Real t = r.cross(a.t).dot(na) / den;
  if (s < -tol || s > a.L + tol || t < -tol || t > b.L + tol) return false;
  pa = a.p0 + std::clamp(s, Real(0), a.L) * a.t;
  pb = b.p0 + std::clamp(t, Real(0), b.L) * b.t;
  return true;
}

// The closest points of the lines of segments a and b, clamped to the segments. False when the
// two are parallel (sin(angle) cutoff <= tol) or the closest points lie beyond either segment by
// more than tol.
inline bool closestOfSegments(const EdgeSegment& a, const EdgeSegment& b, Real cutoff, Real tol, Vec3& pa, Vec3& pb) {
  const Real sin2 = a.t.cross(b.t).squaredNorm();
  if (sin2 * cutoff * cutoff <= tol * tol) return false;
  const Vec3 r = b.p0 - a.p0;
  const Real cosab = a.t.dot(b.t), da = a.t.dot(r), db = b.t.dot(r);
  const Real s = (da - cosab * db) / sin2;
  const Real t = (cosab * da - db) / sin2;
  if (s < -tol || s > a.L + tol || t < -tol || t > b.L + tol) return false;
  pa = a.p0 + std::clamp(s, Real(0), a.L) * a.t;
  pb = b.p0 + std::clamp(t, Real(0), b.L) * b.t;
  return true;
}

// A shape placed in the world: the world-frame copies of its core data the narrow phase
// needs, recomputed by update() when the pose changes.
struct PosedSpheroPolyhedron {
  const SpheroPolyhedron* shape = nullptr;
  Vec3 pos = Vec3::Zero();          // centroid [m]
  Quat ori = Quat::Identity();      // x_world = pos + ori * x_body
  std::vector<Vec3> vertices;       // world core vertices [m]
  std::vector<Vec3> faceNormals;    // world unit outward normals
  std::vector<Real> faceOffsets;    // n . x on the face plane [m]
  std::vector<Vec3> faceLo, faceHi; // per-face AABB [m]
  std::vector<Vec3> edgeDir;        // unit direction v0 -> v1
  std::vector<Real> edgeLength;     // [m]
  std::vector<Vec3> edgeIn0, edgeIn1;  // unit in-face directions perpendicular to the edge,
                                       // pointing into face f0 / f1
  Vec3 coreLo = Vec3::Zero(), coreHi = Vec3::Zero();  // AABB of the core [m]

  // (Re)compute everything above for `s` at pose (pos, ori). `s` must outlive this object.
  void update(const SpheroPolyhedron& s, const Vec3& pos, const Quat& ori);
};

class Ig2_SpheroPolyhedron_SpheroPolyhedron {
 public:
  // Faces of the two bodies whose outward normals satisfy nA . nB <= -patchCosine are
  // treated as a contact patch (see the header comment). 0.9 (about 26 degrees of relative
  // tilt) is far beyond the tilt at which the far corners of a face leave the cutoff
  // 2R for any face wider than 5R.
  static constexpr Real patchCosine = 0.9;

  // Append the contacts between A and B to `out`. Returns false (and appends nothing) when
  // the cores interpenetrate, their interiors overlapping by more than tolerance(): the
  // caller must stop the run (time step too large for the barrier, or bodies created
  // overlapping). Decided when the core boxes overlap: for two convex cores by the
  // separating-axis test (face normals, and cross products of edge pairs that form faces of
  // the Minkowski difference); otherwise by a vertex inside a convex core, a face side
  // through a face, coplanar faces with the same outward normal overlapping over an area, or
  // one core inside the other. Touching cores (gap 0) are not interpenetrating.
  static bool go(const PosedSpheroPolyhedron& A, const PosedSpheroPolyhedron& B, std::vector<SdemGeom>& out);

  // Length tolerance of the feature tests for this pair [m].
  static Real tolerance(const PosedSpheroPolyhedron& A, const PosedSpheroPolyhedron& B);
};

}  // namespace sdem
}  // namespace mpmsdem
