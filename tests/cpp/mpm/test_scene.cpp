// JSON scenes: parameters, particle count and mass of a good scene; every kind of bad input
// raises ParameterError naming the key.
#include <gtest/gtest.h>

#include <cmath>
#include <regex>
#include <set>
#include <nlohmann/json.hpp>

#include "common/Error.hpp"
#include "scene/MpmScene.hpp"
#include "scene/SceneParameters.hpp"
#include "mpm/MpmSolver.hpp"

#include "AgreementHelpers.hpp"

using namespace mpmsdem;
using namespace mpmsdem::mpm;
using nlohmann::json;

namespace {

// Grid 40 x 10 x 20 cells of 0.01 m: material region [0.02, 0.38] x [0.02, 0.08] x [0.02, 0.18].
json goodScene() {
  return json::parse(R"({
    "description": "two boxes in a small inclined flume",
    "grid": {"dx": 0.01, "cells": [40, 10, 20], "origin": [0, 0, 0]},
    "gravity": {"g": 9.81, "incline_deg": 10},
    "flip_alpha": 0.95,
    "flip_reference_dt": "step",
    "cfl": 0.4,
    "walls": {"-z": 0.21, "+x": "noslip", "-x": "free"},
    "material": {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24, "mu_2": 0.65,
                 "grain_diameter": 0.001, "critical_density": 1500},
    "particles": [
      {"lo": [0.02, 0.02, 0.02], "hi": [0.32, 0.08, 0.12], "ppc": 8},
      {"lo": [0.33, 0.02, 0.02], "hi": [0.36, 0.05, 0.06], "ppc": [1, 2, 3], "velocity": [0.5, 0, -0.25]}
    ],
    "run": {"duration": 0.5, "dt": "auto", "output_every": 0.05, "output_dir": "out/flume", "vtk": "ascii"}
  })");
}

// Parse `scene` and require a ParameterError whose message contains every `needle`.
void expectError(const json& scene, std::initializer_list<const char*> needles) {
  try {
    parseScene(scene.dump());
    ADD_FAILURE() << "expected ParameterError for " << scene.dump();
  } catch (const ParameterError& e) {
    for (const char* n : needles) EXPECT_NE(std::string(e.what()).find(n), std::string::npos) << e.what();
  }
}

// A JSON pointer as the messages name the key: "/material/poisson_ratio" -> "material.poisson_ratio",
// "/grid/cells/1" -> "grid.cells[1]".
std::string keyName(const std::string& ptr) {
  std::string name = ptr.substr(1);
  std::size_t pos;
  while ((pos = name.find('/')) != std::string::npos) name.replace(pos, 1, ".");
  return std::regex_replace(name, std::regex("\\.([0-9]+)"), "[$1]");
}

}  // namespace

