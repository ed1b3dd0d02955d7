// Whole-system diagnostics of a particle state: what the driver's and MpmEngine's time series
// record (kinetic and potential energy, front, height, centre of mass, fastest point, flowing
// and gasified fractions), read slice by slice in particle-number order so that the sums are
// those of the whole set and no whole host copy is needed.
#pragma once
#include <array>

#include "mpm/MpmTypes.hpp"

namespace mpmsdem {
namespace mpm {

struct Diagnostics {
  double kineticEnergy = 0;   // sum of m |v|^2 / 2 [J]
  double potential = 0;       // potential energy in gravity g, zero at the origin [J]
  double frontX = 0;          // largest particle x [m]; NaN without particles
  double heightZ = 0;         // largest particle z [m]; NaN without particles
  double com[3] = {0, 0, 0};  // centre of mass [m]; NaN without particles
  double maxSpeed = 0;        // [m/s]
  double flowing = 0;         // fraction of particles in phase 1 (dense, plastic)
  double gasified = 0;        // fraction of particles in phase 2 (stress-free)
};

Diagnostics diagnose(ParticleSlices& particles, const std::array<double, 3>& gravity);

}  // namespace mpm
}  // namespace mpmsdem
