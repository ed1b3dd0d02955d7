// makeSolver: parameter validation, backend selection, the gate's hook. cudaAvailable.
#include <cmath>
#include <sstream>

#include "common/Error.hpp"
#include "mpm/Gate.hpp"
#include "mpm/MpmCpu.hpp"
#include "mpm/MpmSolver.hpp"
#ifdef MPMSDEM_WITH_CUDA
#include "mpm/cuda/MpmCuda.hpp"
#endif

namespace mpmsdem {
namespace mpm {

namespace {

void requirePositive(const std::string& name, double v, const std::string& unit) {
  if (!(v > 0) || !std::isfinite(v)) throwParameter(name, v, unit, "finite and > 0");
}

void validate(const MpmParams& p) {
  requirePositive("dx", p.dx, "m");
  const char* axis[3] = {"x", "y", "z"};
  for (int d = 0; d < 3; ++d) {
    if (p.cells[d] < 2 * kWallLayer) {
      std::ostringstream os;
      os << ">= " << 2 * kWallLayer << " (two wall layers of " << kWallLayer << " cells)";
      throwParameter(std::string("cells[") + axis[d] + "]", p.cells[d], "", os.str());
    }
    if (!std::isfinite(p.origin[d])) throwParameter(std::string("origin[") + axis[d] + "]", p.origin[d], "m", "finite");
    if (!std::isfinite(p.gravity[d])) throwParameter(std::string("gravity[") + axis[d] + "]", p.gravity[d], "m/s^2", "finite");
  }
  // Node and stencil-base indices are ints; 27 stencil bases a block of 3 x 3 x 3 cells number
  // at least the nodes, so they bound both. The stored node records are addressed in 64 bits.
  const double bases = double(kBlockCells) * blocksAlong(p.cells[0]) * blocksAlong(p.cells[1]) * blocksAlong(p.cells[2]);
  if (bases > 2147483647.0)
    throwParameter("cells", std::to_string(p.cells[0]) + "x" + std::to_string(p.cells[1]) + "x" + std::to_string(p.cells[2]),
                   "", "small enough that 27 x (cells[x]/3 + 1)(cells[y]/3 + 1)(cells[z]/3 + 1) < 2^31 (about 2^31 nodes)");
  if (!(p.cfl > 0 && p.cfl <= 1)) throwParameter("cfl", p.cfl, "", "in (0, 1]");
  for (int w = 0; w < 6; ++w)
    if (!std::isfinite(p.walls[w].friction))
      throwParameter("walls[" + std::to_string(w) + "].friction", p.walls[w].friction, "",
                     "finite (< 0 no-slip, 0 free slip, > 0 Coulomb)");
  const GranularMaterial& m = p.material;
  requirePositive("material.density", m.density, "kg/m^3");
  requirePositive("material.youngModulus", m.youngModulus, "Pa");
  if (!(m.poissonRatio >= 0 && m.poissonRatio < 0.5)) throwParameter("material.poissonRatio", m.poissonRatio, "", "in [0, 0.5)");
  if (!(m.muS >= 0) || !std::isfinite(m.muS)) throwParameter("material.muS", m.muS, "", "finite and >= 0");
  if (!(m.mu2 >= m.muS) || !std::isfinite(m.mu2)) {
    std::ostringstream os;
    os << ">= muS = " << m.muS << " and finite";
    throwParameter("material.mu2", m.mu2, "", os.str());
  }
  requirePositive("material.I0", m.I0, "");
  requirePositive("material.grainDiameter", m.grainDiameter, "m");
  requirePositive("material.solidDensity", m.solidDensity, "kg/m^3");
  if (!(m.criticalDensity >= 0) || !std::isfinite(m.criticalDensity))
    throwParameter("material.criticalDensity", m.criticalDensity, "kg/m^3", ">= 0 (0 means = density)");
  validateGate(p);
  p.terrain.validate();
}

std::unique_ptr<MpmSolver> withGate(std::unique_ptr<MpmSolver> solver, const GateSpec& gate) {
  if (gate.enabled) solver->addGridHook(std::make_shared<Gate>(gate));
  return solver;
}

}  // namespace

void MpmSolver::setParticles(ParticleSlices& particles) {
  ParticleSet all;
  forEachSlice(particles, [&all](std::size_t, const ParticleSet& p) {
    ParticleSet::forEachArray([](const char*, std::size_t, ParticleSet::ArrayUse, auto& to,
                                 const auto& from) { to.insert(to.end(), from.begin(), from.end()); },
                              all, p);
  });
  setParticles(all);
}

void MpmSolver::getParticles(ParticleSet& out, std::size_t first, std::size_t count) {
  validateSliceRange("particle slice", first, count, numParticles());
  ParticleSet all;
  getParticles(all);
  copyParticleRange(all, first, count, out);
}

ParticleView MpmSolver::extendForceBuffer() {
  throw RuntimeFailure(name() + ": extendForceBuffer: this solver cannot add a second coupling's forces to the "
                       "next step's (the CPU backend can)");
}

void MpmSolver::launchStep(double) {
  throw RuntimeFailure(name() + ": launchStep: this solver does not queue steps (queuesSteps() is false); call step()");
}

void MpmSolver::finishStep() {
  throw RuntimeFailure(name() + ": finishStep: this solver does not queue steps (queuesSteps() is false)");
}

void MpmSolver::abandonStep() {
  throw RuntimeFailure(name() + ": abandonStep: this solver does not queue steps (queuesSteps() is false)");
}

std::unique_ptr<MpmSolver> makeSolver(const MpmParams& params, Backend backend, Precision precision) {
  validate(params);
  if (backend == Backend::Cpu) {
    if (precision == Precision::Float) return withGate(std::make_unique<MpmCpu<float>>(params), params.gate);
    return withGate(std::make_unique<MpmCpu<double>>(params), params.gate);
  }
#ifdef MPMSDEM_WITH_CUDA
  if (!cudaAvailable()) throw RuntimeFailure("backend = Cuda: this build has the CUDA backend but no CUDA device was found");
  return withGate(makeCudaSolver(params, precision), params.gate);
#else
  throw RuntimeFailure("backend = Cuda: this build has no CUDA backend (nvcc was not found at configure time)");
#endif
}

bool cudaAvailable() {
#ifdef MPMSDEM_WITH_CUDA
  return cudaDevicePresent();
#else
  return false;
#endif
}

}  // namespace mpm
}  // namespace mpmsdem
