// Tests of the SDEM shape: core construction, exact mass properties of the rounded body,
// body frame, point queries, mesh input and error handling, Aabb.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <string>

#include "common/Error.hpp"
#include "sdem/Bo1_SpheroPolyhedron_Aabb.hpp"
#include "sdem/SpheroPolyhedron.hpp"

using namespace mpmsdem;
using namespace mpmsdem::sdem;

namespace {

constexpr Real kPi = 3.14159265358979323846;

// Rounded box, outer half-extents a, sweep radius R, core half-extents c = a - R.
// Pieces: core box 2c1 x 2c2 x 2c3; 3 pairs of slabs of thickness R; 12 quarter cylinders
// (4 along each axis, length 2c_i); 8 eighth spheres. Volume:
//   V = 8 c1 c2 c3 + 8 R (c2 c3 + c1 c3 + c1 c2) + 2 pi R^2 (c1 + c2 + c3) + 4 pi R^3 / 3.
Real boxVolume(const Vec3& a, Real R) {
  const Vec3 c = a - Vec3::Constant(R);
  return 8 * c[0] * c[1] * c[2] + 8 * R * (c[1] * c[2] + c[0] * c[2] + c[0] * c[1]) +
         2 * kPi * R * R * c.sum() + 4 * kPi * R * R * R / 3;
}

// I_ii / density about the centre, for axis i with the other two axes j, k. Per piece:
//  core:      m (c_j^2 + c_k^2)/3 with m = 8 c1 c2 c3
//  +-i slabs: m (c_j^2 + c_k^2)/3 each, m = 4 R c_j c_k (no i extent enters I_ii)
//  +-j slabs: m [R^2/12 + (c_j + R/2)^2 + c_k^2/3], m = 4 R c_i c_k (parallel axis at c_j + R/2)
//  quarter cylinder along i (4): length 2c_i, quarter disc A = pi R^2/4 at corner (c_j, c_k):
//     int (y^2+z^2) dA = A (c_j^2+c_k^2) + 2 (c_j+c_k) R^3/3 + pi R^4/8
//  quarter cylinder along j (4): length 2c_j, quarter disc at (c_i, c_k):
//     int y_j^2 = A 2 c_j^3/3; int y_k^2 = 2c_j [A c_k^2 + 2 c_k R^3/3 + pi R^4/16]
//  eighth sphere (8): m = pi R^3/6, first moment of the octant ball pi R^4/16 per axis,
//     int (r_j^2 + r_k^2) = pi R^5/15:  m (c_j^2+c_k^2) + 2 (c_j + c_k) pi R^4/16 + pi R^5/15.
Real boxInertia(const Vec3& a, Real R, int i) {
  const Vec3 c = a - Vec3::Constant(R);
  const int j = (i + 1) % 3, k = (i + 2) % 3;
  const Real ci = c[i], cj = c[j], ck = c[k];
  const Real A = kPi * R * R / 4;
  Real I = 8 * ci * cj * ck * (cj * cj + ck * ck) / 3;
  I += 2 * 4 * R * cj * ck * (cj * cj + ck * ck) / 3;
  I += 2 * 4 * R * ci * ck * (R * R / 12 + (cj + R / 2) * (cj + R / 2) + ck * ck / 3);
  I += 2 * 4 * R * ci * cj * (R * R / 12 + (ck + R / 2) * (ck + R / 2) + cj * cj / 3);
  I += 4 * 2 * ci * (A * (cj * cj + ck * ck) + 2 * (cj + ck) * R * R * R / 3 + kPi * R * R * R * R / 8);
  I += 4 * (A * 2 * cj * cj * cj / 3 + 2 * cj * (A * ck * ck + 2 * ck * R * R * R / 3 + kPi * std::pow(R, 4) / 16));
  I += 4 * (A * 2 * ck * ck * ck / 3 + 2 * ck * (A * cj * cj + 2 * cj * R * R * R / 3 + kPi * std::pow(R, 4) / 16));
  I += 8 * (kPi * R * R * R / 6 * (cj * cj + ck * ck) + 2 * (cj + ck) * kPi * std::pow(R, 4) / 16 + kPi * std::pow(R, 5) / 15);
  return I;
}

std::vector<Vec3> boxCorners(const Vec3& a) {
  std::vector<Vec3> p;
  for (int i = 0; i < 8; ++i) p.emplace_back((i & 1 ? 1 : -1) * a.x(), (i & 2 ? 1 : -1) * a.y(), (i & 4 ? 1 : -1) * a.z());
  return p;
}

void expectSameShape(const SpheroPolyhedron& s, const SpheroPolyhedron& ref, Real tol) {
  EXPECT_NEAR(s.volume, ref.volume, tol * ref.volume);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(s.inertiaPerDensity[k], ref.inertiaPerDensity[k], tol * ref.inertiaPerDensity.sum());
  ASSERT_EQ(s.vertices.size(), ref.vertices.size());
  for (const Vec3& v : s.vertices) {
    Real best = 1e9;
    for (const Vec3& w : ref.vertices) best = std::min(best, (v - w).norm());
    EXPECT_NEAR(best, 0.0, tol);
  }
  EXPECT_EQ(s.faces.size(), ref.faces.size());
  EXPECT_EQ(s.edges.size(), ref.edges.size());
}

template <typename F>
void expectParameterError(F&& f, const std::string& name) {
  try {
    f();
    ADD_FAILURE() << "no ParameterError thrown (expected one naming " << name << ")";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
  }
}

}  // namespace

