// Narrow-phase contact geometry between sphero-polyhedra (Ig2_SpheroPolyhedron_SpheroPolyhedron).
// Bodies are 0.1 m boxes with R = 0.005 m (core half side a = 0.045 m) unless said otherwise;
// every expected value below is derived by hand in the comment next to it.
#include <gtest/gtest.h>

#include <cmath>

#include "sdem/Ig2_SpheroPolyhedron_SpheroPolyhedron.hpp"
#include "sdem/Law2_SdemGeom_BarrierPhys_Coulomb.hpp"

using namespace mpmsdem;
using namespace mpmsdem::sdem;

namespace {

const Real a = 0.045;   // core half side of the 0.1 m cube
const Real R = 0.005;   // sweep radius of each body
const Real gap = 0.006; // core gap used in the tests (< R_A + R_B = 0.01)

std::shared_ptr<SpheroPolyhedron> cube() { return SpheroPolyhedron::box(Vec3::Constant(0.05), R); }

PosedSpheroPolyhedron pose(const SpheroPolyhedron& s, const Vec3& p, const Quat& q = Quat::Identity()) {
  PosedSpheroPolyhedron ps;
  ps.update(s, p, q);
  return ps;
}

std::vector<SdemGeom> contacts(const PosedSpheroPolyhedron& A, const PosedSpheroPolyhedron& B) {
  std::vector<SdemGeom> out;
  EXPECT_TRUE(Ig2_SpheroPolyhedron_SpheroPolyhedron::go(A, B, out));
  return out;
}

Quat about(const Vec3& axis, Real deg) { return Quat(Eigen::AngleAxis<Real>(deg * M_PI / 180, axis.normalized())); }

// Rotation taking the body diagonal (1,1,1) to (0,0,-1): a corner points straight down.
Quat cornerDown() { return Quat::FromTwoVectors(Vec3(1, 1, 1).normalized(), Vec3(0, 0, -1)); }
Quat cornerUp() { return Quat::FromTwoVectors(Vec3(1, 1, 1).normalized(), Vec3(0, 0, 1)); }

void expectVec(const Vec3& got, const Vec3& want, Real tol) {
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(got[k], want[k], tol) << "component " << k;
}

}  // namespace

// Vertex–face: B corner-down above A's top face. B's lowest core vertex is a sqrt(3) below
// its centre, so with the centre at z = a + gap + a sqrt(3) it sits at (0.01, 0.02, a + gap):
// d = gap, point on A = (0.01, 0.02, a), normal +z, overlap 0.01 - 0.006 = 0.004.
TEST(Contact, VertexFace) {
  auto s = cube();
  const Vec3 c(0.01, 0.02, a + gap + a * std::sqrt(3.0));
  auto g = contacts(pose(*s, Vec3::Zero()), pose(*s, c, cornerDown()));
  ASSERT_EQ(g.size(), 1u);
  EXPECT_EQ(g[0].kindA, FeatureKind::Face);
  EXPECT_EQ(g[0].kindB, FeatureKind::Vertex);
  EXPECT_NEAR(g[0].distance, gap, 1e-12);
  EXPECT_NEAR(g[0].overlap, 0.004, 1e-12);
  expectVec(g[0].pointA, Vec3(0.01, 0.02, a), 1e-12);
  expectVec(g[0].pointB, Vec3(0.01, 0.02, a + gap), 1e-12);
  expectVec(g[0].normal, Vec3(0, 0, 1), 1e-12);
  // midway between A's sphere surface (z = a + 0.005) and B's (z = a + gap - 0.005)
  expectVec(g[0].contactPoint, Vec3(0.01, 0.02, a + 0.5 * gap), 1e-12);
  // the same pair with the roles swapped gives the mirrored contact
  auto h = contacts(pose(*s, c, cornerDown()), pose(*s, Vec3::Zero()));
  ASSERT_EQ(h.size(), 1u);
  EXPECT_EQ(h[0].kindA, FeatureKind::Vertex);
  EXPECT_EQ(h[0].kindB, FeatureKind::Face);
  expectVec(h[0].normal, Vec3(0, 0, -1), 1e-12);
}

// Edge–edge: A rolled 45 deg about x (top ridge along x at z = a sqrt 2), B rolled 45 deg about
// y (bottom ridge along y at z_B - a sqrt 2), B shifted by (0.01, 0.02): the ridges cross at
// x = 0.01, y = 0. Closest points (0.01, 0, a sqrt2) and (0.01, 0, a sqrt2 + gap).
TEST(Contact, EdgeEdgeCrossing) {
  auto s = cube();
  const Real top = a * std::sqrt(2.0);
  const Vec3 c(0.01, 0.02, top + gap + top);
  auto g = contacts(pose(*s, Vec3::Zero(), about(Vec3::UnitX(), 45)), pose(*s, c, about(Vec3::UnitY(), 45)));
  ASSERT_EQ(g.size(), 1u);
  EXPECT_EQ(g[0].kindA, FeatureKind::Edge);
  EXPECT_EQ(g[0].kindB, FeatureKind::Edge);
  EXPECT_NEAR(g[0].distance, gap, 1e-12);
  expectVec(g[0].pointA, Vec3(0.01, 0, top), 1e-12);
  expectVec(g[0].pointB, Vec3(0.01, 0, top + gap), 1e-12);
  expectVec(g[0].normal, Vec3(0, 0, 1), 1e-12);
}

