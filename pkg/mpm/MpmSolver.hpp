// The MPM solver interface. Two backends implement it with the same formulas
// (shared __host__ __device__ functions): CPU (OpenMP) and CUDA, each in float or double.
#pragma once
#include <algorithm>
#include <memory>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "common/Error.hpp"

#include "mpm/Diagnostics.hpp"
#include "mpm/GridBoundary.hpp"
#include "mpm/MpmTypes.hpp"

namespace mpmsdem {
namespace mpm {

enum class Backend { Cpu, Cuda };
enum class Precision { Float, Double };

// Co-simulation face of a solver (what a coupling reads and writes each step, paper §2.3):
// the current particle state in the backend's own memory (host for the CPU backend, device
// for CUDA) and precision, and the external-force buffer of the next step. Arrays are
// structure-of-arrays, one per component, numParticles() long; their element type is double
// or float as `precision` says. A backend may store the particles in an order of its own (the
// CPU backend keeps them sorted by grid block): every array is indexed by storage slot, and
// id[slot] is the number of the particle in that slot (its index in setParticles() and
// getParticles(), which stays with it for the whole run). id is null when slots and numbers
// are the same. The views stay valid until the next step(), setParticles() or
// openForceBuffer().
struct ParticleView {
  Precision precision = Precision::Double;
  bool device = false;             // true: CUDA device pointers
  std::size_t n = 0;               // particle count
  const int* id = nullptr;         // particle number of each slot (null: the slot itself)
  const void* x[3] = {};           // position [m], per slot
  const void* v[3] = {};           // velocity [m/s], per slot
  const void* mass = nullptr;      // [kg], per slot
  const void* volume0 = nullptr;   // initial volume [m^3] (sets the contact radius, Eq 13), per slot
  const void* J = nullptr;         // det F, per slot: current volume = J volume0
  void* force[3] = {};             // external force of the next step [N], per slot: accumulate into it (Eq 14)
};

// The grid as a grid-node hook sees it (GridHook::apply), in the backend's own memory (host
// for the CPU backend, device for CUDA) and precision: the element type of the arrays is
// double or float as `precision` says. Node (i, j, k), at origin + (i, j, k) dx, is element
// stride * ((i * nodes[1] + j) * nodes[2] + k) of every array (the arrays interleave: a node's
// values are stored together). The velocities are those the step ends
// with: momentum over mass with gravity and the internal and external forces of this step
// applied, the walls not yet. A hook may change them in place (the mass is read-only); empty
// nodes have mass 0 and velocity 0 and must stay at rest. Valid only inside apply().
struct GridView {
  Precision precision = Precision::Double;
  bool device = false;      // true: CUDA device pointers
  int nodes[3] = {};        // nodes per axis (cells + 1)
  double origin[3] = {};    // position of node (0, 0, 0) [m]
  double dx = 0;            // node spacing [m]
  int stride = 1;           // elements from one node record to the next in mass and v
  const void* mass = nullptr;  // node mass [kg]
  void* v[3] = {};          // node velocity at the end of the step [m/s]
  // Where the nodes are (GridConst::column): node (i, j, k) has the index
  // n = (i * nodes[1] + j) * nodes[2] + k and its values are at element record(n) * stride. Null
  // column: the dense layout, record(n) = n. Otherwise column[i * nodes[1] + j] is the stored
  // column of (i, j), or -1 where no material point has reached it (its nodes are empty and not
  // stored); in the backend's memory like the arrays (a device view's map is read on the device:
  // storedNodeRecord). storedNodes: the records behind the arrays.
  const int* column = nullptr;
  long storedNodes = 0;
  // The record of the node with index n, or -1 where it is not stored (a host view's).
  long record(long n) const { return storedNodeRecord(column, nodes[2], n); }
  double time = 0;          // time at the start of the step [s] (the velocities are those of time + dt)
  double dt = 0;            // step [s]
};

// A stage of every step on the grid nodes (co-simulation face: boundary conditions or a
// coupling imposed on the grid), run after gravity and external forces and before the
// walls, so that the walls still win. On CUDA, apply() must queue its work on the default
// stream (the step's kernels run there, so nothing needs a host round trip). A hook that
// throws fails the step before any particle changes (the state of the step's start is kept).
class GridHook {
 public:
  virtual ~GridHook() = default;
  virtual void apply(const GridView& grid) = 0;
};

class MpmSolver {
 public:
  virtual ~MpmSolver() = default;
  virtual std::string name() const = 0;              // e.g. "cpu-double", "cuda-float"
  virtual const MpmParams& params() const = 0;