TEST(MpmScene, GoodSceneGivesParameters) {
  const MpmScene s = parseScene(goodScene().dump());
  const MpmParams& p = s.params;
  EXPECT_EQ(p.dx, 0.01);
  EXPECT_EQ(p.cells[0], 40);
  EXPECT_EQ(p.cells[2], 20);
  const double a = 10 * M_PI / 180;
  EXPECT_NEAR(p.gravity[0], 9.81 * std::sin(a), 1e-12);
  EXPECT_NEAR(p.gravity[0], 1.7034886, 1e-6);
  EXPECT_EQ(p.gravity[1], 0.0);
  EXPECT_NEAR(p.gravity[2], -9.81 * std::cos(a), 1e-12);
  EXPECT_NEAR(p.gravity[2], -9.660965, 1e-6);
  EXPECT_TRUE(p.flip == FlipBlend::alphaPerStep(0.95));
  EXPECT_EQ(p.cfl, 0.4);
  EXPECT_EQ(p.walls[4].friction, 0.21);  // -z
  EXPECT_LT(p.walls[1].friction, 0.0);   // +x no-slip
  EXPECT_EQ(p.walls[0].friction, 0.0);   // -x free
  EXPECT_EQ(p.walls[5].friction, 0.0);   // +z default free
  EXPECT_EQ(p.material.density, 1600.0);
  EXPECT_EQ(p.material.youngModulus, 1e6);
  EXPECT_EQ(p.material.mu2, 0.65);
  EXPECT_EQ(p.material.grainDiameter, 0.001);
  EXPECT_EQ(p.material.criticalDensity, 1500.0);
  EXPECT_EQ(p.material.I0, 0.279);          // default
  EXPECT_EQ(p.material.solidDensity, 2500);  // default
  EXPECT_EQ(s.run.duration, 0.5);
  EXPECT_EQ(s.run.dt, 0.0);  // auto
  EXPECT_EQ(s.run.dtFactor, 0.9);
  EXPECT_EQ(s.run.outputEvery, 0.05);
  EXPECT_NEAR(s.run.seriesEvery, 0.005, 1e-15);
  EXPECT_EQ(s.run.outputDir, "out/flume");
  EXPECT_EQ(s.run.vtk, "ascii");
  EXPECT_EQ(s.run.backend, Backend::Cpu);
  EXPECT_EQ(s.run.precision, Precision::Double);
  ASSERT_EQ(s.boxes.size(), 2u);
  EXPECT_EQ(s.boxes[1].ppc[2], 3);
  EXPECT_EQ(json::parse(s.sourceJson), goodScene());
  // float on the CPU backend is a valid pair (cpu-float)
  json f = goodScene();
  f["run"]["precision"] = "float";
  const MpmScene sf = parseScene(f.dump());
  EXPECT_EQ(sf.run.backend, Backend::Cpu);
  EXPECT_EQ(sf.run.precision, Precision::Float);
  EXPECT_EQ(makeSolver(sf.params, sf.run.backend, sf.run.precision)->name(), "cpu-float");
}

TEST(MpmScene, SeedsHandComputedCountAndMass) {
  const MpmScene s = parseScene(goodScene().dump());
  const ParticleSet p = seedParticles(s);
  // Box 0: 30 x 6 x 10 cells x 8 = 14400; box 1: 3 x 3 x 4 cells x 6 = 216.
  ASSERT_EQ(p.size(), 14400u + 216u);
  ASSERT_EQ(p.x.size(), 3 * p.size());
  ASSERT_EQ(p.stress.size(), 6 * p.size());
  ASSERT_EQ(p.fext.size(), 3 * p.size());
  double m0 = 0, m1 = 0, v0 = 0;
  for (std::size_t i = 0; i < 14400; ++i) {
    m0 += p.mass[i];
    v0 += p.volume0[i];
  }
  for (std::size_t i = 14400; i < p.size(); ++i) m1 += p.mass[i];
  const double vol0 = 0.30 * 0.06 * 0.10, vol1 = 0.03 * 0.03 * 0.04;
  EXPECT_NEAR(m0, 1600 * vol0, 1e-12);  // 2.88 kg
  EXPECT_NEAR(m0, 2.88, 1e-12);
  EXPECT_NEAR(m1, 1600 * vol1, 1e-12);  // 0.0576 kg
  EXPECT_NEAR(v0, vol0, 1e-15);
  // Every particle inside its box; box 1 carries its velocity, box 0 is at rest.
  for (std::size_t i = 0; i < p.size(); ++i) {
    const ParticleBox& b = s.boxes[i < 14400 ? 0 : 1];
    for (int a = 0; a < 3; ++a) {
      EXPECT_GT(p.x[3 * i + a], b.lo[a]);
      EXPECT_LT(p.x[3 * i + a], b.hi[a]);
      EXPECT_EQ(p.v[3 * i + a], b.velocity[a]);
    }
    EXPECT_EQ(p.J[i], 1.0);
  }
  EXPECT_EQ(p.v[3 * 14400], 0.5);
  EXPECT_EQ(p.v[3 * 14400 + 2], -0.25);
}

TEST(MpmScene, DefaultsAndPlainGravity) {
  json j = goodScene();
  j["gravity"] = {0.0, -1.0, -9.0};
  j.erase("walls");
  j.erase("flip_alpha");
  j.erase("flip_reference_dt");
  j["run"] = {{"duration", 2.0}, {"dt", 1e-4}};
  const MpmScene s = parseScene(j.dump());
  EXPECT_EQ(s.params.gravity[1], -1.0);
  EXPECT_EQ(s.params.gravity[2], -9.0);
  EXPECT_TRUE(s.params.flip == FlipBlend::viscosity(0.005));
  for (const WallSpec& w : s.params.walls) EXPECT_EQ(w.friction, 0.0);
  EXPECT_EQ(s.run.dt, 1e-4);
  EXPECT_EQ(s.run.outputEvery, 0.1);
  EXPECT_EQ(s.run.outputDir, "out");
  EXPECT_EQ(s.run.vtk, "raw");
}