TEST(SpheroPolyhedronShape, CubeMassPropertiesClosedForm) {
  const Vec3 a(0.05, 0.05, 0.05);
  const Real R = 0.005;
  const auto s = SpheroPolyhedron::box(a, R);
  const Real V = boxVolume(a, R);
  EXPECT_NEAR(s->volume, V, 1e-12 * V);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(s->inertiaPerDensity[i], boxInertia(a, R, i), 1e-12 * boxInertia(a, R, i));
  EXPECT_EQ(s->vertices.size(), 8u);
  EXPECT_EQ(s->edges.size(), 12u);
  EXPECT_EQ(s->faces.size(), 6u);
  for (const auto& ve : s->vertexEdges) EXPECT_EQ(ve.size(), 3u);
  for (const auto& e : s->edges) EXPECT_TRUE(e.convex);
  EXPECT_NEAR(s->coreMinWidth(), 0.09, 1e-15);
  EXPECT_NEAR(s->boundingRadius, std::sqrt(3.0) * 0.045 + 0.005, 1e-15);
  // Independent check: the sharp cube (0.1 m)^3 minus what the rounding removes, i.e. along
  // the 12 edges of length 2c = 0.09 a square R x R minus a quarter disc, and at the 8
  // corners a cube R^3 minus an eighth ball: V = 1e-3 - 12 (1 - pi/4) R^2 0.09 - (8 - 4 pi/3) R^3.
  const Real Vcut = 1e-3 - 12 * (1 - kPi / 4) * R * R * 0.09 - (8 - 4 * kPi / 3) * R * R * R;
  EXPECT_NEAR(s->volume, Vcut, 1e-12 * Vcut);
}

TEST(SpheroPolyhedronShape, NonCubicBoxMassPropertiesAndTopology) {
  const Vec3 a(0.05, 0.03, 0.02);
  const Real R = 0.004;
  const auto s = SpheroPolyhedron::box(a, R);
  EXPECT_NEAR(s->volume, boxVolume(a, R), 1e-12 * boxVolume(a, R));
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(s->inertiaPerDensity[i], boxInertia(a, R, i), 1e-12 * boxInertia(a, R, i));
  EXPECT_NEAR(s->framePosition.norm(), 0.0, 1e-15);
  EXPECT_NEAR(s->frameOrientation.angularDistance(Quat::Identity()), 0.0, 1e-15);
  // Edge/face incidence: f0 sees v0->v1 in its loop, f1 sees v1->v0; faces CCW from outside.
  for (const auto& e : s->edges) {
    auto hasSide = [&](int f, int x, int y) {
      const auto& L = s->faces[f].loop;
      for (size_t i = 0; i < L.size(); ++i)
        if (L[i] == x && L[(i + 1) % L.size()] == y) return true;
      return false;
    };
    EXPECT_TRUE(hasSide(e.f0, e.v0, e.v1));
    EXPECT_TRUE(hasSide(e.f1, e.v1, e.v0));
  }
  for (const auto& f : s->faces) {
    const Vec3 n = (s->vertices[f.loop[1]] - s->vertices[f.loop[0]]).cross(s->vertices[f.loop[2]] - s->vertices[f.loop[1]]);
    EXPECT_NEAR(n.normalized().dot(f.normal), 1.0, 1e-14);
    for (int v : f.loop) EXPECT_NEAR(f.normal.dot(s->vertices[v]), f.offset, 1e-15);
  }
}

TEST(SpheroPolyhedronShape, ConvexHullOfBoxCornersEqualsBox) {
  const Vec3 a(0.05, 0.03, 0.02);
  const Real R = 0.004;
  std::vector<Vec3> pts = boxCorners(a);
  pts.emplace_back(0.01, 0.0, 0.0);     // interior point: not a hull vertex
  pts.emplace_back(0.0, 0.03, 0.02);    // point inside a hull edge
  const auto h = SpheroPolyhedron::convexHull(pts, R);
  const auto b = SpheroPolyhedron::box(a, R);
  expectSameShape(*h, *b, 1e-12);
  for (const auto& f : h->faces) EXPECT_EQ(f.loop.size(), 4u);  // coplanar triangles merged
}