  // Replace all particles (uploads to the device for CUDA). Throws ParameterError when a
  // particle lies outside the grid domain (names the particle index and the domain).
  virtual void setParticles(const ParticleSet& particles) = 0;
  // The same from particles read slice by slice (e.g. SeededParticles), so the caller need not
  // hold the whole set; this version gathers them, a backend that can do without overrides it.
  virtual void setParticles(ParticleSlices& particles);
  // Copy the current particle state into `out` (downloads for CUDA).
  virtual void getParticles(ParticleSet& out) = 0;
  // Particles [first, first + count) by number into `out` (count of them), as getParticles
  // gives them. This version goes through a whole copy; a backend that can do without
  // overrides it.
  virtual void getParticles(ParticleSet& out, std::size_t first, std::size_t count);
  virtual std::size_t numParticles() const = 0;

  // External forces on particles for the NEXT step only [N], 3 per particle (paper Eq 14:
  // spread to the grid with the P2G weights). Cleared after each step. Invalid forces throw
  // ParameterError and leave the solver as it was; a failure while storing them (out of
  // memory) makes step() refuse to run until forces or particles are set again.
  virtual void setExternalForces(const std::vector<double>& f) = 0;

  // Zero the external-force buffer, arm it for the next step() (which spreads it to the grid
  // with the P2G weights, Eq 14, and clears it) and return the particle view with it. A
  // coupling calls this once per step and adds its forces into view.force; nothing crosses
  // between host and device.
  virtual ParticleView openForceBuffer() = 0;
  // The external-force buffer of the next step with the forces already in it, for a second
  // coupling that adds to what the first put there (LevelSet bodies beside SDEM blocks); the
  // zeroed buffer of openForceBuffer() when the next step has none yet. The CPU and CUDA
  // backends have it (on CUDA the second coupling's work is queued after the first's); elsewhere
  // it throws RuntimeFailure.
  virtual ParticleView extendForceBuffer();

  // One explicit step: P2G, grid update (gravity, external forces, grid hooks, walls), G2P,
  // constitutive update. Throws RuntimeFailure on a NaN / blow-up (names the particle).
  virtual void step(double dt) = 0;

  // The step in two halves, for a caller with host work to do while a device runs the step
  // (CoupledWorld moves the blocks meanwhile). Only where queuesSteps() (CUDA): launchStep(dt)
  // queues what step(dt) does and returns; then one of finishStep(), which waits for it and ends
  // it as step(dt) does (the same failures), or abandonStep(), which waits for it and leaves the
  // particles and the clock as they were before it (for a caller whose own part of the step
  // failed), must come before any other call. Elsewhere they throw: step() is the whole step.
  virtual bool queuesSteps() const { return false; }
  virtual void launchStep(double dt);
  virtual void finishStep();
  virtual void abandonStep();

  // False once a step failed in a solver that keeps one copy of the particles
  // (MpmParams::keepLastGoodState false): they are then partly advanced, and step(),
  // getParticles() and openForceBuffer() throw RuntimeFailure until setParticles() replaces
  // them. True otherwise: after a failed step the particles are those of its start.
  bool holdsLastGoodState() const { return !partlyAdvanced_; }

