#include "mpm/Diagnostics.hpp"

#include <algorithm>
#include <cmath>

namespace mpmsdem {
namespace mpm {

Diagnostics diagnose(ParticleSlices& particles, const std::array<double, 3>& g) {
  Diagnostics d;
  const std::size_t n = particles.size();
  if (n == 0) {
    // no flow has no front, height or centre of mass; its energies and fractions are zero
    d.frontX = d.heightZ = d.com[0] = d.com[1] = d.com[2] = std::nan("");
    return d;
  }
  d.frontX = -INFINITY;
  d.heightZ = -INFINITY;
  double mass = 0, maxV2 = 0;
  std::size_t flowing = 0, gasified = 0;
  forEachSlice(particles, [&](std::size_t, const ParticleSet& p) {
    for (std::size_t i = 0; i < p.size(); ++i) {
      const double* v = &p.v[3 * i];
      const double v2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
      d.kineticEnergy += 0.5 * p.mass[i] * v2;
      maxV2 = std::max(maxV2, v2);
      d.frontX = std::max(d.frontX, p.x[3 * i]);
      d.heightZ = std::max(d.heightZ, p.x[3 * i + 2]);
      for (int a = 0; a < 3; ++a) d.com[a] += p.mass[i] * p.x[3 * i + a];
      mass += p.mass[i];
      flowing += p.phase[i] == 1;
      gasified += p.phase[i] == 2;
    }
    for (std::size_t i = 0; i < p.size(); ++i)
      d.potential -= p.mass[i] * (g[0] * p.x[3 * i] + g[1] * p.x[3 * i + 1] + g[2] * p.x[3 * i + 2]);
  });
  for (double& c : d.com) c /= mass;
  d.maxSpeed = std::sqrt(maxV2);
  d.flowing = double(flowing) / n;
  d.gasified = double(gasified) / n;
  return d;
}

}  // namespace mpm
}  // namespace mpmsdem
