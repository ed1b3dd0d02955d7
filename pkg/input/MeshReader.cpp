// STL/OBJ readers (see MeshReader.hpp).
#include "input/MeshReader.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include "common/Error.hpp"

namespace mpmsdem {
namespace io {
namespace {

[[noreturn]] void badFile(const std::string& path, const std::string& why) {
  throwParameter("path", "'" + path + "'", "", "a readable, well-formed .stl or .obj triangle mesh (" + why + ")");
}

// Indexes corners, merging those with identical coordinates.
struct VertexMerger {
  std::map<std::array<Real, 3>, int> index;
  TriangleMesh* mesh;
  int add(const Vec3& p) {
    const std::array<Real, 3> key{p.x(), p.y(), p.z()};
    auto it = index.find(key);
    if (it != index.end()) return it->second;
    const int id = static_cast<int>(mesh->vertices.size());
    mesh->vertices.push_back(p);
    index.emplace(key, id);
    return id;
  }
};

TriangleMesh readStl(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) badFile(path, "cannot open the file");
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  TriangleMesh mesh;
  VertexMerger merger{{}, &mesh};
  uint32_t count = 0;
  if (bytes.size() >= 84) std::memcpy(&count, bytes.data() + 80, 4);
  if (bytes.size() >= 84 && bytes.size() == 84 + 50ull * count) {  // binary STL
    for (uint32_t t = 0; t < count; ++t) {
      const char* rec = bytes.data() + 84 + 50ull * t;
      std::array<int, 3> tri{};
      for (int c = 0; c < 3; ++c) {
        float xyz[3];
        std::memcpy(xyz, rec + 12 + 12 * c, 12);
        if (!std::isfinite(xyz[0]) || !std::isfinite(xyz[1]) || !std::isfinite(xyz[2]))
          badFile(path, "a non-finite coordinate (NaN or infinity) in triangle " + std::to_string(t) + " of the binary STL");
        tri[c] = merger.add(Vec3(xyz[0], xyz[1], xyz[2]));
      }
      mesh.triangles.push_back(tri);
    }
    return mesh;
  }
  std::istringstream text(bytes);
  std::string word;
  if (!(text >> word) || word != "solid") badFile(path, "neither binary STL nor ASCII STL starting with 'solid'");
  std::array<int, 3> tri{};
  int corner = 0;
  while (text >> word) {
    if (word == "vertex") {
      Vec3 p;
      if (!(text >> p.x() >> p.y() >> p.z())) badFile(path, "bad 'vertex' line");
      if (corner >= 3) badFile(path, "a facet with more than three vertices");
      tri[corner++] = merger.add(p);
    } else if (word == "endloop") {
      if (corner != 3) badFile(path, "a facet without three vertices");
      mesh.triangles.push_back(tri);
      corner = 0;
    }
  }
  if (corner != 0) badFile(path, "a facet without 'endloop' at the end of the file (a truncated file?)");
  if (mesh.triangles.empty()) badFile(path, "no facets");
  return mesh;
}

TriangleMesh readObj(const std::string& path) {
  std::ifstream in(path);
  if (!in) badFile(path, "cannot open the file");
  TriangleMesh mesh;
  VertexMerger merger{{}, &mesh};
  std::vector<int> merged;  // OBJ vertex number - 1 -> merged vertex index
  std::string line;
  int lineNo = 0;
  while (std::getline(in, line)) {
    ++lineNo;
    std::istringstream ls(line);
    std::string tag;
    if (!(ls >> tag)) continue;
    if (tag == "v") {
      Vec3 p;
      if (!(ls >> p.x() >> p.y() >> p.z())) badFile(path, "bad vertex on line " + std::to_string(lineNo));
      merged.push_back(merger.add(p));
    } else if (tag == "f") {
      std::vector<int> corners;
      std::string tok;
      while (ls >> tok) {
        // The vertex number before any '/' (v/vt/vn): a whole integer, 1 to n or -n to -1
        // (relative to the end). atoi took "1x" as 1 and wrapped 4294967297 into 1.
        const std::string number = tok.substr(0, tok.find('/'));
        char* end = nullptr;
        errno = 0;
        const long long idx = std::strtoll(number.c_str(), &end, 10);
        const long long n = static_cast<long long>(merged.size());
        if (number.empty() || *end != '\0' || errno == ERANGE || idx == 0 || idx > n || idx < -n)
          badFile(path, "face corner '" + tok.substr(0, 40) + "' on line " + std::to_string(lineNo) +
                            " is not a vertex number in [1, " + std::to_string(n) + "] or [-" + std::to_string(n) +
                            ", -1]");
        corners.push_back(merged[static_cast<std::size_t>(idx > 0 ? idx - 1 : n + idx)]);
      }
      if (corners.size() < 3) badFile(path, "face with fewer than 3 corners on line " + std::to_string(lineNo));
      for (size_t i = 1; i + 1 < corners.size(); ++i) mesh.triangles.push_back({corners[0], corners[i], corners[i + 1]});
    }
  }
  if (mesh.triangles.empty()) badFile(path, "no faces");
  return mesh;
}

}  // namespace

TriangleMesh readMesh(const std::string& path, Real scale) {
  if (!(scale > 0) || !std::isfinite(scale)) throwParameter("scale", scale, "", "finite and > 0");
  std::string ext = path.substr(path.find_last_of('.') == std::string::npos ? path.size() : path.find_last_of('.'));
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  TriangleMesh mesh;
  if (ext == ".stl") {
    mesh = readStl(path);
  } else if (ext == ".obj") {
    mesh = readObj(path);
  } else {
    badFile(path, "unknown extension, expected .stl or .obj");
  }
  for (Vec3& v : mesh.vertices) {
    v *= scale;
    if (!v.allFinite()) throwParameter("scale", scale, "", "such that the scaled coordinates of '" + path + "' stay finite");
  }
  return mesh;
}

}  // namespace io
}  // namespace mpmsdem
