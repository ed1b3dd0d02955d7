// The parameters of the flow's scene (pkg/scene/MpmScene.hpp), one entry each: what parseScene
// reads and checks, the Python API's names for them and docs/parameters.md. The flow model's
// entries are mpm::solverParameter (pkg/mpm, where makeSolver checks against them), the
// scene adds its own; the blocks' keys are coupling::blockParameter.
#pragma once
#include "common/Parameters.hpp"

namespace mpmsdem {
namespace mpm {

// In section order; an object or a list (grid, run, flow_probes) comes first as one entry at the
// top level, its keys then under it ("run.dt", "flow_probes[].x").
ParameterTable listSceneParameters();
inline constexpr ParameterCatalog<listSceneParameters> sceneParameter{};

}  // namespace mpm
}  // namespace mpmsdem
