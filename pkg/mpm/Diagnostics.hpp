// Whole-system diagnostics of a particle state: what the driver's and MpmEngine's time series
// record (kinetic and potential energy, front, height, centre of mass, fastest point, flowing
// and gasified fractions), read slice by slice in particle-number order so that the sums are
// those of the whole set and no whole host copy is needed.
#pragma once
#include <array>
#include <optional>
#include <vector>

#include "mpm/DiagnosticsKernels.hpp"
#include "mpm/MpmTypes.hpp"

namespace mpmsdem {
namespace mpm {

// A station across a flume where the free flow's depth and velocity are taken (the paper's
// free-flow tests, §3.2.3 and §5: h_f and v_f at the block's station before the block is there).
// Units and ranges: the "flow_probes[]." entries of scene/SceneParameters (docs/parameters.md).
struct FlowProbeSpec {
  double x = 0;          // station along x
  double halfWidth = 0;  // the points with |x_p - x| <= halfWidth are the flow at the station
  double bedZ = 0;       // bed height: depth = highest of those points - bedZ
  int minPoints = 4;     // with fewer points the front has not arrived
  double window = 0.05;  // h_f and v_f: means of the records within window after the arrival
};

// The flow at one probe in one particle state; depth and velocity are 0 while fewer than
// minPoints points are at the station.
struct ProbeSample {
  double depth = 0;     // highest point above the bed [m]
  double velocity = 0;  // mass-weighted mean velocity along x [m/s]
  long points = 0;      // points at the station
};

struct Diagnostics {
  double kineticEnergy = 0;   // sum of m |v|^2 / 2 [J]
  double potential = 0;       // potential energy in gravity g, zero at the origin [J]
  double frontX = 0;          // largest particle x [m]; NaN without particles
  double heightZ = 0;         // largest particle z [m]; NaN without particles
  double com[3] = {0, 0, 0};  // centre of mass [m]; NaN without particles
  double maxSpeed = 0;        // [m/s]
  double flowing = 0;         // fraction of particles in phase 1 (dense, plastic)
  double gasified = 0;        // fraction of particles in phase 2 (stress-free)
  // the flow at each probe given to diagnose, in its order
  std::vector<ProbeSample> probes;
};

Diagnostics diagnose(ParticleSlices& particles, const std::array<double, 3>& gravity,
                     const std::vector<FlowProbeSpec>& probes = {});

// The stations (x and half-width) of the probes, as the per-particle formulas read them.
std::vector<ProbeStation> probeStations(const std::vector<FlowProbeSpec>& probes);

// The diagnostics of `n` particles from their sums (DiagnosticsKernels.hpp), one ProbeSums
// per probe: what diagnose() and a solver's own reduction (MpmSolver::diagnose) report.
Diagnostics finishDiagnostics(const DiagnosticSums& sums, const std::vector<ProbeSums>& probeSums, std::size_t n,
                              const std::vector<FlowProbeSpec>& probes);

// A probe's records over a run: the front's arrival (the first record with the flow at the
// station) and the means of depth and velocity over the records up to `window` after it, as
// the paper's free-flow tests report h_f and v_f.
class FlowProbeRecord {
 public:
  explicit FlowProbeRecord(const FlowProbeSpec& spec) : spec_(spec) {}
  void add(double time, const ProbeSample& sample);
  const FlowProbeSpec& spec() const { return spec_; }
  std::optional<double> arrival() const { return arrival_; }
  // The front has arrived and a record later than arrival + window has been added.
  bool complete() const { return complete_; }
  double depth() const { return count_ ? depthSum_ / count_ : 0; }        // h_f [m]; 0 before the arrival
  double velocity() const { return count_ ? velocitySum_ / count_ : 0; }  // v_f [m/s]
  long records() const { return records_; }

 private:
  FlowProbeSpec spec_;
  std::optional<double> arrival_;
  bool complete_ = false;
  double depthSum_ = 0, velocitySum_ = 0;
  long count_ = 0, records_ = 0;
};

}  // namespace mpm
}  // namespace mpmsdem
