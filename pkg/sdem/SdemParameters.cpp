#include "sdem/SdemParameters.hpp"

#include <cmath>

#include "sdem/SdemMaterial.hpp"

namespace mpmsdem {
namespace sdem {

// The defaults are SdemMaterial's: the table names them, the struct holds them.
ParameterTable listMaterialParameters() {
  using namespace parameter_entries;
  const SdemMaterial m{};
  // key, python, kind, unit, default, default in words, lo, hi, lo and hi allowed, range in
  // words, equation, meaning
  return {
      {"block_materials.<name>.density", "density", K::kNumber, "kg/m^3", kNone, kRequired, 0, kInf, false, false,
       "", "", "block density; mass = density x rounded volume (not needed in terrain_material)"},
      {"block_materials.<name>.friction", "friction", K::kNumber, "", m.friction, "", 0, kInf, true, false, "", "Eq 9",
       "block-block Coulomb friction coefficient"},
      {"block_materials.<name>.poisson", "poisson", K::kNumber, "", m.poisson, "", -1, 0.5, false, false, "", "Eq 11",
       "nu of the tangential stiffness K_t = k_n / (2 (1 + nu))"},
      {"block_materials.<name>.barrier_stiffness", "barrierStiffness", K::kNumber, "N/m", m.barrierStiffness, "", 0,
       kInf, false, false, "", "Eq 10", "k_c of the log-barrier normal law (read as a force)"},
      {"block_materials.<name>.normal_damping", "normalDamping", K::kNumber, "", m.normalDamping, "", 0, kInf, true,
       false, "", "", "normal viscous damping, a fraction of critical (0: an elastic barrier)"},
      {"block_materials.<name>.tangential_damping", "tangentialDamping", K::kNumber, "", m.tangentialDamping, "", 0,
       kInf, true, false, "", "Eq 9", "tangential viscous damping, a fraction of critical"},
  };
}

// A material made in C++ or Python is named by its Python keywords ("barrierStiffness"), a
// scene's by its keys (the scene reader checks those first).
void SdemMaterial::validate() const {
  const auto check = [](const char* key, double value) {
    const ParameterSpec& spec = materialParameter(key);
    checkParameter(spec, spec.python, value, spec.lo, spec.hi);
  };
  check("block_materials.<name>.density", density);
  check("block_materials.<name>.friction", friction);
  check("block_materials.<name>.poisson", poisson);
  check("block_materials.<name>.barrier_stiffness", barrierStiffness);
  check("block_materials.<name>.normal_damping", normalDamping);
  check("block_materials.<name>.tangential_damping", tangentialDamping);
}

}  // namespace sdem
}  // namespace mpmsdem
