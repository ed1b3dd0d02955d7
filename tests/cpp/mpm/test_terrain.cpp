// The terrain under the flow (common/Terrain.hpp, mpm/TerrainBoundary.hpp, input/TerrainRaster, the scene's "terrain"): heights
// read off the raster, the boundary on grid nodes against the walls' law, and flows on a slope
// against the sliding block's analytic motion.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "common/Error.hpp"
#include "input/TerrainRaster.hpp"
#include "mpm/MpmKernelsCommon.hpp"
#include "scene/MpmScene.hpp"
#include "mpm/MpmSolver.hpp"
#include "mpm/Seeding.hpp"

#include "AgreementHelpers.hpp"
#include "GranularColumn.hpp"

using namespace mpmsdem;
using namespace mpmsdem::mpm;

namespace {

// The plane z = a + b x + c y on an nx x ny raster of spacing s from (x0, y0).
TerrainSpec planeRaster(double a, double b, double c, int nx, int ny, double x0, double y0, double s) {
  TerrainSpec t;
  t.nx = nx;
  t.ny = ny;
  t.x0 = x0;
  t.y0 = y0;
  t.spacing = s;
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j) t.heights.push_back(a + b * (x0 + i * s) + c * (y0 + j * s));
  return t;
}

TerrainView<double> viewOf(const TerrainSpec& t) { return terrainViewOf(t, t.heights.data()); }

std::string writeFile(const std::string& name, const std::string& text) {
  const std::string path = (std::filesystem::temp_directory_path() / name).string();
  std::ofstream(path) << text;
  return path;
}

}  // namespace

TEST(TerrainHeight, PlaneIsExactInsideAndContinuesFlatOutside) {
  const TerrainSpec t = planeRaster(1.5, -0.3, 0.2, 7, 5, -1.0, 2.0, 0.25);
  const TerrainView<double> v = viewOf(t);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ux(-1.0, 0.5), uy(2.0, 3.0);
  for (int k = 0; k < 200; ++k) {
    const double x = ux(rng), y = uy(rng);
    double gx, gy;
    EXPECT_NEAR(terrainHeight(v, x, y, gx, gy), 1.5 - 0.3 * x + 0.2 * y, 1e-14);
    EXPECT_NEAR(gx, -0.3, 1e-13);
    EXPECT_NEAR(gy, 0.2, 1e-13);
  }
  // Beyond the raster the edge heights continue flat: no slope along the axis left behind.
  double gx, gy;
  EXPECT_NEAR(terrainHeight(v, -3.0, 2.5, gx, gy), 1.5 - 0.3 * -1.0 + 0.2 * 2.5, 1e-14);
  EXPECT_EQ(gx, 0.0);
  EXPECT_NEAR(gy, 0.2, 1e-13);
  EXPECT_NEAR(terrainHeight(v, 0.0, 9.0, gx, gy), 1.5 + 0.2 * 3.0, 1e-14);
  EXPECT_NEAR(gx, -0.3, 1e-13);
  EXPECT_EQ(gy, 0.0);
}

