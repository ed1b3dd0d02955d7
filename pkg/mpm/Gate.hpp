// A release gate on the MPM grid (MpmParams::gate, GateSpec): the grid-node hook that
// releases the column of the flume experiments, where a gate is lifted at finite speed.
//
// The gate is a plane normal to x at x_g with its lower edge at z_g(t) = z_0 + v max(0, t -
// t_open) (instant removal at t_open when v is 0 or infinite). Each step it acts like a wall
// facing -x (Coulomb friction as for the walls, GridBoundary.hpp) on the nodes within the
// B-spline reach of the gate, 1.5 dx: nodes with |x_node - x_g| < 1.5 dx and z_node > z_g -
// 1.5 dx, where z_g is taken at the end of the step. Every material point at or above the edge
// then has all its grid nodes held, so no such point crosses the plane, and a closed gate with
// its edge on the bed holds the whole column; points below z_g - 3 dx are free, those in
// between partly held. The opening the flow sees thus lags the edge by about 1.5 dx (1.5 dx / v
// in time): the price of never letting material above the edge through. Like a wall it only
// removes the velocity into the gate: material may move away from it.
#pragma once
#include <array>

#include "mpm/GridBoundary.hpp"
#include "mpm/MpmSolver.hpp"

namespace mpmsdem {
namespace mpm {

// Throws ParameterError naming "gate.<field>" and its range unless the gate of `params` is
// valid (only checked when enabled).
void validateGate(const MpmParams& params);

class Gate : public GridHook {
 public:
  explicit Gate(const GateSpec& spec);  // spec validated by validateGate
  ~Gate() override;
  Gate(const Gate&) = delete;
  Gate& operator=(const Gate&) = delete;

  void apply(const GridView& grid) override;

  const GateSpec& spec() const { return spec_; }
  // Height of the lower edge z_g(t) [m]; infinity once the gate is gone (instant removal).
  double edgeHeight(double t) const;
  // The nodes the gate acts on in a step that ends at time t, for a grid like `grid`.
  GateBand band(const GridView& grid, double t) const;
  // Total impulse the gate has given the material since it was built [N s] (its x component
  // is minus the impulse of the material on the gate). Downloads 3 numbers on CUDA.
  std::array<double, 3> impulse() const;

 private:
  GateSpec spec_;
  std::array<double, 3> hostImpulse_{};
  double* deviceImpulse_ = nullptr;  // 3 doubles on the device once a device grid was seen
};

}  // namespace mpm
}  // namespace mpmsdem
