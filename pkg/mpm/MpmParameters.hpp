// The parameters of the flow model, one entry each: the grid, gravity, the FLIP/PIC blend, the
// walls, the gate and the granular material. makeSolver checks an MpmParams against these
// entries (naming each value by its scene key), the scene parser reads them through the same
// entries (scene/SceneParameters adds the scene's own: particles, probes, terrain file, run),
// and docs/parameters.md is generated from both.
#pragma once
#include "common/Parameters.hpp"

namespace mpmsdem {
namespace mpm {

// Objects first (grid, gravity, walls, gate, material) as one entry each at the top level, with
// the blend's and the step's values; their keys then under them ("material.mu_s").
ParameterTable listSolverParameters();
inline constexpr ParameterCatalog<listSolverParameters> solverParameter{};

}  // namespace mpm
}  // namespace mpmsdem
