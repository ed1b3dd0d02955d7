// The contact material of a block, one entry per value (SdemMaterial's members): its key in
// a driver scene ("block_materials.<name>.friction"), its name in Python (mpmsdem.material's
// keyword), unit, default, range, the paper's equation. SdemMaterial::validate checks against
// these entries; coupling::blockParameter places them among the scene's block keys, and
// docs/parameters.md is generated from it.
#pragma once
#include "common/Parameters.hpp"

namespace mpmsdem {
namespace sdem {

ParameterTable listMaterialParameters();
inline constexpr ParameterCatalog<listMaterialParameters> materialParameter{};

}  // namespace sdem
}  // namespace mpmsdem
