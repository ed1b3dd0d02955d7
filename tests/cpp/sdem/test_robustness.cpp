// Robustness of the SDEM shape construction and narrow phase: canonical (repeatable) hull
// construction, rejection of meshes made of several disjoint parts, and detection of
// interpenetrating cores that have no vertex strictly inside the other core.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <array>
#include <cstdio>
#include <fstream>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "common/Error.hpp"
#include "sdem/Ig2_SpheroPolyhedron_SpheroPolyhedron.hpp"
#include "sdem/SdemEngine.hpp"
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

// A rock: n points near an ellipsoid of semi-axes (0.05, 0.035, 0.025) m.
std::vector<Vec3> rockPoints(int n = 40) {
  Lcg g{12345};
  std::vector<Vec3> p;
  for (int i = 0; i < n; ++i) {
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

// ---- narrow phase. Cubes: outer half side 0.05 m, R = 0.005 m, core half side a = 0.045 m.
const Real kR = 0.005, kA = 0.045;

PosedSpheroPolyhedron pose(const SpheroPolyhedron& s, const Vec3& p, const Quat& q = Quat::Identity()) {
  PosedSpheroPolyhedron ps;
  ps.update(s, p, q);
  return ps;
}

// A shape built from a mesh placed so that x_world = shift + x_input.
PosedSpheroPolyhedron poseInput(const SpheroPolyhedron& s, const Vec3& shift, const Quat& q = Quat::Identity()) {
  return pose(s, shift + q * s.framePosition, q * s.frameOrientation);
}

Quat about(const Vec3& axis, Real deg) { return Quat(Eigen::AngleAxis<Real>(deg * M_PI / 180, axis.normalized())); }

// go() in both orders; true when both report interpenetration (and add no contact).
bool flagged(const PosedSpheroPolyhedron& A, const PosedSpheroPolyhedron& B) {
  std::vector<SdemGeom> ab, ba;
  const bool okAB = Ig2_SpheroPolyhedron_SpheroPolyhedron::go(A, B, ab);
  const bool okBA = Ig2_SpheroPolyhedron_SpheroPolyhedron::go(B, A, ba);
  EXPECT_EQ(okAB, okBA) << "the answer depends on the order of the bodies";
  if (!okAB) EXPECT_TRUE(ab.empty());
  if (!okBA) EXPECT_TRUE(ba.empty());
  return !okAB && !okBA;
}

std::vector<SdemGeom> contactsOf(const PosedSpheroPolyhedron& A, const PosedSpheroPolyhedron& B) {
  std::vector<SdemGeom> out;
  EXPECT_TRUE(Ig2_SpheroPolyhedron_SpheroPolyhedron::go(A, B, out)) << "flagged as interpenetrating";
  return out;
}

bool coreBoxesOverlap(const PosedSpheroPolyhedron& A, const PosedSpheroPolyhedron& B) {
  return (A.coreHi.cwiseMin(B.coreHi) - A.coreLo.cwiseMax(B.coreLo)).minCoeff() > 0;
}

// Largest separation of two convex cores over ALL candidate axes (face normals and every
// edge-pair cross product), each with the full projection of both cores: the plain
// separating-axis test the narrow phase must agree with.
Real bruteSeparation(const PosedSpheroPolyhedron& A, const PosedSpheroPolyhedron& B) {
  auto gap = [&](const Vec3& n) {
    Real maxA = -INFINITY, minA = INFINITY, maxB = -INFINITY, minB = INFINITY;
    for (const Vec3& x : A.vertices) maxA = std::max(maxA, n.dot(x)), minA = std::min(minA, n.dot(x));
    for (const Vec3& x : B.vertices) maxB = std::max(maxB, n.dot(x)), minB = std::min(minB, n.dot(x));
    return std::max(minB - maxA, minA - maxB);
  };
  Real best = -INFINITY;
  for (const Vec3& n : A.faceNormals) best = std::max(best, gap(n));
  for (const Vec3& n : B.faceNormals) best = std::max(best, gap(n));
  for (const Vec3& ta : A.edgeDir)
    for (const Vec3& tb : B.edgeDir) {
      const Vec3 n = ta.cross(tb);
      if (n.norm() > 1e-9) best = std::max(best, gap(n.normalized()));
    }
  return best;
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

// Equal aligned cubes that overlap with aligned faces have no core vertex strictly inside the
// other core, yet their interiors overlap: coincident, overlapping by half a side, shifted
// along a face diagonal (edges crossing in the common top and bottom planes), and turned by
// 45 degrees about the common vertical axis (each core's edges through the other's faces).
TEST(Robustness, InterpenetratingCoresWithNoVertexInsideAreFlagged) {
  const auto cube = SpheroPolyhedron::box(Vec3::Constant(0.05), kR);
  const PosedSpheroPolyhedron A = pose(*cube, Vec3::Zero());
  EXPECT_TRUE(flagged(A, pose(*cube, Vec3::Zero()))) << "coincident";
  EXPECT_TRUE(flagged(A, pose(*cube, Vec3(0.03, 0, 0)))) << "overlap 0.06 m of the 0.09 m cores";
  EXPECT_TRUE(flagged(A, pose(*cube, Vec3(0.05, 0, 0)))) << "overlap by half a side";
  EXPECT_TRUE(flagged(A, pose(*cube, Vec3(0.05, 0.05, 0)))) << "shifted along a face diagonal";
  EXPECT_TRUE(flagged(A, pose(*cube, Vec3(0.03, -0.02, 0.01)))) << "shifted, faces parallel";
  EXPECT_TRUE(flagged(A, pose(*cube, Vec3(0, 0, 0.01), about(Vec3::UnitZ(), 45)))) << "star";
  // the same with a cube built from its corners (convex hull path, other vertex numbering)
  std::vector<Vec3> corners;
  for (int i = 0; i < 8; ++i) corners.emplace_back(i & 1 ? 0.05 : -0.05, i & 2 ? 0.05 : -0.05, i & 4 ? 0.05 : -0.05);
  const auto hull = SpheroPolyhedron::convexHull(corners, kR);
  EXPECT_TRUE(flagged(A, poseInput(*hull, Vec3::Zero()))) << "coincident hull";
  EXPECT_TRUE(flagged(A, poseInput(*hull, Vec3(0.05, 0.05, 0)))) << "hull along a face diagonal";
  // Overlap just above the tolerance is flagged; just below, it is a touching, with no force.
  const Real tol = Ig2_SpheroPolyhedron_SpheroPolyhedron::tolerance(A, A);
  EXPECT_TRUE(flagged(A, pose(*cube, Vec3(2 * kA - 10 * tol, 0.01, 0))));
  EXPECT_FALSE(flagged(A, pose(*cube, Vec3(2 * kA, 0.01, 0)))) << "faces touching";
  EXPECT_FALSE(flagged(A, pose(*cube, Vec3(2 * kA, 2 * kA, 0)))) << "edges touching";
}

// Bodies created overlapping are refused at the first step, naming the two bodies.
TEST(Robustness, EngineRefusesBodiesCreatedOverlapping) {
  SdemEngine e;
  SdemMaterial m;
  m.density = 3000;
  const int mat = e.addMaterial(m);
  const auto cube = SpheroPolyhedron::box(Vec3::Constant(0.05), kR);
  const int b0 = e.addBody(cube, mat, 1.0, Vec3::Ones(), 11);
  const int b1 = e.addBody(cube, mat, 1.0, Vec3::Ones(), 12);
  e.setState(b0, Vec3::Zero(), Quat::Identity(), Vec3::Zero(), Vec3::Zero());
  e.setState(b1, Vec3(0.05, 0, 0), Quat::Identity(), Vec3::Zero(), Vec3::Zero());
  try {
    e.computeForces(1e-5);
    ADD_FAILURE() << "overlapping bodies accepted";
  } catch (const RuntimeFailure& err) {
    const std::string msg = err.what();
    EXPECT_NE(msg.find("interpenetrate"), std::string::npos) << msg;
    EXPECT_NE(msg.find("11"), std::string::npos) << msg;
    EXPECT_NE(msg.find("12"), std::string::npos) << msg;
  }
}

// Ordinary contacts are not flagged: a cube face-down on a slab at rest (4 contacts), also
// on a tilted slab where the core boxes overlap and the full test runs; cubes 0.5 R apart
// (core gap), face to face and edge to edge, touching through their spheres only.
TEST(Robustness, ContactsAreNotFlagged) {
  const auto cube = SpheroPolyhedron::box(Vec3::Constant(0.05), kR);
  const auto slab = SpheroPolyhedron::box(Vec3(1, 1, 0.05), kR);
  const Real restGap = 0.0095;  // core gap at the resting overlap 2R - gap = 0.5 mm
  for (Real tilt : {0.0, 20.0}) {
    for (Real yaw : {0.0, 17.0, 45.0}) {
      const Quat q = about(Vec3::UnitX(), tilt);
      const PosedSpheroPolyhedron S = pose(*slab, Vec3::Zero(), q);
      const PosedSpheroPolyhedron C = pose(*cube, q * Vec3(0.1, -0.2, kA + restGap + kA), q * about(Vec3::UnitZ(), yaw));
      if (tilt > 0) EXPECT_TRUE(coreBoxesOverlap(S, C));
      const auto g = contactsOf(S, C);
      EXPECT_EQ(g.size(), 4u) << "tilt " << tilt << " yaw " << yaw;
      for (const auto& k : g) EXPECT_NEAR(k.distance, restGap, 1e-12);
      EXPECT_EQ(contactsOf(C, S).size(), 4u);
    }
  }
  const Real gap = 0.5 * kR;
  const PosedSpheroPolyhedron A = pose(*cube, Vec3::Zero());
  auto face = contactsOf(A, pose(*cube, Vec3(2 * kA + gap, 0.01, 0)));
  EXPECT_EQ(face.size(), 4u);
  // Edge to edge: A's edge along x at (y, z) = (a, a) and an edge of B along (0, 1, -1)/sqrt2,
  // crossing it at right angles, gap apart along m = (0, 1, 1)/sqrt2. B is A turned by -90
  // degrees about -m (its edge at local y = z = -a goes to the direction (0, 1, -1)), so its
  // centre is that edge's midpoint + a sqrt2 m; B is then slid along A's edge, and turned about
  // m, which keeps the crossing.
  const Vec3 mdir = Vec3(0, 1, 1).normalized();
  for (Real slide : {0.0, 0.02}) {
    for (Real spin : {0.0, 30.0}) {
      const Quat qb = about(mdir, spin) * about(-mdir, -90);
      const Vec3 cb = Vec3(slide, kA, kA) + (gap + kA * std::sqrt(2.0)) * mdir;
      const PosedSpheroPolyhedron B = pose(*cube, cb, qb);
      if (slide > 0 && spin > 0) EXPECT_TRUE(coreBoxesOverlap(A, B));
      const auto g = contactsOf(A, B);
      ASSERT_EQ(g.size(), 1u) << "slide " << slide << " spin " << spin;
      EXPECT_NEAR(g[0].distance, gap, 1e-12);
      EXPECT_NEAR(bruteSeparation(A, B), gap, 1e-12);
      EXPECT_EQ(contactsOf(B, A).size(), 1u);
    }
  }
}

// The separating-axis shortcut (edge pairs limited to faces of the Minkowski difference, each
// with an O(1) separation) agrees with the plain test over every axis, for random poses of a
// cube and a rock: flagged exactly when the plain separation is below -tol (configurations
// within 1e-6 m of the threshold skipped).
TEST(Robustness, SeparatingAxisMatchesBruteForce) {
  const auto cube = SpheroPolyhedron::box(Vec3(0.05, 0.03, 0.02), kR);
  const auto rock = SpheroPolyhedron::convexHull(rockPoints(12), 0.004);
  Lcg g{99};
  auto randomQuat = [&] {
    Quat q(g.next() - 0.5, g.next() - 0.5, g.next() - 0.5, g.next() - 0.5);
    return q.normalized();
  };
  int flaggedCount = 0, clearCount = 0;
  for (int n = 0; n < 1500; ++n) {
    const SpheroPolyhedron& sa = n % 3 == 0 ? *cube : *rock;
    const SpheroPolyhedron& sb = n % 2 == 0 ? *cube : *rock;
    const PosedSpheroPolyhedron A = pose(sa, Vec3::Zero(), randomQuat());
    const Vec3 dir = Vec3(g.next() - 0.5, g.next() - 0.5, g.next() - 0.5).normalized();
    const PosedSpheroPolyhedron B = pose(sb, (0.03 + 0.08 * g.next()) * dir, randomQuat());
    const Real sep = bruteSeparation(A, B);
    const Real tol = Ig2_SpheroPolyhedron_SpheroPolyhedron::tolerance(A, B);
    if (std::abs(sep + tol) < 1e-6) continue;
    std::vector<SdemGeom> out;
    const bool ok = Ig2_SpheroPolyhedron_SpheroPolyhedron::go(A, B, out);
    EXPECT_EQ(ok, sep > -tol) << "pose " << n << " separation " << sep;
    (ok ? clearCount : flaggedCount)++;
  }
  // both outcomes well represented
  EXPECT_GT(flaggedCount, 300);
  EXPECT_GT(clearCount, 300);
}

// Non-convex cores (no separating-axis theorem): L prisms (cross-section 0.2 m with a 0.1 m
// notch, 0.1 m thick, R = 0.005 m) overlapping with coincident faces, a cube turned 45 degrees
// in the L's corner (surfaces crossing, its corners inside the L), a small cube entirely
// inside an arm (surfaces apart). Not flagged: a cube in the notch with a core gap of 0.5 R to
// both walls, and an L on a slab.
TEST(Robustness, NonConvexCoresInterpenetration) {
  const Mesh lm = lPrismMesh(0.1), cm = cubeMesh(0.05), sm = cubeMesh(0.02);
  const auto ell = SpheroPolyhedron::mesh(lm.v, lm.t, kR);
  const auto cube = SpheroPolyhedron::mesh(cm.v, cm.t, kR);
  const auto small = SpheroPolyhedron::mesh(sm.v, sm.t, kR);
  ASSERT_FALSE(ell->convex);
  const PosedSpheroPolyhedron L = poseInput(*ell, Vec3::Zero());
  EXPECT_TRUE(flagged(L, poseInput(*ell, Vec3::Zero()))) << "coincident";
  EXPECT_TRUE(flagged(L, poseInput(*ell, Vec3(0.05, 0.05, 0)))) << "shifted along a diagonal";
  EXPECT_TRUE(flagged(L, poseInput(*ell, Vec3(0.03, 0, 0)))) << "shifted along x";
  EXPECT_TRUE(flagged(L, poseInput(*cube, Vec3(0.05, 0.05, 0.05)))) << "cube filling the corner";
  EXPECT_TRUE(flagged(L, poseInput(*cube, Vec3(0.05, 0.05, 0.06), about(Vec3::UnitZ(), 45)))) << "turned cube";
  EXPECT_TRUE(flagged(L, poseInput(*small, Vec3(0.05, 0.15, 0.05)))) << "small cube inside an arm";
  // an L turned upside down about x, shifted by (0.05, 0.15, 0.07): arms crossing at mid-height
  EXPECT_TRUE(flagged(L, poseInput(*ell, Vec3(0.05, 0.15, 0.07), about(Vec3::UnitX(), 180)))) << "crossed Ls";
  // in the notch: walls' cores at x = 0.1 - R and y = 0.1 - R, cube core half side 0.045
  const Real c = 0.1 - kR + 0.5 * kR + kA;
  const PosedSpheroPolyhedron inNotch = poseInput(*cube, Vec3(c, c, 0.05));
  EXPECT_TRUE(coreBoxesOverlap(L, inNotch));
  const auto g = contactsOf(L, inNotch);
  EXPECT_FALSE(g.empty());
  for (const auto& k : g) EXPECT_NEAR(k.distance, 0.5 * kR, 1e-12);
  EXPECT_FALSE(contactsOf(inNotch, L).empty());
  const auto slab = SpheroPolyhedron::box(Vec3(1, 1, 0.05), kR);
  const Real restGap = 0.0095;
  const auto onSlab = contactsOf(pose(*slab, Vec3::Zero()), poseInput(*ell, Vec3(0, 0, 0.05 - 2 * kR + restGap)));
  EXPECT_EQ(onSlab.size(), 6u);  // the 6 corners of the L's bottom face
}