TEST(SpheroPolyhedronShape, SmallFacetVanishesFromCore) {
  // Cube of half-side 0.1 with the corner (1,1,1)*0.1 cut off at distance t along its three
  // edges: cut plane x + y + z = 0.3 - t. After moving every plane in by R the cut plane still
  // clips the core corner (0.1 - R)(1,1,1) iff (0.3 - t)/sqrt3 - R < sqrt3 (0.1 - R), i.e.
  // t > (3 - sqrt3) R = 1.268 R.
  auto cutCube = [](Real t) {
    std::vector<Vec3> p;
    for (const Vec3& c : boxCorners(Vec3::Constant(0.1)))
      if (c.minCoeff() < 0) p.push_back(c);
    p.emplace_back(0.1 - t, 0.1, 0.1);
    p.emplace_back(0.1, 0.1 - t, 0.1);
    p.emplace_back(0.1, 0.1, 0.1 - t);
    return p;
  };
  const Real R = 0.02;
  const auto gone = SpheroPolyhedron::convexHull(cutCube(0.02), R);  // t = R < 1.268 R
  EXPECT_EQ(gone->faces.size(), 6u);
  EXPECT_EQ(gone->vertices.size(), 8u);
  EXPECT_NEAR(gone->volume, boxVolume(Vec3::Constant(0.1), R), 1e-12 * gone->volume);
  const auto kept = SpheroPolyhedron::convexHull(cutCube(0.03), R);  // t = 1.5 R
  EXPECT_EQ(kept->faces.size(), 7u);
  EXPECT_EQ(kept->vertices.size(), 10u);
  EXPECT_LT(kept->volume, gone->volume);
}

TEST(SpheroPolyhedronShape, ManyFacetHullConsistentWithSteiner) {
  // Hull of 500 pseudo-random points on a sphere of radius 0.1 (many small faces, vertices
  // where the shifted planes split). Steiner's formula with the core's own geometry
  // V_R = V + A R + M R^2 + 4 pi R^3/3 (M = 1/2 sum_e L_e angle(n0, n1)) checks the piecewise
  // integration (slabs, wedges, vertex sectors whose solid angles must add up to 4 pi).
  std::vector<Vec3> p;
  unsigned state = 12345u;
  auto uniform = [&]() {
    state = state * 1664525u + 1013904223u;
    return (state >> 8) / 16777216.0;
  };
  while (p.size() < 500) {
    const Vec3 v(2 * uniform() - 1, 2 * uniform() - 1, 2 * uniform() - 1);
    if (v.norm() > 0.2 && v.norm() < 1) p.push_back(0.1 * v.normalized());
  }
  const Real R = 0.01;
  const auto s = SpheroPolyhedron::convexHull(p, R);
  Real V = 0, A = 0, M = 0;
  for (const auto& f : s->faces)
    for (size_t i = 1; i + 1 < f.loop.size(); ++i) {
      const Vec3 &a = s->vertices[f.loop[0]], &b = s->vertices[f.loop[i]], &c = s->vertices[f.loop[i + 1]];
      V += a.dot(b.cross(c)) / 6;
      A += 0.5 * (b - a).cross(c - a).norm();
    }
  for (const auto& e : s->edges) {
    const Vec3 &n0 = s->faces[e.f0].normal, &n1 = s->faces[e.f1].normal;
    M += 0.5 * (s->vertices[e.v1] - s->vertices[e.v0]).norm() * std::atan2(n0.cross(n1).norm(), n0.dot(n1));
  }
  const Real VR = V + A * R + M * R * R + 4 * kPi * R * R * R / 3;
  EXPECT_NEAR(s->volume, VR, 1e-12 * VR);
  // the rounded body lies inside P, itself inside the sphere
  EXPECT_LT(s->volume, 4 * kPi / 3 * 1e-3);
  EXPECT_GT(s->volume, 0.9 * 4 * kPi / 3 * 1e-3);
  // core is convex: every vertex on the inner side of every face plane
  Real worst = 0;
  for (const auto& f : s->faces)
    for (const auto& v : s->vertices) worst = std::max(worst, f.normal.dot(v) - f.offset);
  EXPECT_NEAR(worst, 0.0, 1e-12);
  EXPECT_NEAR(s->inertiaPerDensity[0], s->inertiaPerDensity[2], 0.02 * s->inertiaPerDensity[2]);
}