TEST(MpmScene, UnknownKeysAreNamed) {
  json j = goodScene();
  j["gravty"] = 9.81;
  expectError(j, {"unknown key 'gravty'"});
  j = goodScene();
  j["material"]["densty"] = 1600;
  expectError(j, {"unknown key 'material.densty'", "density"});
  j = goodScene();
  j["particles"][1]["ppcc"] = 8;
  expectError(j, {"unknown key 'particles[1].ppcc'"});
  j = goodScene();
  j["walls"]["-w"] = 0.1;
  expectError(j, {"unknown key 'walls.-w'"});
  j = goodScene();
  j["run"]["output"] = "x";
  expectError(j, {"unknown key 'run.output'"});
  // a key of the other form of a two-form section is refused, the message listing this form's keys
  j = goodScene();
  j["particles"][1]["scale"] = 2;  // a box with a mesh's key
  expectError(j, {"unknown key 'particles[1].scale'", "are lo, hi, ppc, velocity"});
  j = goodScene();
  j["particles"][1] = {{"mesh", "cube.stl"}, {"lo", {0.33, 0.02, 0.02}}};  // a mesh with a box's key
  expectError(j, {"unknown key 'particles[1].lo'", "are mesh, scale, offset, ppc, velocity"});
  j = goodScene();
  j["terrain"] = {{"file", "dem.asc"}, {"nx", 2}};  // a file with the raster's own key
  expectError(j, {"unknown key 'terrain.nx'", "are file, origin, friction"});
  j = goodScene();
  j["terrain"] = {{"nx", 2}, {"origin", {0, 0, 0}}};
  expectError(j, {"unknown key 'terrain.origin'", "are nx, ny, x0, y0, spacing, heights, friction"});
  j = goodScene();
  j["particles"] = 3;
  expectError(j, {"boxes {lo, hi, ppc, velocity} or meshes {mesh, scale, offset, ppc, velocity}"});
}

TEST(MpmScene, MissingKeysAreNamed) {
  for (const char* key : {"grid", "material", "particles", "run"}) {
    json j = goodScene();
    j.erase(key);
    expectError(j, {"missing required key", key});
  }
  json j = goodScene();
  j["run"].erase("duration");
  expectError(j, {"missing required key 'run.duration'"});
  j = goodScene();
  j["material"].erase("mu_2");
  expectError(j, {"missing required key 'material.mu_2'"});
  j = goodScene();
  j["grid"].erase("dx");
  expectError(j, {"missing required key 'grid.dx'"});
  j = goodScene();
  j["particles"][0].erase("hi");
  expectError(j, {"missing required key 'particles[0].hi'"});
}

TEST(MpmScene, ParticlesOutsideTheGrid) {
  json j = goodScene();
  j["particles"][0]["hi"] = {0.32, 0.08, 0.19};  // z region ends at 0.18 (wall layers)
  expectError(j, {"particles[0]", "outside the grid", "0.18"});
  j = goodScene();
  j["particles"][0]["lo"] = {0.01, 0.02, 0.02};  // inside the -x wall layer
  expectError(j, {"particles[0]", "outside the grid", "0.02"});
  j = goodScene();
  j["particles"][1]["lo"] = {0.30, 0.02, 0.02};  // overlaps box 0
  expectError(j, {"particles[1]", "overlapping particles[0]"});
  j = goodScene();
  j["particles"][0]["hi"] = {0.325, 0.08, 0.12};  // not on a grid line
  expectError(j, {"particles[0].hi[0]", "grid line"});
  j = goodScene();
  j["particles"][0]["hi"] = {0.02, 0.08, 0.12};  // empty
  expectError(j, {"particles[0].hi[0]"});
  j = goodScene();
  j["particles"] = json::object();
  expectError(j, {"particles", "an array"});
}

