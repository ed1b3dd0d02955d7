// SpheroPolyhedron: the SDEM shape (paper §2.2, Fig 2; docs/physics.md).
// A block of outer shape P is the Minkowski sum of an eroded core S (P shrunk by R)
// and a sphere of radius R. All geometry here is in the BODY frame: origin at the
// centroid of the rounded body, axes along its principal axes of inertia.
#pragma once
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "common/Types.hpp"

namespace mpmsdem {
namespace sdem {

// A planar face of the core. Convex polygon, vertex loop counter-clockwise seen from
// outside (right-hand rule gives the outward normal).
struct CoreFace {
  std::vector<int> loop;  // indices into SpheroPolyhedron::vertices
  Vec3 normal;            // unit outward normal (body frame)
  Real offset;            // plane: normal.dot(x) == offset for x on the face
};

// An edge of the core between two faces that are not coplanar (a ridge or a valley).
struct CoreEdge {
  int v0, v1;       // vertex indices
  int f0, f1;       // adjacent faces (f0 sees v0->v1 in its loop, f1 sees v1->v0)
  bool convex;      // true: dihedral angle < pi seen from inside (a ridge)
};

struct SpheroPolyhedron {
  // ---- core geometry (body frame)
  std::vector<Vec3> vertices;                 // core vertices [m]
  std::vector<CoreEdge> edges;                // ridges/valleys; flat diagonals are not edges
  std::vector<CoreFace> faces;                // planar convex polygons
  std::vector<std::vector<int>> vertexEdges;  // per vertex, indices of incident edges
  // per face, per loop side i (loop[i] -> loop[i+1]): index into edges, or -1 when that side
  // lies between two coplanar triangles of a non-convex mesh (a flat diagonal, not an edge)
  std::vector<std::vector<int>> faceEdges;
  Real sweepRadius = 0;                       // R [m], the Minkowski sphere radius (paper Eq 7)
  bool convex = true;                         // core is a convex polyhedron

  // ---- mass properties of the ROUNDED body, per unit density
  Real volume = 0;                    // [m^3]
  Vec3 inertiaPerDensity = Vec3::Zero();  // principal moments / density [m^5], body frame

  // ---- outer shape P in the body frame (what the user described; used for display)
  std::vector<Vec3> outerVertices;
  std::vector<std::array<int, 3>> outerTriangles;

  // ---- pose of the body frame in the frame the user described the shape in:
  // x_input = framePosition + frameOrientation * x_body
  Vec3 framePosition = Vec3::Zero();
  Quat frameOrientation = Quat::Identity();

  Real boundingRadius = 0;  // max |vertex| + R: radius of a sphere enclosing the rounded body [m]

  // ---- factories. Each one erodes P by R (core), then computes everything above.
  // Throw ParameterError naming the parameter and its allowed range on bad input
  // (R <= 0 or R >= half the thinnest dimension, degenerate/open mesh, ...).
  //
  // box: halfExtents = OUTER half-extents of P [m], each > 0; R in (0, min(halfExtents)).
  //   Core = box of half-extents halfExtents - R. Body frame = input frame.
  // convexHull: points [m] = P's corners (interior points allowed), at least 4 not coplanar.
  //   Coplanar hull triangles are merged into polygon faces; core = intersection of P's face
  //   planes moved in by R (faces of P may vanish from the core when R is large);
  //   R in (0, min(inradius of P, half its min width over face normals)).
  // mesh: closed, consistently oriented (counter-clockwise seen from outside) triangle mesh of
  //   P [m], non-convex allowed; every edge in exactly two triangles, no zero-area triangle,
  //   one connected surface (a mesh of several parts is refused: one body per part).
  //   A convex mesh takes the convexHull path. Otherwise faces = triangles (sides between
  //   coplanar triangles are not edges), each vertex moves so that each distinct incident
  //   face plane moves in by R (least squares; exact where at most 3 distinct planes meet),
  //   and R must stay below half of every wall thickness (rays from face centroids) with no
  //   eroded triangle flipping.
  // meshFile: path = .stl (ASCII/binary) or .obj file, scale = factor from file units to m
  //   (> 0, e.g. 1e-3 for millimetres); then as mesh.
  // Mass properties: see MassProperties.hpp (exact for convex cores and extruded shapes).
  static std::shared_ptr<SpheroPolyhedron> box(const Vec3& halfExtents, Real R);
  static std::shared_ptr<SpheroPolyhedron> convexHull(const std::vector<Vec3>& points, Real R);
  static std::shared_ptr<SpheroPolyhedron> mesh(const std::vector<Vec3>& vertices,
                                                const std::vector<std::array<int, 3>>& triangles, Real R);
  static std::shared_ptr<SpheroPolyhedron> meshFile(const std::string& path, Real R, Real scale = 1.0);
  // fromCore: a shape table, as the factories above made it (how the driver's scene files carry
  //   blocks to machines without CGAL): core vertices [m], faces as vertex loops counter-clockwise
  //   seen from outside (planar polygons, convex cores; triangles, non-convex ones), R [m] > 0,
  //   whether the core is convex, and optionally the outer shape for display (else the core's
  //   faces). Refused with a ParameterError naming the entry: indices out of range, a face that
  //   is not planar or has no area, a surface that is not closed and consistently oriented, an
  //   inward-oriented surface, a core flagged convex that is not. Needs no CGAL. Topology, mass
  //   properties and the body frame are computed as by the other factories: a table taken in a
  //   body frame comes back in that frame (framePosition, frameOrientation = identity, to
  //   round-off).
  static std::shared_ptr<SpheroPolyhedron> fromCore(const std::vector<Vec3>& vertices,
                                                    const std::vector<std::vector<int>>& faces, Real R, bool convex,
                                                    const std::vector<Vec3>& outerVertices = {},
                                                    const std::vector<std::array<int, 3>>& outerTriangles = {});

  // Closest point of the CORE to a point p given in the body frame.
  // Returns the distance d >= 0 (0 if p is inside the core), the closest point, the feature
  // kind hit (0 = face interior, 1 = edge, 2 = vertex) and its index.
  // Inside the core: distance 0, closest = p, and the feature is the nearest surface feature.
  // Cost: linear in the number of faces.
  struct PointQuery {
    Real distance;
    Vec3 closest;
    int featureKind;
    int featureIndex;
  };
  PointQuery closestPoint(const Vec3& p) const;

  // Minimal width of the core over the face-normal directions [m]: min over faces of
  // (offset - min over vertices of normal.x), the extent of the core along that normal
  // (for a non-convex core an upper bound of its thinnest wall).
  Real coreMinWidth() const;
};

}  // namespace sdem
}  // namespace mpmsdem
