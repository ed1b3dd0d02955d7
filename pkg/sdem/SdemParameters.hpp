// The contact material of a block, one entry per value (SdemMaterial's members): its key in
// a driver scene ("block_materials.<name>.friction"), its name in Python (mpmsdem.material's
// keyword), unit, default, range, the paper's equation. SdemMaterial::validate checks against
// these entries; coupling::blockParameters() places them among the scene's block keys, and
// docs/parameters.md is generated from it.
#pragma once
#include "common/Parameters.hpp"

namespace mpmsdem {
namespace sdem {

const ParameterTable& materialParameters();
// The entry of `key` (e.g. "block_materials.<name>.friction") in materialParameters().
const ParameterSpec& materialParameter(const char* key);

}  // namespace sdem
}  // namespace mpmsdem
