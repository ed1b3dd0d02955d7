// Seeding material points inside closed triangle meshes (mpm::seedMesh) and the "mesh" form of
// the scene's "particles" entries: a box-shaped mesh reproduces seedBox exactly, an icosphere
// gets the sphere's mass within the sampling bound, the non-convex L-prism gets its hand count,
// bad meshes are refused naming the mesh.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "common/Error.hpp"
#include "input/MeshReader.hpp"
#include "scene/MpmScene.hpp"
#include "mpm/Seeding.hpp"

using namespace mpmsdem;
using namespace mpmsdem::mpm;
using Tris = std::vector<std::array<int, 3>>;

namespace {

MpmParams grid(double dx, std::array<int, 3> cells, std::array<double, 3> origin) {
  MpmParams p;
  p.dx = dx;
  p.cells = cells;
  p.origin = origin;
  p.material.density = 1600;
  return p;
}

// Box [lo, hi] as 8 vertices (index = x + 2 y + 4 z, 0 = lo, 1 = hi) and 12 triangles,
// counter-clockwise seen from outside.
void boxMesh(const std::array<double, 3>& lo, const std::array<double, 3>& hi, std::vector<Vec3>& V, Tris& T) {
  V.clear();
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) V.emplace_back(i ? hi[0] : lo[0], j ? hi[1] : lo[1], k ? hi[2] : lo[2]);
  const int quads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  T.clear();
  for (const auto& q : quads) {
    T.push_back({q[0], q[1], q[2]});
    T.push_back({q[0], q[2], q[3]});
  }
}

// Splits every triangle into 4 through its edge midpoints (shared between neighbours),
// `levels` times; with `project` the new vertices are pushed onto the unit sphere.
void subdivide(std::vector<Vec3>& u, Tris& T, int levels, bool project) {
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      const Vec3 m = 0.5 * (u[a] + u[b]);
      u.push_back(project ? m.normalized() : m);
      return mid[key] = static_cast<int>(u.size()) - 1;
    };
    Tris next;
    for (const auto& t : T) {
      const int ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]), ca = midpoint(t[2], t[0]);
      next.push_back({t[0], ab, ca});
      next.push_back({t[1], bc, ab});
      next.push_back({t[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    T.swap(next);
  }
}

// Icosphere of radius r about c: the 20 faces of the icosahedron are the triples of mutually
// nearest vertices, oriented outward; each level splits every triangle into 4, the new
// (shared) edge midpoints pushed onto the sphere.
void icosphere(const Vec3& c, double r, int levels, std::vector<Vec3>& V, Tris& T) {
  const double g = (1 + std::sqrt(5.0)) / 2;
  std::vector<Vec3> u;
  for (int s1 : {-1, 1})
    for (int s2 : {-1, 1}) {
      u.emplace_back(0, s1, s2 * g);
      u.emplace_back(s1, s2 * g, 0);
      u.emplace_back(s2 * g, 0, s1);
    }
  for (Vec3& p : u) p.normalize();
  double edge = INFINITY;
  for (std::size_t i = 0; i < u.size(); ++i)
    for (std::size_t j = i + 1; j < u.size(); ++j) edge = std::min(edge, (u[i] - u[j]).norm());
  auto adjacent = [&](int i, int j) { return (u[i] - u[j]).norm() < edge * 1.01; };
  T.clear();
  for (int i = 0; i < 12; ++i)
    for (int j = i + 1; j < 12; ++j)
      for (int k = j + 1; k < 12; ++k)
        if (adjacent(i, j) && adjacent(j, k) && adjacent(i, k)) {
          if ((u[j] - u[i]).cross(u[k] - u[i]).dot(u[i] + u[j] + u[k]) > 0)
            T.push_back({i, j, k});
          else
            T.push_back({i, k, j});
        }
  subdivide(u, T, levels, true);
  V.clear();
  for (const Vec3& p : u) V.push_back(c + r * p);
}

double totalMass(const ParticleSet& p) {
  double m = 0;
  for (double x : p.mass) m += x;
  return m;
}

// Positions as sorted triples, to compare particle sets seeded in different orders.
std::vector<std::array<double, 3>> sortedPositions(const ParticleSet& p) {
  std::vector<std::array<double, 3>> out(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) out[i] = {p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2]};
  std::sort(out.begin(), out.end());
  return out;
}

