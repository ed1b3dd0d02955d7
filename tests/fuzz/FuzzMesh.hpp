// The mesh path of mpm::parseScene (parseMesh) for the OBJ and STL targets: read the file
// (io::readMesh) and check it as a body to seed (mpm::checkSeedMesh, its closedness and
// orientation) in a grid of 1 m^3 around the origin, as a scene's "particles": [{"mesh": ...}]
// entry does. A mesh the reader returns must have finite vertices and triangles that index them
// (what "well-formed" promises, MeshReader.hpp): anything else aborts as a finding.
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "FuzzInput.hpp"
#include "input/MeshReader.hpp"
#include "mpm/MpmTypes.hpp"
#include "mpm/Seeding.hpp"

namespace mpmsdem {
namespace fuzz {

inline void readAndCheckMesh(const std::string& name, const std::uint8_t* data, std::size_t size) {
  const std::string path = inputFile(name, data, size);
  expectOnlyDocumentedErrors([&] {
    const io::TriangleMesh mesh = io::readMesh(path, 1.0);
    for (const Vec3& v : mesh.vertices)
      if (!v.allFinite()) {
        std::fprintf(stderr, "readMesh returned a non-finite vertex\n");
        std::abort();
      }
    for (const auto& t : mesh.triangles)
      for (int i : t)
        if (i < 0 || i >= static_cast<int>(mesh.vertices.size())) {
          std::fprintf(stderr, "readMesh returned a triangle with vertex index %d of %zu\n", i, mesh.vertices.size());
          std::abort();
        }
    mpm::MpmParams p;
    p.dx = 0.01;
    p.cells = {100, 100, 100};
    p.origin = {-0.5, -0.5, -0.5};
    (void)mpm::checkSeedMesh(p, mesh.vertices, mesh.triangles, path);
  });
}

}  // namespace fuzz
}  // namespace mpmsdem
