// The parameters of a coupled scene's blocks (pkg/coupling/CoupledScene.hpp), one entry each:
// what parseBlocks reads and checks, the Python API's names for them and docs/parameters.md.
// The flow's keys are mpm::sceneParameter.
#pragma once
#include "common/Parameters.hpp"

namespace mpmsdem {
namespace coupling {

// The top-level keys first (blocks, block_materials, terrain_material), then a block material's
// ("block_materials.<name>.density"; terrain_material takes them but flow), its flow pair's
// ("block_materials.<name>.flow.friction") and a block's ("blocks[].sweep_radius").
ParameterTable listBlockParameters();
inline constexpr ParameterCatalog<listBlockParameters> blockParameter{};

}  // namespace coupling
}  // namespace mpmsdem
