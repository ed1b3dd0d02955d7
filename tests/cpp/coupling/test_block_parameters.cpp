// The blocks' parameter table: the scene reader refuses a value out of an entry's range naming
// the key and the table's range, applies its defaults, and SdemMaterial::validate refuses a
// material made in Python with the same entries' ranges (sdem/SdemParameters).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <string>

#include "common/Error.hpp"
#include "coupling/BlockParameters.hpp"
#include "coupling/CoupledScene.hpp"

using namespace mpmsdem;
using namespace mpmsdem::coupling;
using nlohmann::json;

namespace {

json sceneWith(const json& material) {
  return {{"block_materials", {{"wood", material}}},
          {"blocks", {{{"material", "wood"}, {"box", {0.02, 0.02, 0.02}}, {"sweep_radius", 0.003},
                       {"position", {0.1, 0.05, 0.04}}}}}};
}

// A value beyond a finite hi, else below lo.
double outside(const ParameterSpec& s) {
  return std::isinf(s.hi) ? s.lo - 1 : (s.hiInclusive ? s.hi + 0.5 : s.hi);
}

std::string refusal(const json& scene) {
  try {
    parseBlocks(scene.dump());
  } catch (const ParameterError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(BlockParameters, DefaultsAreTheReaders) {
  const SceneBlocks s = parseBlocks(sceneWith({{"density", 500}, {"flow", {{"friction", 0.2}}}}).dump());
  const auto def = [](const char* key) { return blockParameter(key).defaultValue; };
  const sdem::SdemMaterial& m = s.materials.at(0).material;
  EXPECT_EQ(m.friction, def("block_materials.<name>.friction"));
  EXPECT_EQ(m.poisson, def("block_materials.<name>.poisson"));
  EXPECT_EQ(m.barrierStiffness, def("block_materials.<name>.barrier_stiffness"));
  EXPECT_EQ(m.normalDamping, def("block_materials.<name>.normal_damping"));
  EXPECT_EQ(m.tangentialDamping, def("block_materials.<name>.tangential_damping"));
  const sdem::BarrierPhys& f = s.materials.at(0).flow;
  EXPECT_EQ(f.barrierStiffness, def("block_materials.<name>.flow.barrier_stiffness"));
  EXPECT_EQ(f.poisson, def("block_materials.<name>.flow.poisson"));
  EXPECT_EQ(f.normalDamping, def("block_materials.<name>.flow.normal_damping"));
  EXPECT_EQ(f.tangentialDamping, def("block_materials.<name>.flow.tangential_damping"));
  EXPECT_EQ(def("block_materials.<name>.barrier_stiffness"), 1e4);  // the paper's k_c (Tables 1 and 2)
}

TEST(BlockParameters, RangesAreTheReadersAndTheMaterials) {
  for (const char* leaf : {"density", "friction", "poisson", "barrier_stiffness", "normal_damping",
                           "tangential_damping"}) {
    const std::string key = std::string("block_materials.<name>.") + leaf;
    const ParameterSpec& spec = blockParameter(key.c_str());
    SCOPED_TRACE(key);
    json material = {{"density", 500}, {"flow", {{"friction", 0.2}}}};
    material[leaf] = outside(spec);
    const std::string what = refusal(sceneWith(material));
    EXPECT_NE(what.find(std::string("block_materials.wood.") + leaf + " = "), std::string::npos) << what;
    EXPECT_NE(what.find("must be " + rangeText(spec)), std::string::npos) << what;
    // the same value is refused by the material's own check (a material made in Python)
    json values = {{"density", 500}, {"friction", 0.5}, {"poisson", 0.3}, {"barrier_stiffness", 1e4},
                   {"normal_damping", 0}, {"tangential_damping", 0.1}};
    values[leaf] = outside(spec);
    sdem::SdemMaterial m;
    m.density = values["density"];
    m.friction = values["friction"];
    m.poisson = values["poisson"];
    m.barrierStiffness = values["barrier_stiffness"];
    m.normalDamping = values["normal_damping"];
    m.tangentialDamping = values["tangential_damping"];
    // in the same words, the value named as Python names it (sdem/SdemParameters holds both)
    std::string own;
    try {
      m.validate();
    } catch (const ParameterError& e) {
      own = e.what();
    }
    EXPECT_EQ(own.rfind(std::string(spec.python) + " = ", 0), 0u) << own;
    EXPECT_NE(own.find("must be " + rangeText(spec)), std::string::npos) << own;
  }
  json pair = {{"density", 500}, {"flow", {{"friction", 0.2}, {"poisson", 0.5}}}};
  const std::string what = refusal(sceneWith(pair));
  EXPECT_NE(what.find("block_materials.wood.flow.poisson = 0.5: must be in (-1, 0.5)"), std::string::npos) << what;
}