TEST(SpheroPolyhedronShape, RegularOctahedronAndTetrahedronSteiner) {
  // Steiner: V_R = V + A R + M R^2 + 4 pi R^3/3, M = 1/2 sum_e L_e (pi - interior dihedral).
  {
    // Octahedron with vertices +-a e_i: inradius a/sqrt(3); the core is the octahedron with
    // vertices +-ac e_i, ac = a - sqrt(3) R. Volume 4 ac^3/3, area 8 (sqrt3/4)(sqrt2 ac)^2 =
    // 4 sqrt3 ac^2, 12 edges of length sqrt2 ac, pi - dihedral = acos(1/3).
    const Real a = 0.1, R = 0.01, ac = a - std::sqrt(3.0) * R;
    std::vector<Vec3> p;
    for (int i = 0; i < 3; ++i) {
      p.push_back(a * Vec3::Unit(i));
      p.push_back(-a * Vec3::Unit(i));
    }
    const auto s = SpheroPolyhedron::convexHull(p, R);
    const Real V = 4 * ac * ac * ac / 3 + 4 * std::sqrt(3.0) * ac * ac * R +
                   0.5 * 12 * std::sqrt(2.0) * ac * std::acos(1.0 / 3) * R * R + 4 * kPi * R * R * R / 3;
    EXPECT_NEAR(s->volume, V, 1e-12 * V);
    EXPECT_EQ(s->vertices.size(), 6u);
    EXPECT_EQ(s->faces.size(), 8u);
    EXPECT_EQ(s->edges.size(), 12u);
    for (const auto& v : s->vertices) EXPECT_NEAR(v.norm(), ac, 1e-13);
    // cubic symmetry: isotropic inertia
    EXPECT_NEAR(s->inertiaPerDensity[0], s->inertiaPerDensity[2], 1e-12 * s->inertiaPerDensity[2]);
  }
  {
    // Tetrahedron (s,s,s),(s,-s,-s),(-s,s,-s),(-s,-s,s): inradius s/sqrt3; core scaled by
    // (s/sqrt3 - R)/(s/sqrt3); edge L = 2 sqrt2 sc, V = L^3/(6 sqrt2), A = sqrt3 L^2,
    // pi - dihedral = pi - acos(1/3).
    const Real sz = 0.1, R = 0.01, sc = sz * (sz / std::sqrt(3.0) - R) / (sz / std::sqrt(3.0));
    const Real L = 2 * std::sqrt(2.0) * sc;
    const std::vector<Vec3> p{{sz, sz, sz}, {sz, -sz, -sz}, {-sz, sz, -sz}, {-sz, -sz, sz}};
    const auto s = SpheroPolyhedron::convexHull(p, R);
    const Real V = L * L * L / (6 * std::sqrt(2.0)) + std::sqrt(3.0) * L * L * R +
                   0.5 * 6 * L * (kPi - std::acos(1.0 / 3)) * R * R + 4 * kPi * R * R * R / 3;
    EXPECT_NEAR(s->volume, V, 1e-12 * V);
    EXPECT_EQ(s->faces.size(), 4u);
    EXPECT_NEAR(s->inertiaPerDensity[0], s->inertiaPerDensity[1], 1e-12 * s->inertiaPerDensity[1]);
    EXPECT_NEAR(s->inertiaPerDensity[0], s->inertiaPerDensity[2], 1e-12 * s->inertiaPerDensity[2]);
  }
}

TEST(SpheroPolyhedronShape, MeshFilesOfBoxEqualBox) {
  const Vec3 a(0.05, 0.03, 0.02);
  const Real R = 0.004;
  const auto b = SpheroPolyhedron::box(a, R);
  for (const char* name : {"box_offset.stl", "box_offset.obj"}) {
    const auto s = SpheroPolyhedron::meshFile(std::string(MPMSDEM_TEST_DATA) + "/" + name, R);
    expectSameShape(*s, *b, 1e-12);
    // the files describe the box centred at (0.1, 0.2, 0.3), axes aligned
    EXPECT_NEAR((s->framePosition - Vec3(0.1, 0.2, 0.3)).norm(), 0.0, 1e-14) << name;
    EXPECT_NEAR(s->frameOrientation.angularDistance(Quat::Identity()), 0.0, 1e-14) << name;
    EXPECT_EQ(s->outerVertices.size(), 8u) << name;  // STL corners merged
  }
  // Binary STL, half-extents (0.5, 0.25, 0.125) in file units, read in millimetres.
  const auto s = SpheroPolyhedron::meshFile(std::string(MPMSDEM_TEST_DATA) + "/box_binary.stl", 0.01e-3, 1e-3);
  const auto ref = SpheroPolyhedron::box(Vec3(0.5e-3, 0.25e-3, 0.125e-3), 0.01e-3);
  expectSameShape(*s, *ref, 1e-12);
}