TEST(TerrainHeight, CellsAreTwoPlanarTrianglesThroughTheNodes) {
  TerrainSpec t = planeRaster(0, 0, 0, 6, 4, 0.0, 0.0, 0.5);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> uz(-2.0, 2.0);
  for (double& z : t.heights) z = uz(rng);
  const TerrainView<double> v = viewOf(t);
  double gx, gy;
  for (int i = 0; i < t.nx; ++i)
    for (int j = 0; j < t.ny; ++j) EXPECT_DOUBLE_EQ(terrainHeight(v, 0.5 * i, 0.5 * j, gx, gy), t.heights[i * t.ny + j]);
  // across the edge x = 1.0 between raster cells 1 and 2, at several y
  for (double y : {0.1, 0.7, 1.3}) {
    const double below = terrainHeight(v, 1.0 - 1e-9, y, gx, gy), above = terrainHeight(v, 1.0 + 1e-9, y, gx, gy);
    EXPECT_NEAR(below, above, 1e-8);
  }
  // Each cell is two planar triangles split along the diagonal from (i+1, j) to (i, j+1): inside
  // one, the height is the plane through its three nodes, with that plane's slopes; the two
  // planes meet on the diagonal.
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int i = 2, j = 1;
  auto z = [&t](int a, int b) { return t.heights[a * t.ny + b]; };
  for (int k = 0; k < 100; ++k) {
    const double fx = u(rng), fy = u(rng);
    const double h = terrainHeight(v, 0.5 * (i + fx), 0.5 * (j + fy), gx, gy);
    if (fx + fy <= 1) {
      EXPECT_NEAR(h, z(i, j) + fx * (z(i + 1, j) - z(i, j)) + fy * (z(i, j + 1) - z(i, j)), 1e-12);
      EXPECT_NEAR(gx, (z(i + 1, j) - z(i, j)) / 0.5, 1e-12);
      EXPECT_NEAR(gy, (z(i, j + 1) - z(i, j)) / 0.5, 1e-12);
    } else {
      EXPECT_NEAR(h, z(i + 1, j + 1) + (1 - fx) * (z(i, j + 1) - z(i + 1, j + 1)) + (1 - fy) * (z(i + 1, j) - z(i + 1, j + 1)),
                  1e-12);
      EXPECT_NEAR(gx, (z(i + 1, j + 1) - z(i, j + 1)) / 0.5, 1e-12);
      EXPECT_NEAR(gy, (z(i + 1, j + 1) - z(i + 1, j)) / 0.5, 1e-12);
    }
    const double on = terrainHeight(v, 0.5 * (i + fx), 0.5 * (j + 1 - fx) + 1e-10, gx, gy);
    EXPECT_NEAR(on, (1 - fx) * z(i, j + 1) + fx * z(i + 1, j), 1e-9);
  }
}

TEST(ApplyTerrain, FlatTerrainIsTheBedWall) {
  // The bed wall (applyWall on -z) and a flat terrain must do the same to a node at or below it,
  // for every friction law; a node above the surface is left alone.
  const TerrainSpec t = planeRaster(0.3, 0, 0, 3, 3, 0.0, 0.0, 1.0);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (double mu : {-1.0, 0.0, 0.3, 5.0}) {
    TerrainView<double> v = viewOf(t);
    v.friction = mu;
    for (int k = 0; k < 500; ++k) {
      Vec3T<double> a{u(rng), u(rng), u(rng)};
      if (k % 7 == 0) a.x = 0;  // no tangential velocity along one axis
      if (k % 11 == 0) a.z = 0;
      Vec3T<double> b = a, c = a;
      applyWall(a, 2, -1.0, mu);
      applyTerrain(b, Vec3T<double>{0.4, 1.2, k % 2 ? 0.3 : -0.1}, v);
      EXPECT_EQ(a.x, b.x) << "mu " << mu << " case " << k;
      EXPECT_EQ(a.y, b.y) << "mu " << mu << " case " << k;
      EXPECT_EQ(a.z, b.z) << "mu " << mu << " case " << k;
      const Vec3T<double> before = c;
      applyTerrain(c, Vec3T<double>{0.4, 1.2, 0.3 + 1e-12}, v);
      EXPECT_TRUE(c.x == before.x && c.y == before.y && c.z == before.z);
    }
  }
}

TEST(ApplyTerrain, SlopeRemovesTheVelocityIntoItWithCoulombFriction) {
  // On a slope the law is the wall's in the slope's frame: the velocity into the terrain along
  // its normal is removed, the tangential speed falls by mu |v_n| (to zero at most) without
  // turning, a velocity away from the terrain passes, no-slip keeps only that.
  const TerrainSpec t = planeRaster(0.0, -0.4, 0.25, 3, 3, -2.0, -2.0, 2.0);
  const double s = std::sqrt(1 + 0.4 * 0.4 + 0.25 * 0.25);
  const Vec3T<double> n{0.4 / s, -0.25 / s, 1 / s};
  const Vec3T<double> below{0.1, 0.2, -0.5};
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (double mu : {-1.0, 0.0, 0.5}) {
    TerrainView<double> v = viewOf(t);
    v.friction = mu;
    for (int k = 0; k < 300; ++k) {
      const Vec3T<double> a{u(rng), u(rng), u(rng)};
      Vec3T<double> b = a;
      applyTerrain(b, below, v);
      const double an = dot(a, n), bn = dot(b, n);
      const Vec3T<double> at = a - an * n, bt = b - bn * n;
      const double atn = std::sqrt(dot(at, at)), btn = std::sqrt(dot(bt, bt));
      EXPECT_NEAR(bn, std::max(an, 0.0), 1e-14);
      double expected = atn;
      if (mu < 0) expected = 0;
      if (mu > 0 && an < 0) expected = std::max(0.0, atn + mu * an);
      EXPECT_NEAR(btn, expected, 1e-14) << "mu " << mu << " case " << k;
      if (btn > 1e-12) EXPECT_NEAR(dot(at, bt), atn * btn, 1e-12);  // same direction
    }
  }
}