// Vertex–edge: A's top ridge along x (as above); B corner-down with its lowest vertex at
// (0.01, 0, a sqrt2 + gap). Its projection on either face of the ridge falls beyond the ridge,
// so only the vertex–edge pair carries the contact: d = gap, point on A (0.01, 0, a sqrt2).
TEST(Contact, VertexEdge) {
  auto s = cube();
  const Real top = a * std::sqrt(2.0);
  const Vec3 c(0.01, 0, top + gap + a * std::sqrt(3.0));
  auto g = contacts(pose(*s, Vec3::Zero(), about(Vec3::UnitX(), 45)), pose(*s, c, cornerDown()));
  ASSERT_EQ(g.size(), 1u);
  EXPECT_EQ(g[0].kindA, FeatureKind::Edge);
  EXPECT_EQ(g[0].kindB, FeatureKind::Vertex);
  EXPECT_NEAR(g[0].distance, gap, 1e-12);
  expectVec(g[0].pointA, Vec3(0.01, 0, top), 1e-12);
  expectVec(g[0].normal, Vec3(0, 0, 1), 1e-12);
}

// Vertex–vertex: A corner-up (top vertex at z = a sqrt3), B corner-down right above it.
TEST(Contact, VertexVertex) {
  auto s = cube();
  const Real h = a * std::sqrt(3.0);
  auto g = contacts(pose(*s, Vec3::Zero(), cornerUp()), pose(*s, Vec3(0, 0, 2 * h + gap), cornerDown()));
  ASSERT_EQ(g.size(), 1u);
  EXPECT_EQ(g[0].kindA, FeatureKind::Vertex);
  EXPECT_EQ(g[0].kindB, FeatureKind::Vertex);
  EXPECT_NEAR(g[0].distance, gap, 1e-12);
  expectVec(g[0].pointA, Vec3(0, 0, h), 1e-12);
  expectVec(g[0].pointB, Vec3(0, 0, h + gap), 1e-12);
}

// A vertex of B exactly over the ridge x = a of A's top face: vertex–face (projection on the
// face boundary) and vertex–edge describe the same contact, counted once; moving B by +-1e-9 m
// across the ridge keeps one contact with the same distance (gap) on either side.
TEST(Contact, VertexExactlyOverEdge) {
  auto s = cube();
  for (Real dx : {0.0, 1e-9, -1e-9}) {
    const Vec3 c(a + dx, 0, a + gap + a * std::sqrt(3.0));
    auto g = contacts(pose(*s, Vec3::Zero()), pose(*s, c, cornerDown()));
    ASSERT_EQ(g.size(), 1u) << "dx = " << dx;
    EXPECT_NEAR(g[0].distance, gap, 1e-12);
    // inside the face (dx <= 0) the normal is the face normal; beyond the ridge (dx > 0) it is
    // the vertex–edge normal (dx, 0, gap)/d, tilted by dx/gap = 1.7e-7 rad
    expectVec(g[0].normal, Vec3(std::max(dx, 0.0) / gap, 0, 1), 1e-12);
    expectVec(g[0].pointA, Vec3(a + std::min(dx, 0.0), 0, a), 1e-15);
  }
}

// Parallel edges: both A and B rolled 45 deg about x so A's top ridge and B's bottom ridge are
// parallel (along x), B shifted by 0.03 m in x. The overlap of the ridges is x in [-0.015, 0.045];
// its two ends carry one contact each (vertex–edge pairs), both at distance gap.
TEST(Contact, ParallelEdges) {
  auto s = cube();
  const Real top = a * std::sqrt(2.0);
  for (Real shift : {0.03, 0.0}) {
    const Vec3 c(shift, 0, 2 * top + gap);
    auto g = contacts(pose(*s, Vec3::Zero(), about(Vec3::UnitX(), 45)), pose(*s, c, about(Vec3::UnitX(), 45)));
    ASSERT_EQ(g.size(), 2u) << "shift = " << shift;
    Real xmin = 1, xmax = -1;
    for (const auto& k : g) {
      EXPECT_NEAR(k.distance, gap, 1e-12);
      expectVec(k.normal, Vec3(0, 0, 1), 1e-12);
      xmin = std::min(xmin, k.pointA.x());
      xmax = std::max(xmax, k.pointA.x());
    }
    EXPECT_NEAR(xmin, shift - a, 1e-12);  // B's end of the overlap
    EXPECT_NEAR(xmax, a, 1e-12);          // A's end
  }
}