// Seeding held compactly (positions and runs of equal mass, volume and velocity) hands out
// exactly the seeded set, over any range and across the boundary of the two boxes (which
// differ in mass, volume and velocity), and a solver loaded from it slice by slice holds the
// particles a solver loaded from the whole set holds, after steps too.
TEST(MpmScene, CompactSeedingGivesTheSeededSetAndTheSameSolver) {
  const MpmScene s = parseScene(goodScene().dump());
  const ParticleSet whole = seedParticles(s);
  SeededParticles compact = seedParticleSlices(s);
  const std::size_t n = whole.size();
  ASSERT_EQ(compact.size(), n);
  const std::pair<std::size_t, std::size_t> ranges[] = {{0, n}, {0, 1}, {14399, 2}, {n - 5, 5}, {100, 14400}, {n, 0}};
  for (const auto& [first, count] : ranges) {
    const ParticleSet& p = compact.slice(first, count);
    ASSERT_EQ(p.size(), count);
    agreement::expectRangeOf(p, whole, first);
  }
  EXPECT_NE(whole.v[3 * (n - 1)], whole.v[0]);  // the boxes' runs differ
  EXPECT_THROW(compact.slice(n - 1, 2), ParameterError);
  auto a = makeSolver(s.params), b = makeSolver(s.params);
  a->setParticles(whole);
  b->setParticles(compact);
  for (int k = 0; k < 3; ++k) {
    a->step(1e-4);
    b->step(1e-4);
  }
  ParticleSet pa, pb;
  a->getParticles(pa);
  b->getParticles(pb);
  EXPECT_EQ(pa.x, pb.x);
  EXPECT_EQ(pa.v, pb.v);
  EXPECT_EQ(pa.stress, pb.stress);
  // a bad point in a later slice is named by its number
  SeededParticles bad;
  const double inside[3] = {0.1, 0.05, 0.05}, outside[3] = {0.1, 0.05, 5.0};
  for (int k = 0; k < 70000; ++k) bad.add(k == 69999 ? outside : inside, 1e-4, 1e-7, {0, 0, 0});
  ASSERT_GT(bad.size(), bad.sliceSize());
  try {
    makeSolver(s.params)->setParticles(bad);
    ADD_FAILURE() << "a point outside the grid was loaded";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("particle x[69999][2]"), std::string::npos) << e.what();
  }
}

// No flow: an empty particle list is a scene of grid and walls only (a coupled scene whose
// blocks move alone); the solver steps it with its CFL step and no particle to move.
TEST(MpmScene, EmptyParticleListIsASceneWithoutFlow) {
  json j = goodScene();
  j["particles"] = json::array();
  const MpmScene s = parseScene(j.dump());
  const ParticleSet p = seedParticles(s);
  EXPECT_EQ(p.size(), 0u);
  auto solver = makeSolver(s.params, s.run.backend, s.run.precision);
  solver->setParticles(p);
  ASSERT_EQ(solver->numParticles(), 0u);
  const double dt = solver->stableTimeStep();
  // the CFL step of the material's wave speed, with no particle velocity to add to it:
  // cfl dx / sqrt((K + 4G/3) / rho)
  const double E = 1e6, nu = 0.3, rho = 1600;
  const double c = std::sqrt(E * (1 - nu) / ((1 + nu) * (1 - 2 * nu)) / rho);
  EXPECT_NEAR(dt, 0.4 * 0.01 / c, 1e-9 * dt);
  for (int k = 0; k < 10; ++k) solver->step(dt);
  EXPECT_NEAR(solver->time(), 10 * dt, 1e-12 * dt);
  EXPECT_EQ(solver->steps(), 10);
  ParticleSet out;
  solver->getParticles(out);
  EXPECT_EQ(out.size(), 0u);
}

