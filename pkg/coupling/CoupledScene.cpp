#include "coupling/CoupledScene.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "common/Error.hpp"
#include "common/SceneJson.hpp"
#include "coupling/BlockParameters.hpp"

namespace mpmsdem {
namespace coupling {

namespace {

using namespace scenejson;

Vec3 toVec(const std::array<double, 3>& a) { return Vec3(a[0], a[1], a[2]); }

Vec3 optVec(const json& obj, const std::string& path, const char* key, const Vec3& def) {
  if (!obj.contains(key)) return def;
  const Vec3 v = toVec(vec3(obj.at(key), join(path, key)));
  if (!v.allFinite()) throwParameter(join(path, key), obj.at(key).dump(), "", "finite numbers");
  return v;
}

void readPhys(const json& j, const std::string& path, sdem::BarrierPhys& p) {
  checkKeys(j, path, sectionKeys(blockParameter.table(), "block_materials.<name>.flow"));
  const auto read = [&](const char* key) { return readNumber(j, path, blockParameter(key)); };
  p.friction = read("block_materials.<name>.flow.friction");
  p.barrierStiffness = read("block_materials.<name>.flow.barrier_stiffness");
  p.poisson = read("block_materials.<name>.flow.poisson");
  p.normalDamping = read("block_materials.<name>.flow.normal_damping");
  p.tangentialDamping = read("block_materials.<name>.flow.tangential_damping");
}

// withFlow: a block material (its "flow" pair required); else the terrain's (no flow key, no
// density needed: the ground does not move).
BlockMaterialSpec readMaterial(const json& j, const std::string& path, const std::string& name, bool withFlow = true) {
  if (!j.is_object()) throwParameter(path, j.dump(), "", "a JSON object");
  std::vector<std::string> keys = sectionKeys(blockParameter.table(), "block_materials.<name>");
  if (!withFlow) keys.erase(std::find(keys.begin(), keys.end(), "flow"));
  checkKeys(j, path, keys);
  BlockMaterialSpec m;
  m.name = name;
  sdem::SdemMaterial& s = m.material;
  const auto read = [&](const char* key) { return readNumber(j, path, blockParameter(key)); };
  const ParameterSpec& density = blockParameter("block_materials.<name>.density");
  s.density = withFlow ? readNumber(j, path, density) : readNumber(j, path, density, s.density);
  s.friction = read("block_materials.<name>.friction");
  s.poisson = read("block_materials.<name>.poisson");
  s.barrierStiffness = read("block_materials.<name>.barrier_stiffness");
  s.normalDamping = read("block_materials.<name>.normal_damping");
  s.tangentialDamping = read("block_materials.<name>.tangential_damping");
  if (withFlow) readPhys(requireObject(j, path, "flow"), join(path, "flow"), m.flow);
  return m;
}

std::vector<Vec3> points(const json& v, const std::string& name) {
  if (!v.is_array()) throwParameter(name, v.dump().substr(0, 80), "", "an array of [x, y, z] points");
  std::vector<Vec3> out;
  for (std::size_t i = 0; i < v.size(); ++i) out.push_back(toVec(vec3(v[i], name + "[" + std::to_string(i) + "]")));
  return out;
}

std::vector<int> indices(const json& v, const std::string& name) {
  if (!v.is_array()) throwParameter(name, v.dump().substr(0, 80), "", "an array of vertex indices");
  std::vector<int> out;
  for (std::size_t i = 0; i < v.size(); ++i) {
    const std::string n = name + "[" + std::to_string(i) + "]";
    // An index beyond int would wrap into another vertex (2^32 + 1 is vertex 1): refused here,
    // the shape factories check the rest of the range.
    const bool inRange = v[i].is_number_unsigned() ? v[i].get<unsigned long long>() <= 2147483647ull
                                                   : v[i].is_number_integer() && v[i].get<long long>() >= -2147483648LL &&
                                                         v[i].get<long long>() <= 2147483647LL;
    if (!inRange) throwParameter(n, v[i].dump(), "", "an integer vertex index");
    out.push_back(v[i].get<int>());
  }
  return out;
}

std::shared_ptr<const sdem::SpheroPolyhedron> readShape(const json& b, const std::string& path) {
  const bool isBox = b.contains("box"), isCore = b.contains("core");
  if (isBox == isCore) throw ParameterError(path + ": give exactly one of \"box\" or \"core\" (the block's shape)");
  if (isBox && b.contains("outer"))
    throw ParameterError(path + ".outer: only with \"core\" (a box is displayed as itself)");
  const double R = requireNumber(b, path, "sweep_radius");
  try {
    if (isBox) return sdem::SpheroPolyhedron::box(toVec(vec3(b.at("box"), join(path, "box"))), R);
    const std::string cp = join(path, "core");
    const json& c = requireObject(b, path, "core");
    checkKeys(c, cp, {"vertices", "faces", "convex"});
    if (!c.contains("vertices") || !c.contains("faces"))
      throw ParameterError(cp + ": needs \"vertices\" and \"faces\"");
    const std::vector<Vec3> verts = points(c.at("vertices"), join(cp, "vertices"));
    const json& f = c.at("faces");
    if (!f.is_array()) throwParameter(join(cp, "faces"), f.dump().substr(0, 80), "", "an array of vertex loops");
    std::vector<std::vector<int>> faces;
    for (std::size_t i = 0; i < f.size(); ++i) faces.push_back(indices(f[i], join(cp, "faces") + "[" + std::to_string(i) + "]"));
    bool convex = true;
    if (c.contains("convex")) {
      if (!c.at("convex").is_boolean()) throwParameter(join(cp, "convex"), c.at("convex").dump(), "", "true or false");
      convex = c.at("convex").get<bool>();
    }
    std::vector<Vec3> outerV;
    std::vector<std::array<int, 3>> outerT;
    if (b.contains("outer")) {
      const std::string op = join(path, "outer");
      const json& o = requireObject(b, path, "outer");
      checkKeys(o, op, {"vertices", "triangles"});
      if (!o.contains("vertices") || !o.contains("triangles"))
        throw ParameterError(op + ": needs \"vertices\" and \"triangles\"");
      outerV = points(o.at("vertices"), join(op, "vertices"));
      const json& t = o.at("triangles");
      if (!t.is_array()) throwParameter(join(op, "triangles"), t.dump().substr(0, 80), "", "an array of triangles");
      for (std::size_t i = 0; i < t.size(); ++i) {
        const std::string n = join(op, "triangles") + "[" + std::to_string(i) + "]";
        const std::vector<int> tri = indices(t[i], n);
        if (tri.size() != 3) throwParameter(n, t[i].dump(), "", "3 vertex indices");
        outerT.push_back({tri[0], tri[1], tri[2]});
      }
    }
    return sdem::SpheroPolyhedron::fromCore(verts, faces, R, convex, outerV, outerT);
  } catch (const ParameterError& e) {
    const std::string msg = e.what();
    if (msg.rfind(path, 0) == 0) throw;
    // the factories name their own parameters (sweepRadius, core.faces[3], ...): say which block
    throw ParameterError(path + ": " + msg);
  }
}

// The corners of the MPM grid box [m].
void gridBox(const mpm::MpmParams& p, Vec3& lo, Vec3& hi) {
  for (int d = 0; d < 3; ++d) {
    lo[d] = p.origin[d];
    hi[d] = p.origin[d] + p.cells[d] * p.dx;
  }
}

}  // namespace

SceneBlocks parseBlocks(const std::string& sceneJson) {
  const json root = scenejson::parse(sceneJson, "scene");
  SceneBlocks out;
  if (!root.contains("blocks")) {
    if (root.contains("block_materials"))
      throw ParameterError("block_materials without blocks: add \"blocks\" or remove \"block_materials\"");
    return out;
  }
  const json& list = root.at("blocks");
  if (!list.is_array()) throwParameter("blocks", list.dump().substr(0, 80), "", "a list of blocks");
  if (list.empty()) return out;
  const json& mats = requireObject(root, "", "block_materials");
  std::map<std::string, int> matIndex;
  for (auto it = mats.begin(); it != mats.end(); ++it) {
    matIndex[it.key()] = static_cast<int>(out.materials.size());
    out.materials.push_back(readMaterial(it.value(), join("block_materials", it.key()), it.key()));
  }
  std::set<int> ids;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string path = "blocks[" + std::to_string(i) + "]";
    const json& b = list[i];
    if (!b.is_object()) throwParameter(path, b.dump().substr(0, 80), "", "a JSON object");
    checkKeys(b, path, sectionKeys(blockParameter.table(), "blocks[]"));
    BlockSpec s;
    if (!b.contains("material") || !b.at("material").is_string())
      throw ParameterError(path + ".material: required, the name of one of block_materials");
    const std::string mat = b.at("material").get<std::string>();
    if (!matIndex.count(mat)) {
      std::string names;
      for (const auto& kv : matIndex) names += (names.empty() ? "\"" : ", \"") + kv.first + "\"";
      throwParameter(join(path, "material"), "\"" + mat + "\"", "", "one of block_materials: " + names);
    }
    s.material = matIndex.at(mat);
    s.shape = readShape(b, path);
    if (!b.contains("position")) throw ParameterError("missing required key '" + join(path, "position") + "'");
    s.position = optVec(b, path, "position", Vec3::Zero());
    if (b.contains("orientation")) {
      const json& q = b.at("orientation");
      if (!q.is_array() || q.size() != 4) throwParameter(join(path, "orientation"), q.dump(), "", "[w, x, y, z]");
      double c[4];
      for (int k = 0; k < 4; ++k) c[k] = number(q[k], join(path, "orientation") + "[" + std::to_string(k) + "]");
      s.orientation = Quat(c[0], c[1], c[2], c[3]);
      if (!(std::abs(s.orientation.norm() - 1) < 1e-6))
        throwParameter(join(path, "orientation"), q.dump(), "", "a unit quaternion [w, x, y, z] (norm 1 within 1e-6)");
      s.orientation.normalize();
    }
    s.velocity = optVec(b, path, "velocity", Vec3::Zero());
    s.angularVelocity = optVec(b, path, "angular_velocity", Vec3::Zero());
    s.fixed = readBool(b, path, blockParameter("blocks[].fixed"), s.fixed);
    if (b.contains("blocked_dofs")) {
      const json& d = b.at("blocked_dofs");
      const std::string letters = "xyzXYZ";
      if (!d.is_string() || d.get<std::string>().find_first_not_of(letters) != std::string::npos)
        throwParameter(join(path, "blocked_dofs"), d.dump(), "", rangeText(blockParameter("blocks[].blocked_dofs")));
      s.blockedDofs = d.get<std::string>();
    }
    s.id = b.contains("id") ? static_cast<int>(integer(b.at("id"), join(path, "id"), blockParameter("blocks[].id")))
                            : static_cast<int>(i);
    if (!ids.insert(s.id).second) throwParameter(join(path, "id"), s.id, "", "unique among the blocks");
    out.blocks.push_back(s);
  }
  if (root.contains("terrain_material")) {
    if (!root.contains("terrain"))
      throw ParameterError("terrain_material without terrain: add the flow's \"terrain\" or remove \"terrain_material\"");
    out.terrainMaterial.reset(new sdem::SdemMaterial(
        readMaterial(root.at("terrain_material"), "terrain_material", "terrain", false).material));
  } else if (root.contains("terrain")) {
    for (const BlockSpec& b : out.blocks)
      if (!b.fixed)
        throw ParameterError("terrain_material: required in a scene with a terrain and moving blocks (the blocks' "
                             "contact with the ground: friction, barrier_stiffness, poisson, normal_damping, "
                             "tangential_damping), else they fall through it");
  }
  return out;
}

void checkBlockSpeed(const sdem::SdemEngine& engine, int i, double maxSpeed, const std::string& name,
                     const std::string& key) {
  const double speed = engine.pointSpeedBound(i);
  if (speed <= maxSpeed) return;
  std::ostringstream m;
  m << name << ": speed " << speed << " m/s (|velocity| + |angular_velocity| x bounding radius "
    << engine.shape(i).boundingRadius
    << " m) exceeds " << key << " = " << maxSpeed
    << " m/s (default: ten times the flow's P-wave speed): no flow or wave of the scene reaches it, and the step "
       "that follows it (the block moves its sweep radius in ten steps) would crawl. Give a physical velocity, or "
       "raise "
    << key;
  throw ParameterError(m.str());
}

double distanceFromGrid(const sdem::SdemEngine& engine, int i, const mpm::MpmParams& p) {
  Vec3 lo, hi;
  gridBox(p, lo, hi);
  const Vec3 c = engine.position(i);
  return (lo - c).cwiseMax(c - hi).cwiseMax(Vec3::Zero()).norm() - engine.shape(i).boundingRadius;
}

std::string outsideGridMessage(const sdem::SdemEngine& engine, int i, const mpm::MpmParams& p) {
  const Vec3 c = engine.position(i);
  Vec3 lo, hi;
  gridBox(p, lo, hi);
  std::ostringstream m;
  m << "can never touch the flow: its rounded body (centre [" << c.x() << ", " << c.y() << ", " << c.z()
    << "] m, bounding radius " << engine.shape(i).boundingRadius << " m) lies wholly outside the MPM grid";
  for (int d = 0; d < 3; ++d) m << (d ? " x [" : " [") << lo[d] << ", " << hi[d] << "]";
  m << " m";
  return m.str();
}

std::vector<std::string> checkBlockStates(const SceneBlocks& scene, CoupledWorld& world, double maxBlockSpeed) {
  const sdem::SdemEngine& engine = world.world.engine;
  const mpm::MpmParams& p = world.mpm().params();
  Vec3 lo, hi;
  gridBox(p, lo, hi);
  const double diagonal = (hi - lo).norm();
  std::vector<std::string> warnings;
  for (int i = 0; i < engine.numBodies(); ++i) {
    const std::string name = "blocks[" + std::to_string(i) + "] (id " + std::to_string(scene.blocks[i].id) + ")";
    checkBlockSpeed(engine, i, maxBlockSpeed, name, "run.max_block_speed");
    const double away = distanceFromGrid(engine, i, p);
    if (away > 100 * diagonal) {
      std::ostringstream m;
      m << name << ".position: its rounded body lies " << away << " m from the MPM grid box, more than 100 grid "
        << "diagonals (" << 100 * diagonal << " m): no scene places a block there (a unit mistake?)";
      throw ParameterError(m.str());
    }
    if (away > 0) warnings.push_back(name + " " + outsideGridMessage(engine, i, p));
  }
  return warnings;
}

void addBlocks(const SceneBlocks& scene, CoupledWorld& world) {
  sdem::SdemEngine& engine = world.world.engine;
  const auto& g = world.mpm().params().gravity;
  world.world.gravity = Vec3(g[0], g[1], g[2]);
  std::vector<int> matIndex;
  for (const BlockMaterialSpec& m : scene.materials) {
    matIndex.push_back(engine.addMaterial(m.material));
    world.coupling.setPair(matIndex.back(), m.flow);
  }
  for (const BlockSpec& b : scene.blocks) {
    const sdem::SpheroPolyhedron& s = *b.shape;
    const double rho = scene.materials[b.material].material.density;
    const int i = engine.addBody(b.shape, matIndex[b.material], rho * s.volume, rho * s.inertiaPerDensity, b.id);
    const Vec3 centroid = b.position + b.orientation * s.framePosition;
    const Quat ori = (b.orientation * s.frameOrientation).normalized();
    engine.setState(i, centroid, ori, b.velocity, b.angularVelocity);
    engine.setFixed(i, b.fixed);
    if (!b.blockedDofs.empty()) world.world.setBlockedDofs(i, b.blockedDofs);
  }
  if (scene.terrainMaterial) engine.setTerrain(world.mpm().params().terrain, engine.addMaterial(*scene.terrainMaterial));
}

}  // namespace coupling
}  // namespace mpmsdem
