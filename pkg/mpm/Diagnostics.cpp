#include "mpm/Diagnostics.hpp"

#include <algorithm>
#include <cmath>

namespace mpmsdem {
namespace mpm {

Diagnostics diagnose(ParticleSlices& particles, const std::array<double, 3>& g,
                     const std::vector<FlowProbeSpec>& probes) {
  DiagnosticSums sums = emptyDiagnosticSums();
  std::vector<ProbeSums> probeSums(probes.size(), emptyProbeSums());
  const std::vector<ProbeStation> stations = probeStations(probes);
  const double gravity[3] = {g[0], g[1], g[2]};
  forEachSlice(particles, [&](std::size_t, const ParticleSet& p) {
    for (std::size_t i = 0; i < p.size(); ++i) {
      const double* x = &p.x[3 * i];
      addParticleDiagnostics(sums, x, &p.v[3 * i], p.mass[i], p.phase[i], gravity);
      for (std::size_t k = 0; k < probes.size(); ++k)
        addProbeSample(probeSums[k], stations[k], x, p.v[3 * i], p.mass[i]);
    }
  });
  return finishDiagnostics(sums, probeSums, particles.size(), probes);
}

std::vector<ProbeStation> probeStations(const std::vector<FlowProbeSpec>& probes) {
  std::vector<ProbeStation> stations;
  for (const FlowProbeSpec& p : probes) stations.push_back({p.x, p.halfWidth});
  return stations;
}

Diagnostics finishDiagnostics(const DiagnosticSums& sums, const std::vector<ProbeSums>& probeSums, std::size_t n,
                              const std::vector<FlowProbeSpec>& probes) {
  Diagnostics d;
  d.probes.assign(probes.size(), ProbeSample{});
  if (n == 0) {
    // no flow has no front, height or centre of mass; its energies and fractions are zero
    d.frontX = d.heightZ = d.com[0] = d.com[1] = d.com[2] = std::nan("");
    return d;
  }
  d.kineticEnergy = sums.kinetic;
  d.potential = sums.potential;
  d.frontX = sums.front;
  d.heightZ = sums.height;
  for (int a = 0; a < 3; ++a) d.com[a] = sums.moment[a] / sums.mass;
  d.maxSpeed = std::sqrt(sums.maxV2);
  d.flowing = double(sums.flowing) / n;
  d.gasified = double(sums.gasified) / n;
  for (std::size_t k = 0; k < probes.size(); ++k) {
    const ProbeSums& q = probeSums[k];
    ProbeSample& s = d.probes[k];
    s.points = q.points;
    if (q.points < probes[k].minPoints) continue;  // the front has not arrived: depth and velocity 0
    s.depth = q.top - probes[k].bedZ;
    s.velocity = q.momentumX / q.mass;
  }
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