TEST(TerrainRaster, EsriAsciiGridIsReadNorthRowFirstAtCellCentres) {
  const std::string path = writeFile("mpmsdem_terrain_ok.asc",
                                     "ncols 3\nNROWS 2\nxllcorner 100\nyllcorner 200.0\ncellsize 10\n"
                                     "NODATA_value -9999\n1 2 3\n4 5 6\n");
  const io::TerrainRaster r = io::readEsriAscii(path);
  EXPECT_EQ(r.nx, 3);
  EXPECT_EQ(r.ny, 2);
  EXPECT_DOUBLE_EQ(r.x0, 105);
  EXPECT_DOUBLE_EQ(r.y0, 205);
  EXPECT_DOUBLE_EQ(r.spacing, 10);
  // row "4 5 6" is the south one (j = 0)
  const std::vector<double> expected{4, 1, 5, 2, 6, 3};
  EXPECT_EQ(r.heights, expected);
  const io::TerrainRaster c = io::readEsriAscii(
      writeFile("mpmsdem_terrain_centre.asc", "ncols 2 nrows 2 xllcenter 1 yllcenter 2 cellsize 0.5 7 8 9 10"));
  EXPECT_DOUBLE_EQ(c.x0, 1);
  EXPECT_DOUBLE_EQ(c.y0, 2);
  std::remove(path.c_str());
}

TEST(TerrainRaster, BadFilesAreRefusedSayingWhy) {
  auto refused = [](const std::string& text, const std::string& words) {
    const std::string path = writeFile("mpmsdem_terrain_bad.asc", text);
    try {
      io::readEsriAscii(path);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const ParameterError& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
    std::remove(path.c_str());
  };
  const std::string head = "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\nnodata_value -9999\n";
  refused(head + "1 2 3\n", "4 values expected, 3 found");
  refused(head + "1 2 3 4 5\n", "more than ncols x nrows = 4 values");
  refused(head + "1 2 x 4\n", "'x' is not a number");
  refused(head + "1 2\n-9999 4\n", "1 no-data values, the first at column 0, row 1");
  refused("ncols 2\nnrows 2\nxllcorner 0\ncellsize 1\n1 2 3 4\n", "one of yllcorner and yllcenter");
  refused("ncols 1\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n", "ncols must be a whole number >= 2");
  refused("ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 0\n1 2 3 4\n", "cellsize must be > 0");
  refused("ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\ncolour 3\n1 2 3 4\n", "unknown header key 'colour'");
}

TEST(TerrainScene, FileOrHeightsPlaceTheTerrainAndItsGroundSeedsNoPoints) {
  // A raster file moved by its origin and the same heights given in the scene are one terrain;
  // the box reaching into the ground is seeded only above the surface.
  const std::string asc = writeFile("mpmsdem_scene_terrain.asc",
                                    "ncols 2\nnrows 2\nxllcorner 999.95\nyllcorner 1999.95\ncellsize 0.1\n"
                                    "10.06 10.06\n10.02 10.02\n");
  const std::string common =
      R"("grid": {"dx": 0.01, "origin": [0, 0, 0], "cells": [16, 8, 16]},
         "material": {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24, "mu_2": 0.65},
         "particles": [{"lo": [0.02, 0.02, 0.02], "hi": [0.14, 0.06, 0.12], "ppc": 8}],
         "run": {"duration": 0.1})";
  const MpmScene fromFile = parseScene(
      "{" + common + R"(, "terrain": {"file": ")" + asc + R"(", "origin": [1000, 2000, 10], "friction": 0.3}})", "t");
  const MpmScene inline_ = parseScene(
      "{" + common + R"(, "terrain": {"nx": 2, "ny": 2, "x0": 0.0, "y0": 0.0, "spacing": 0.1,
                                      "heights": [0.02, 0.06, 0.02, 0.06], "friction": 0.3}})", "t");
  for (const MpmScene* s : {&fromFile, &inline_}) {
    const TerrainSpec& t = s->params.terrain;
    ASSERT_EQ(t.nx, 2);
    EXPECT_NEAR(t.x0, 0.0, 1e-9);
    EXPECT_NEAR(t.y0, 0.0, 1e-9);
    ASSERT_EQ(t.heights.size(), 4u);
    EXPECT_NEAR(t.heights[1], 0.06, 1e-12);  // node (0, 1): the north row
    EXPECT_EQ(t.friction, 0.3);
  }
  const ParticleSet ps = seedParticles(inline_);
  // The surface z = 0.02 + 0.4 y: the points of the box are on 24 x 8 x 20 sites of 5 mm, at
  // y = 0.0225 + 0.005 k; a site is kept where z >= 0.02 + 0.4 y.
  std::size_t expected = 0;
  for (int k = 0; k < 8; ++k)
    for (int l = 0; l < 20; ++l) expected += (0.0225 + 0.005 * l >= 0.02 + 0.4 * (0.0225 + 0.005 * k)) ? 24 : 0;
  EXPECT_EQ(ps.size(), expected);
  EXPECT_LT(ps.size(), 24u * 8 * 20);
  for (std::size_t p = 0; p < ps.size(); ++p) EXPECT_GE(ps.x[3 * p + 2], 0.02 + 0.4 * ps.x[3 * p + 1] - 1e-12);
  // A box reaching into the ground below the grid's material region is cut at the region's
  // floor when the terrain lies above it everywhere, and refused otherwise.
  const std::string deep =
      R"("grid": {"dx": 0.01, "origin": [0, 0, 0], "cells": [16, 8, 16]},
         "material": {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24, "mu_2": 0.65},
         "particles": [{"lo": [0.02, 0.02, -0.05], "hi": [0.14, 0.06, 0.12], "ppc": 8}], "run": {"duration": 0.1})";
  const MpmScene cut = parseScene(
      "{" + deep + R"(, "terrain": {"nx": 2, "ny": 2, "x0": 0.0, "y0": 0.0, "spacing": 0.1,
                                    "heights": [0.02, 0.06, 0.02, 0.06]}})", "t");
  EXPECT_EQ(seedParticles(cut).size(), expected);
  EXPECT_THROW(parseScene("{" + deep + R"(, "terrain": {"nx": 2, "ny": 2, "x0": 0.0, "y0": 0.0, "spacing": 0.1,
                                                        "heights": [0.01, 0.06, 0.02, 0.06]}})", "t"),
               ParameterError);
  EXPECT_THROW(parseScene("{" + common + R"(, "terrain": {"nx": 2, "ny": 2, "x0": 0, "y0": 0, "spacing": 0.1,
                                              "heights": [1, 2, 3]}})", "t"), ParameterError);
  EXPECT_THROW(parseScene("{" + common + R"(, "terrain": {"file": ")" + asc + R"(", "friction": -0.2}})", "t"),
               ParameterError);
  std::remove(asc.c_str());
}

