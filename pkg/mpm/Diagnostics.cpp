#include "mpm/Diagnostics.hpp"

#include <algorithm>
#include <cmath>

namespace mpmsdem {
namespace mpm {

Diagnostics diagnose(ParticleSlices& particles, const std::array<double, 3>& g,
                     const std::vector<FlowProbeSpec>& probes) {
  Diagnostics d;
  d.probes.assign(probes.size(), ProbeSample{});
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
  std::vector<double> top(probes.size(), -INFINITY), probeMass(probes.size(), 0.0);
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
    for (std::size_t k = 0; k < probes.size(); ++k) {
      ProbeSample& s = d.probes[k];
      for (std::size_t i = 0; i < p.size(); ++i) {
        if (std::abs(p.x[3 * i] - probes[k].x) > probes[k].halfWidth) continue;
        ++s.points;
        top[k] = std::max(top[k], p.x[3 * i + 2]);
        probeMass[k] += p.mass[i];
        s.velocity += p.mass[i] * p.v[3 * i];
      }
    }
  });
  for (std::size_t k = 0; k < probes.size(); ++k) {
    ProbeSample& s = d.probes[k];
    if (s.points < probes[k].minPoints) {
      s.depth = s.velocity = 0;
      continue;
    }
    s.depth = top[k] - probes[k].bedZ;
    s.velocity /= probeMass[k];
  }
  for (double& c : d.com) c /= mass;
  d.maxSpeed = std::sqrt(maxV2);
  d.flowing = double(flowing) / n;
  d.gasified = double(gasified) / n;
  return d;
}

void FlowProbeRecord::add(double t, const ProbeSample& s) {
  ++records_;
  const bool here = s.points >= spec_.minPoints;
  if (!arrival_) {
    if (!here) return;
    arrival_ = t;
  }
  if (t > *arrival_ + spec_.window) {
    complete_ = true;
    return;
  }
  if (!here) return;  // a record within the window without the flow: the front thinned out
  depthSum_ += s.depth;
  velocitySum_ += s.velocity;
  ++count_;
}

}  // namespace mpm
}  // namespace mpmsdem