// Run `f` and require a ParameterError whose message contains every needle.
template <typename F>
void expectError(F f, std::initializer_list<const char*> needles) {
  try {
    f();
    ADD_FAILURE() << "expected ParameterError";
  } catch (const ParameterError& e) {
    for (const char* n : needles) EXPECT_NE(std::string(e.what()).find(n), std::string::npos) << e.what();
  }
}

// A fresh folder for this test process.
std::filesystem::path tempDir(const std::string& tag) {
  const auto d = std::filesystem::temp_directory_path() / ("mpmsdem_seed_mesh_" + tag + "_" + std::to_string(getpid()));
  std::filesystem::create_directories(d);
  return d;
}

void writeAsciiStl(const std::filesystem::path& file, const std::vector<Vec3>& V, const Tris& T) {
  std::ofstream os(file);
  os.precision(17);
  os << "solid test\n";
  for (const auto& t : T) {
    os << " facet normal 0 0 0\n  outer loop\n";
    for (int c = 0; c < 3; ++c) os << "   vertex " << V[t[c]].x() << " " << V[t[c]].y() << " " << V[t[c]].z() << "\n";
    os << "  endloop\n endfacet\n";
  }
  os << "endsolid test\n";
}

}  // namespace

// Box-shaped mesh on grid lines == seedBox, element by element, for either orientation.
TEST(SeedMesh, BoxMeshEqualsSeedBox) {
  // dx = 0.01, 12 cells: material region [0.02, 0.10] on every axis.
  const MpmParams prm = grid(0.01, {12, 12, 12}, {0, 0, 0});
  const std::array<double, 3> lo{0.03, 0.02, 0.04}, hi{0.07, 0.05, 0.09};
  std::vector<Vec3> V;
  Tris T;
  boxMesh(lo, hi, V, T);
  for (const std::array<int, 3> ppc : {std::array<int, 3>{2, 3, 1}, std::array<int, 3>{2, 2, 2}}) {
    for (bool reversed : {false, true}) {
      Tris tris = T;
      if (reversed)
        for (auto& t : tris) std::swap(t[1], t[2]);
      ParticleSet box, mesh;
      const std::size_t nb = seedBox(prm, lo, hi, ppc, box);
      const std::size_t nm = seedMesh(prm, V, tris, ppc, {0.5, -1, 2}, mesh, "box");
      // 4 x 3 x 5 cells of 0.01 m.
      const std::size_t expected = 60u * ppc[0] * ppc[1] * ppc[2];
      ASSERT_EQ(nb, expected);
      ASSERT_EQ(nm, expected);
      ASSERT_EQ(mesh.size(), expected);
      mesh.validateSizes(false);  // every array a snapshot holds
      for (std::size_t i = 0; i < 3 * expected; ++i) ASSERT_EQ(mesh.x[i], box.x[i]) << "coordinate " << i;
      for (std::size_t i = 0; i < expected; ++i) {
        ASSERT_EQ(mesh.mass[i], box.mass[i]);
        ASSERT_EQ(mesh.volume0[i], box.volume0[i]);
        ASSERT_EQ(mesh.v[3 * i], 0.5);
        ASSERT_EQ(mesh.v[3 * i + 1], -1.0);
        ASSERT_EQ(mesh.v[3 * i + 2], 2.0);
      }
      // rho_0 x box volume = 1600 x 0.04 x 0.03 x 0.05 = 0.096 kg.
      EXPECT_NEAR(totalMass(mesh), 0.096, 1e-12);
    }
  }
}

