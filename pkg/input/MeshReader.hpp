// Triangle-mesh readers for SDEM block shapes: STL (ASCII and binary) and Wavefront OBJ.
#pragma once
#include <array>
#include <string>
#include <vector>

#include "common/Types.hpp"

namespace mpmsdem {
namespace io {

struct TriangleMesh {
  std::vector<Vec3> vertices;                // [m] after scaling
  std::vector<std::array<int, 3>> triangles;  // vertex indices, counter-clockwise seen from outside
};

// Read a mesh; the format is chosen by the extension (.stl or .obj, any case).
// Vertices with identical coordinates are merged into one (STL stores each triangle's
// corners separately; some OBJ exporters duplicate vertices along seams), so that the mesh
// is indexed as the closedness check needs.
// OBJ polygons with more than three corners are split into a fan of triangles.
// scale multiplies every coordinate (e.g. 0.001 for a file in millimetres); must be > 0.
// Throws ParameterError naming `path` (missing/unreadable file, unknown extension,
// malformed content) or `scale`.
TriangleMesh readMesh(const std::string& path, Real scale = 1.0);

}  // namespace io
}  // namespace mpmsdem