  // Add a grid-node hook, run every step in the order added (see GridHook). makeSolver adds
  // the gate of MpmParams::gate this way.
  void addGridHook(std::shared_ptr<GridHook> hook) {
    if (!hook) throwParameter("hook", "null", "", "a GridHook");
    hooks_.push_back(std::move(hook));
  }
  // The first hook of type H, or nullptr.
  template <class H>
  H* findGridHook() const {
    for (const auto& h : hooks_)
      if (auto* p = dynamic_cast<H*>(h.get())) return p;
    return nullptr;
  }

  // The CFL step: cfl * dx / (elastic wave speed + max particle speed) [s].
  virtual double cflTimeStep() = 0;
  // Largest stable step [s]: the CFL step, and no longer than the blend's stepLimit (a PIC
  // viscosity hands PIC 4 nu dt / dx^2 of the velocity per step, at most all of it).
  double stableTimeStep() { return std::min(cflTimeStep(), params().flip.stepLimit(params().dx)); }
  // Whether the blend's stepLimit, not the CFL step, sets stableTimeStep().
  bool blendLimitsStep() { return params().flip.stepLimit(params().dx) < cflTimeStep(); }
  // What sets stableTimeStep(), in words.
  std::string stableStepName() {
    return blendLimitsStep() ? "the blend's step dx^2/(4 nu) of its PIC viscosity" : "the flow's CFL step";
  }

  // Throws ParameterError unless 0 < dt <= stableTimeStep() (1e-4 relative slack for
  // round-off), e.g. "dt = 0.001 s: must be in (0, 0.0002] s (CFL 0.3 ...)". step() calls it
  // on its first step and every 100 steps; callers changing dt may call it themselves.
  void checkTimeStep(double dt) {
    const double limit = stableTimeStep();
    if (!(dt > 0) || !(dt <= limit * 1.0001)) {
      std::ostringstream os;
      os << "in (0, " << limit << "] s (";
      if (blendLimitsStep())
        os << "dx^2/(4 nu) of the PIC viscosity " << params().flip.setViscosity()
           << " m^2/s: a step hands PIC 4 nu dt/dx^2 of the velocity, at most all of it)";
      else
        os << "CFL " << params().cfl << " times dx over the elastic wave speed plus the largest particle speed)";
      throwParameter("dt", dt, "s", os.str());
    }
  }

  // The sums behind the whole-system diagnostics of the current particles (mpm::diagnose's
  // per-particle formulas, DiagnosticsKernels.hpp; one ProbeSums per station into
  // `probeSums`) reduced where the particles are, so that a few hundred bytes cross instead of
  // the whole state: true where this backend does that (CUDA, with at most kMaxDeviceProbes
  // stations; sums in a fixed order), false where the caller reads slices.
  virtual bool diagnosticSums(const std::array<double, 3>& /*gravity*/, const std::vector<ProbeStation>& /*stations*/,
                              DiagnosticSums& /*sums*/, std::vector<ProbeSums>& /*probeSums*/) {
    return false;
  }

  // Bytes of device (CUDA) or host (CPU) memory held for particles and grid.
  virtual std::size_t memoryBytes() const = 0;

  // Device time of the stages of the steps taken since setStageTiming(true) [s], by stage name
  // (CUDA: sort, p2g, grid, g2p, measured with device events at a cost of a few microseconds
  // a step); empty where the backend has no such clock (the CPU) or timing is off.
  virtual void setStageTiming(bool) {}
  virtual std::vector<std::pair<std::string, double>> stageSeconds() const { return {}; }

  double time() const { return time_; }
  long steps() const { return steps_; }
  // Set the simulated time [s] (>= 0) and step count (>= 0), e.g. when restarting from a
  // snapshot taken at that time.
  void setClock(double time, long steps) {
    if (!(time >= 0)) throwParameter("time", time, "s", ">= 0");
    if (steps < 0) throwParameter("steps", steps, "", ">= 0");
    time_ = time;
    steps_ = steps;
  }