TEST(MpmScene, BadValueRanges) {
  const std::vector<std::pair<std::string, json>> cases = {
      {"/grid/dx", -0.01},          {"/grid/cells/1", 3},       {"/grid/cells/0", 10.5},
      {"/material/density", 0},     {"/material/poisson_ratio", 0.5}, {"/material/mu_2", 0.2},
      {"/material/young_modulus", -1e6}, {"/material/I0", 0},   {"/flip_alpha", 1.5},
      {"/cfl", 0},                  {"/walls/-z", -0.2},        {"/walls/+x", "sticky"},
      {"/gravity/incline_deg", 90}, {"/run/duration", 0},       {"/run/dt", 1.0},
      {"/run/dt", "fast"},          {"/run/dt_factor", 1.5},    {"/run/backend", "gpu"},
      {"/run/precision", "half"},   {"/run/vtk", "binary"},     {"/particles/0/ppc", 9},
      {"/particles/0/ppc", [] { return json::array({1, 9, 1}); }()},
      {"/material/density", "heavy"}};
  for (const auto& [ptr, value] : cases) {
    json j = goodScene();
    j[json::json_pointer(ptr)] = value;
    SCOPED_TRACE(ptr);
    expectError(j, {keyName(ptr).c_str(), "must be"});
  }
  // Not JSON, not an object, missing file.
  EXPECT_THROW(parseScene("{\"grid\": "), ParameterError);
  EXPECT_THROW(parseScene("[1, 2]"), ParameterError);
  EXPECT_THROW(loadScene("/nonexistent/scene.json"), ParameterError);
}

TEST(MpmScene, FlowProbesAndStopRules) {
  json j = goodScene();
  j["flow_probes"] = json::parse(R"([{"x": 0.3}, {"x": 0.1, "half_width": 0.02, "bed_z": 0.02, "min_points": 1,
                                      "window": 0}])");
  j["run"]["stop_when_probed"] = true;
  j["run"]["stop_when_front_still"] = 0.3;
  j["run"]["snapshot_when_front_at"] = -0.5;  // any x: a snapshot from the start when the front is past it
  const MpmScene s = parseScene(j.dump());
  ASSERT_EQ(s.probes.size(), 2u);
  EXPECT_EQ(s.probes[0].x, 0.3);
  EXPECT_EQ(s.probes[0].halfWidth, 0.01);  // default: one cell
  EXPECT_EQ(s.probes[0].bedZ, 0.0);
  EXPECT_EQ(s.probes[0].minPoints, 4);
  EXPECT_EQ(s.probes[0].window, 0.05);
  EXPECT_EQ(s.probes[1].halfWidth, 0.02);
  EXPECT_EQ(s.probes[1].bedZ, 0.02);
  EXPECT_EQ(s.probes[1].minPoints, 1);
  EXPECT_EQ(s.probes[1].window, 0.0);
  EXPECT_TRUE(s.run.stopWhenProbed);
  EXPECT_EQ(s.run.stopWhenFrontStill, 0.3);
  EXPECT_EQ(s.run.snapshotsWhenFrontAt, std::vector<double>{-0.5});
  EXPECT_FALSE(s.run.snapshotsIndexed);
  json several = j;
  several["run"]["snapshot_when_front_at"] = json::array({0.1, 0.2});
  const MpmScene list = parseScene(several.dump());
  EXPECT_EQ(list.run.snapshotsWhenFrontAt, (std::vector<double>{0.1, 0.2}));
  EXPECT_TRUE(list.run.snapshotsIndexed);
  const MpmScene plain = parseScene(goodScene().dump());
  EXPECT_TRUE(plain.run.snapshotsWhenFrontAt.empty());
  EXPECT_TRUE(plain.probes.empty());
  EXPECT_FALSE(plain.run.stopWhenProbed);
  EXPECT_EQ(plain.run.stopWhenFrontStill, 0.0);

  const std::vector<std::pair<std::string, json>> bad = {
      {"/flow_probes/0/x", 0.39},           // beyond the material region [0.02, 0.38]
      {"/flow_probes/0/half_width", 0},     {"/flow_probes/0/min_points", 0},
      {"/flow_probes/0/min_points", 2.5},   {"/flow_probes/0/window", -0.01},
      {"/run/stop_when_front_still", -1},   {"/run/stop_when_probed", 1},
      {"/run/snapshot_when_front_at", "far"}, {"/run/snapshot_when_front_at", json::array({0.2, 0.1})},
      {"/run/snapshot_when_front_at", json::array()}};
  for (const auto& [ptr, value] : bad) {
    json b = j;
    b[json::json_pointer(ptr)] = value;
    SCOPED_TRACE(ptr);
    expectError(b, {keyName(ptr).c_str(), "must be"});
  }
  json noX = j;
  noX["flow_probes"][0].erase("x");
  expectError(noX, {"flow_probes[0]", "x"});
  json unknown = j;
  unknown["flow_probes"][0]["depth"] = 1;
  expectError(unknown, {"depth"});
  json nothing = goodScene();
  nothing["run"]["stop_when_probed"] = true;
  expectError(nothing, {"run.stop_when_probed", "flow_probes"});
}

