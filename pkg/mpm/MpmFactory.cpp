// makeSolver: parameter validation, backend selection, the gate's hook. cudaAvailable.
#include <cmath>

#include "common/Error.hpp"
#include "mpm/Gate.hpp"
#include "mpm/MpmCpu.hpp"
#include "mpm/MpmParameters.hpp"
#include "mpm/MpmSolver.hpp"
#ifdef MPMSDEM_WITH_CUDA
#include "mpm/cuda/MpmCuda.hpp"
#endif

namespace mpmsdem {
namespace mpm {

namespace {

// An MpmParams filled in C++ is checked against the same entries the scene parser reads with
// (mpm/MpmParameters), and the messages name the scene's keys: a value refused here is refused
// with the same words in a scene.
void validate(const MpmParams& p) {
  checkParameter(solverParameter("grid.dx"), p.dx);
  const ParameterSpec& cells = solverParameter("grid.cells");
  const char* axis[3] = {"x", "y", "z"};
  for (int d = 0; d < 3; ++d) {
    if (p.cells[d] < cells.lo || p.cells[d] > cells.hi)
      throwParameter(std::string("grid.cells[") + axis[d] + "]", p.cells[d], "",
                     rangeText(cells) + " (two wall layers of " + std::to_string(kWallLayer) + " cells at each end)");
    if (!std::isfinite(p.origin[d]))
      throwParameter(std::string("grid.origin[") + axis[d] + "]", p.origin[d], "m", "finite");
    if (!std::isfinite(p.gravity[d])) throwParameter(std::string("gravity[") + axis[d] + "]", p.gravity[d], "m/s^2", "finite");
  }
  // Node and stencil-base indices are ints; 27 stencil bases a block of 3 x 3 x 3 cells number
  // at least the nodes, so they bound both. The stored node records are addressed in 64 bits.
  const double bases = double(kBlockCells) * blocksAlong(p.cells[0]) * blocksAlong(p.cells[1]) * blocksAlong(p.cells[2]);
  if (bases > 2147483647.0)
    throwParameter("grid.cells", std::to_string(p.cells[0]) + "x" + std::to_string(p.cells[1]) + "x" + std::to_string(p.cells[2]),
                   "", "small enough that 27 x (cells[x]/3 + 1)(cells[y]/3 + 1)(cells[z]/3 + 1) < 2^31 (about 2^31 nodes)");
  checkParameter(solverParameter("cfl"), p.cfl);
  // In C++ a negative friction is no-slip (the scene's "noslip"): only a number that is not one is refused.
  for (int w = 0; w < 6; ++w)
    if (!std::isfinite(p.walls[w].friction))
      throwParameter(std::string("walls.") + kWallNames[w], p.walls[w].friction, "",
                     "finite (< 0 no-slip, 0 free slip, > 0 Coulomb)");
  const GranularMaterial& m = p.material;
  checkParameter(solverParameter("material.density"), m.density);
  checkParameter(solverParameter("material.young_modulus"), m.youngModulus);
  checkParameter(solverParameter("material.poisson_ratio"), m.poissonRatio);
  checkParameter(solverParameter("material.mu_s"), m.muS);
  const ParameterSpec& mu2 = solverParameter("material.mu_2");
  checkParameter(mu2, mu2.key, m.mu2, m.muS, mu2.hi);  // as the scene reads it: mu_s, checked above, is its bound
  checkParameter(solverParameter("material.I0"), m.I0);
  checkParameter(solverParameter("material.grain_diameter"), m.grainDiameter);
  checkParameter(solverParameter("material.solid_density"), m.solidDensity);
  checkParameter(solverParameter("material.critical_density"), m.criticalDensity);
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
                       "next step's (the CPU and CUDA backends can)");
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