TEST(SpheroPolyhedronShape, LShapedPrismNonConvex) {
  // L cross-section (0,0) (0.2,0) (0.2,0.1) (0.1,0.1) (0.1,0.2) (0,0.2), z in [0, 0.1], R = 0.01.
  // Core: cross-section Q with corners (R,R) (0.2-R,R) (0.2-R,0.1-R) (0.1-R,0.1-R) (0.1-R,0.2-R)
  // (R,0.2-R): area AQ = 0.18*0.08 + 0.08*0.10 = 0.0224, perimeter PQ = 0.72; length Lz = 0.08.
  // Exact rounded volume, written as integral over the cross-section of the z-extent:
  //   V = Lz (AQ + PQ R + (5 pi/4 - 1) R^2) + 2 AQ R + (pi/2) PQ R^2 + (5 pi/3) R^3 - (4/3) R^3
  // (5 convex corners: quarter discs / eighth spheres; reflex corner: slab overlap R^2 per
  // unit length, and at each end the two cap-edge wedges overlap by
  // int_[0,R]^2 sqrt(R^2 - max(a,b)^2) da db = 2R^3/3).
  const Real R = 0.01, AQ = 0.0224, PQ = 0.72, Lz = 0.08;
  const Real V = Lz * (AQ + PQ * R + (5 * kPi / 4 - 1) * R * R) + 2 * AQ * R + kPi / 2 * PQ * R * R +
                 5 * kPi / 3 * R * R * R - 4.0 / 3 * R * R * R;
  const auto s = SpheroPolyhedron::meshFile(std::string(MPMSDEM_TEST_DATA) + "/l_prism.obj", R);
  EXPECT_FALSE(s->convex);
  EXPECT_NEAR(s->volume, V, 1e-12 * V);
  // 12 vertices; edges: 6 vertical (5 ridges, 1 valley) + 12 cap edges (the cap diagonals
  // and side-quad diagonals are flat, not edges).
  EXPECT_EQ(s->vertices.size(), 12u);
  EXPECT_EQ(s->edges.size(), 18u);
  int valleys = 0;
  for (const auto& e : s->edges) valleys += e.convex ? 0 : 1;
  EXPECT_EQ(valleys, 1);
  // Symmetry about the plane x = y: the centroid lies on it and one principal axis is z.
  EXPECT_NEAR(s->framePosition.x(), s->framePosition.y(), 1e-14);
  EXPECT_NEAR(s->framePosition.z(), 0.05, 1e-14);
  const Mat3 Q = s->frameOrientation.toRotationMatrix();
  Real zAxis = 0;
  for (int k = 0; k < 3; ++k) zAxis = std::max(zAxis, std::abs(Q.col(k).z()));
  EXPECT_NEAR(zAxis, 1.0, 1e-12);
  // Inertia: independent check by quadrature of the same 2D x 1D description. For a point
  // (x, y) at distance d from the core L polygon (0 inside), the body's z-extent is
  // [R - H, h - R + H] with H = sqrt(R^2 - d^2) (H = R inside). Midpoint rule on a 3000^2
  // grid; the sqrt edge limits it: measured errors 2.5e-6 (volume), 1.5e-8 m (centroid),
  // 4.3e-6 (inertia, relative), each 7-9x smaller than on a 1500^2 grid, i.e. quadrature
  // error. Compared to the body-frame moments rotated back to the input frame.
  {
    const std::vector<Vec3> Lc{{R, R, 0}, {0.2 - R, R, 0}, {0.2 - R, 0.1 - R, 0}, {0.1 - R, 0.1 - R, 0},
                               {0.1 - R, 0.2 - R, 0}, {R, 0.2 - R, 0}};
    auto inside = [&](Real x, Real y) {
      return (x >= R && x <= 0.2 - R && y >= R && y <= 0.1 - R) || (x >= R && x <= 0.1 - R && y >= R && y <= 0.2 - R);
    };
    auto dist = [&](Real x, Real y) {
      Real d = 1e9;
      for (size_t i = 0; i < Lc.size(); ++i) {
        const Vec3 a = Lc[i], b = Lc[(i + 1) % Lc.size()], p(x, y, 0);
        const Real t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
        d = std::min(d, (p - a - t * (b - a)).norm());
      }
      return d;
    };
    const int N = 3000;
    const Real lo = 0.0, span = 0.2, dA = (span / N) * (span / N), h = 0.1;
    Real m0 = 0;
    Vec3 m1 = Vec3::Zero();
    Mat3 m2 = Mat3::Zero();
    for (int i = 0; i < N; ++i)
      for (int j = 0; j < N; ++j) {
        const Real x = lo + (i + 0.5) * span / N, y = lo + (j + 0.5) * span / N;
        Real H;
        if (inside(x, y)) {
          H = R;
        } else {
          const Real d = dist(x, y);
          if (d >= R) continue;
          H = std::sqrt(R * R - d * d);
        }
        const Real z0 = R - H, z1 = h - R + H, len = z1 - z0;
        const Real iz = 0.5 * (z1 * z1 - z0 * z0), izz = (z1 * z1 * z1 - z0 * z0 * z0) / 3;
        m0 += len * dA;
        m1 += Vec3(x * len, y * len, iz) * dA;
        Mat3 q;
        q << x * x * len, x * y * len, x * iz, x * y * len, y * y * len, y * iz, x * iz, y * iz, izz;
        m2 += q * dA;
      }
    const Vec3 cq = m1 / m0;
    const Mat3 J = m2 - m0 * cq * cq.transpose();
    const Mat3 Iq = J.trace() * Mat3::Identity() - J;
    const Mat3 Is = Q * s->inertiaPerDensity.asDiagonal() * Q.transpose();
    EXPECT_NEAR(m0, V, 5e-6 * V);  // the quadrature itself, against the hand volume
    EXPECT_NEAR((cq - s->framePosition).norm(), 0.0, 5e-8);
    EXPECT_NEAR((Iq - Is).norm() / Is.norm(), 0.0, 1e-5);
  }
  // Eroded reflex vertex at (0.1-R, 0.1-R) in the input frame.
  bool found = false;
  for (const auto& v : s->vertices) {
    const Vec3 x = s->framePosition + Q * v;
    found = found || (x - Vec3(0.1 - R, 0.1 - R, R)).norm() < 1e-14;
  }
  EXPECT_TRUE(found);
  // closestPoint in the valley: a point over the valley edge region at equal distance 0.5R
  // from both side walls is 0.5R from the core, nearest to a face interior.
  const Vec3 pIn = Q.transpose() * (Vec3(0.1 - R + 0.5 * R, 0.1 - R + 0.5 * R, 0.05) - s->framePosition);
  const auto q = s->closestPoint(pIn);
  EXPECT_NEAR(q.distance, 0.5 * R, 1e-14);
  EXPECT_EQ(q.featureKind, 0);
  const auto qInside = s->closestPoint(Q.transpose() * (Vec3(0.05, 0.05, 0.05) - s->framePosition));
  EXPECT_EQ(qInside.distance, 0.0);
}

