// ShapeTable: the flat, backend-neutral copy of a set of SpheroPolyhedron cores that the shared
// __host__ __device__ queries of SdemKernelsCommon.hpp read (closest core point of a material
// point, feature hit). Built once on the host from the shapes; CUDA uploads the same arrays.
#pragma once
#include <cstdint>
#include <vector>

#include "sdem/SdemKernelsCommon.hpp"
#include "sdem/SpheroPolyhedron.hpp"

namespace mpmsdem {
namespace sdem {

class ShapeTable {
 public:
  // Append a shape; returns its index in the table.
  int add(const SpheroPolyhedron& shape);
  int size() const { return static_cast<int>(sweepRadius.size()); }
  // A view over the double arrays (CPU).
  ShapeTableView<double> view() const;

  // The arrays of ShapeTableView, double precision (see there for their meaning).
  std::vector<double> vertex, faceNormal, faceOffset, sweepRadius, boundingRadius;
  std::vector<int> faceLoopStart{0}, loopVertex, loopEdge, shapeFaceStart{0}, shapeVertexStart{0}, shapeEdgeStart{0};
  std::vector<std::uint8_t> convex;
};

}  // namespace sdem
}  // namespace mpmsdem
