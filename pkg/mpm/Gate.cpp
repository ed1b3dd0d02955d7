#include "mpm/Gate.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "common/Error.hpp"
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
  const double lo = p.origin[0] + kWallLayer * p.dx, hi = p.origin[0] + (p.cells[0] - kWallLayer) * p.dx;
  if (!(g.x >= lo && g.x <= hi)) {
    std::ostringstream os;
    os << "in [" << lo << ", " << hi << "] m (along x, the grid box less its " << kWallLayer << "-cell wall layers)";
    throwParameter("gate.x", g.x, "m", os.str());
  }
  if (!std::isfinite(g.bottom)) throwParameter("gate.bottom", g.bottom, "m", "finite");
  if (!(g.speed >= 0)) throwParameter("gate.speed", g.speed, "m/s", ">= 0 (0 or infinity: removed at once at gate.openAt)");
  if (!(g.openAt >= 0) || !std::isfinite(g.openAt)) throwParameter("gate.openAt", g.openAt, "s", "finite and >= 0");
  if (!(g.friction >= 0) || !std::isfinite(g.friction)) throwParameter("gate.friction", g.friction, "", "finite and >= 0");
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
