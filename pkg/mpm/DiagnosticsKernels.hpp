// The per-particle formulas of the whole-system diagnostics (Diagnostics.hpp), shared by the
// host's pass over particle slices and the CUDA backend's reduction on the device, so that
// the two differ only in the order of their sums. Values in double whatever the solver's
// precision (a float state is widened point by point, as its slices are).
#pragma once
#include <cmath>

#include "common/MathHD.hpp"

namespace mpmsdem {
namespace mpm {

// Probes a device reduction carries in registers; a run with more reads slices on the host.
constexpr int kMaxDeviceProbes = 8;

// Sums and extremes over a set of particles. Maxima start at -inf (no particle).
struct DiagnosticSums {
  double kinetic;    // sum of m |v|^2 / 2 [J]
  double potential;  // sum of -m g.x [J]
  double mass;       // [kg]
  double moment[3];  // sum of m x [kg m]
  double maxV2;      // largest |v|^2 [m^2/s^2]
  double front;      // largest x [m]
  double height;     // largest z [m]
  long long flowing, gasified;  // particles in phase 1, 2
};

// What one probe station reads: the points within halfWidth of x.
struct ProbeStation {
  double x, halfWidth;
};
struct ProbeSums {
  long long points;
  double top;        // highest z [m]
  double mass;       // [kg]
  double momentumX;  // sum of m v_x [kg m/s]
};

MPM_HD_INLINE DiagnosticSums emptyDiagnosticSums() {
  return {0, 0, 0, {0, 0, 0}, 0, -INFINITY, -INFINITY, 0, 0};
}
MPM_HD_INLINE ProbeSums emptyProbeSums() { return {0, -INFINITY, 0, 0}; }

MPM_HD_INLINE void addParticleDiagnostics(DiagnosticSums& s, const double x[3], const double v[3], double m,
                                          int phase, const double g[3]) {
  const double v2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
  s.kinetic += 0.5 * m * v2;
  s.potential -= m * (g[0] * x[0] + g[1] * x[1] + g[2] * x[2]);
  s.mass += m;
  for (int a = 0; a < 3; ++a) s.moment[a] += m * x[a];
  // (a NaN coordinate or speed leaves a maximum as it was, as std::max(a, NaN) does)
  s.maxV2 = v2 > s.maxV2 ? v2 : s.maxV2;
  s.front = x[0] > s.front ? x[0] : s.front;
  s.height = x[2] > s.height ? x[2] : s.height;
  s.flowing += phase == 1;
  s.gasified += phase == 2;
}

MPM_HD_INLINE void addProbeSample(ProbeSums& p, const ProbeStation& st, const double x[3], double vx, double m) {
  if (fabs(x[0] - st.x) > st.halfWidth) return;
  ++p.points;
  p.top = x[2] > p.top ? x[2] : p.top;
  p.mass += m;
  p.momentumX += m * vx;
}

MPM_HD_INLINE void combineDiagnostics(DiagnosticSums& a, const DiagnosticSums& b) {
  a.kinetic += b.kinetic;
  a.potential += b.potential;
  a.mass += b.mass;
  for (int d = 0; d < 3; ++d) a.moment[d] += b.moment[d];
  a.maxV2 = b.maxV2 > a.maxV2 ? b.maxV2 : a.maxV2;
  a.front = b.front > a.front ? b.front : a.front;
  a.height = b.height > a.height ? b.height : a.height;
  a.flowing += b.flowing;
  a.gasified += b.gasified;
}

MPM_HD_INLINE void combineProbe(ProbeSums& a, const ProbeSums& b) {
  a.points += b.points;
  a.top = b.top > a.top ? b.top : a.top;
  a.mass += b.mass;
  a.momentumX += b.momentumX;
}

}  // namespace mpm
}  // namespace mpmsdem
