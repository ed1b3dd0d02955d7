#include "scene/MpmScene.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <set>
#include <sstream>

#include "common/Error.hpp"
#include "common/SceneJson.hpp"
#include "input/MeshReader.hpp"
#include "input/TerrainRaster.hpp"
#include "mpm/GridBoundary.hpp"
#include "mpm/MpmKernelsCommon.hpp"
#include "mpm/Seeding.hpp"
#include "scene/SceneParameters.hpp"

namespace mpmsdem {
namespace mpm {

namespace {

using nlohmann::json;

using namespace scenejson;

// The keys a section may have: its entries in the table.
std::vector<std::string> keysOf(const char* section) { return sectionKeys(sceneParameter.table(), section); }

// The keys of one form of a section that has two (a box or a mesh, a terrain from a file or
// given here): the section's keys less those only the other form has. A key both forms share is
// then in each without being listed here.
std::vector<std::string> formKeys(const char* section, std::initializer_list<const char*> otherFormOnly) {
  std::vector<std::string> keys = keysOf(section);
  for (const char* k : otherFormOnly) keys.erase(std::remove(keys.begin(), keys.end(), std::string(k)), keys.end());
  return keys;
}

// "{a, b, c}", as the messages show a form's keys.
std::string braced(const std::vector<std::string>& keys) {
  std::string out;
  for (const std::string& k : keys) out += (out.empty() ? "{" : ", ") + k;
  return out + "}";
}

// The two forms of a terrain and of a particle region.
const std::vector<std::string>& terrainFileKeys() {
  static const std::vector<std::string> keys = formKeys("terrain", {"nx", "ny", "x0", "y0", "spacing", "heights"});
  return keys;
}
const std::vector<std::string>& terrainHeightKeys() {
  static const std::vector<std::string> keys = formKeys("terrain", {"file", "origin"});
  return keys;
}
const std::vector<std::string>& boxKeys() {
  static const std::vector<std::string> keys = formKeys("particles[]", {"mesh", "scale", "offset"});
  return keys;
}
const std::vector<std::string>& meshKeys() {
  static const std::vector<std::string> keys = formKeys("particles[]", {"lo", "hi"});
  return keys;
}

void parseGrid(const json& root, MpmParams& p) {
  const json& g = requireObject(root, "", "grid");
  checkKeys(g, "grid", keysOf("grid"));
  p.dx = readNumber(g, "grid", sceneParameter("grid.dx"));
  if (!g.contains("cells")) throw ParameterError("missing required key 'grid.cells'");
  const json& c = g.at("cells");
  if (!c.is_array() || c.size() != 3) throwParameter("grid.cells", c.dump(), "", "an array of 3 integers");
  for (int a = 0; a < 3; ++a)
    p.cells[a] = static_cast<int>(integer(c[a], "grid.cells[" + std::to_string(a) + "]", sceneParameter("grid.cells")));
  if (g.contains("origin")) p.origin = vec3(g.at("origin"), "grid.origin");
}

void parseGravity(const json& root, MpmParams& p) {
  if (!root.contains("gravity")) return;
  const json& g = root.at("gravity");
  if (g.is_array()) {
    p.gravity = vec3(g, "gravity");
    return;
  }
  if (!g.is_object())
    throwParameter("gravity", g.dump(), "", "an array [gx, gy, gz] or an object {\"g\", \"incline_deg\"}");
  checkKeys(g, "gravity", keysOf("gravity"));
  const double mag = readNumber(g, "gravity", sceneParameter("gravity.g"));
  const double deg = readNumber(g, "gravity", sceneParameter("gravity.incline_deg"));
  const double a = deg * M_PI / 180.0;
  p.gravity = {mag * std::sin(a), 0.0, -mag * std::cos(a)};
}

// The blend (mpm/FlipBlend.hpp): "flip_viscosity" [m^2/s], or "flip_alpha" per
// "flip_reference_dt" (a step in seconds, or "step" for Eq 4 as written); neither: the default
// viscosity. A bare 0 reference is refused: it meant "per step" before the blend had a
// reference, and a scene should say which it wants. flip_alpha alone is refused: without a
// reference it has no time scale.
FlipBlend parseFlipBlend(const json& root) {
  const bool viscosity = root.contains("flip_viscosity"), reference = root.contains("flip_reference_dt");
  if (viscosity && (reference || root.contains("flip_alpha")))
    throwParameter(reference ? "flip_reference_dt" : "flip_alpha",
                   root.at(reference ? "flip_reference_dt" : "flip_alpha").dump(), "",
                   "absent when flip_viscosity is given (the viscosity alone sets the blend)");
  if (root.contains("flip_alpha") && !reference)
    throwParameter("flip_alpha", root.at("flip_alpha").dump(), "",
                   "given with flip_reference_dt (alpha per that much simulated time, e.g. the paper's 0.99 per "
                   "5e-6 s, or \"step\": per step, Eq 4 as written); without it the blend is flip_viscosity "
                   "[m^2/s] (default 0.005)");
  if (viscosity) return FlipBlend::viscosity(readNumber(root, "", sceneParameter("flip_viscosity")));
  if (!reference) return FlipBlend();
  const double alpha = readNumber(root, "", sceneParameter("flip_alpha"));
  const json& v = root.at("flip_reference_dt");
  if (v.is_string() && v.get<std::string>() == "step") return FlipBlend::alphaPerStep(alpha);
  if (!v.is_number())
    throwParameter("flip_reference_dt", v.dump(), "s",
                   "a step > 0 (flip_alpha is kept per that much simulated time; the paper's blend is 0.99 per "
                   "5e-6) or \"step\" (flip_alpha per step, Eq 4 as written: the damping then changes with the "
                   "step)");
  return FlipBlend::alphaPer(alpha, v.get<double>());  // which refuses a step <= 0
}

// A wall's or the terrain's friction: "free" (0), "noslip" (-1) or a Coulomb coefficient in the
// range of `spec`.
double parseFriction(const json& v, const std::string& name, const ParameterSpec& spec) {
  if (v.is_string() && v.get<std::string>() == "free") return 0;
  if (v.is_string() && v.get<std::string>() == "noslip") return -1;
  if (!v.is_number()) throwParameter(name, v.dump(), "", "\"free\", \"noslip\" or a friction coefficient >= 0");
  const double mu = v.get<double>();
  checkParameter(spec, name, mu, spec.lo, spec.hi);
  return mu;
}

void parseWalls(const json& root, MpmParams& p) {
  if (!root.contains("walls")) return;
  const json& w = root.at("walls");
  if (!w.is_object()) throwParameter("walls", w.dump(), "", "a JSON object with keys -x, +x, -y, +y, -z, +z");
  checkKeys(w, "walls", std::vector<std::string>(std::begin(kWallNames), std::end(kWallNames)));
  for (int i = 0; i < 6; ++i) {
    if (!w.contains(kWallNames[i])) continue;
    p.walls[i].friction =
        parseFriction(w.at(kWallNames[i]), std::string("walls.") + kWallNames[i], sceneParameter("walls.<face>"));
  }
}

void parseGate(const json& root, MpmParams& p) {
  if (!root.contains("gate")) return;
  const json& j = root.at("gate");
  if (!j.is_object()) throwParameter("gate", j.dump(), "", "a JSON object {x, bottom, speed, open_at, friction}");
  checkKeys(j, "gate", keysOf("gate"));
  GateSpec& g = p.gate;
  g.enabled = true;
  g.x = readNumberIn(j, "gate", sceneParameter("gate.x"), materialRegionLo(p)[0], materialRegionHi(p)[0]);
  g.bottom = readNumber(j, "gate", sceneParameter("gate.bottom"));
  g.speed = readNumber(j, "gate", sceneParameter("gate.speed"));
  g.openAt = readNumber(j, "gate", sceneParameter("gate.open_at"));
  g.friction = readNumber(j, "gate", sceneParameter("gate.friction"));
}
// "terrain": an ESRI ASCII grid {file, origin, friction} (the file's point `origin` [m] goes to
// the grid frame's zero; the file relative to the scene's folder) or the heights themselves {nx,
// ny, x0, y0, spacing, heights (nx * ny, i-major: heights[i * ny + j]), friction}. friction:
// "free", "noslip" or a Coulomb coefficient >= 0, as for the walls (default "free").
void parseTerrain(const json& root, MpmParams& p, const std::string& baseDir) {
  if (!root.contains("terrain")) return;
  const json& j = root.at("terrain");
  if (!j.is_object())
    throwParameter("terrain", j.dump(), "", "a JSON object " + braced(terrainFileKeys()) + " or " +
                                            braced(terrainHeightKeys()));
  TerrainSpec& t = p.terrain;
  if (j.contains("file")) {
    checkKeys(j, "terrain", terrainFileKeys());
    const json& f = j.at("file");
    if (!f.is_string() || f.get<std::string>().empty())
      throwParameter("terrain.file", f.dump(), "", "a non-empty path to an ESRI ASCII grid (.asc)");
    const std::filesystem::path file(f.get<std::string>());
    const std::string path = (baseDir.empty() || file.is_absolute()) ? file.string() : (std::filesystem::path(baseDir) / file).string();
    io::TerrainRaster r = io::readEsriAscii(path);
    const std::array<double, 3> o = j.contains("origin") ? vec3(j.at("origin"), "terrain.origin") : std::array<double, 3>{0, 0, 0};
    t.nx = r.nx;
    t.ny = r.ny;
    t.x0 = r.x0 - o[0];
    t.y0 = r.y0 - o[1];
    t.spacing = r.spacing;
    t.heights = std::move(r.heights);
    for (double& z : t.heights) z -= o[2];
  } else {
    checkKeys(j, "terrain", terrainHeightKeys());
    const ParameterSpec &nxSpec = sceneParameter("terrain.nx"), &nySpec = sceneParameter("terrain.ny");
    const double nx = readNumber(j, "terrain", nxSpec), ny = readNumber(j, "terrain", nySpec);
    if (nx != std::floor(nx)) throwParameter("terrain.nx", nx, "", rangeText(nxSpec));
    if (ny != std::floor(ny)) throwParameter("terrain.ny", ny, "", rangeText(nySpec));
    t.nx = static_cast<int>(nx);
    t.ny = static_cast<int>(ny);
    t.x0 = readNumber(j, "terrain", sceneParameter("terrain.x0"));
    t.y0 = readNumber(j, "terrain", sceneParameter("terrain.y0"));
    t.spacing = readNumber(j, "terrain", sceneParameter("terrain.spacing"));
    if (!j.contains("heights") || !j.at("heights").is_array())
      throw ParameterError("terrain.heights: required, an array of nx * ny heights [m] (heights[i * ny + j])");
    const json& h = j.at("heights");
    if (double(h.size()) != nx * ny)
      throwParameter("terrain.heights", std::to_string(h.size()) + " values", "", "nx * ny = " + std::to_string(t.nx) +
                     " x " + std::to_string(t.ny) + " values");
    t.heights.reserve(h.size());
    for (std::size_t k = 0; k < h.size(); ++k) t.heights.push_back(number(h[k], "terrain.heights[" + std::to_string(k) + "]"));
  }
  const ParameterSpec& friction = sceneParameter("terrain.friction");
  t.friction = j.contains("friction") ? parseFriction(j.at("friction"), "terrain.friction", friction) : 0;
  t.validate();  // before the seeding reads it
}

void parseMaterial(const json& root, MpmParams& p) {
  const json& m = requireObject(root, "", "material");
  checkKeys(m, "material", keysOf("material"));
  GranularMaterial& g = p.material;
  const auto read = [&m](const char* key) { return readNumber(m, "material", sceneParameter(key)); };
  g.density = read("material.density");
  g.youngModulus = read("material.young_modulus");
  g.poissonRatio = read("material.poisson_ratio");
  g.muS = read("material.mu_s");
  const ParameterSpec& mu2 = sceneParameter("material.mu_2");
  g.mu2 = readNumberIn(m, "material", mu2, g.muS, mu2.hi);
  g.I0 = read("material.I0");
  g.grainDiameter = read("material.grain_diameter");
  g.solidDensity = read("material.solid_density");
  g.criticalDensity = read("material.critical_density");
}

// Number of whole cells between two grid-line coordinates on axis `a`; throws unless both
// lie on grid lines (origin + k dx) and hi > lo.
std::size_t cellSpan(const MpmParams& p, int a, double lo, double hi, const std::string& path) {
  static const char axis[3] = {'x', 'y', 'z'};
  const double values[2] = {lo, hi};
  const char* names[2] = {".lo[", ".hi["};
  long idx[2];
  for (int e = 0; e < 2; ++e) {
    const double k = (values[e] - p.origin[a]) / p.dx;
    idx[e] = std::lround(k);
    if (std::fabs(k - static_cast<double>(idx[e])) > 1e-6) {
      std::ostringstream range;
      range << "on a grid line origin + k dx (origin[" << a << "] = " << p.origin[a] << " m, dx = " << p.dx
            << " m) on " << axis[a];
      throwParameter(path + names[e] + std::to_string(a) + "]", values[e], "m", range.str());
    }
  }
  return static_cast<std::size_t>(idx[1] - idx[0]);
}

// "ppc": a cube n^3 or [nx, ny, nz].
std::array<int, 3> parsePpc(const json& c, const std::string& path) {
  std::array<int, 3> ppc{};
  if (c.is_number_integer()) {
    const long n = c.get<long>();
    const long k = std::lround(std::cbrt(static_cast<double>(n)));
    if (n < 1 || k * k * k != n || k > 8)
      throwParameter(path + ".ppc", n, "", "a cube n^3 with n in [1, 8] (1, 8, 27, ..., 512) or [nx, ny, nz]");
    ppc = {int(k), int(k), int(k)};
  } else if (c.is_array() && c.size() == 3) {
    for (int a = 0; a < 3; ++a) {
      const std::string name = path + ".ppc[" + std::to_string(a) + "]";
      if (!c[a].is_number_integer() || c[a].get<long>() < 1 || c[a].get<long>() > 8)
        throwParameter(name, c[a].dump(), "", "an integer in [1, 8]");
      ppc[a] = c[a].get<int>();
    }
  } else {
    throwParameter(path + ".ppc", c.dump(), "", "a cube n^3 (1, 8, 27, ...) or [nx, ny, nz]");
  }
  return ppc;
}

// Box corners lo/hi: on grid lines, hi > lo, inside the material region. Over a terrain that
// lies inside the region everywhere, a box may reach down into the ground below the region: its
// points there would be under the terrain, so it is cut at the region's floor.
void parseBoxCorners(const json& j, const std::string& path, const MpmParams& p, ParticleBox& box) {
  const auto lo = materialRegionLo(p), hi = materialRegionHi(p);
  const double tol = 1e-9 * p.dx;
  if (!j.contains("lo")) throw ParameterError("missing required key '" + path + ".lo' (or '" + path + ".mesh')");
  if (!j.contains("hi")) throw ParameterError("missing required key '" + path + ".hi'");
  box.lo = vec3(j.at("lo"), path + ".lo");
  box.hi = vec3(j.at("hi"), path + ".hi");
  const std::vector<double>& ground = p.terrain.heights;
  if (!ground.empty() && *std::min_element(ground.begin(), ground.end()) >= lo[2] && box.hi[2] > lo[2])
    box.lo[2] = std::max(box.lo[2], lo[2]);
  static const char axis[3] = {'x', 'y', 'z'};
  for (int a = 0; a < 3; ++a) {
    const std::string ax(1, axis[a]);
    if (!(box.hi[a] > box.lo[a])) {
      std::ostringstream range;
      range << "> " << path << ".lo[" << a << "] = " << box.lo[a] << " m";
      throwParameter(path + ".hi[" + std::to_string(a) + "]", box.hi[a], "m", range.str());
    }
    if (box.lo[a] < lo[a] - tol || box.hi[a] > hi[a] + tol) {
      std::ostringstream msg;
      msg << path << " (lo, hi on " << ax << ") = [" << box.lo[a] << ", " << box.hi[a]
          << "] m: particles outside the grid; must lie in the material region [" << lo[a] << ", " << hi[a]
          << "] m (grid box minus the " << kWallLayer << "-cell wall layers)";
      throw ParameterError(msg.str());
    }
    cellSpan(p, a, box.lo[a], box.hi[a], path);
  }
}

// Mesh file, scale and offset: read, place and check the mesh; lo/hi get its bounding box.
void parseMesh(const json& j, const std::string& path, const std::string& baseDir, const MpmParams& p,
               ParticleBox& box) {
  const json& m = j.at("mesh");
  if (!m.is_string() || m.get<std::string>().empty())
    throwParameter(path + ".mesh", m.dump(), "", "a non-empty path to a .stl or .obj file");
  const std::string given = m.get<std::string>();
  const std::filesystem::path file(given);
  box.mesh = (baseDir.empty() || file.is_absolute()) ? given : (std::filesystem::path(baseDir) / file).string();
  box.scale = readNumber(j, path, sceneParameter("particles[].scale"));
  if (j.contains("offset")) box.offset = vec3(j.at("offset"), path + ".offset");
  try {
    io::TriangleMesh mesh = io::readMesh(box.mesh, box.scale);
    for (Vec3& v : mesh.vertices) v += Vec3(box.offset[0], box.offset[1], box.offset[2]);
    const MeshBounds mb = checkSeedMesh(p, mesh.vertices, mesh.triangles, box.mesh);
    box.lo = mb.lo;
    box.hi = mb.hi;
    box.vertices = std::move(mesh.vertices);
    box.triangles = std::move(mesh.triangles);
  } catch (const ParameterError& e) {
    throw ParameterError(path + ".mesh: " + e.what());
  }
}

void parseParticles(const json& root, MpmScene& s, const std::string& baseDir) {
  if (!root.contains("particles")) throw ParameterError("missing required key 'particles'");
  const json& list = root.at("particles");
  // An empty array is a scene without flow: the coupled engine then moves its blocks alone.
  if (!list.is_array())
    throwParameter("particles", list.dump().substr(0, 80), "",
                   "an array (empty for no flow) of boxes " + braced(boxKeys()) + " or meshes " + braced(meshKeys()));
  const double tol = 1e-9 * s.params.dx;
  for (std::size_t b = 0; b < list.size(); ++b) {
    const std::string path = "particles[" + std::to_string(b) + "]";
    const json& j = list[b];
    if (!j.is_object())
      throwParameter(path, j.dump(), "", "a JSON object " + braced(boxKeys()) + " or " + braced(meshKeys()));
    const bool isMesh = j.contains("mesh");
    checkKeys(j, path, isMesh ? meshKeys() : boxKeys());
    ParticleBox box;
    if (j.contains("velocity")) box.velocity = vec3(j.at("velocity"), path + ".velocity");
    if (j.contains("ppc")) box.ppc = parsePpc(j.at("ppc"), path);
    if (isMesh)
      parseMesh(j, path, baseDir, s.params, box);
    else
      parseBoxCorners(j, path, s.params, box);
    for (std::size_t o = 0; o < s.boxes.size(); ++o) {
      const ParticleBox& q = s.boxes[o];
      bool overlap = true;
      for (int a = 0; a < 3; ++a) overlap = overlap && box.lo[a] < q.hi[a] - tol && q.lo[a] < box.hi[a] - tol;
      if (!overlap) continue;
      if (box.mesh.empty() && q.mesh.empty())
        throwParameter(path, "box overlapping particles[" + std::to_string(o) + "]", "",
                       "disjoint from the other boxes (overlap would double the mass)");
      std::ostringstream value;
      value << (box.mesh.empty() ? "box" : "mesh bounding box") << " [" << box.lo[0] << ", " << box.lo[1] << ", "
            << box.lo[2] << "] - [" << box.hi[0] << ", " << box.hi[1] << ", " << box.hi[2] << "] m overlapping particles["
            << o << "]" << (q.mesh.empty() ? "" : " (mesh '" + q.mesh + "')");
      throwParameter(path + (box.mesh.empty() ? "" : " (mesh '" + box.mesh + "')"), value.str(), "",
                     "disjoint from the other entries (a mesh is refused when its bounding box overlaps another "
                     "entry's box or mesh bounding box)");
    }
    s.boxes.push_back(std::move(box));
  }
}

void parseProbes(const json& root, MpmScene& s) {
  if (!root.contains("flow_probes")) return;
  const json& list = root.at("flow_probes");
  if (!list.is_array()) throwParameter("flow_probes", list.dump(), "", "a list of {x, half_width, bed_z, min_points, window}");
  const double lo = materialRegionLo(s.params)[0], hi = materialRegionHi(s.params)[0];
  for (std::size_t k = 0; k < list.size(); ++k) {
    const std::string path = "flow_probes[" + std::to_string(k) + "]";
    const json& j = list[k];
    if (!j.is_object()) throwParameter(path, j.dump(), "", "an object {x, half_width, bed_z, min_points, window}");
    checkKeys(j, path, keysOf("flow_probes[]"));
    FlowProbeSpec p;
    p.x = readNumberIn(j, path, sceneParameter("flow_probes[].x"), lo, hi);
    p.halfWidth = readNumber(j, path, sceneParameter("flow_probes[].half_width"), s.params.dx);
    p.bedZ = readNumber(j, path, sceneParameter("flow_probes[].bed_z"));
    if (j.contains("min_points"))
      p.minPoints = static_cast<int>(
          integer(j.at("min_points"), path + ".min_points", sceneParameter("flow_probes[].min_points")));
    p.window = readNumber(j, path, sceneParameter("flow_probes[].window"));
    s.probes.push_back(p);
  }
}

void parseRun(const json& root, RunSettings& r) {
  const json& j = requireObject(root, "", "run");
  checkKeys(j, "run", keysOf("run"));
  r.duration = readNumber(j, "run", sceneParameter("run.duration"));
  if (j.contains("dt")) {
    const json& d = j.at("dt");
    if (d.is_string() && d.get<std::string>() == "auto") {
      r.dt = 0;
    } else if (d.is_number()) {
      r.dt = d.get<double>();
      checkParameter(sceneParameter("run.dt"), "run.dt", r.dt, 0, r.duration);
    } else {
      throwParameter("run.dt", d.dump(), "", rangeText(sceneParameter("run.dt")));
    }
  }
  r.dtFactor = readNumber(j, "run", sceneParameter("run.dt_factor"));
  r.minStepFraction = readNumber(j, "run", sceneParameter("run.min_step_fraction"));
  if (j.contains("max_block_speed")) r.maxBlockSpeed = readNumber(j, "run", sceneParameter("run.max_block_speed"), 0);
  r.progressEvery = readNumber(j, "run", sceneParameter("run.progress_every"));
  r.stopWhenProbed = readBool(j, "run", sceneParameter("run.stop_when_probed"), r.stopWhenProbed);
  r.stopWhenFrontStill = readNumber(j, "run", sceneParameter("run.stop_when_front_still"));
  if (j.contains("snapshot_when_front_at")) {
    const json& at = j.at("snapshot_when_front_at");
    r.snapshotsIndexed = at.is_array();
    if (r.snapshotsIndexed && at.empty())
      throwParameter("run.snapshot_when_front_at", "[]", "", "a number or a non-empty list of ascending numbers [m]");
    for (std::size_t k = 0; k < (r.snapshotsIndexed ? at.size() : 1); ++k) {
      const std::string name = "run.snapshot_when_front_at" + (r.snapshotsIndexed ? "[" + std::to_string(k) + "]" : "");
      const json& x = r.snapshotsIndexed ? at.at(k) : at;
      if (!x.is_number()) throwParameter(name, x.dump(), "", "a number [m]");
      const double v = x.get<double>();
      const ParameterSpec& front = sceneParameter("run.snapshot_when_front_at");
      const double after = r.snapshotsWhenFrontAt.empty() ? front.lo : r.snapshotsWhenFrontAt.back();
      checkParameter(front, name, v, after, front.hi);
      r.snapshotsWhenFrontAt.push_back(v);
    }
  }
  r.outputEvery = readNumber(j, "run", sceneParameter("run.output_every"), r.duration / 20);
  r.seriesEvery = readNumber(j, "run", sceneParameter("run.series_every"), r.outputEvery / 10);
  if (j.contains("output_dir")) {
    const json& d = j.at("output_dir");
    if (!d.is_string() || d.get<std::string>().empty())
      throwParameter("run.output_dir", d.dump(), "", rangeText(sceneParameter("run.output_dir")));
    r.outputDir = d.get<std::string>();
  }
  r.vtk = readChoice(j, "run", sceneParameter("run.vtk"));
  r.backend = readChoice(j, "run", sceneParameter("run.backend")) == "cuda" ? Backend::Cuda : Backend::Cpu;
  r.precision = readChoice(j, "run", sceneParameter("run.precision")) == "float" ? Precision::Float : Precision::Double;
}

}  // namespace

std::array<double, 3> materialRegionLo(const MpmParams& p) {
  std::array<double, 3> lo{};
  for (int a = 0; a < 3; ++a) lo[a] = p.origin[a] + kWallLayer * p.dx;
  return lo;
}

std::array<double, 3> materialRegionHi(const MpmParams& p) {
  std::array<double, 3> hi{};
  for (int a = 0; a < 3; ++a) hi[a] = p.origin[a] + (p.cells[a] - kWallLayer) * p.dx;
  return hi;
}

MpmScene parseScene(const std::string& jsonText, const std::string& source, const std::string& baseDir) {
  const json root = scenejson::parse(jsonText, source);
  if (!root.is_object()) throw ParameterError(source + ": the scene must be a JSON object");
  // "blocks", "block_materials" and "terrain_material" are read by coupling::parseBlocks (a
  // coupled scene)
  std::vector<std::string> keys = keysOf("");
  keys.insert(keys.end(), {"blocks", "block_materials", "terrain_material"});
  checkKeys(root, "", keys);
  if (root.contains("description") && !root.at("description").is_string())
    throwParameter("description", root.at("description").dump(), "", rangeText(sceneParameter("description")));
  MpmScene s;
  parseGrid(root, s.params);
  parseGravity(root, s.params);
  s.params.flip = parseFlipBlend(root);
  s.params.cfl = readNumber(root, "", sceneParameter("cfl"));
  s.params.keepLastGoodState = readBool(root, "", sceneParameter("keep_last_good_state"), s.params.keepLastGoodState);
  parseWalls(root, s.params);
  parseGate(root, s.params);
  parseTerrain(root, s.params, baseDir);
  parseMaterial(root, s.params);
  parseParticles(root, s, baseDir);
  parseProbes(root, s);
  parseRun(root, s.run);
  if (s.run.stopWhenProbed && s.probes.empty())
    throwParameter("run.stop_when_probed", "true", "", "false in a scene without flow_probes (nothing to wait for)");
  if (s.run.maxBlockSpeed == 0) s.run.maxBlockSpeed = 10 * pWaveSpeed(s.params.material);
  s.sourceJson = root.dump();
  return s;
}

MpmScene loadScene(const std::string& path) {
  // A device or a pipe (e.g. /dev/zero) would be read forever: only regular files, and of a
  // size no scene reaches (meshes live in their own files).
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throwParameter("scene file", "'" + path + "'", "", "an existing, readable regular JSON file");
  const auto size = std::filesystem::file_size(path, ec);
  if (!ec && size > kMaxSceneBytes)
    throwParameter("scene file", "'" + path + "' (" + std::to_string(size) + " bytes)", "",
                   "a JSON file of at most " + std::to_string(kMaxSceneBytes) + " bytes");
  std::ifstream is(path);
  if (!is) throwParameter("scene file", "'" + path + "'", "", "an existing, readable JSON file");
  std::stringstream ss;
  ss << is.rdbuf();
  return parseScene(ss.str(), path, std::filesystem::path(path).parent_path().string());
}

std::string sceneSizeDescription(const MpmScene& scene) {
  const auto& c = scene.params.cells;
  const double nodes = double(c[0] + 1) * double(c[1] + 1) * double(c[2] + 1);
  double particles = 0;  // boxes exactly; meshes by their bounding box (an upper bound)
  for (const ParticleBox& b : scene.boxes) {
    double n = 1;
    for (int a = 0; a < 3; ++a) n *= std::round((b.hi[a] - b.lo[a]) / scene.params.dx) * b.ppc[a];
    particles += n;
  }
  std::ostringstream os;
  // 8 values per node (mass, old and new velocity, a pad) and ~20 per particle in double, twice
  // (the solver keeps the state at the start of a step)
  os << "grid.cells = [" << c[0] << ", " << c[1] << ", " << c[2] << "] (" << nodes << " nodes, about "
     << nodes * 8 * 8 / 1e9 << " GB as the dense grid CUDA holds; the CPU backend holds the node columns the flow "
     << "reaches) and about " << particles << " particles (about " << particles * 2 * 20 * 8 / 1e9 << " GB)";
  return os.str();
}

namespace {

// With a terrain, a region's points below its surface are not seeded: a box reaching into the
// ground seeds the material above it.
class AboveTerrain : public SeedSink {
 public:
  AboveTerrain(const TerrainSpec& t, SeedSink& out) : view_(terrainViewOf(t, t.heights.data())), out_(out) {}
  void add(const double x[3], double mass, double volume0, const std::array<double, 3>& velocity) override {
    double gx, gy;
    if (x[2] >= terrainHeight(view_, x[0], x[1], gx, gy)) out_.add(x, mass, volume0, velocity);
  }

 private:
  TerrainView<double> view_;
  SeedSink& out_;
};

void seedScene(const MpmScene& scene, SeedSink& sink) {
  AboveTerrain above(scene.params.terrain, sink);
  SeedSink& to = scene.params.terrain.enabled() ? static_cast<SeedSink&>(above) : sink;
  for (const ParticleBox& b : scene.boxes) {
    if (!b.mesh.empty())
      seedMesh(scene.params, b.vertices, b.triangles, b.ppc, b.velocity, to, b.mesh);
    else
      seedBox(scene.params, b.lo, b.hi, b.ppc, b.velocity, to);
  }
}

}  // namespace

ParticleSet seedParticles(const MpmScene& scene) {
  ParticleSet p;
  ParticleSetSink sink(p);
  seedScene(scene, sink);
  return p;
}

SeededParticles seedParticleSlices(const MpmScene& scene) {
  SeededParticles p;
  seedScene(scene, p);
  p.shrink();
  return p;
}

const char* backendName(Backend backend) { return backend == Backend::Cuda ? "cuda" : "cpu"; }
const char* precisionName(Precision precision) { return precision == Precision::Float ? "float" : "double"; }

}  // namespace mpm
}  // namespace mpmsdem