// A 0.1 m cube face-down on a 2 x 2 x 0.1 m slab (top core face at z = a), at several yaws:
// exactly its 4 bottom core corners touch, each at distance gap with normal +z.
TEST(Contact, CubeOnSlabFaceDown) {
  auto s = cube();
  auto slab = SpheroPolyhedron::box(Vec3(1, 1, 0.05), R);
  for (Real yaw : {0.0, 17.0, 45.0}) {
    const Quat q = about(Vec3::UnitZ(), yaw);
    auto g = contacts(pose(*slab, Vec3::Zero()), pose(*s, Vec3(0.1, -0.2, a + gap + a), q));
    ASSERT_EQ(g.size(), 4u) << "yaw " << yaw;
    Vec3 sumPoint = Vec3::Zero();
    for (const auto& k : g) {
      EXPECT_EQ(k.kindA, FeatureKind::Face);
      EXPECT_EQ(k.kindB, FeatureKind::Vertex);
      EXPECT_NEAR(k.distance, gap, 1e-12);
      EXPECT_EQ(k.normal, Vec3(0, 0, 1));
      sumPoint += k.contactPoint;
    }
    // the 4 points are the rotated corners: their mean is below the cube's centre
    expectVec(sumPoint / 4, Vec3(0.1, -0.2, a + 0.5 * gap), 1e-12);
  }
}

// Edge-down (rolled 45 deg about y): the lowest ridge, a sqrt2 below the centre, touches with its
// two end vertices. Corner-down: one vertex.
TEST(Contact, CubeOnSlabEdgeAndCorner) {
  auto s = cube();
  auto slab = SpheroPolyhedron::box(Vec3(1, 1, 0.05), R);
  auto edge = contacts(pose(*slab, Vec3::Zero()),
                       pose(*s, Vec3(0, 0, a + gap + a * std::sqrt(2.0)), about(Vec3::UnitY(), 45)));
  ASSERT_EQ(edge.size(), 2u);
  EXPECT_NEAR(std::abs(edge[0].pointB.y() - edge[1].pointB.y()), 2 * a, 1e-12);
  for (const auto& k : edge) EXPECT_NEAR(k.distance, gap, 1e-12);
  auto corner =
      contacts(pose(*slab, Vec3::Zero()), pose(*s, Vec3(0, 0, a + gap + a * std::sqrt(3.0)), cornerDown()));
  ASSERT_EQ(corner.size(), 1u);
  EXPECT_NEAR(corner[0].distance, gap, 1e-12);
}

// Two equal cubes face to face along x: 4 contacts at the corners of the common square, no
// net moment about the centre of the contact square. Offsetting B by 1e-9 m sideways changes which features
// carry the corners but not the total normal force (4 F_n(0.004) either way).
TEST(Contact, AlignedCubesAndContinuity) {
  auto s = cube();
  const Real kc = 1e4, Rsum = 2 * R;
  Real total[2];
  int idx = 0;
  for (Real off : {0.0, 1e-9}) {
    const Vec3 cb(2 * a + gap, off, 0);
    auto g = contacts(pose(*s, Vec3::Zero()), pose(*s, cb));
    ASSERT_EQ(g.size(), 4u) << "offset " << off;
    Vec3 f = Vec3::Zero(), m = Vec3::Zero();
    for (const auto& k : g) {
      EXPECT_NEAR(k.distance, gap, 1e-12);
      const Vec3 fk = Law2_SdemGeom_BarrierPhys_Coulomb::normalForce(kc, Rsum, k.overlap) * k.normal;
      f += fk;
      m += (k.contactPoint - Vec3(a + 0.5 * gap, 0.5 * off, 0)).cross(fk);
    }
    EXPECT_NEAR(f.y(), 0, 1e-12);
    EXPECT_NEAR(f.z(), 0, 1e-12);
    EXPECT_NEAR(m.norm(), 0, 1e-12);
    total[idx++] = f.x();
  }
  // F_n(0.004) with R = 0.01: -1e4 * 0.004 * (2 ln 0.6 - 1/0.6 + 1) = 40 * 1.6883179 = 67.532717 N, times 4
  EXPECT_NEAR(total[0], 4 * 67.532717, 4 * 67.532717 * 1e-6);
  EXPECT_NEAR(total[1] / total[0], 1.0, 1e-6);
}

// Interpenetrating cores are reported, not silently skipped.
TEST(Contact, InterpenetrationDetected) {
  auto s = cube();
  std::vector<SdemGeom> out;
  PosedSpheroPolyhedron A = pose(*s, Vec3::Zero()), B = pose(*s, Vec3(0.06, 0.01, 0.02), about(Vec3::UnitZ(), 30));
  EXPECT_FALSE(Ig2_SpheroPolyhedron_SpheroPolyhedron::go(A, B, out));
}