TEST(TerrainScene, SolverRefusesAnInconsistentTerrain) {
  MpmParams p = testing_scenes::granularColumnParams(0.01, {10, 10, 10}, 1e5);
  p.terrain = planeRaster(0, 0, 0, 3, 3, 0, 0, 0.1);
  p.terrain.heights.pop_back();
  EXPECT_THROW(makeSolver(p, Backend::Cpu, Precision::Double), ParameterError);
  p.terrain = planeRaster(0, 0, 0, 3, 3, 0, 0, 0.1);
  p.terrain.heights[4] = std::nan("");
  try {
    makeSolver(p, Backend::Cpu, Precision::Double);
    ADD_FAILURE() << "a NaN height was accepted";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("terrain.heights[4] (node i 1, j 1)"), std::string::npos) << e.what();
  }
  p.terrain = planeRaster(0, 0, 0, 3, 3, 0, 0, 0.1);
  p.terrain.spacing = 0;
  EXPECT_THROW(makeSolver(p, Backend::Cpu, Precision::Double), ParameterError);
}

class TerrainEveryBackend : public agreement::EveryBackend {};
INSTANTIATE_TEST_SUITE_P(Kinds, TerrainEveryBackend, ::testing::ValuesIn(agreement::everyKind()),
                         agreement::kindName);

