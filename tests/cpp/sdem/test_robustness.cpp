// Robustness of the SDEM shape construction and narrow phase: canonical (repeatable) hull
// construction, rejection of meshes made of several disjoint parts, and detection of
// interpenetrating cores that have no vertex strictly inside the other core.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <fstream>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "common/Error.hpp"
#include "sdem/SpheroPolyhedron.hpp"

using namespace mpmsdem;
using namespace mpmsdem::sdem;

namespace {

std::uint64_t bits(Real x) {
  std::uint64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

// Every stored number compared by its bit pattern: equal values computed in a different
// order would differ in the last bits.
void expectBitIdentical(const SpheroPolyhedron& s, const SpheroPolyhedron& r, const std::string& what) {
  SCOPED_TRACE(what);
  auto same = [](const Vec3& a, const Vec3& b) {
    return bits(a.x()) == bits(b.x()) && bits(a.y()) == bits(b.y()) && bits(a.z()) == bits(b.z());
  };
  ASSERT_EQ(s.vertices.size(), r.vertices.size());
  for (size_t i = 0; i < s.vertices.size(); ++i) EXPECT_TRUE(same(s.vertices[i], r.vertices[i])) << "vertex " << i;
  ASSERT_EQ(s.edges.size(), r.edges.size());
  for (size_t i = 0; i < s.edges.size(); ++i) {
    const CoreEdge &e = s.edges[i], &f = r.edges[i];
    EXPECT_TRUE(e.v0 == f.v0 && e.v1 == f.v1 && e.f0 == f.f0 && e.f1 == f.f1 && e.convex == f.convex) << "edge " << i;
  }
  ASSERT_EQ(s.faces.size(), r.faces.size());
  for (size_t i = 0; i < s.faces.size(); ++i) {
    EXPECT_EQ(s.faces[i].loop, r.faces[i].loop) << "face " << i;
    EXPECT_TRUE(same(s.faces[i].normal, r.faces[i].normal)) << "face " << i;
    EXPECT_EQ(bits(s.faces[i].offset), bits(r.faces[i].offset)) << "face " << i;
  }
  EXPECT_EQ(s.vertexEdges, r.vertexEdges);
  EXPECT_EQ(s.faceEdges, r.faceEdges);
  EXPECT_EQ(bits(s.volume), bits(r.volume));
  EXPECT_TRUE(same(s.inertiaPerDensity, r.inertiaPerDensity));
  EXPECT_TRUE(same(s.framePosition, r.framePosition));
  EXPECT_EQ(bits(s.frameOrientation.w()), bits(r.frameOrientation.w()));
  EXPECT_TRUE(same(s.frameOrientation.vec(), r.frameOrientation.vec()));
  EXPECT_EQ(bits(s.boundingRadius), bits(r.boundingRadius));
  ASSERT_EQ(s.outerVertices.size(), r.outerVertices.size());
  for (size_t i = 0; i < s.outerVertices.size(); ++i) EXPECT_TRUE(same(s.outerVertices[i], r.outerVertices[i]));
  EXPECT_EQ(s.outerTriangles, r.outerTriangles);
}

// Deterministic pseudo-random numbers in [0, 1) (no library generator: its sequence may
// differ between standard libraries).
struct Lcg {
  std::uint64_t state;
  Real next() {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<Real>(state >> 11) * (1.0 / 9007199254740992.0);
  }
};

// A rock: 40 points near an ellipsoid of semi-axes (0.05, 0.035, 0.025) m.
std::vector<Vec3> rockPoints() {
  Lcg g{12345};
  std::vector<Vec3> p;
  for (int i = 0; i < 40; ++i) {
    Vec3 d(2 * g.next() - 1, 2 * g.next() - 1, 2 * g.next() - 1);
    if (d.norm() < 1e-3) continue;
    d.normalize();
    const Real r = 0.9 + 0.1 * g.next();
    p.emplace_back(0.05 * r * d.x() + 0.3, 0.035 * r * d.y() - 0.1, 0.025 * r * d.z() + 0.02);
  }
  return p;
}

// Box corners, face centres and edge midpoints: coplanar hull triangles (any triangulation
// of a face is valid) and points inside hull edges.
std::vector<Vec3> boxWithExtraPoints() {
  std::vector<Vec3> p;
  for (int i = -1; i <= 1; ++i)
    for (int j = -1; j <= 1; ++j)
      for (int k = -1; k <= 1; ++k)
        if (std::abs(i) + std::abs(j) + std::abs(k) >= 2) p.emplace_back(0.05 * i, 0.03 * j + 0.01, 0.02 * k);
  p.emplace_back(0.05, 0.01, 0.0);  // one face centre
  return p;
}

// Triangle mesh in memory.
struct Mesh {
  std::vector<Vec3> v;
  std::vector<std::array<int, 3>> t;
  void add(const Mesh& m, const Vec3& shift) {
    const int base = static_cast<int>(v.size());
    for (const Vec3& p : m.v) v.push_back(p + shift);
    for (const auto& tri : m.t) t.push_back({tri[0] + base, tri[1] + base, tri[2] + base});
  }
};

// Cube of half side h centred at the origin, triangles counter-clockwise seen from outside.
Mesh cubeMesh(Real h) {
  Mesh m;
  for (int i = 0; i < 8; ++i) m.v.emplace_back((i & 1 ? h : -h), (i & 2 ? h : -h), (i & 4 ? h : -h));
  const int quads[6][4] = {{1, 3, 7, 5}, {0, 4, 6, 2}, {2, 6, 7, 3}, {0, 1, 5, 4}, {4, 5, 7, 6}, {0, 2, 3, 1}};
  for (const auto& q : quads) {
    m.t.push_back({q[0], q[1], q[2]});
    m.t.push_back({q[0], q[2], q[3]});
  }
  return m;
}

// L-shaped prism (non-convex): cross-section (0,0) (2,0) (2,1) (1,1) (1,2) (0,2) times u,
// z in [0, u]. Caps are fans from the reflex corner 3.
Mesh lPrismMesh(Real u) {
  const Real xy[6][2] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  Mesh m;
  for (int z = 0; z < 2; ++z)
    for (const auto& p : xy) m.v.emplace_back(u * p[0], u * p[1], u * z);  // bottom 0..5, top 6..11
  for (int i = 0; i < 6; ++i) {
    const int j = (i + 1) % 6;
    m.t.push_back({i, j, j + 6});
    m.t.push_back({i, j + 6, i + 6});
  }
  for (int k : {4, 5, 0, 1}) {
    const int k1 = k == 5 ? 0 : k + 1;
    m.t.push_back({3 + 6, k + 6, k1 + 6});  // top, counter-clockwise seen from +z
    m.t.push_back({3, k1, k});              // bottom
  }
  return m;
}

void expectComponentsError(const Mesh& m, Real R, int parts) {
  try {
    SpheroPolyhedron::mesh(m.v, m.t, R);
    ADD_FAILURE() << "a mesh of " << parts << " parts was accepted";
  } catch (const ParameterError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("mesh = " + std::to_string(parts) + " disconnected components"), std::string::npos) << msg;
    EXPECT_NE(msg.find("one body per part"), std::string::npos) << msg;
  }
}

}  // namespace

