// Parameters shared by the MPM tests that collapse a granular column.
#pragma once
#include <array>

#include "mpm/MpmTypes.hpp"

namespace mpmsdem {
namespace mpm {
namespace testing_scenes {

// A quasi-2D grid (cells[1] thin in y) with a rough base (wall friction 0.4) and free-slip
// walls elsewhere, holding Dunatunga & Kamrin's (2015) glass beads: mu_s = tan 20.9 deg,
// mu_2 = tan 32.76 deg, I_0 0.278, d 0.53 mm, rho_s 2450, bulk 1550 kg/m^3; E [Pa], nu 0.3.
inline MpmParams granularColumnParams(double dx, std::array<int, 3> cells, double youngModulus) {
  MpmParams p;
  p.dx = dx;
  p.cells = cells;
  p.material.youngModulus = youngModulus;
  p.material.poissonRatio = 0.3;
  p.material.muS = 0.3819;
  p.material.mu2 = 0.6435;
  p.material.I0 = 0.278;
  p.material.grainDiameter = 0.00053;
  p.material.solidDensity = 2450;
  p.material.density = 1550;
  for (auto& w : p.walls) w.friction = 0;
  p.walls[4].friction = 0.4;
  return p;
}

}  // namespace testing_scenes
}  // namespace mpm
}  // namespace mpmsdem