TEST(SpheroPolyhedronShape, ObtuseValleyPrismMatchesCrossSectionFormula) {
  // Prism of height h = 0.1 over the pentagon (0,0) (0.2,0) (0.2,0.1) (0.1,0.1) (0,0.2): a reflex
  // corner at (0.1,0.1) with interior angle 225 deg (free opening alpha = 135 deg).
  // For an extruded polygon the rounded volume is the integral over the plane of the z-extent
  // (core length Lz = h - 2R plus 2 sqrt(R^2 - d^2) where d is the distance to the core polygon):
  //   V = Lz Area(Qc (+) disc R) + 2 [A R + (pi R^2/4) P + sum_convex ext_i R^3/3 - X],
  //   Area(Qc (+) disc) = A + P R + sum_convex ext_i R^2/2 - K,
  // with K the area counted twice by the two edge strips at the reflex corner and X the
  // integral of sqrt(R^2 - max(t0,t1)^2) over it. With c = n0.n1 = cos(45 deg) > 0 (obtuse)
  // that region is a kite: in (t0, t1) coordinates the triangles 0 <= c t0 <= t1 <= t0 <= R
  // and its mirror, area element dt0 dt1 / sqrt(1 - c^2):
  //   K = (1 - c) R^2 / sqrt(1 - c^2),   X = 2 (1 - c) R^3 / (3 sqrt(1 - c^2)).
  // Convex corners: three of 90 deg (exterior pi/2) and one of 45 deg (exterior 3 pi/4).
  // Core polygon (edges moved in by R; the slanted edge x + y = 0.2 by R): corners
  // (R,R) (0.2-R,R) (0.2-R,0.1-R) (0.1+R-sqrt2 R, 0.1-R) (R, 0.2-sqrt2 R-R).
  const Real R = 0.01, h = 0.1, Lz = h - 2 * R, r2 = std::sqrt(2.0);
  const std::vector<Vec3> core2d{{R, R, 0}, {0.2 - R, R, 0}, {0.2 - R, 0.1 - R, 0}, {0.1 + R - r2 * R, 0.1 - R, 0},
                                 {R, 0.2 - r2 * R - R, 0}};
  Real A = 0, P = 0;
  for (size_t i = 0; i < core2d.size(); ++i) {
    const Vec3& p = core2d[i];
    const Vec3& q = core2d[(i + 1) % core2d.size()];
    A += 0.5 * (p.x() * q.y() - q.x() * p.y());
    P += (q - p).norm();
  }
  const Real ext = 3 * kPi / 2 + 3 * kPi / 4, c = 1 / r2, sg = std::sqrt(1 - c * c);
  const Real K = (1 - c) * R * R / sg, X = 2 * (1 - c) * R * R * R / (3 * sg);
  const Real V = Lz * (A + P * R + ext * R * R / 2 - K) + 2 * (A * R + kPi * R * R / 4 * P + ext * R * R * R / 3 - X);
  const std::vector<Vec3> poly{{0, 0, 0}, {0.2, 0, 0}, {0.2, 0.1, 0}, {0.1, 0.1, 0}, {0, 0.2, 0}};
  std::vector<Vec3> verts;
  for (int k = 0; k < 2; ++k)
    for (const Vec3& p : poly) verts.push_back(p + Vec3(0, 0, k * h));
  std::vector<std::array<int, 3>> tris{{5, 6, 7}, {5, 7, 8}, {5, 8, 9}, {0, 2, 1}, {0, 3, 2}, {0, 4, 3}};
  for (int i = 0; i < 5; ++i) {
    const int j = (i + 1) % 5;
    tris.push_back({i, j, j + 5});
    tris.push_back({i, j + 5, i + 5});
  }
  const auto s = SpheroPolyhedron::mesh(verts, tris, R);
  EXPECT_FALSE(s->convex);
  EXPECT_NEAR(s->volume, V, 1e-12 * V);
}

TEST(SpheroPolyhedronShape, BodyFrameRecoversInputPose) {
  const Vec3 a(0.05, 0.03, 0.02);
  const Real R = 0.004;
  const Quat q0 = Quat(Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()));
  const Vec3 t0(0.3, -0.2, 1.1);
  std::vector<Vec3> pts;
  for (const Vec3& p : boxCorners(a)) pts.push_back(t0 + q0 * p);
  const auto s = SpheroPolyhedron::convexHull(pts, R);
  EXPECT_NEAR((s->framePosition - t0).norm(), 0.0, 1e-14);
  // Principal moments ascending: I_x < I_y < I_z for this box, so body axes are the box axes
  // (each up to its sign).
  const Mat3 Q = s->frameOrientation.toRotationMatrix(), Q0 = q0.toRotationMatrix();
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(std::abs(Q.col(k).dot(Q0.col(k))), 1.0, 1e-12);
  EXPECT_NEAR(Q.determinant(), 1.0, 1e-14);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(s->inertiaPerDensity[i], boxInertia(a, R, i), 1e-12 * boxInertia(a, R, i));
  // Core vertices in the body frame are the box corners +-(a - R).
  for (const Vec3& v : s->vertices) EXPECT_NEAR((v.cwiseAbs() - (a - Vec3::Constant(R))).norm(), 0.0, 1e-15);
  for (const Vec3& v : s->outerVertices) EXPECT_NEAR((v.cwiseAbs() - a).norm(), 0.0, 1e-15);
}

