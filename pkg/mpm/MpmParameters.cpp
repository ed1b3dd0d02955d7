#include "mpm/MpmParameters.hpp"

#include <cmath>

#include "mpm/FlipBlend.hpp"
#include "mpm/GridBoundary.hpp"
#include "mpm/MpmTypes.hpp"

namespace mpmsdem {
namespace mpm {

// The defaults of the keys a scene may leave out are the structs' (MpmParams, GranularMaterial,
// GateSpec): the table names them, the structs hold them.
ParameterTable listSolverParameters() {
  using namespace parameter_entries;
  const MpmParams p{};
  const GranularMaterial& m = p.material;
  const GateSpec& g = p.gate;
  // key, python, kind, unit, default, default in words, lo, hi, lo and hi allowed, range in
  // words, equation, meaning
  return {
      {"grid", "grid", K::kObject, "", kNone, kRequired, 0, 0, false, false, "", "",
       "the grid box; its walls act on the kWallLayer = 2 outer node layers, so material lies in the material region "
       "[origin + 2 dx, origin + (cells - 2) dx]"},
      {"gravity", "gravity", K::kVector, "m/s^2", kNone, "[0, 0, -9.81]", 0, 0, false, false,
       "[gx, gy, gz], or an object {g, incline_deg}", "",
       "gravity; as an object a flume inclined by incline_deg about y, descending toward +x: g (sin a, 0, -cos a)"},
      {"flip_viscosity", "flipViscosity", K::kNumber, "m^2/s", FlipBlend::kDefaultViscosity, "", 0, kInf, false, false, "", "Eq 4",
       "PIC viscosity nu of the FLIP/PIC blend: a step of length dt hands PIC the share 4 nu dt / dx^2 (the stable "
       "step is at most dx^2 / (4 nu)), the same flow at any step and grid (docs/physics.md, \"The blend as a "
       "viscosity\")"},
      {"flip_alpha", "flipAlpha", K::kNumber, "", FlipBlend::kTableAlpha, "", 0, 1, true, true, "", "Eq 4, Table 1",
       "instead of flip_viscosity: the FLIP fraction alpha kept per flip_reference_dt of simulated time; needs "
       "flip_reference_dt"},
      {"flip_reference_dt", "flipReferenceDt", K::kNumber, "s", kNone, "none", 0, kInf, false, false,
       "in (0, inf), or \"step\"", "Eq 4",
       "the reference step of flip_alpha (the paper's: 5e-6 s); \"step\": alpha per step, Eq 4 as written (the "
       "damping then changes with the step)"},
      {"cfl", "cfl", K::kNumber, "", p.cfl, "", 0, 1, false, true, "", "", "CFL number of the stable-step estimate"},
      {"keep_last_good_state", "keepLastGoodState", K::kBoolean, "", kNone, p.keepLastGoodState ? "true" : "false",
       0, 0, false, false, "", "",
       "keep a second copy of the particles, so that a failed step leaves the state at its start to save; false: "
       "one copy (docs/benchmarks.md), a failed step then leaves no state beyond the last snapshot"},
      {"walls", "walls", K::kObject, "", kNone, "\"free\" on every face", 0, 0, false, false,
       "keys -x, +x, -y, +y, -z, +z", "", "the six walls of the grid box; walls never let material through"},
      {"gate", "gate", K::kObject, "", kNone, "none", 0, 0, false, false, "", "",
       "a release gate (mpm/Gate.hpp): a plane normal to x holding the material upstream of it above its lower edge, "
       "which is lifted along z"},
      {"material", "material", K::kObject, "", kNone, kRequired, 0, 0, false, false, "", "Appendix B",
       "the granular material (mu(I) rheology)"},
      {"grid.dx", "dx", K::kNumber, "m", kNone, kRequired, 0, kInf, false, false, "", "", "cell size"},
      {"grid.cells", "cells", K::kInteger, "", kNone, kRequired, 2 * kWallLayer, double(1L << 30), true, true, "", "",
       "cells per axis [nx, ny, nz] (nodes: cells + 1)"},
      {"grid.origin", "origin", K::kVector, "m", kNone, "[0, 0, 0]", 0, 0, false, false, "", "",
       "lower corner of the grid box"},

      {"gravity.g", "g", K::kNumber, "m/s^2", kNone, kRequired, 0, kInf, true, false, "", "", "magnitude"},
      {"gravity.incline_deg", "incline_deg", K::kNumber, "deg", 0, "", 0, 90, true, false, "", "",
       "inclination of the flume about y"},

      {"walls.<face>", "<face>", K::kNumber, "", kNone, "\"free\"", 0, kInf, true, false,
       "\"free\", \"noslip\" or in [0, inf)", "Appendix A",
       "a wall's friction: free slip, no slip or a Coulomb coefficient (0: free slip)"},

      {"gate.x", "x", K::kNumber, "m", kNone, kRequired, -kInf, kInf, true, true, "in the material region", "",
       "plane of the gate, normal to x; it holds the material upstream of it (x below)"},
      {"gate.bottom", "bottom", K::kNumber, "m", g.bottom, "", -kInf, kInf, true, true, "any", "",
       "z_0, height of the lower edge until open_at (z is the bed normal in a flume)"},
      {"gate.speed", "speed", K::kNumber, "m/s", g.speed, "", 0, kInf, true, false, "", "",
       "lift speed of the edge; 0: removed at once at open_at; the edge is at z_0 + speed max(0, t - open_at)"},
      {"gate.open_at", "open_at", K::kNumber, "s", g.openAt, "", 0, kInf, true, false, "", "",
       "t_open, when the lift starts"},
      {"gate.friction", "friction", K::kNumber, "", g.friction, "", 0, kInf, true, false, "", "",
       "Coulomb coefficient between material and gate (0: smooth)"},

      {"material.density", "density", K::kNumber, "kg/m^3", kNone, kRequired, 0, kInf, false, false, "", "",
       "rho_0, initial bulk density of the material points"},
      {"material.young_modulus", "young_modulus", K::kNumber, "Pa", kNone, kRequired, 0, kInf, false, false, "",
       "Table 1", "E, Young's modulus"},
      {"material.poisson_ratio", "poisson_ratio", K::kNumber, "", kNone, kRequired, 0, 0.5, true, false, "", "",
       "nu, Poisson's ratio"},
      {"material.mu_s", "mu_s", K::kNumber, "", kNone, kRequired, 0, kInf, true, false, "", "Eq B.2",
       "mu_s, static friction coefficient"},
      {"material.mu_2", "mu_2", K::kNumber, "", kNone, kRequired, 0, kInf, true, false, "[mu_s, inf)", "Eq B.2",
       "mu_2, limiting dynamic friction coefficient"},
      {"material.I0", "I0", K::kNumber, "", m.I0, "", 0, kInf, false, false, "", "Eq B.2",
       "I_0, inertial-number scale"},
      {"material.grain_diameter", "grain_diameter", K::kNumber, "m", m.grainDiameter, "", 0, kInf, false, false, "",
       "Eq B.2", "d, grain diameter of the inertial number"},
      {"material.solid_density", "solid_density", K::kNumber, "kg/m^3", m.solidDensity, "", 0, kInf, false, false,
       "", "", "rho_s, grain density"},
      {"material.critical_density", "critical_density", K::kNumber, "kg/m^3", m.criticalDensity, "", 0, kInf, true,
       false, "", "§2.1", "rho_c; stress-free below it; 0: rho_0"},
  };
}

}  // namespace mpm
}  // namespace mpmsdem
