#include "coupling/LevelSetSurface.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <unordered_map>

namespace mpmsdem {
namespace coupling {

namespace {

// Corner c of a cell as offsets (bit 0: +x, bit 1: +y, bit 2: +z), numbered so that the six
// tetrahedra below all share the diagonal from corner 0 to corner 7.
constexpr int kTets[6][4] = {{0, 1, 3, 7}, {0, 3, 2, 7}, {0, 2, 6, 7}, {0, 6, 4, 7}, {0, 4, 5, 7}, {0, 5, 1, 7}};

class Mesher {
 public:
  Mesher(const LevelSetGrid& g, io::RigidSurface& out) : g_(g), out_(out) {}

  void cell(int i, int j, int k) {
    long node[8];
    for (int c = 0; c < 8; ++c) node[c] = index(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
    for (const auto& t : kTets) tetrahedron({node[t[0]], node[t[1]], node[t[2]], node[t[3]]});
  }

 private:
  long index(int i, int j, int k) const { return (static_cast<long>(i) * g_.nGP[1] + j) * g_.nGP[2] + k; }
  Vec3 position(long n) const {
    const long k = n % g_.nGP[2], j = (n / g_.nGP[2]) % g_.nGP[1], i = n / (static_cast<long>(g_.nGP[1]) * g_.nGP[2]);
    return g_.min + g_.spacing * Vec3(double(i), double(j), double(k));
  }
  bool inside(long n) const { return g_.dist[n] < 0; }

  // The vertex where phi crosses zero on the edge from inside node a to outside node b.
  int vertex(long a, long b) {
    const std::uint64_t total = std::uint64_t(g_.dist.size());
    const std::uint64_t key = std::uint64_t(std::min(a, b)) * total + std::uint64_t(std::max(a, b));
    const auto found = vertexOf_.find(key);
    if (found != vertexOf_.end()) return found->second;
    const double t = g_.dist[a] / (g_.dist[a] - g_.dist[b]);
    const Vec3 p = position(a) + t * (position(b) - position(a));
    out_.vertices.push_back({p[0], p[1], p[2]});
    const int v = static_cast<int>(out_.vertices.size()) - 1;
    vertexOf_.emplace(key, v);
    return v;
  }

  Vec3 at(int v) const { return Vec3(out_.vertices[v][0], out_.vertices[v][1], out_.vertices[v][2]); }

  // Adds triangle (a, b, c), wound so that its normal has a positive part along `outward`.
  void triangle(int a, int b, int c, const Vec3& outward) {
    const Vec3 n = (at(b) - at(a)).cross(at(c) - at(a));
    if (n.dot(outward) < 0) std::swap(b, c);
    out_.triangles.push_back({a, b, c});
  }

  void tetrahedron(const std::array<long, 4>& v) {
    long in[4], out[4];
    int nIn = 0, nOut = 0;
    for (long n : v) (inside(n) ? in[nIn++] : out[nOut++]) = n;
    if (nIn == 0 || nOut == 0) return;
    if (nIn == 1 || nOut == 1) {  // one corner cut off: a triangle across its three edges
      const bool lone = nIn == 1;
      const long a = lone ? in[0] : out[0];
      const long* others = lone ? out : in;
      int e[3];
      for (int m = 0; m < 3; ++m) e[m] = lone ? vertex(a, others[m]) : vertex(others[m], a);
      const Vec3 centroid = (at(e[0]) + at(e[1]) + at(e[2])) / 3.0;
      triangle(e[0], e[1], e[2], lone ? Vec3(centroid - position(a)) : Vec3(position(a) - centroid));
      return;
    }
    // two in, two out: a quadrilateral across the four edges between them, in cyclic order
    const int q[4] = {vertex(in[0], out[0]), vertex(in[0], out[1]), vertex(in[1], out[1]), vertex(in[1], out[0])};
    const Vec3 outward = position(out[0]) + position(out[1]) - position(in[0]) - position(in[1]);
    triangle(q[0], q[1], q[2], outward);
    triangle(q[0], q[2], q[3], outward);
  }

  const LevelSetGrid& g_;
  io::RigidSurface& out_;
  std::unordered_map<std::uint64_t, int> vertexOf_;
};

}  // namespace

io::RigidSurface levelSetSurface(const LevelSetGrid& grid, int id) {
  io::RigidSurface s;
  s.id = id;
  Mesher m(grid, s);
  for (int i = 0; i + 1 < grid.nGP[0]; ++i)
    for (int j = 0; j + 1 < grid.nGP[1]; ++j)
      for (int k = 0; k + 1 < grid.nGP[2]; ++k) m.cell(i, j, k);
  return s;
}

io::RigidSurface placedSurface(const io::RigidSurface& local, const Vec3& pos, const Mat3& R) {
  io::RigidSurface s = local;
  for (auto& v : s.vertices) {
    const Vec3 w = pos + R * Vec3(v[0], v[1], v[2]);
    v = {w[0], w[1], w[2]};
  }
  return s;
}

}  // namespace coupling
}  // namespace mpmsdem