TEST(SpheroPolyhedronShape, ClosestPointHandValues) {
  const auto s = SpheroPolyhedron::box(Vec3(0.05, 0.03, 0.02), 0.005);  // core half (0.045, 0.025, 0.015)
  auto q = s->closestPoint(Vec3(0.01, -0.005, 0.1));                      // over the +z face
  EXPECT_NEAR(q.distance, 0.085, 1e-15);
  EXPECT_NEAR((q.closest - Vec3(0.01, -0.005, 0.015)).norm(), 0.0, 1e-15);
  EXPECT_EQ(q.featureKind, 0);
  EXPECT_NEAR(s->faces[q.featureIndex].normal.z(), 1.0, 1e-15);
  q = s->closestPoint(Vec3(0.0, 0.035, 0.025));  // beyond the edge y = 0.025, z = 0.015
  EXPECT_NEAR(q.distance, std::sqrt(2.0) * 0.01, 1e-15);
  EXPECT_NEAR((q.closest - Vec3(0.0, 0.025, 0.015)).norm(), 0.0, 1e-15);
  ASSERT_EQ(q.featureKind, 1);
  const auto& e = s->edges[q.featureIndex];
  EXPECT_NEAR(s->vertices[e.v0].y(), 0.025, 1e-15);
  EXPECT_NEAR(s->vertices[e.v1].z(), 0.015, 1e-15);
  q = s->closestPoint(Vec3(0.055, 0.035, 0.025));  // beyond the corner
  EXPECT_NEAR(q.distance, std::sqrt(3.0) * 0.01, 1e-15);
  ASSERT_EQ(q.featureKind, 2);
  EXPECT_NEAR((s->vertices[q.featureIndex] - Vec3(0.045, 0.025, 0.015)).norm(), 0.0, 1e-15);
  q = s->closestPoint(Vec3(0.01, 0.0, 0.0));  // inside the core
  EXPECT_EQ(q.distance, 0.0);
  EXPECT_NEAR((q.closest - Vec3(0.01, 0.0, 0.0)).norm(), 0.0, 1e-15);
}