// Robust fallback: a box whose faces are tessellated at the cell size, so that the vertical
// lines through the sub-cell centres with a == b run exactly along triangle diagonals (and the
// lines through cell corners would hit vertices); the result is still exactly seedBox's.
TEST(SeedMesh, TessellatedBoxMeshEqualsSeedBox) {
  const MpmParams prm = grid(0.01, {12, 12, 12}, {0, 0, 0});
  const std::array<double, 3> lo{0.02, 0.03, 0.02}, hi{0.06, 0.07, 0.06};
  std::vector<Vec3> V;
  Tris T;
  boxMesh(lo, hi, V, T);
  subdivide(V, T, 2, false);  // 0.04 m faces -> edges of 0.01 m
  ASSERT_EQ(T.size(), 12u * 16u);
  for (int k : {1, 2, 3}) {
    ParticleSet box, mesh;
    const std::size_t n = seedBox(prm, lo, hi, k * k * k, box);
    ASSERT_EQ(n, 64u * k * k * k);  // 4 x 4 x 4 cells
    ASSERT_EQ(seedMesh(prm, V, T, {k, k, k}, {0, 0, 0}, mesh, "tessellated"), n);
    for (std::size_t i = 0; i < 3 * n; ++i) ASSERT_EQ(mesh.x[i], box.x[i]) << "ppc " << k << ", coordinate " << i;
  }
}

TEST(SeedMesh, WindingNumberOfCube) {
  std::vector<Vec3> V;
  Tris T;
  boxMesh({0, 0, 0}, {1, 1, 1}, V, T);
  EXPECT_NEAR(windingNumber(V, T, Vec3(0.5, 0.5, 0.5)), 1.0, 1e-12);
  EXPECT_NEAR(windingNumber(V, T, Vec3(0.01, 0.99, 0.3)), 1.0, 1e-12);
  EXPECT_NEAR(windingNumber(V, T, Vec3(1.5, 0.5, 0.5)), 0.0, 1e-12);
  EXPECT_NEAR(windingNumber(V, T, Vec3(-3, 7, 2)), 0.0, 1e-12);
  // Seen from the middle of a face, the cube covers half the sphere of directions.
  EXPECT_NEAR(windingNumber(V, T, Vec3(0.5, 0.5, 1.0)), 0.5, 1e-12);
  for (auto& t : T) std::swap(t[1], t[2]);
  EXPECT_NEAR(windingNumber(V, T, Vec3(0.5, 0.5, 0.5)), -1.0, 1e-12);
}

// Non-convex L-prism with faces on grid lines: the notch stays empty and the count is the
// hand count, the same points as the two boxes making up the L.
TEST(SeedMesh, LPrismHandCount) {
  const io::TriangleMesh L = io::readMesh(std::string(MPMSDEM_TEST_DATA) + "/l_prism.obj");
  {
    // dx = 0.05, origin -2 dx: material region [0, 0.2]. L area 0.2^2 - 0.1^2 = 0.03 m^2,
    // volume 0.003 m^3 = 24 cells of 0.05^3; 8 per cell -> 192 points, mass 1600 x 0.003 = 4.8 kg.
    const MpmParams prm = grid(0.05, {8, 8, 6}, {-0.1, -0.1, -0.1});
    ParticleSet p;
    EXPECT_EQ(seedMesh(prm, L.vertices, L.triangles, {2, 2, 2}, {0, 0, 0}, p, "l_prism"), 192u);
    EXPECT_NEAR(totalMass(p), 4.8, 1e-12);
    for (std::size_t i = 0; i < p.size(); ++i) EXPECT_FALSE(p.x[3 * i] > 0.1 && p.x[3 * i + 1] > 0.1) << i;
  }
  {
    // dx = 0.025: 0.003 / 0.025^3 = 192 cells, x 2 x 1 x 3 = 1152 points.
    const MpmParams prm = grid(0.025, {12, 12, 8}, {-0.05, -0.05, -0.05});
    ParticleSet mesh, boxes;
    EXPECT_EQ(seedMesh(prm, L.vertices, L.triangles, {2, 1, 3}, {0, 0, 0}, mesh, "l_prism"), 1152u);
    EXPECT_NEAR(totalMass(mesh), 4.8, 1e-12);
    seedBox(prm, {0, 0, 0}, {0.2, 0.1, 0.1}, {2, 1, 3}, boxes);
    seedBox(prm, {0, 0.1, 0}, {0.1, 0.2, 0.1}, {2, 1, 3}, boxes);
    EXPECT_EQ(sortedPositions(mesh), sortedPositions(boxes));
  }
}

