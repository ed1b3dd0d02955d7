#include "sdem/ShapeTable.hpp"

namespace mpmsdem {
namespace sdem {

int ShapeTable::add(const SpheroPolyhedron& s) {
  const int v0 = shapeVertexStart.back(), e0 = shapeEdgeStart.back();
  for (const Vec3& v : s.vertices)
    for (int d = 0; d < 3; ++d) vertex.push_back(v[d]);
  for (std::size_t f = 0; f < s.faces.size(); ++f) {
    const CoreFace& F = s.faces[f];
    for (int d = 0; d < 3; ++d) faceNormal.push_back(F.normal[d]);
    faceOffset.push_back(F.offset);
    for (std::size_t i = 0; i < F.loop.size(); ++i) {
      loopVertex.push_back(v0 + F.loop[i]);
      const int e = s.faceEdges[f][i];
      loopEdge.push_back(e >= 0 ? e0 + e : -1);
    }
    faceLoopStart.push_back(static_cast<int>(loopVertex.size()));
  }
  shapeFaceStart.push_back(static_cast<int>(faceOffset.size()));
  shapeVertexStart.push_back(v0 + static_cast<int>(s.vertices.size()));
  shapeEdgeStart.push_back(e0 + static_cast<int>(s.edges.size()));
  sweepRadius.push_back(s.sweepRadius);
  boundingRadius.push_back(s.boundingRadius);
  convex.push_back(s.convex ? 1 : 0);
  return size() - 1;
}

ShapeTableView<double> ShapeTable::view() const {
  return {size(),
          vertex.data(),
          faceNormal.data(),
          faceOffset.data(),
          faceLoopStart.data(),
          loopVertex.data(),
          loopEdge.data(),
          shapeFaceStart.data(),
          shapeVertexStart.data(),
          shapeEdgeStart.data(),
          sweepRadius.data(),
          boundingRadius.data(),
          convex.data()};
}

}  // namespace sdem
}  // namespace mpmsdem
