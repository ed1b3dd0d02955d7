#include "scene/SceneParameters.hpp"

#include <cmath>

#include "mpm/Diagnostics.hpp"
#include "mpm/MpmTypes.hpp"
#include "scene/MpmScene.hpp"

namespace mpmsdem {
namespace mpm {

namespace {

using K = ParameterKind;
constexpr double kInf = INFINITY, kNone = NAN;

// The defaults of the keys a scene may leave out are the structs' (MpmParams, GranularMaterial,
// GateSpec, FlowProbeSpec, RunSettings): the table names them, the structs hold them.
ParameterTable makeTable() {
  const MpmParams p{};
  const GranularMaterial& m = p.material;
  const GateSpec& g = p.gate;
  const FlowProbeSpec probe{};
  const RunSettings r{};
  // key, python, kind, unit, default, default in words, lo, hi, lo and hi allowed, range in
  // words (a kChoice: its choices), equation, meaning
  return {
      {"description", "", K::kText, "", kNone, "", 0, 0, false, false, "a string", "",
       "free text, kept in the outputs"},
      {"grid", "grid", K::kObject, "", kNone, kRequired, 0, 0, false, false, "", "",
       "the grid box; its walls act on the kWallLayer = 2 outer node layers, so material lies in the material region "
       "[origin + 2 dx, origin + (cells - 2) dx]"},
      {"gravity", "gravity", K::kVector, "m/s^2", kNone, "[0, 0, -9.81]", 0, 0, false, false,
       "[gx, gy, gz], or an object {g, incline_deg}", "",
       "gravity; as an object a flume inclined by incline_deg about y, descending toward +x: g (sin a, 0, -cos a)"},
      {"flip_viscosity", "flipViscosity", K::kNumber, "m^2/s", FlipBlend::kDefaultViscosity, "", 0, kInf, false, false, "", "Eq 4",
       "PIC viscosity nu of the FLIP/PIC blend: a step of length dt blends with exp(-4 nu dt / dx^2) of FLIP, the "
       "same flow at any step and grid (docs/physics.md, \"The blend as a viscosity\")"},
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
      {"terrain", "terrain", K::kObject, "", kNone, "none", 0, 0, false, false,
       "{file, origin, friction} or {nx, ny, x0, y0, spacing, heights, friction}", "",
       "a raster height field under the flow (an ESRI ASCII grid or the heights themselves); boxes are seeded above "
       "it"},
      {"material", "material", K::kObject, "", kNone, kRequired, 0, 0, false, false, "", "Appendix B",
       "the granular material (mu(I) rheology)"},
      {"particles", "particles", K::kObject, "", kNone, kRequired, 0, 0, false, false,
       "a list of boxes and closed meshes, disjoint; [] for a scene without flow", "",
       "the material points' initial regions"},
      {"flow_probes", "flowProbes", K::kObject, "", kNone, "none", 0, 0, false, false, "a list of probes", "",
       "stations where the flow's depth and velocity are recorded (the paper's free-flow tests, §3.2.3 and §5)"},
      {"run", "", K::kObject, "", kNone, kRequired, 0, 0, false, false, "", "",
       "how the scene is run and written; in Python the keywords of mpmsdem.driver.writeScene"},

      {"grid.dx", "dx", K::kNumber, "m", kNone, kRequired, 0, kInf, false, false, "", "", "cell size"},
      {"grid.cells", "cells", K::kInteger, "", kNone, kRequired, 4, double(1L << 30), true, true, "", "",
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

      {"terrain.file", "file", K::kText, "", kNone, "", 0, 0, false, false, "a path to an ESRI ASCII grid (.asc)", "",
       "the raster, relative to the scene file's folder"},
      {"terrain.origin", "origin", K::kVector, "m", kNone, "[0, 0, 0]", 0, 0, false, false, "", "",
       "with file: the file's point that goes to the grid frame's zero"},
      {"terrain.friction", "friction", K::kNumber, "", kNone, "\"free\"", 0, kInf, true, false,
       "\"free\", \"noslip\" or in [0, inf)", "", "friction between the flow and the terrain, as for the walls"},
      {"terrain.nx", "nx", K::kNumber, "", kNone, kRequired, 2, 1e8, true, true, "a whole number in [2, 1e+08]", "",
       "without file: heights along x"},
      {"terrain.ny", "ny", K::kNumber, "", kNone, kRequired, 2, 1e8, true, true, "a whole number in [2, 1e+08]", "",
       "without file: heights along y"},
      {"terrain.x0", "x0", K::kNumber, "m", kNone, kRequired, -kInf, kInf, true, true, "any", "",
       "without file: x of the first height"},
      {"terrain.y0", "y0", K::kNumber, "m", kNone, kRequired, -kInf, kInf, true, true, "any", "",
       "without file: y of the first height"},
      {"terrain.spacing", "spacing", K::kNumber, "m", kNone, kRequired, 0, kInf, false, false, "", "",
       "without file: distance between heights"},
      {"terrain.heights", "heights", K::kVector, "m", kNone, kRequired, 0, 0, false, false, "nx * ny numbers", "",
       "without file: the heights, i-major (heights[i * ny + j])"},

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

      {"particles[].lo", "lo", K::kVector, "m", kNone, kRequired, 0, 0, false, false,
       "on grid lines, inside the material region", "", "a box's lower corner"},
      {"particles[].hi", "hi", K::kVector, "m", kNone, kRequired, 0, 0, false, false,
       "on grid lines, > lo, inside the material region", "", "a box's upper corner"},
      {"particles[].mesh", "mesh", K::kText, "", kNone, "", 0, 0, false, false, "a path to a .stl or .obj file", "",
       "instead of lo and hi: a closed, consistently oriented triangle mesh, relative to the scene file's folder"},
      {"particles[].scale", "scale", K::kNumber, "", 1.0, "", 0, kInf, false, false, "", "",
       "with mesh: factor on the file's coordinates (0.001 for millimetres)"},
      {"particles[].offset", "offset", K::kVector, "m", kNone, "[0, 0, 0]", 0, 0, false, false, "", "",
       "with mesh: added to the scaled coordinates"},
      {"particles[].ppc", "ppc", K::kInteger, "", kNone, "8", 1, 8, true, true,
       "a cube n^3 with n in [1, 8], or [nx, ny, nz] each in [1, 8]", "", "particles per cell"},
      {"particles[].velocity", "velocity", K::kVector, "m/s", kNone, "[0, 0, 0]", 0, 0, false, false, "", "",
       "initial velocity"},

      {"flow_probes[].x", "x", K::kNumber, "m", kNone, kRequired, -kInf, kInf, true, true, "in the material region", "",
       "station along x"},
      {"flow_probes[].half_width", "halfWidth", K::kNumber, "m", kNone, "grid.dx", 0, kInf, false, false, "", "",
       "the points with |x_p - x| <= half_width are the flow at the station"},
      {"flow_probes[].bed_z", "bedZ", K::kNumber, "m", probe.bedZ, "", -kInf, kInf, true, true, "any", "",
       "bed height: depth = highest of those points - bed_z"},
      {"flow_probes[].min_points", "minPoints", K::kInteger, "", double(probe.minPoints), "", 1, double(1L << 30),
       true, true, "", "", "with fewer points the front has not arrived"},
      {"flow_probes[].window", "window", K::kNumber, "s", probe.window, "", 0, kInf, true, false, "", "",
       "h_f and v_f: means over the records within window after the arrival"},

      {"run.duration", "duration", K::kNumber, "s", kNone, kRequired, 0, kInf, false, false, "", "", "simulated time"},
      {"run.dt", "dt", K::kNumber, "s", kNone, "\"auto\"", 0, kInf, false, true, "\"auto\" or in (0, run.duration]",
       "", "fixed step; \"auto\": dt_factor times the stable step, re-evaluated every step"},
      {"run.dt_factor", "dtFactor", K::kNumber, "", r.dtFactor, "", 0, 1, false, true, "", "",
       "with dt \"auto\": the fraction of the stable step taken"},
      {"run.output_every", "outputEvery", K::kNumber, "s", kNone, "run.duration / 20", 0, kInf, false, false, "", "",
       "snapshot interval (HDF5 snapshot and VTK file)"},
      {"run.series_every", "seriesEvery", K::kNumber, "s", kNone, "run.output_every / 10", 0, kInf, false, false, "",
       "", "time-series interval"},
      {"run.output_dir", "outputDir", K::kText, "", kNone, "out", 0, 0, false, false, "a non-empty string", "",
       "output folder, created when absent"},
      {"run.vtk", "vtk", K::kChoice, "", kNone, "raw", 0, 0, false, false, "raw|ascii|none", "",
       "VTK particle files: appended binary, ASCII or none"},
      {"run.backend", "backend", K::kChoice, "", kNone, "cpu", 0, 0, false, false, "cpu|cuda", "", "the solver"},
      {"run.precision", "precision", K::kChoice, "", kNone, "double", 0, 0, false, false, "double|float", "",
       "floating-point precision of the solver, on either backend"},
      {"run.min_step_fraction", "minStepFraction", K::kNumber, "", r.minStepFraction, "", 0, 1, true, false, "", "",
       "with dt \"auto\": the run stops (last good state saved) when the step falls below this fraction of the flow's "
       "CFL step; 0: never"},
      {"run.max_block_speed", "maxBlockSpeed", K::kNumber, "m/s", kNone, "10 c_p", 0, kInf, false, false, "", "",
       "a block faster than this at load (|v| + |w| times its bounding radius) is refused; default ten times the "
       "flow's P-wave speed c_p = sqrt((K + 4G/3) / rho_0)"},
      {"run.progress_every", "progressEvery", K::kNumber, "s", r.progressEvery, "", 0, kInf, false, false, "", "",
       "wall time between progress lines (also every 5 % of the run)"},
      {"run.stop_when_probed", "stopWhenProbed", K::kBoolean, "", kNone, r.stopWhenProbed ? "true" : "false", 0, 0,
       false, false, "", "", "end the run once every flow probe's result is complete"},
      {"run.stop_when_front_still", "stopWhenFrontStill", K::kNumber, "s", r.stopWhenFrontStill, "", 0, kInf, true,
       false, "", "", "end the run when the front has not advanced by dx/2 for this long; 0: never"},
      {"run.snapshot_when_front_at", "snapshotWhenFrontAt", K::kNumber, "m", kNone, "none", -kInf, kInf, false, false,
       "a number, or a non-empty list of ascending numbers", "",
       "write a snapshot and front_snapshot.json when the front first reaches this x (a list: one for each, "
       "front_snapshot_<k>.json), where another scene of the flow starts (mpmsdem-run --flow-from)"},
  };
}

}  // namespace

const ParameterTable& sceneParameters() {
  static const ParameterTable table = makeTable();
  return table;
}

const ParameterSpec& sceneParameter(const char* key) { return findParameter(sceneParameters(), key); }

}  // namespace mpm
}  // namespace mpmsdem
