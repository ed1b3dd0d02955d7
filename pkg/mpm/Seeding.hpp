// Seeding material points in a box region on a regular sub-lattice of the grid cells.
#pragma once
#include <array>

#include "mpm/MpmTypes.hpp"

namespace mpmsdem {
namespace mpm {

// Appends to `out` the material points of the box [lo, hi] (m): each grid cell (of spacing
// params.dx, aligned with params.origin) whose centre lies in the box receives perAxis[0] x
// perAxis[1] x perAxis[2] points at the centres of an equal subdivision of the cell (each
// perAxis in [1, 8]). Each point gets mass rho_0 dx^3 / n (n = product of perAxis, rho_0 =
// params.material.density), volume0 dx^3 / n, J = 1, zero velocity, stress and force,
// phase 0. Throws ParameterError when the box is empty, not inside the admissible particle
// box (the grid domain less its kWallLayer-cell wall layers), or perAxis is out of range.
// Returns the number of points added.
std::size_t seedBox(const MpmParams& params, const std::array<double, 3>& lo, const std::array<double, 3>& hi,
                    const std::array<int, 3>& perAxis, ParticleSet& out);

// Same with n points per cell, n a perfect cube (1, 8, 27, ...): n^(1/3) per axis.
std::size_t seedBox(const MpmParams& params, const std::array<double, 3>& lo, const std::array<double, 3>& hi,
                    int perCell, ParticleSet& out);

}  // namespace mpm
}  // namespace mpmsdem