// The same points give the same shape, bit for bit, however often it is built and in
// whatever order the points are listed (runs must be repeatable and shapes comparable).
TEST(Robustness, ConvexHullIsCanonical) {
  for (int set = 0; set < 2; ++set) {
    const std::vector<Vec3> pts = set == 0 ? rockPoints() : boxWithExtraPoints();
    const Real R = set == 0 ? 0.004 : 0.002;
    const auto ref = SpheroPolyhedron::convexHull(pts, R);
    for (int n = 0; n < 50; ++n)
      expectBitIdentical(*SpheroPolyhedron::convexHull(pts, R), *ref, "set " + std::to_string(set) + " build " + std::to_string(n));
    std::vector<Vec3> perm(pts.rbegin(), pts.rend());
    expectBitIdentical(*SpheroPolyhedron::convexHull(perm, R), *ref, "reversed points");
    Lcg g{7};
    for (int n = 0; n < 5; ++n) {
      for (size_t i = perm.size() - 1; i > 0; --i) std::swap(perm[i], perm[static_cast<size_t>(g.next() * (i + 1))]);
      expectBitIdentical(*SpheroPolyhedron::convexHull(perm, R), *ref, "shuffled points " + std::to_string(n));
    }
  }
}

// A closed mesh of several disjoint parts is refused instead of becoming the convex hull of
// all of them (convex parts) or one rigid body of separate pieces (non-convex parts).
TEST(Robustness, MeshOfDisjointPartsRefused) {
  const Real R = 0.005;
  const Mesh cube = cubeMesh(0.05), ell = lPrismMesh(0.1);
  // each part alone is a valid body
  EXPECT_TRUE(SpheroPolyhedron::mesh(cube.v, cube.t, R)->convex);
  EXPECT_FALSE(SpheroPolyhedron::mesh(ell.v, ell.t, R)->convex);
  Mesh twoCubes;
  twoCubes.add(cube, Vec3::Zero());
  twoCubes.add(cube, Vec3(0.3, 0, 0));
  expectComponentsError(twoCubes, R, 2);
  Mesh twoEll;
  twoEll.add(ell, Vec3::Zero());
  twoEll.add(ell, Vec3(0.5, 0.1, 0));
  expectComponentsError(twoEll, R, 2);
  Mesh three = twoEll;
  three.add(cube, Vec3(0, 0, 0.4));
  expectComponentsError(three, R, 3);
  // the same through a mesh file
  const std::string path = ::testing::TempDir() + "/mpmsdem_two_cubes.obj";
  {
    std::ofstream f(path);
    for (const Vec3& p : twoCubes.v) f << "v " << p.x() << " " << p.y() << " " << p.z() << "\n";
    for (const auto& t : twoCubes.t) f << "f " << t[0] + 1 << " " << t[1] + 1 << " " << t[2] + 1 << "\n";
  }
  try {
    SpheroPolyhedron::meshFile(path, R);
    ADD_FAILURE() << "a mesh file of 2 parts was accepted";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("2 disconnected components"), std::string::npos) << e.what();
  }
  std::remove(path.c_str());
}