// The table's defaults are what the parser applies to a scene that leaves the keys out.
TEST(SceneParameters, DefaultsAreTheParsers) {
  json j = goodScene();
  for (const char* key : {"flip_alpha", "flip_reference_dt", "cfl"}) j.erase(key);
  for (const char* key : {"grain_diameter", "critical_density"}) j["material"].erase(key);
  j["gate"] = json::parse(R"({"x": 0.3})");
  j["flow_probes"] = json::parse(R"([{"x": 0.3}])");
  const MpmScene s = parseScene(j.dump());
  const auto def = [](const char* key) { return sceneParameter(key).defaultValue; };
  EXPECT_EQ(s.params.flip.setViscosity(), def("flip_viscosity"));
  EXPECT_EQ(s.params.cfl, def("cfl"));
  EXPECT_EQ(s.params.material.I0, def("material.I0"));
  EXPECT_EQ(s.params.material.grainDiameter, def("material.grain_diameter"));
  EXPECT_EQ(s.params.material.solidDensity, def("material.solid_density"));
  EXPECT_EQ(s.params.material.criticalDensity, def("material.critical_density"));
  EXPECT_EQ(s.params.gate.bottom, def("gate.bottom"));
  EXPECT_EQ(s.params.gate.speed, def("gate.speed"));
  EXPECT_EQ(s.params.gate.openAt, def("gate.open_at"));
  EXPECT_EQ(s.params.gate.friction, def("gate.friction"));
  EXPECT_EQ(s.probes.at(0).bedZ, def("flow_probes[].bed_z"));
  EXPECT_EQ(s.probes.at(0).minPoints, def("flow_probes[].min_points"));
  EXPECT_EQ(s.probes.at(0).window, def("flow_probes[].window"));
  EXPECT_EQ(s.run.dtFactor, def("run.dt_factor"));
  EXPECT_EQ(s.run.minStepFraction, def("run.min_step_fraction"));
  EXPECT_EQ(s.run.progressEvery, def("run.progress_every"));
  EXPECT_EQ(s.run.stopWhenFrontStill, def("run.stop_when_front_still"));
  EXPECT_EQ(s.run.backend == Backend::Cuda ? "cuda" : "cpu", std::string(sceneParameter("run.backend").defaultText));
  // the values Table 1 and the schema state
  EXPECT_EQ(def("cfl"), 0.3);
  EXPECT_EQ(def("flip_viscosity"), 0.005);
  EXPECT_EQ(def("material.I0"), 0.279);
}

// A value just outside a numeric entry's range is refused, naming the key and the table's range.
TEST(SceneParameters, RangeErrorsNameTheTablesRange) {
  const std::vector<std::pair<std::string, const char*>> cases = {
      {"/grid/dx", "grid.dx"},
      {"/gravity/incline_deg", "gravity.incline_deg"},
      {"/cfl", "cfl"},
      {"/material/density", "material.density"},
      {"/material/poisson_ratio", "material.poisson_ratio"},
      {"/material/I0", "material.I0"},
      {"/material/critical_density", "material.critical_density"},
      {"/run/duration", "run.duration"},
      {"/run/dt_factor", "run.dt_factor"},
      {"/run/min_step_fraction", "run.min_step_fraction"},
      {"/run/output_every", "run.output_every"}};
  for (const auto& [ptr, key] : cases) {
    const ParameterSpec& spec = sceneParameter(key);
    // beyond a finite hi, else below lo
    const double bad = std::isinf(spec.hi) ? spec.lo - 1 : (spec.hiInclusive ? spec.hi + 0.5 : spec.hi);
    json j = goodScene();
    j[json::json_pointer(ptr)] = bad;
    SCOPED_TRACE(key);
    expectError(j, {(std::string(key) + " = ").c_str(), ("must be " + rangeText(spec)).c_str()});
  }
}