TEST_P(TerrainEveryBackend, FlatTerrainOnTheBedLayerIsTheBedWall) {
  // A collapsing column on a rough bed wall (friction 0.4) and the same column with a smooth bed
  // wall and a flat terrain of friction 0.4 on the bed's node layer: the terrain acts on the
  // wall's nodes with the wall's law, so the runs agree to round-off (the law's arithmetic is the
  // wall's in another order: 1e-16 m apart in double after 600 steps, 5e-8 m in float). The flow
  // stays away from the side walls: where a node is on two walls the terrain's friction acts
  // before the side wall, the bed wall's after.
  auto run = [this](bool terrain) {
    MpmParams prm = testing_scenes::granularColumnParams(0.01, {40, 16, 20}, 2e5);
    if (terrain) {
      prm.walls[4].friction = 0;
      prm.terrain = planeRaster(prm.origin[2] + 2 * prm.dx, 0, 0, 2, 2, 0.0, 0.0, 0.5);
      prm.terrain.friction = 0.4;
    }
    ParticleSet ps;
    seedBox(prm, {0.1, 0.07, 0.02}, {0.16, 0.09, 0.14}, {2, 2, 2}, ps);
    auto s = solver(prm);
    s->setParticles(ps);
    for (int n = 0; n < 600; ++n) s->step(2e-4);
    ParticleSet out;
    s->getParticles(out);
    return out;
  };
  const ParticleSet wall = run(false), terrain = run(true);
  double lo = 1, hi = 0;
  for (std::size_t p = 0; p < wall.size(); ++p) {
    lo = std::min(lo, wall.x[3 * p]);
    hi = std::max(hi, wall.x[3 * p]);
  }
  EXPECT_LT(lo, 0.095);  // the column collapsed both ways
  EXPECT_GT(hi, 0.165);
  EXPECT_GT(lo, 0.05);   // and stayed away from the end walls (2 wall cells and 3 of stencil)
  EXPECT_LT(hi, 0.35);
  double ylo = 1, yhi = 0;
  for (std::size_t p = 0; p < wall.size(); ++p) {
    ylo = std::min(ylo, wall.x[3 * p + 1]);
    yhi = std::max(yhi, wall.x[3 * p + 1]);
  }
  EXPECT_GT(ylo, 0.035);  // nor near the side walls
  EXPECT_LT(yhi, 0.125);
  const agreement::Agreement a = agreement::compare(wall, terrain);
  const double eps = agreement::roundOff(precision());
  EXPECT_LT(a.position, 1000 * eps * 0.4);  // the domain's length
  EXPECT_LT(a.velocity, 1000 * eps * 1.0);  // the flow's speed scale
}

namespace {

// A block of stiff material on a planar slope of angle theta rising towards -x, released at
// rest, run for `duration` s; the velocity of its centre of mass along the slope (downhill
// positive) and the lowest clearance of a point above the surface [m].
struct SlopeRun {
  double speed;
  double clearance;
  double massChange;
  std::size_t points;
};

}  // namespace