 protected:
  // A view of the grid without its arrays (the backend sets precision, device, mass and v).
  GridView gridViewFrame(double dt) const {
    GridView g;
    const MpmParams& p = params();
    for (int d = 0; d < 3; ++d) {
      g.nodes[d] = p.cells[d] + 1;
      g.origin[d] = p.origin[d];
    }
    g.dx = p.dx;
    g.time = time_;
    g.dt = dt;
    return g;
  }
  void applyGridHooks(const GridView& grid) {
    for (const auto& h : hooks_) h->apply(grid);
  }
  // Throws RuntimeFailure naming `what` when a failed step left the particles partly advanced.
  void requireLastGoodState(const char* what) const {
    if (partlyAdvanced_)
      throw RuntimeFailure(std::string(what) + ": a failed step left the particles partly advanced (keepLastGoodState "
                           "is off, so no copy of their state was kept); load the last snapshot with setParticles()");
  }

  // Throws RuntimeFailure naming `what` when the last setExternalForces or openForceBuffer
  // failed before the whole force buffer was in place (e.g. out of memory): a step would run
  // without the forces the caller meant, so none runs until the buffer is set again.
  void requireCompleteForces(const char* what) const {
    if (forcesIncomplete_)
      throw RuntimeFailure(std::string(what) + ": the last setExternalForces or openForceBuffer failed before all "
                           "forces were in place (e.g. out of memory); call it again, or setParticles(), first");
  }

  double time_ = 0;
  long steps_ = 0;
  bool partlyAdvanced_ = false;
  bool forcesIncomplete_ = false;  // set while a force buffer is being replaced; see requireCompleteForces
  std::vector<std::shared_ptr<GridHook>> hooks_;
};

// A solver's current particles in slices of `sliceSize` (what writers read an output from),
// fetched with getParticles(out, first, count) into one reused buffer.
class SolverParticleSlices : public ParticleSlices {
 public:
  SolverParticleSlices(MpmSolver& solver, std::size_t sliceSize) : solver_(solver), sliceSize_(sliceSize) {
    if (sliceSize == 0) throwParameter("sliceSize", 0, "particles", ">= 1");
  }
  std::size_t size() const override { return solver_.numParticles(); }
  std::size_t sliceSize() const override { return sliceSize_; }
  const ParticleSet& slice(std::size_t first, std::size_t count) override {
    solver_.getParticles(buffer_, first, count);
    return buffer_;
  }

 private:
  MpmSolver& solver_;
  std::size_t sliceSize_;
  ParticleSet buffer_;
};

// The diagnostics of a solver's current particles: its own reduction where it has one
// (MpmSolver::diagnosticSums), else a pass over `slices` of them (mpm::diagnose).
inline Diagnostics diagnose(MpmSolver& solver, ParticleSlices& slices, const std::array<double, 3>& gravity,
                            const std::vector<FlowProbeSpec>& probes = {}) {
  DiagnosticSums sums;
  std::vector<ProbeSums> probeSums;
  if (solver.diagnosticSums(gravity, probeStations(probes), sums, probeSums))
    return finishDiagnostics(sums, probeSums, solver.numParticles(), probes);
  return diagnose(slices, gravity, probes);
}

// Build a solver, with a Gate hook when params.gate is enabled (findGridHook<Gate>() reads
// it). Throws ParameterError on invalid parameters (each names the parameter and its range),
// and RuntimeFailure when the CUDA backend is asked for but unavailable.
std::unique_ptr<MpmSolver> makeSolver(const MpmParams& params, Backend backend = Backend::Cpu,
                                      Precision precision = Precision::Double);

// True when this build has the CUDA backend AND a CUDA device is present at run time.
bool cudaAvailable();

}  // namespace mpm
}  // namespace mpmsdem
