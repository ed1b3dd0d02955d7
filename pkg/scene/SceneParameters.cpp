#include "scene/SceneParameters.hpp"

#include <cmath>
#include <cstring>

#include "mpm/Diagnostics.hpp"
#include "mpm/MpmParameters.hpp"
#include "scene/MpmScene.hpp"

namespace mpmsdem {
namespace mpm {

namespace {

// The scene's own keys (the particles' regions, the probes, the terrain's raster, the run); the
// flow model's come from mpm/MpmParameters. Their defaults are the structs' (FlowProbeSpec,
// RunSettings): the table names them, the structs hold them.
ParameterTable ownTable() {
  using namespace parameter_entries;
  const FlowProbeSpec probe{};
  const RunSettings r{};
  // key, python, kind, unit, default, default in words, lo, hi, lo and hi allowed, range in
  // words (a kChoice: its choices), equation, meaning
  return {
      {"description", "", K::kText, "", kNone, "", 0, 0, false, false, "a string", "",
       "free text, kept in the outputs"},
      {"terrain", "terrain", K::kObject, "", kNone, "none", 0, 0, false, false,
       "{file, origin, friction} or {nx, ny, x0, y0, spacing, heights, friction}", "",
       "a raster height field under the flow (an ESRI ASCII grid or the heights themselves); boxes are seeded above "
       "it"},
      {"particles", "particles", K::kObject, "", kNone, kRequired, 0, 0, false, false,
       "a list of boxes and closed meshes, disjoint; [] for a scene without flow", "",
       "the material points' initial regions"},
      {"flow_probes", "flowProbes", K::kObject, "", kNone, "none", 0, 0, false, false, "a list of probes", "",
       "stations where the flow's depth and velocity are recorded (the paper's free-flow tests, §3.2.3 and §5)"},
      {"run", "", K::kObject, "", kNone, kRequired, 0, 0, false, false, "", "",
       "how the scene is run and written; in Python the keywords of mpmsdem.driver.writeScene"},

      {"terrain.file", "file", K::kText, "", kNone, "", 0, 0, false, false, "a path to an ESRI ASCII grid (.asc)", "",
       "the raster, relative to the scene file's folder"},
      {"terrain.origin", "origin", K::kVector, "m", kNone, "[0, 0, 0]", 0, 0, false, false, "", "",
       "with file: the file's point that goes to the grid frame's zero"},
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
      {"terrain.friction", "friction", K::kNumber, "", kNone, "\"free\"", 0, kInf, true, false,
       "\"free\", \"noslip\" or in [0, inf)", "", "friction between the flow and the terrain, as for the walls"},

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

bool topLevel(const ParameterSpec& s) { return std::strpbrk(s.key, ".[") == nullptr; }

}  // namespace

// In the order docs/parameters.md shows them: the description, the flow model's objects and
// values, the scene's objects, then the keys under each object in the same order.
ParameterTable listSceneParameters() {
  const ParameterTable own = ownTable(), &model = solverParameter.table();
  ParameterTable table(own.begin(), own.begin() + 1);  // "description"
  for (const bool top : {true, false})
    for (const ParameterTable* from : {&model, &own})
      for (const ParameterSpec& s : *from)
        if (topLevel(s) == top && std::strcmp(s.key, "description") != 0) table.push_back(s);
  return table;
}

}  // namespace mpm
}  // namespace mpmsdem