TEST_P(TerrainEveryBackend, BlockSlidesDownASlopeAsTheAnalyticBlock) {
  // A frictionless slope lets a block go at g sin(theta); a Coulomb slope of friction mu at
  // g (sin(theta) - mu cos(theta)) (a rigid block sliding; the flow's material stays a block
  // because the slope's friction is below its own). The grid is level and gravity vertical: the
  // slope is the terrain's, crossing the grid's nodes as a staircase.
  const double theta = 25.0 * M_PI / 180.0, g = 9.81, duration = 0.2;
  auto run = [this, theta, duration](double mu) {
    MpmParams prm = testing_scenes::granularColumnParams(0.01, {70, 5, 50}, 2e6);
    prm.walls[4].friction = 0;
    prm.material.muS = 0.9;  // a block: its own friction far above the slope's
    prm.material.mu2 = 1.2;
    const double tanT = std::tan(theta);
    // z = 0.42 - tan(theta) x over the whole domain (x from 0 to 0.7 m)
    prm.terrain = planeRaster(0.42, -tanT, 0, 2, 2, 0.0, 0.0, 0.7);
    prm.terrain.friction = mu;
    // the block: the points of a box within 0.06 m above the slope
    struct Band : SeedSink {
      double tanT;
      ParticleSet ps;
      ParticleSetSink out{ps};
      void add(const double x[3], double mass, double volume0, const std::array<double, 3>& velocity) override {
        const double h = 0.42 - tanT * x[0];
        if (x[2] >= h && x[2] <= h + 0.06) out.add(x, mass, volume0, velocity);
      }
    } band;
    band.tanT = tanT;
    seedBox(prm, {0.10, 0.02, 0.20}, {0.20, 0.03, 0.40}, {3, 1, 3}, {0, 0, 0}, band);
    const ParticleSet& ps = band.ps;
    auto s = solver(prm);
    s->setParticles(ps);
    const double M = std::accumulate(ps.mass.begin(), ps.mass.end(), 0.0);
    const double dt = 0.5 * s->stableTimeStep();
    const int steps = static_cast<int>(std::ceil(duration / dt));
    for (int n = 0; n < steps; ++n) s->step(duration / steps);
    ParticleSet out;
    s->getParticles(out);
    SlopeRun r{0, 1, 0, out.size()};
    double vx = 0, vz = 0, m = 0;
    for (std::size_t p = 0; p < out.size(); ++p) {
      vx += out.mass[p] * out.v[3 * p];
      vz += out.mass[p] * out.v[3 * p + 2];
      m += out.mass[p];
      r.clearance = std::min(r.clearance, out.x[3 * p + 2] - (0.42 - tanT * out.x[3 * p]));
    }
    r.speed = (vx * std::cos(theta) - vz * std::sin(theta)) / m;
    r.massChange = m / M - 1;
    return r;
  };
  for (double mu : {0.0, 0.2}) {
    const SlopeRun r = run(mu);
    const double expected = g * (std::sin(theta) - mu * std::cos(theta)) * duration;
    EXPECT_GT(r.points, 300u);
    // Frictionless, the slope's forces are normal to it: the momentum along it grows at
    // M g sin(theta), exactly (1e-13 in double). The grid's Coulomb law holds the block 1.8 %
    // less than a rigid block's friction would (0.482 against 0.474 m/s at 0.2 s).
    EXPECT_NEAR(r.speed, expected, (mu == 0 ? 1e-6 : 0.03) * expected) << "mu " << mu;
    EXPECT_GE(r.clearance, -1e-5) << "mu " << mu;  // no point below the surface (float: its round-off)
    EXPECT_NEAR(r.massChange, 0.0, 1e4 * agreement::roundOff(precision())) << "mu " << mu;
  }
}

TEST(Terrain, CpuAndCudaAgree) {
  if (!cudaAvailable()) GTEST_SKIP() << "no CUDA device in this build/machine: CPU-vs-CUDA terrain check skipped";
  // A column collapsing onto a bumpy terrain (random heights on a coarse raster) with Coulomb
  // friction 0.3: the terrain's law and the lift on both backends, 200 steps. Each precision
  // against the CPU in the same precision: this scene amplifies round-off (the CPU's float run
  // leaves its double run by 3.9e-7 m after 10 steps, 3.7e-5 m after 50, 5.1e-4 m after 200:
  // nodes switch between sticking and sliding), so float against double would test the scene.
  MpmParams prm = testing_scenes::granularColumnParams(0.01, {30, 12, 24}, 2e5);
  prm.walls[4].friction = 0;
  prm.terrain = planeRaster(0.05, -0.1, 0.0, 7, 4, 0.0, 0.0, 0.05);
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> bump(-0.01, 0.01);
  for (double& z : prm.terrain.heights) z += bump(rng);
  prm.terrain.friction = 0.3;
  ParticleSet ps;
  {
    MpmScene scene;
    scene.params = prm;
    ParticleBox box;
    box.lo = {0.06, 0.04, 0.02};
    box.hi = {0.14, 0.08, 0.20};
    box.ppc = {2, 2, 2};
    scene.boxes.push_back(box);
    ps = seedParticles(scene);
  }
  auto probe = makeSolver(prm);
  probe->setParticles(ps);
  const double dt = 0.8 * probe->stableTimeStep();
  for (auto prec : {Precision::Double, Precision::Float}) {
    auto cpu = makeSolver(prm, Backend::Cpu, prec);
    auto gpu = makeSolver(prm, Backend::Cuda, prec);
    ParticleSet a, b;
    agreement::runPair(*cpu, *gpu, ps, dt, 200, a, b);
    // summation order only: 1e-9 in double; in float 1e-4 of the domain for positions and 1e-3
    // of the largest stress (an H200 gave 3.0e-8 m and 0.54 Pa of 4023 Pa, 1.35e-4: the
    // frictional collapse amplifies the stresses' float round-off)
    const bool dbl = prec == Precision::Double;
    agreement::expectAgree(a, b, dbl ? 1e-9 : 1e-4, 0.3, 100.0, gpu->name() + " and " + cpu->name(),
                           dbl ? 1e-9 : 1e-3);
  }
}
