#include "mpm/Gate.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/Error.hpp"
#include "mpm/MpmParameters.hpp"
#ifdef MPMSDEM_WITH_CUDA
#include "mpm/cuda/GateCuda.hpp"
#endif

namespace mpmsdem {
namespace mpm {

namespace {

// Reach of a node's B-spline weight [cells]: a point feels the nodes closer than this.
constexpr double kReach = 1.5;

template <typename T>
void applyHost(const GridView& g, const GateBand& b, double friction, std::array<double, 3>& impulse) {
  const T* mass = static_cast<const T*>(g.mass);
  T* v[3] = {static_cast<T*>(g.v[0]), static_cast<T*>(g.v[1]), static_cast<T*>(g.v[2])};
  // Serial: the band is a few node layers, and a fixed order keeps the impulse sum independent
  // of the thread count.
  const int n = gateBandSize(b);
  for (int t = 0; t < n; ++t) {
    const long r = storedNodeRecord(g.column, b.nodes[2], gateBandNode(t, b));
    if (r < 0) continue;  // a column no point has reached: empty nodes
    const Vec3T<T> p = applyGateNode(g.stride * r, mass, v[0], v[1], v[2], static_cast<T>(friction));
    for (int d = 0; d < 3; ++d) impulse[d] += static_cast<double>(p[d]);
  }
}

// Node index bounds as doubles clamped to the grid before conversion (an edge far above or
// below the grid must not overflow an int).
int clampIndex(double k, int nodes) { return static_cast<int>(std::min<double>(std::max(k, -1.0), nodes)); }

}  // namespace

void validateGate(const MpmParams& p) {
  const GateSpec& g = p.gate;
  if (!g.enabled) return;
  // gate.x: in the material region, the grid box less its wall layers (the scene's bound too).
  checkParameter(solverParameter("gate.x"), "gate.x", g.x, p.origin[0] + kWallLayer * p.dx,
                 p.origin[0] + (p.cells[0] - kWallLayer) * p.dx);
  checkParameter(solverParameter("gate.bottom"), g.bottom);
  // An infinite speed is a removal at once, as 0 is (a scene says 0: JSON has no infinity).
  if (!(std::isinf(g.speed) && g.speed > 0)) checkParameter(solverParameter("gate.speed"), g.speed);
  checkParameter(solverParameter("gate.open_at"), g.openAt);
  checkParameter(solverParameter("gate.friction"), g.friction);
}

Gate::Gate(const GateSpec& spec) : spec_(spec) {}

Gate::~Gate() {
#ifdef MPMSDEM_WITH_CUDA
  freeGateImpulse(deviceImpulse_);
#endif
}

double Gate::edgeHeight(double t) const {
  if (t <= spec_.openAt) return spec_.bottom;
  if (spec_.speed == 0 || std::isinf(spec_.speed)) return std::numeric_limits<double>::infinity();
  return spec_.bottom + spec_.speed * (t - spec_.openAt);
}

GateBand Gate::band(const GridView& g, double t) const {
  GateBand b;
  for (int d = 0; d < 3; ++d) b.nodes[d] = g.nodes[d];
  const double xi = (spec_.x - g.origin[0]) / g.dx;
  b.i0 = std::max(0, clampIndex(std::floor(xi - kReach) + 1, g.nodes[0]));
  b.i1 = std::min(g.nodes[0] - 1, clampIndex(std::ceil(xi + kReach) - 1, g.nodes[0]));
  const double zeta = (edgeHeight(t) - g.origin[2]) / g.dx - kReach;  // +inf once removed
  b.k0 = std::max(0, clampIndex(std::floor(zeta) + 1, g.nodes[2]));
  return b;
}

void Gate::apply(const GridView& g) {
  const GateBand b = band(g, g.time + g.dt);
  if (gateBandSize(b) == 0) return;
  if (g.device) {
#ifdef MPMSDEM_WITH_CUDA
    applyGateCuda(g, b, spec_.friction, &deviceImpulse_);
    return;
#else
    throw RuntimeFailure("gate: a device grid in a build without CUDA");
#endif
  }
  if (g.precision == Precision::Double)
    applyHost<double>(g, b, spec_.friction, hostImpulse_);
  else
    applyHost<float>(g, b, spec_.friction, hostImpulse_);
}

std::array<double, 3> Gate::impulse() const {
  std::array<double, 3> total = hostImpulse_;
#ifdef MPMSDEM_WITH_CUDA
  if (deviceImpulse_) {
    const std::array<double, 3> dev = downloadGateImpulse(deviceImpulse_);
    for (int d = 0; d < 3; ++d) total[d] += dev[d];
  }
#endif
  return total;
}

}  // namespace mpm
}  // namespace mpmsdem
