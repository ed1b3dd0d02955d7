// Binding of the SDEM shape (SpheroPolyhedron): factories and read-only geometry.
#include "PyConvert.hpp"
#include "sdem/SpheroPolyhedron.hpp"

namespace mpmsdem {
namespace py {

using sdem::SpheroPolyhedron;
using ShapePtr = std::shared_ptr<SpheroPolyhedron>;

namespace {

std::vector<Vec3> toPoints(const bp::object& seq, const char* name) {
  std::vector<Vec3> out;
  const long n = bp::len(seq);
  out.reserve(n);
  for (long i = 0; i < n; ++i) out.push_back(toVec3(seq[i], name));
  return out;
}

ShapePtr makeBox(const bp::object& halfExtents, double R) {
  return SpheroPolyhedron::box(toVec3(halfExtents, "halfExtents"), R);
}
ShapePtr makeHull(const bp::object& points, double R) {
  return SpheroPolyhedron::convexHull(toPoints(points, "points"), R);
}
ShapePtr makeMesh(const bp::object& vertices, const bp::object& triangles, double R) {
  std::vector<std::array<int, 3>> tris;
  const long n = bp::len(triangles);
  for (long i = 0; i < n; ++i) {
    bp::object t = triangles[i];
    if (bp::len(t) != 3) throw ParameterError("triangles: each triangle must have 3 vertex indices");
    tris.push_back({bp::extract<int>(t[0]), bp::extract<int>(t[1]), bp::extract<int>(t[2])});
  }
  return SpheroPolyhedron::mesh(toPoints(vertices, "vertices"), tris, R);
}
ShapePtr makeMeshFile(const std::string& path, double R, double scale) {
  return SpheroPolyhedron::meshFile(path, R, scale);
}

bp::list vecList(const std::vector<Vec3>& v) {
  bp::list l;
  for (const auto& x : v) l.append(x);
  return l;
}
bp::list coreVertices(const SpheroPolyhedron& s) { return vecList(s.vertices); }
bp::list outerVertices(const SpheroPolyhedron& s) { return vecList(s.outerVertices); }
bp::list outerTriangles(const SpheroPolyhedron& s) {
  bp::list l;
  for (const auto& t : s.outerTriangles) l.append(bp::make_tuple(t[0], t[1], t[2]));
  return l;
}
bp::list coreFaces(const SpheroPolyhedron& s) {
  bp::list l;
  for (const auto& f : s.faces) {
    bp::list loop;
    for (int i : f.loop) loop.append(i);
    l.append(loop);
  }
  return l;
}
bp::list coreEdges(const SpheroPolyhedron& s) {
  bp::list l;
  for (const auto& e : s.edges) l.append(bp::make_tuple(e.v0, e.v1));
  return l;
}
bp::tuple closestPoint(const SpheroPolyhedron& s, const bp::object& p) {
  const auto q = s.closestPoint(toVec3(p, "point"));
  static const char* kinds[] = {"face", "edge", "vertex"};
  return bp::make_tuple(q.distance, q.closest, kinds[q.featureKind], q.featureIndex);
}
double volume(const SpheroPolyhedron& s) { return s.volume; }
Vec3 inertiaPerDensity(const SpheroPolyhedron& s) { return s.inertiaPerDensity; }
double sweepRadius(const SpheroPolyhedron& s) { return s.sweepRadius; }
bool isConvex(const SpheroPolyhedron& s) { return s.convex; }
Vec3 framePosition(const SpheroPolyhedron& s) { return s.framePosition; }
Quat frameOrientation(const SpheroPolyhedron& s) { return s.frameOrientation; }
double boundingRadius(const SpheroPolyhedron& s) { return s.boundingRadius; }

}  // namespace

void exportShapes() {
  bp::class_<SpheroPolyhedron, ShapePtr, boost::noncopyable>(
      "SpheroPolyhedron",
      "Sphero-polyhedron shape (paper §2.2): eroded core polyhedron + sweep sphere of radius R.\n"
      "Geometry is in the body frame (origin at the rounded body's centroid, principal axes).\n"
      "Build with SpheroPolyhedron.box / .convexHull / .mesh / .meshFile.",
      bp::no_init)
      .def("box", &makeBox, (bp::arg("halfExtents"), bp::arg("sweepRadius")),
           "Rounded box of OUTER half-extents [m]; core half-extents = halfExtents - R; 0 < R < min(halfExtents).")
      .staticmethod("box")
      .def("convexHull", &makeHull, (bp::arg("points"), bp::arg("sweepRadius")),
           "Rounded convex hull of points [m] (the outer shape), eroded by R.")
      .staticmethod("convexHull")
      .def("mesh", &makeMesh, (bp::arg("vertices"), bp::arg("triangles"), bp::arg("sweepRadius")),
           "Closed, outward-oriented triangle mesh (non-convex allowed) as the outer shape, eroded by R.")
      .staticmethod("mesh")
      .def("meshFile", &makeMeshFile, (bp::arg("path"), bp::arg("sweepRadius"), bp::arg("scale") = 1.0),
           "Closed triangle mesh from an STL (ascii/binary) or OBJ file; coordinates multiplied by scale.")
      .staticmethod("meshFile")
      .add_property("volume", &volume, "Volume of the rounded body [m^3].")
      .add_property("inertiaPerDensity", &inertiaPerDensity, "Principal moments of inertia / density [m^5].")
      .add_property("sweepRadius", &sweepRadius, "Sweep radius R [m].")
      .add_property("convex", &isConvex, "True when the core is convex.")
      .add_property("framePosition", &framePosition,
                    "Body-frame origin (rounded centroid) in the frame the shape was described in [m].")
      .add_property("frameOrientation", &frameOrientation,
                    "Rotation from the body frame (principal axes) to the frame the shape was described in.")
      .add_property("boundingRadius", &boundingRadius, "Radius of a sphere around the centroid enclosing the body [m].")
      .def("coreVertices", &coreVertices, "Core vertices in the body frame [m].")
      .def("coreFaces", &coreFaces, "Core faces as vertex-index loops (outward, counter-clockwise).")
      .def("coreEdges", &coreEdges, "Core edges (ridges and valleys) as vertex-index pairs.")
      .def("outerVertices", &outerVertices, "Vertices of the outer shape P in the body frame [m] (display).")
      .def("outerTriangles", &outerTriangles, "Triangles of the outer shape P (display).")
      .def("closestPoint", &closestPoint, (bp::arg("point")),
           "(distance, closest point, 'face'|'edge'|'vertex', index) of the core to a body-frame point.")
      .def("coreMinWidth", &SpheroPolyhedron::coreMinWidth, "Minimal width of the core over face normals [m].");
}

}  // namespace py
}  // namespace mpmsdem