// Icosphere (5120 triangles) of radius r = 0.1 m, ~0.6 million candidates.
// Sampling bound: each kept or dropped point stands for a cube of side h = dx / 4; only
// cubes cut by the surface can be wrong, each by at most half its volume (a point on the
// inner side of a plane through the cube holds >= 1/2 of it inside), and there are at most
// sqrt(3) A / h^2 such cubes (A = 4 pi r^2; the cut cubes' projections along the normal
// n cover A (|n_x| + |n_y| + |n_z|) <= sqrt(3) A). So |V_points - V_mesh| <= (sqrt(3)/2) A h,
// and V_sphere - V_mesh (the inscribed polyhedron's deficit, computed here) adds to it:
// |M - rho_0 (4/3) pi r^3| <= rho_0 [(sqrt(3)/2) A h + (V_sphere - V_mesh)] (6.5 % + deficit).
TEST(SeedMesh, IcosphereMassAndCentre) {
  const MpmParams prm = grid(0.01, {26, 26, 26}, {0, 0, 0});  // region [0.02, 0.24]
  const Vec3 c(0.1313, 0.1271, 0.1337);  // sphere box inside the region, off the lattice symmetry
  const double r = 0.1, h = prm.dx / 4, rho = prm.material.density;
  std::vector<Vec3> V;
  Tris T;
  icosphere(c, r, 4, V, T);
  ASSERT_EQ(T.size(), 5120u);
  double vMesh = 0, dMin = INFINITY;  // enclosed volume; smallest centre-to-face-plane distance
  for (const auto& t : T) {
    const Vec3 a = V[t[0]] - c, b = V[t[1]] - c, e = V[t[2]] - c;
    vMesh += a.dot(b.cross(e)) / 6;
    const Vec3 n = (b - a).cross(e - a).normalized();
    dMin = std::min(dMin, n.dot(a));
  }
  const double vSphere = 4.0 / 3.0 * M_PI * r * r * r;
  ASSERT_GT(vMesh, 0.99 * vSphere);
  ASSERT_LT(vMesh, vSphere);

  ParticleSet p;
  const auto t0 = std::chrono::steady_clock::now();
  const std::size_t n = seedMesh(prm, V, T, {4, 4, 4}, {0, 0, 0}, p, "icosphere");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::cout << "icosphere: " << n << " points in " << seconds << " s\n";
  const double mass = totalMass(p);
  const double bound = rho * (std::sqrt(3.0) / 2 * 4 * M_PI * r * r * h + (vSphere - vMesh));
  std::cout << "mass error " << (mass - rho * vSphere) / (rho * vSphere) * 100 << " %, bound "
            << bound / (rho * vSphere) * 100 << " %\n";
  EXPECT_NEAR(mass, rho * vSphere, bound);
  EXPECT_NEAR(mass, rho * vMesh, rho * std::sqrt(3.0) / 2 * 4 * M_PI * r * r * h);
  Vec3 com = Vec3::Zero();
  for (std::size_t i = 0; i < n; ++i) com += p.mass[i] * Vec3(p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2]);
  com /= mass;
  EXPECT_LT((com - c).norm(), h);
  // Exact membership away from the surface: every point nearer the centre than all face
  // planes is inside the mesh, every point beyond r is outside; so the kept points are all
  // within r, and every lattice point within dMin is kept.
  std::size_t keptInner = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double d = (Vec3(p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2]) - c).norm();
    ASSERT_LE(d, r);
    keptInner += d < dMin;
  }
  std::size_t latticeInner = 0;
  for (int m = 0; m < 4 * prm.cells[0]; ++m)
    for (int q = 0; q < 4 * prm.cells[1]; ++q)
      for (int s = 0; s < 4 * prm.cells[2]; ++s)
        latticeInner += (Vec3((m + 0.5) * h, (q + 0.5) * h, (s + 0.5) * h) - c).norm() < dMin;
  EXPECT_EQ(keptInner, latticeInner);
  EXPECT_LT(seconds, 3.0);
}