// Every key a section's reader allows is in the table, once, with a consistent range.
TEST(SceneParameters, TableIsConsistent) {
  std::set<std::string> keys;
  for (const ParameterSpec& s : sceneParameter.table()) {
    SCOPED_TRACE(s.key);
    EXPECT_TRUE(keys.insert(s.key).second);
    EXPECT_TRUE(*s.doc);
    if (s.kind == ParameterKind::kNumber || s.kind == ParameterKind::kInteger) {
      EXPECT_LE(s.lo, s.hi);
      if (!isRequired(s) && !std::isnan(s.defaultValue)) {
        EXPECT_TRUE(s.loInclusive ? s.defaultValue >= s.lo : s.defaultValue > s.lo);
        EXPECT_TRUE(s.hiInclusive ? s.defaultValue <= s.hi : s.defaultValue < s.hi);
      }
    }
  }
  EXPECT_EQ(sectionKeys(sceneParameter.table(), "flow_probes[]"),
            (std::vector<std::string>{"x", "half_width", "bed_z", "min_points", "window"}));
  EXPECT_EQ(rangeText(sceneParameter("grid.cells")), "an integer in [4, 2^30]");
  EXPECT_EQ(rangeText(sceneParameter("run.vtk")), "one of \"raw\", \"ascii\", \"none\"");
  EXPECT_EQ(rangeText(sceneParameter("material.poisson_ratio")), "in [0, 0.5)");
  EXPECT_THROW(sceneParameter("material.mu_3"), std::logic_error);
}

// The flow model's ranges are declared once (mpm/MpmParameters): a value the scene parser refuses
// is refused by makeSolver in the same words when an MpmParams is filled in C++, and a value at
// an allowed bound passes both.
TEST(MpmScene, SolverAndSceneRefuseFromOneTable) {
  struct Case {
    const char* section;
    const char* key;
    double value;
    void (*set)(MpmParams&, double);
  };
  const Case cases[] = {
      {"material", "poisson_ratio", 0.5, [](MpmParams& p, double v) { p.material.poissonRatio = v; }},
      {"material", "young_modulus", 0, [](MpmParams& p, double v) { p.material.youngModulus = v; }},
      {"material", "mu_2", 0.2, [](MpmParams& p, double v) { p.material.mu2 = v; }},  // below mu_s 0.24
      {"material", "grain_diameter", -1e-3, [](MpmParams& p, double v) { p.material.grainDiameter = v; }},
      {"material", "critical_density", -1, [](MpmParams& p, double v) { p.material.criticalDensity = v; }},
      {"grid", "dx", 0, [](MpmParams& p, double v) { p.dx = v; }},
      {"gate", "friction", -0.1, [](MpmParams& p, double v) { p.gate.friction = v; }},
      {"gate", "open_at", -1, [](MpmParams& p, double v) { p.gate.openAt = v; }},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.key);
    json scene = goodScene();
    scene["gate"] = {{"x", 0.33}};
    scene[c.section][c.key] = c.value;
    std::string fromScene, fromSolver;
    try {
      parseScene(scene.dump());
    } catch (const ParameterError& e) {
      fromScene = e.what();
    }
    MpmParams p = parseScene(goodScene().dump()).params;
    p.gate.enabled = true;
    p.gate.x = 0.33;
    c.set(p, c.value);
    try {
      makeSolver(p);
    } catch (const ParameterError& e) {
      fromSolver = e.what();
    }
    EXPECT_EQ(fromSolver.rfind(std::string(c.section) + "." + c.key + " = ", 0), 0u) << fromSolver;
    EXPECT_EQ(fromSolver, fromScene);
  }
  MpmParams p = parseScene(goodScene().dump()).params;
  p.material.poissonRatio = 0;  // the closed lower bound of [0, 0.5)
  p.material.mu2 = p.material.muS;
  EXPECT_NO_THROW(makeSolver(p));
}
