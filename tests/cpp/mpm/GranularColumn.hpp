// Flows shared by the tests: the granular column of the MPM tests, and Table 1's glass beads of
// the flume experiments that the gate and coupling tests use.
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

// Table 1's glass beads (ρ 1600 kg/m³, E 1 MPa, ν 0.3, μ_s 0.24, μ_2 0.65) on a grid of `cells`
// at spacing `dx` [m], with `gravity` [m/s²].
inline MpmParams tableOneBeads(std::array<int, 3> cells, double dx, std::array<double, 3> gravity = {0, 0, -9.81}) {
  MpmParams p;
  p.dx = dx;
  p.cells = cells;
  p.gravity = gravity;
  p.material.density = 1600;
  p.material.youngModulus = 1e6;
  p.material.poissonRatio = 0.3;
  p.material.muS = 0.24;
  p.material.mu2 = 0.65;
  return p;
}

}  // namespace testing_scenes
}  // namespace mpm
}  // namespace mpmsdem