TEST(SeedMesh, BadMeshesNameTheMesh) {
  const MpmParams prm = grid(0.01, {12, 12, 12}, {0, 0, 0});
  std::vector<Vec3> V;
  Tris T;
  boxMesh({0.03, 0.03, 0.03}, {0.07, 0.07, 0.07}, V, T);
  ParticleSet p;
  // Open: one triangle missing -> its 3 edges have 1 triangle each.
  Tris open(T.begin(), T.end() - 1);
  expectError([&] { seedMesh(prm, V, open, {2, 2, 2}, {0, 0, 0}, p, "open.stl"); },
              {"mesh 'open.stl'", "triangle count = 1", "exactly 2", "3 edge(s)"});
  // One triangle flipped: its edges run the same way as the neighbours'.
  Tris flipped = T;
  std::swap(flipped[0][1], flipped[0][2]);
  expectError([&] { seedMesh(prm, V, flipped, {2, 2, 2}, {0, 0, 0}, p, "flip.stl"); },
              {"mesh 'flip.stl'", "direction", "consistently oriented"});
  // Sticks out of the material region [0.02, 0.10] on y.
  std::vector<Vec3> out = V;
  for (Vec3& v : out) v.y() += 0.05;
  expectError([&] { seedMesh(prm, out, T, {2, 2, 2}, {0, 0, 0}, p, "out.stl"); },
              {"mesh 'out.stl'", "bounding box on y", "[0.08, 0.12]", "material region [0.02, 0.1]"});
  // Closed and oriented but flat: a triangle and its reverse enclose nothing.
  const std::vector<Vec3> flatV{{0.03, 0.03, 0.05}, {0.07, 0.03, 0.05}, {0.03, 0.07, 0.05}};
  expectError([&] { seedMesh(prm, flatV, {{0, 1, 2}, {0, 2, 1}}, {2, 2, 2}, {0, 0, 0}, p, "flat.stl"); },
              {"mesh 'flat.stl'", "enclosed volume"});
  Tris badIndex = T;
  badIndex[3][2] = 8;
  expectError([&] { seedMesh(prm, V, badIndex, {2, 2, 2}, {0, 0, 0}, p, "idx.stl"); },
              {"mesh 'idx.stl'", "vertex index = 8", "[0, 7]"});
  expectError([&] { seedMesh(prm, V, {}, {2, 2, 2}, {0, 0, 0}, p); }, {"mesh 'mesh'", "triangle count = 0"});
  // Thinner than the point spacing: a slab 0.001 m thick between two point layers.
  std::vector<Vec3> thinV;
  Tris thinT;
  boxMesh({0.03, 0.03, 0.0301}, {0.07, 0.07, 0.0311}, thinV, thinT);
  expectError([&] { seedMesh(prm, thinV, thinT, {2, 2, 2}, {0, 0, 0}, p, "thin.stl"); },
              {"mesh 'thin.stl'", "particle count = 0"});
  expectError([&] { seedMesh(prm, V, T, {2, 9, 2}, {0, 0, 0}, p); }, {"perAxis[y] = 9"});
  EXPECT_EQ(p.size(), 0u);
}

