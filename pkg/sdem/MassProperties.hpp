// Mass properties of a rounded sphero-polyhedron (paper §2.2; docs/physics.md).
// The rounded body is the Minkowski sum of the core polyhedron S and a ball of radius R.
// It is split into disjoint pieces whose moments are integrated in closed form:
//   core polyhedron            signed tetrahedra from the origin (exact, any closed core)
//   face slabs                 prism of height R over each face along its outward normal
//   ridge (convex) edge wedges cylindrical sector of radius R, angle = angle between the
//                              two face normals, length = edge length
//   convex vertex sectors      ball sector of radius R over the vertex normal cone; its
//                              solid angle is the angle defect 2*pi - sum of face corner
//                              angles, its first and second moments come from boundary
//                              integrals over the cone's great-circle arcs (exact)
//   valley (concave) edges     no wedge; the two adjacent slabs overlap in a prism of the
//                              edge length over a quadrilateral cross-section, subtracted.
//   reflex corners             where a valley edge meets a cap plane at a right angle
//                              (extruded shapes), the two ridge wedges along the cap edges
//                              overlap; that overlap is subtracted (closed-form inner
//                              integral, Gauss quadrature outer, round-off accurate).
// Accuracy: exact to round-off (~1e-15 relative) for convex cores and for non-convex cores
// whose valley edges end on caps perpendicular to them (prisms/extrusions of any polygon).
// At other vertices touching a valley edge (saddle-like vertices of general meshes) no
// sector is added and the overlap of the wedges meeting there is not subtracted: the error
// is O(R^3) per such vertex, i.e. a relative error of order (R/h)^3 for a body of size h.
#pragma once
#include "common/Types.hpp"

namespace mpmsdem {
namespace sdem {

struct SpheroPolyhedron;

// Raw moments of a region: m0 = integral of 1 [m^3], m1 = integral of x [m^4],
// m2 = integral of x x^T [m^5], in the frame the geometry is expressed in.
struct Moments {
  Real m0 = 0;
  Vec3 m1 = Vec3::Zero();
  Mat3 m2 = Mat3::Zero();
  Moments& operator+=(const Moments& o) {
    m0 += o.m0;
    m1 += o.m1;
    m2 += o.m2;
    return *this;
  }
  Moments& operator-=(const Moments& o) {
    m0 -= o.m0;
    m1 -= o.m1;
    m2 -= o.m2;
    return *this;
  }
};

// Moments of the rounded body described by s.vertices, s.faces, s.edges (with their convex
// flags), s.vertexEdges and s.sweepRadius, in the frame those are expressed in.
Moments roundedBodyMoments(const SpheroPolyhedron& s);

// Inertia tensor per unit density [m^5] about the point c, from raw moments:
// J = integral of (x-c)(x-c)^T = m2 - m1 c^T - c m1^T + m0 c c^T, I = trace(J) Id - J.
Mat3 inertiaAbout(const Moments& m, const Vec3& c);

}  // namespace sdem
}  // namespace mpmsdem
