// The parameters of the flow's scene (pkg/scene/MpmScene.hpp), one entry each: what parseScene
// reads and checks, the Python API's names for them and docs/parameters.md. The flow model's
// entries are mpm::solverParameters() (pkg/mpm, where makeSolver checks against them), the
// scene adds its own; the blocks' keys are coupling::blockParameters().
#pragma once
#include "common/Parameters.hpp"

namespace mpmsdem {
namespace mpm {

// In section order; an object or a list (grid, run, flow_probes) comes first as one entry at the
// top level, its keys then under it ("run.dt", "flow_probes[].x").
const ParameterTable& sceneParameters();
// The entry of `key` (e.g. "material.mu_s") in sceneParameters().
const ParameterSpec& sceneParameter(const char* key);

}  // namespace mpm
}  // namespace mpmsdem