TEST(SpheroPolyhedronShape, BadInputThrowsParameterError) {
  const Vec3 a(0.05, 0.03, 0.02);
  expectParameterError([&] { SpheroPolyhedron::box(a, 0.02); }, "sweepRadius");   // R = min half-extent
  expectParameterError([&] { SpheroPolyhedron::box(a, 0.0); }, "sweepRadius");
  expectParameterError([&] { SpheroPolyhedron::box(a, -0.001); }, "sweepRadius");
  expectParameterError([&] { SpheroPolyhedron::box(Vec3(0.05, -0.03, 0.02), 0.001); }, "halfExtents");
  expectParameterError([&] { SpheroPolyhedron::convexHull(boxCorners(a), 0.02); }, "sweepRadius");
  // fewer than 4 points, and coplanar points
  expectParameterError([&] { SpheroPolyhedron::convexHull({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, 0.01); }, "points");
  expectParameterError(
      [&] { SpheroPolyhedron::convexHull({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0.5, 0.2, 0}}, 0.01); }, "points");
  // Tetrahedron mesh: vertices 0..3, outward triangles.
  const std::vector<Vec3> tv{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const std::vector<std::array<int, 3>> tet{{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  EXPECT_NO_THROW(SpheroPolyhedron::mesh(tv, tet, 0.01));
  // One triangle flipped: its sides run the same way as their neighbours' (inconsistent).
  expectParameterError([&] { SpheroPolyhedron::mesh(tv, {tet[0], tet[1], tet[2], {1, 3, 2}}, 0.01); }, "mesh = edge");
  // Open: a cube missing one face (10 triangles).
  {
    std::vector<std::array<int, 3>> cube;
    const int quads[6][4] = {{1, 3, 7, 5}, {0, 4, 6, 2}, {2, 6, 7, 3}, {0, 1, 5, 4}, {4, 5, 7, 6}, {0, 2, 3, 1}};
    for (int f = 0; f < 5; ++f) {
      cube.push_back({quads[f][0], quads[f][1], quads[f][2]});
      cube.push_back({quads[f][0], quads[f][2], quads[f][3]});
    }
    try {
      SpheroPolyhedron::mesh(boxCorners(a), cube, 0.001);
      ADD_FAILURE() << "open mesh accepted";
    } catch (const ParameterError& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("mesh"), std::string::npos);
      EXPECT_NE(m.find("open"), std::string::npos) << m;
    }
  }
  // Non-manifold edge: two tetrahedra sharing the edge (0,1) only.
  {
    std::vector<Vec3> v = tv;
    v.push_back({0, 0, -1});
    v.push_back({0, -1, 0});
    std::vector<std::array<int, 3>> t = tet;
    const std::vector<std::array<int, 3>> tet2{{0, 5, 1}, {0, 1, 4}, {0, 4, 5}, {1, 5, 4}};
    t.insert(t.end(), tet2.begin(), tet2.end());
    try {
      SpheroPolyhedron::mesh(v, t, 0.001);
      ADD_FAILURE() << "non-manifold mesh accepted";
    } catch (const ParameterError& e) {
      // the side 1->0 is used by triangles of both tetrahedra
      EXPECT_NE(std::string(e.what()).find("mesh = edge (1, 0)"), std::string::npos) << e.what();
    }
  }
  // Zero-area triangle.
  {
    // vertex 4 lies on the edge 1-2: the triangle (1, 2, 4) has zero area
    std::vector<Vec3> v = tv;
    v.push_back({0.5, 0.5, 0});
    const std::vector<std::array<int, 3>> t{{0, 2, 4}, {0, 4, 1}, {0, 1, 3}, {0, 3, 2}, {1, 4, 3}, {4, 2, 3}, {1, 2, 4}, {2, 1, 4}};
    try {
      SpheroPolyhedron::mesh(v, t, 0.01);
      ADD_FAILURE() << "zero-area triangle accepted";
    } catch (const ParameterError& e) {
      EXPECT_NE(std::string(e.what()).find("zero area"), std::string::npos) << e.what();
    }
  }
  // Inward-oriented (all triangles reversed).
  {
    std::vector<std::array<int, 3>> inv;
    for (const auto& t : tet) inv.push_back({t[0], t[2], t[1]});
    try {
      SpheroPolyhedron::mesh(tv, inv, 0.01);
      ADD_FAILURE() << "inward mesh accepted";
    } catch (const ParameterError& e) {
      EXPECT_NE(std::string(e.what()).find("inward"), std::string::npos) << e.what();
    }
  }
  // corner tetrahedron: inradius 3V/A = 0.5/(1.5 + sqrt3/2) = 0.2113 < half width 1/(2 sqrt3)
  expectParameterError([&] { SpheroPolyhedron::mesh(tv, tet, 0.212); }, "sweepRadius");
  EXPECT_NO_THROW(SpheroPolyhedron::mesh(tv, tet, 0.21));
  expectParameterError([&] { SpheroPolyhedron::meshFile("/nonexistent/shape.stl", 0.01); }, "path");
  expectParameterError([&] { SpheroPolyhedron::meshFile(std::string(MPMSDEM_TEST_DATA) + "/box_offset.ply", 0.01); }, "path");
  expectParameterError([&] { SpheroPolyhedron::meshFile(std::string(MPMSDEM_TEST_DATA) + "/box_offset.obj", 0.001, 0.0); },
                       "scale");
  expectParameterError([&] { SpheroPolyhedron::meshFile(std::string(MPMSDEM_TEST_DATA) + "/l_prism.obj", 0.06); },
                       "sweepRadius");
}

TEST(SpheroPolyhedronShape, AabbOfRotatedBox) {
  const auto s = SpheroPolyhedron::box(Vec3(0.05, 0.03, 0.02), 0.005);  // core half (0.045, 0.025, 0.015)
  const Vec3 pos(1.0, 2.0, 3.0);
  const Quat ori(Eigen::AngleAxisd(kPi / 4, Vec3::UnitZ()));
  Vec3 lo, hi;
  Bo1_SpheroPolyhedron_Aabb::go(*s, pos, ori, lo, hi);
  // 45 deg about z: x' = (x - y)/sqrt2, y' = (x + y)/sqrt2; max over corners (0.045 + 0.025)/sqrt2.
  const Real h = 0.07 / std::sqrt(2.0) + 0.005;
  EXPECT_NEAR((hi - (pos + Vec3(h, h, 0.02))).norm(), 0.0, 1e-15);
  EXPECT_NEAR((lo - (pos - Vec3(h, h, 0.02))).norm(), 0.0, 1e-15);
}

TEST(Bo1SpheroPolyhedronAabb, PosedShapeGivesTheSameBox) {
  // The broad phase bounds bodies from their posed cores: it must agree with the pose form.
  auto s = SpheroPolyhedron::box(Vec3(0.1, 0.2, 0.3), 0.02);
  const Vec3 pos(1, -2, 0.5);
  const Quat ori(Eigen::AngleAxis<Real>(0.7, Vec3(1, 2, 3).normalized()));
  PosedSpheroPolyhedron posed;
  posed.update(*s, pos, ori);
  Vec3 lo1, hi1, lo2, hi2;
  Bo1_SpheroPolyhedron_Aabb::go(*s, pos, ori, lo1, hi1);
  Bo1_SpheroPolyhedron_Aabb::go(posed, lo2, hi2);
  EXPECT_LT((lo1 - lo2).norm(), 1e-15);
  EXPECT_LT((hi1 - hi2).norm(), 1e-15);
}