// "mesh" entries: a unit cube STL scaled by 0.04 and offset, next to a box; path relative
// to the scene file's folder; overlap and key errors.
TEST(SeedMesh, SceneMeshEntry) {
  const auto dir = tempDir("scene");
  std::vector<Vec3> V;
  Tris T;
  boxMesh({0, 0, 0}, {1, 1, 1}, V, T);
  writeAsciiStl(dir / "cube.stl", V, T);
  // dx = 0.01, 10 cells: region [0.02, 0.08]. Mesh -> [0.02, 0.06] x [0.03, 0.07] x [0.02, 0.06]
  // = 64 cells x 8 = 512 points, 1600 x 6.4e-5 = 0.1024 kg; the box [0.06, 0.08] x [0.02, 0.08]
  // x [0.02, 0.04] touches it: 24 cells x 8 = 192 points, 0.0384 kg.
  nlohmann::json scene = nlohmann::json::parse(R"({
    "grid": {"dx": 0.01, "cells": [10, 10, 10]},
    "material": {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24, "mu_2": 0.65},
    "particles": [
      {"mesh": "cube.stl", "scale": 0.04, "offset": [0.02, 0.03, 0.02], "ppc": 8, "velocity": [0.5, 0, 0]},
      {"lo": [0.06, 0.02, 0.02], "hi": [0.08, 0.08, 0.04]}
    ],
    "run": {"duration": 0.01}
  })");
  {
    std::ofstream(dir / "scene.json") << scene.dump(2);
  }
  const MpmScene s = loadScene((dir / "scene.json").string());
  ASSERT_EQ(s.boxes.size(), 2u);
  EXPECT_EQ(s.boxes[0].mesh, (dir / "cube.stl").string());
  EXPECT_EQ(s.boxes[0].scale, 0.04);
  EXPECT_NEAR(s.boxes[0].lo[1], 0.03, 1e-15);
  EXPECT_NEAR(s.boxes[0].hi[1], 0.07, 1e-15);
  EXPECT_TRUE(s.boxes[1].mesh.empty());
  const ParticleSet p = seedParticles(s);
  ASSERT_EQ(p.size(), 512u + 192u);
  EXPECT_NEAR(totalMass(p), 0.1024 + 0.0384, 1e-12);
  ParticleSet expected;
  seedBox(s.params, {0.02, 0.03, 0.02}, {0.06, 0.07, 0.06}, 8, expected);
  seedBox(s.params, {0.06, 0.02, 0.02}, {0.08, 0.08, 0.04}, 8, expected);
  for (std::size_t i = 0; i < 3 * p.size(); ++i) ASSERT_EQ(p.x[i], expected.x[i]);
  for (std::size_t i = 0; i < p.size(); ++i) ASSERT_EQ(p.v[3 * i], i < 512 ? 0.5 : 0.0);

  // parseScene without a base folder takes the path as given (here absolute).
  nlohmann::json abs = scene;
  abs["particles"][0]["mesh"] = (dir / "cube.stl").string();
  EXPECT_EQ(seedParticles(parseScene(abs.dump())).size(), 704u);

  auto expectSceneError = [&](const nlohmann::json& j, std::initializer_list<const char*> needles) {
    expectError([&] { parseScene(j.dump(), "scene", dir.string()); }, needles);
  };
  nlohmann::json j = scene;
  j["particles"][1]["lo"] = {0.05, 0.02, 0.02};  // box now reaches into the mesh's bounding box
  expectSceneError(j, {"particles[1]", "overlapping particles[0] (mesh '"});
  j = scene;
  j["particles"][0]["offset"] = {0.05, 0.03, 0.02};  // [0.05, 0.09] on x: out of the region
  expectSceneError(j, {"particles[0].mesh", "mesh '", "material region [0.02, 0.08]"});
  j = scene;
  j["particles"][0]["lo"] = {0.02, 0.02, 0.02};
  expectSceneError(j, {"unknown key 'particles[0].lo'"});
  j = scene;
  j["particles"][0]["scale"] = 0;
  expectSceneError(j, {"particles[0].scale = 0"});
  j = scene;
  j["particles"][0]["mesh"] = "missing.stl";
  expectSceneError(j, {"particles[0].mesh", "missing.stl"});
  j = scene;
  j["particles"][0]["mesh"] = 3;
  expectSceneError(j, {"particles[0].mesh = 3"});
  // An open mesh file.
  writeAsciiStl(dir / "open.stl", V, Tris(T.begin() + 1, T.end()));
  j = scene;
  j["particles"][0]["mesh"] = "open.stl";
  expectSceneError(j, {"particles[0].mesh", "open.stl", "exactly 2"});
  std::filesystem::remove_all(dir);
}
