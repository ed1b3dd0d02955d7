// Host control of the gate on a CUDA grid (mpm/Gate.hpp); the kernel is in
// MpmCudaKernels.cuh. Plain C++ interface, so that Gate.cpp needs no CUDA headers.
#pragma once
#include <array>

#include "mpm/GridBoundary.hpp"
#include "mpm/MpmSolver.hpp"

namespace mpmsdem {
namespace mpm {

// Apply the gate to the nodes of `band` of a device grid view, on the default stream, and add
// its impulse to *impulse (3 doubles on the device; allocated and zeroed when null).
void applyGateCuda(const GridView& grid, const GateBand& band, double friction, double** impulse);
// The 3 accumulated doubles (a blocking download).
std::array<double, 3> downloadGateImpulse(const double* impulse);
// Frees the accumulator (null: nothing); reports a failure on stderr instead of throwing.
void freeGateImpulse(double* impulse);

}  // namespace mpm
}  // namespace mpmsdem
