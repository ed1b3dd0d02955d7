// MPM data shared by the CPU backend, the CUDA backend, the I/O writers, the JSON
// driver and the Python binding. Host-side containers are double precision; the CUDA
// backend may run in float and converts at upload/download.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "common/Error.hpp"
#include "common/Terrain.hpp"
#include "mpm/FlipBlend.hpp"

namespace mpmsdem {
namespace mpm {

// Granular material of Appendix B (with the corrections of docs/physics.md). SI units; each
// member's unit and range: its "material." entry in mpm/MpmParameters (docs/parameters.md).
struct GranularMaterial {
  double density = 1600;       // rho_0, initial bulk density of the material points
  double youngModulus = 1e6;   // E (Table 1)
  double poissonRatio = 0.3;   // nu
  double muS = 0.24;           // mu_s, static friction coefficient, Eq B.2
  double mu2 = 0.65;           // mu_2, limiting dynamic friction, Eq B.2
  double I0 = 0.279;           // I_0, inertial-number scale, Eq B.2
  double grainDiameter = 0.002;  // d
  double solidDensity = 2500;  // rho_s, grain density
  double criticalDensity = 0;  // rho_c; 0 means "= density" (paper §2.1). Stress-free below it.
};

// One wall of the box-shaped grid domain: index 0..5 = -x,+x,-y,+y,-z,+z (kWallNames, the
// scene's keys under "walls").
inline constexpr const char* kWallNames[6] = {"-x", "+x", "-y", "+y", "-z", "+z"};
// friction < 0 means no-slip; 0 = free slip; > 0 = Coulomb with mu_w (Appendix A, corrected).
struct WallSpec {
  double friction = 0;
};

// A release gate (mpm/Gate.hpp): a plane normal to x at `x` holding the material on its
// upstream side (x below `x`) above its lower edge, which is lifted along z. Heights are in
// the grid frame: for an inclined flume (gravity rotated, grid not) z is the bed normal.
// Edge height z_g(t) = bottom + speed * max(0, t - openAt); speed 0 or infinity: the gate is
// removed at once at openAt. Applied on the grid nodes after gravity and external forces and
// before the walls. Units and ranges: the "gate." entries of mpm/MpmParameters
// (docs/parameters.md), against which makeSolver checks them (ParameterError naming the key).
struct GateSpec {
  bool enabled = false;  // false: no gate
  double x = 0;          // plane position, inside the material region (inside the wall layers)
  double bottom = 0;     // z_0, height of the lower edge until openAt
  double speed = 0;      // lift speed of the edge (0 or infinity: instant removal at openAt)
  double openAt = 0;     // t_open, when the lift starts
  double friction = 0;   // Coulomb coefficient between material and gate (0 = smooth)
};

// The scene's keys, units and ranges of these members: mpm/MpmParameters (docs/parameters.md).
struct MpmParams {
  double dx = 0.01;                        // grid spacing Delta x
  std::array<double, 3> origin{0, 0, 0};   // lower corner of the grid domain
  std::array<int, 3> cells{10, 10, 10};    // number of cells per axis (nodes = cells+1)
  std::array<double, 3> gravity{0, 0, -9.81};  // incline: rotate gravity, not the grid
  FlipBlend flip;                          // the FLIP/PIC blend of Eq 4 (mpm/FlipBlend.hpp)
  double cfl = 0.3;                        // CFL number for the time-step estimate
  // Keep a second copy of the particle state (default true), so that a step that fails (NaN,
  // blow-up) leaves the particles as they were at its start, ready to be saved. false: one
  // copy, updated in place, 125 B per particle less in double and 65 in float
  // (docs/benchmarks.md), with results equal to the last bit; a failed step then leaves the
  // particles partly advanced: the solver refuses to step or hand them out again
  // (MpmSolver::holdsLastGoodState), and the last good state is the last snapshot saved. The
  // CUDA backend keeps the copy either way.
  bool keepLastGoodState = true;
  std::array<WallSpec, 6> walls{};         // box walls of the grid domain
  GateSpec gate{};                         // release gate (default: none)
  TerrainSpec terrain{};                   // terrain under the flow (default: none)
  GranularMaterial material{};
};

// Structure-of-arrays particle storage (host side, double).
struct ParticleSet {
  std::vector<double> x, v;        // position [m], velocity [m/s]: 3 per particle
  std::vector<double> stress;      // Cauchy stress (tension positive) [Pa]: 6 per particle, xx yy zz yz xz xy
  std::vector<double> mass;        // [kg]
  std::vector<double> volume0;     // initial volume [m^3]
  std::vector<double> J;           // det F, current volume = J * volume0
  std::vector<double> gammaDotP;   // equivalent plastic shear rate of the last step [1/s]
  std::vector<double> fext;        // external force on the particle this step [N]: 3 per particle (coupling, Eq 14)
  std::vector<std::uint8_t> phase; // 0 = dense elastic, 1 = dense plastic (flowing), 2 = gasified (stress-free)
  std::size_t size() const { return mass.size(); }
  // Current density rho = m / (J V0) of particle i [kg/m^3].
  double density(std::size_t i) const { return mass[i] / (J[i] * volume0[i]); }
  // How an array may be absent: a kRequired array always holds values; a set handed to a
  // solver may leave the others empty (the solver starts them: no plastic rate, dense elastic,
  // no external force); a snapshot holds every array but kNotInSnapshot.
  enum ArrayUse { kRequired, kOptional, kNotInSnapshot };
  // Calls f(name, valuesPerParticle, use, s.member...) for every per-particle array, with the
  // same member of each set given.
  template <typename F, typename... Sets>
  static void forEachArray(F&& f, Sets&... s) {
    f("x", 3, kRequired, s.x...);
    f("v", 3, kRequired, s.v...);
    f("stress", 6, kRequired, s.stress...);
    f("mass", 1, kRequired, s.mass...);
    f("volume0", 1, kRequired, s.volume0...);
    f("J", 1, kRequired, s.J...);
    f("gammaDotP", 1, kOptional, s.gammaDotP...);
    f("phase", 1, kOptional, s.phase...);
    f("fext", 3, kNotInSnapshot, s.fext...);
  }
  // Throws ParameterError naming the first array whose length is not its values per particle
  // times size() (the number of masses): for a set handed to a solver (forSolver: optional
  // arrays may be empty) or for a snapshot (every array but the external force).
  void validateSizes(bool forSolver) const {
    const std::size_t n = size();
    forEachArray(
        [&](const char* name, std::size_t per, ArrayUse use, const auto& a) {
          if (a.size() == per * n) return;
          if (forSolver ? use != kRequired && a.empty() : use == kNotInSnapshot) return;
          std::ostringstream range;
          range << per << " x " << n << " values (" << n << " particles: the number of masses)";
          throwParameter(std::string("ParticleSet.") + name + ".size()", a.size(), "", range.str());
        },
        *this);
  }
};

// The per-particle arrays of a particle snapshot, as the HDF5 snapshots (io::Hdf5Writer) and
// MpmEngine.particles() give them: name, values per particle, what they hold (the density,
// m / (J V0), is derived for readers and never read back) and, for the doubles of the state, the
// ParticleSet member holding them. The external forces are not part of a snapshot.
enum class ColumnKind { kState, kPhase, kDensity };
struct ParticleColumn {
  const char* name;
  std::size_t values;
  ColumnKind kind;
  std::vector<double> ParticleSet::*member;  // null unless kind is kState
};
inline constexpr ParticleColumn kParticleColumns[] = {
    {"x", 3, ColumnKind::kState, &ParticleSet::x},
    {"v", 3, ColumnKind::kState, &ParticleSet::v},
    {"stress", 6, ColumnKind::kState, &ParticleSet::stress},
    {"density", 1, ColumnKind::kDensity, nullptr},
    {"phase", 1, ColumnKind::kPhase, nullptr},
    {"gammaDotP", 1, ColumnKind::kState, &ParticleSet::gammaDotP},
    {"mass", 1, ColumnKind::kState, &ParticleSet::mass},
    {"volume0", 1, ColumnKind::kState, &ParticleSet::volume0},
    {"J", 1, ColumnKind::kState, &ParticleSet::J}};

// Particles [first, first + count) of `from` into `to` (an optional array left empty in `from`
// stays empty); the range must lie within `from`.
inline void copyParticleRange(const ParticleSet& from, std::size_t first, std::size_t count, ParticleSet& to) {
  ParticleSet::forEachArray(
      [first, count](const char*, std::size_t per, ParticleSet::ArrayUse, const auto& a, auto& b) {
        if (a.empty())
          b.clear();
        else
          b.assign(a.begin() + per * first, a.begin() + per * (first + count));
      },
      from, to);
}

// Throws ParameterError, naming `what` (e.g. "particle slice"), unless particles
// [first, first + count) lie within the n particles (of `whose`, e.g. " of /snapshots/3 in f.h5").
inline void validateSliceRange(const char* what, std::size_t first, std::size_t count, std::size_t n,
                               const std::string& whose = "") {
  if (first > n || count > n - first)
    throwParameter(what, std::to_string(first) + " + " + std::to_string(count), "",
                   "within the " + std::to_string(n) + " particles" + whose);
}

// Particles handed out in slices by particle number, so that a writer needs a slice of the
// set on the host at a time and not the whole set (an output of 10^6 particles would otherwise
// add 145 B per particle to the solver's memory while it is written).
class ParticleSlices {
 public:
  virtual ~ParticleSlices() = default;
  virtual std::size_t size() const = 0;       // particles in all
  virtual std::size_t sliceSize() const = 0;  // particles per slice (> 0)
  // Particles [first, first + count) by number; valid until the next call.
  virtual const ParticleSet& slice(std::size_t first, std::size_t count) = 0;
};

// Calls fn(first, slice) for the slices of `particles` in order, after checking that each came
// back with the particles asked for.
template <typename Fn>
void forEachSlice(ParticleSlices& particles, Fn&& fn) {
  const std::size_t n = particles.size();
  for (std::size_t first = 0; first < n; first += particles.sliceSize()) {
    const std::size_t count = std::min(particles.sliceSize(), n - first);
    const ParticleSet& p = particles.slice(first, count);
    if (p.size() != count)
      throwParameter("particle slice " + std::to_string(first) + " size", p.size(), "", std::to_string(count));
    fn(first, p);
  }
}

// A set already on the host: one slice, the set itself.
class WholeParticleSet : public ParticleSlices {
 public:
  explicit WholeParticleSet(const ParticleSet& set) : set_(set) {}
  std::size_t size() const override { return set_.size(); }
  std::size_t sliceSize() const override { return set_.size() ? set_.size() : 1; }
  const ParticleSet& slice(std::size_t first, std::size_t count) override {
    if (first != 0 || count != set_.size())
      throwParameter("slice", std::to_string(first) + " + " + std::to_string(count), "",
                     "0 + " + std::to_string(set_.size()) + " (a whole set is one slice)");
    return set_;
  }

 private:
  const ParticleSet& set_;
};

}  // namespace mpm
}  // namespace mpmsdem
