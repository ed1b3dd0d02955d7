// A JSON-described MPM scene: grid, material, walls, particle boxes and run settings, as
// read by the plain C++ driver `mpmsdem-run` (apps/mpmsdem-run.cpp). SI units throughout.
//
// Schema (keys are case-sensitive; an unknown key anywhere is a ParameterError naming it;
// "(req)" marks required keys, the others show their default). Each key's unit and range are
// its entry in scene/SceneParameters, which the parser checks against (docs/parameters.md is
// generated from it); this is the shape of a scene:
//
// {
//   "description": "free text (optional)",
//   "grid": {                       (req)
//     "dx": 0.01,                   (req) cell size
//     "cells": [180, 20, 40],       (req) cells per axis
//     "origin": [0, 0, 0]           lower corner of the grid box
//   },                              The walls act on the 2 outer node layers (kWallLayer),
//                                   so particles must lie in [origin + 2 dx, origin + (cells-2) dx].
//   "gravity": [0, 0, -9.81]        or {"g": 9.81, "incline_deg": 10}: a flume
//                                   inclined by incline_deg about y, descending
//                                   toward +x: gravity = g (sin a, 0, -cos a).
//   "flip_viscosity": 0.005,        PIC viscosity of the FLIP/PIC blend (Eq 4)
//                                   (mpm/FlipBlend.hpp): a step of length dt hands PIC the
//                                   share 4 nu dt / dx^2, the same flow at any step and grid
//   "flip_alpha": 0.99,             instead of flip_viscosity: alpha kept per
//   "flip_reference_dt": 5e-6,      flip_reference_dt of simulated time, or "step":
//                                   alpha per step, as Eq 4 is written (the damping then
//                                   changes with the step); flip_alpha needs flip_reference_dt
//   "cfl": 0.3,                     CFL number of the stable-step estimate
//   "keep_last_good_state": true,   false: one copy of the particles, 109 (double) or 57
//                                   (float) bytes per particle less; a failed step then leaves
//                                   no state to save beyond the last snapshot
//                                   (MpmParams::keepLastGoodState)
//   "walls": {"-x": "free", "+x": "free", "-y": "free", "+y": "free", "-z": "free", "+z": "free"},
//                                   each wall: "free" (free slip, the default), "noslip",
//                                   or a Coulomb friction coefficient (0 = free slip).
//                                   Walls never let material through.
//   "gate": {                       a release gate (mpm/Gate.hpp); absent: none
//     "x": 0.3,                     (req) plane of the gate, normal to x, in the material
//                                   region; it holds the material upstream of it (x below)
//     "bottom": 0,                  z_0, height of its lower edge until open_at (z is the
//                                   bed normal in a flume: gravity is rotated, the grid not)
//     "speed": 0,                   lift speed of the edge; 0: removed at once
//     "open_at": 0,                 t_open, when the lift starts; the edge is at
//                                   z_0 + speed * max(0, t - open_at)
//     "friction": 0                 Coulomb coefficient between material and gate
//   },
//   "material": {                   (req)
//     "density": 1600,              (req) initial bulk density rho_0
//     "young_modulus": 1e6,         (req) Young's modulus E
//     "poisson_ratio": 0.3,         (req) Poisson's ratio nu
//     "mu_s": 0.24,                 (req) static friction coefficient
//     "mu_2": 0.65,                 (req) limiting friction coefficient
//     "I0": 0.279,                  inertial-number scale
//     "grain_diameter": 0.002,      grain diameter d
//     "solid_density": 2500,        grain density rho_s
//     "critical_density": 0         critical density rho_c; 0 means rho_0
//   },
//   "particles": [                  (req) list of non-overlapping entries, each a box or a
//                                   closed triangle mesh; [] for a scene without flow:
//     {"lo": [x,y,z], "hi": [x,y,z],   (req for a box) box corners on grid lines (origin + k dx),
//                                      hi > lo on every axis, inside the material region
//      "ppc": 8,                       particles per cell: a cube n^3 (1, 8, 27, ..., 512) or
//                                      per axis [nx, ny, nz]
//      "velocity": [0, 0, 0]},         initial velocity
//     {"mesh": "block.stl",            (req for a mesh) closed triangle mesh, .stl (ASCII or
//                                      binary) or .obj; a relative path is taken from the scene
//                                      file's folder (loadScene) or as given (parseScene without
//                                      a base folder). The mesh must be watertight and
//                                      consistently oriented (every edge shared by exactly 2
//                                      triangles), enclose a volume, and lie, once placed,
//                                      inside the material region.
//      "scale": 1.0,                   factor on the file's coordinates (0.001 for millimetres)
//      "offset": [0, 0, 0],            added to the scaled coordinates
//      "ppc": 8, "velocity": [0, 0, 0]}   as for a box
//   ],                              A mesh entry may not have lo/hi, a box entry may not have
//                                   mesh/scale/offset. Overlap: two boxes may touch but not
//                                   overlap; a mesh's bounding box may not overlap any other
//                                   entry's box or mesh bounding box (a refusal by bounding
//                                   boxes: simple, and it never lets two entries put material
//                                   in the same place, whatever their ppc).
//   "flow_probes": [                stations where the flow's depth and velocity are recorded
//                                   (the paper's free-flow tests, §3.2.3 and §5: h_f and v_f at
//                                   a block's station, run without the block); absent: none
//     {"x": 0.51,                   (req) station along x, inside the material region
//      "half_width": dx,            the points with |x_p - x| <= half_width are the flow at the
//                                   station
//      "bed_z": 0,                  bed height: depth = highest of those points - bed_z
//      "min_points": 4,             with fewer points the front has not arrived
//      "window": 0.05}              h_f, v_f: means over the records within window
//   ],                              after the arrival (mpm::FlowProbeRecord). Recorded every
//                                   run.series_every; the driver writes the results to
//                                   flow_probes.json
//   "blocks": [...], "block_materials": {...}   rigid blocks coupled with the flow: see
//                                   pkg/coupling/CoupledScene.hpp (a scene without them is MPM only)
//   "run": {                        (req)
//     "duration": 1.0,              (req) simulated time
//     "dt": "auto",                 fixed step, or "auto": dt_factor * the stable step,
//                                   re-evaluated every step (with blocks: coupling::coupledAutoStep,
//                                   which also bounds how far a block moves in a step, how deep
//                                   a material point may start a step in a barrier it has just
//                                   reached, and how fast the step grows)
//     "dt_factor": 0.9,             only with "dt": "auto"
//     "min_step_fraction": 1e-4,    with "dt": "auto", the run stops (last good state saved,
//                                   exit 3) when the step falls below this fraction of the
//                                   flow's CFL step, naming what forces it (a block's speed, a
//                                   contact): a run at such steps crawls; 0: never
//     "max_block_speed": 10 c_p,    a block whose speed (|v| + |w| times its bounding
//                                   radius) exceeds it at load is refused, naming it. Default ten
//                                   times the flow's P-wave speed c_p = sqrt((K + 4G/3)/rho_0),
//                                   far beyond any speed the scene's waves or flows reach
//     "stop_when_probed": false,    true: end the run at the first series record after every
//                                   flow probe's arrival + window (its result is complete)
//     "stop_when_front_still": 0,   end the run when the front (the largest particle x)
//                                   has not advanced by dx/2 for this long at the series records
//                                   (a flow that stopped); 0: never
//     "snapshot_when_front_at": none, a number: at the first series record where the front
//                                   (the largest particle x) has reached this x, write a snapshot
//                                   and front_snapshot.json naming it (with the blocks' MP
//                                   contacts in a coupled run): another scene of the same flow
//                                   starts there with mpmsdem-run --flow-from (the blocks ahead
//                                   of the front join it, their steps before it run alone). A
//                                   list of ascending numbers: one such state for each, named
//                                   front_snapshot_<k>.json (k from 0, the list's order)
//     "progress_every": 10,         wall time: a progress line at least this often
//                                   (and every 5 % of the run), with the step and what limits it
//     "output_every": duration/20,  snapshot interval (HDF5 snapshot + VTK file)
//     "series_every": output_every/10,  time-series interval
//     "output_dir": "out",          created when absent
//     "vtk": "raw",                 VTK particle files: "raw" (appended binary), "ascii", "none"
//     "backend": "cpu",             "cpu" or "cuda"
//     "precision": "double"         "double" or "float", on either backend
//   }
// }
//
// Seeding (mpm::seedBox): every grid cell of a box gets nx ny nz particles at the centres
// of an equal subdivision of the cell, each with volume dx^3/(nx ny nz), mass rho_0 times
// that, zero stress, J = 1 and the box velocity. Particle count of a box =
// box volume / dx^3 * nx ny nz; total mass = rho_0 * box volume.
// A mesh (mpm::seedMesh) gets the same candidate points over the cells covering its bounding
// box and keeps those inside the surface, with the same volume and mass each: its total mass
// is rho_0 * mesh volume up to about the surface area times the point spacing / 2 (exactly
// that of the box for a box-shaped mesh with faces on grid lines).
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "common/Types.hpp"
#include "mpm/Diagnostics.hpp"
#include "mpm/MpmSolver.hpp"
#include "mpm/MpmTypes.hpp"
#include "mpm/Seeding.hpp"

namespace mpmsdem {
namespace mpm {

// One entry of "particles" (see above): a box, or a closed triangle mesh when `mesh` is set.
// Units and ranges: the "particles[]." entries of scene/SceneParameters.
struct ParticleBox {
  std::array<double, 3> lo{0, 0, 0};        // lower corner (a mesh: of its bounding box)
  std::array<double, 3> hi{0, 0, 0};        // upper corner (a mesh: of its bounding box)
  std::array<int, 3> ppc{2, 2, 2};          // particles per cell per axis
  std::array<double, 3> velocity{0, 0, 0};  // initial velocity
  std::string mesh;                         // mesh file as resolved (scene folder applied); empty: a box
  double scale = 1.0;                       // factor on the file's coordinates
  std::array<double, 3> offset{0, 0, 0};    // added to the scaled coordinates
  std::vector<Vec3> vertices;               // the mesh's vertices after scale and offset [m]
  std::vector<std::array<int, 3>> triangles;  // the mesh's triangles (vertex indices)
};

// How the scene is run and written (see "run" above; units and ranges: the "run." entries of
// scene/SceneParameters, docs/parameters.md).
struct RunSettings {
  double duration = 0;            // simulated time
  double dt = 0;                  // fixed step; 0 means "auto"
  double dtFactor = 0.9;          // auto step = dtFactor * stableTimeStep()
  double minStepFraction = 1e-4;  // auto step floor, a fraction of the CFL step
  double maxBlockSpeed = 0;       // 0: 10 x the flow's P-wave speed (set by parseScene)
  double progressEvery = 10;      // wall-time interval of progress lines
  bool stopWhenProbed = false;    // end once every flow probe's result is complete
  double stopWhenFrontStill = 0;  // end when the front has been still this long; 0: never
  // run.snapshot_when_front_at: the x at which the front's first arrival is saved, ascending
  // (empty: none); indexed: given as a list, so the records are front_snapshot_<k>.json
  std::vector<double> snapshotsWhenFrontAt;
  bool snapshotsIndexed = false;
  double outputEvery = 0;         // snapshot interval
  double seriesEvery = 0;         // time-series record interval
  std::string outputDir = "out";  // output folder
  std::string vtk = "raw";        // "raw", "ascii" or "none"
  Backend backend = Backend::Cpu;
  Precision precision = Precision::Double;
};

struct MpmScene {
  MpmParams params;
  std::vector<ParticleBox> boxes;  // the "particles" entries, boxes and meshes, in order
  RunSettings run;
  std::vector<FlowProbeSpec> probes;  // "flow_probes", in order
  std::string sourceJson;  // the scene as parsed (compact JSON), kept for output metadata
};

// Parse and validate a scene (mesh files are read and checked here). Throws ParameterError
// naming the key path (e.g. "material.poisson_ratio") and the allowed range; `source` names
// the text in messages; relative mesh paths are taken from `baseDir` (as given when empty).
MpmScene parseScene(const std::string& jsonText, const std::string& source = "scene",
                    const std::string& baseDir = "");
// Read the file and parse it, mesh paths relative to the file's folder; a missing file, one
// that is not a regular file (a device, a pipe) or one above kMaxSceneBytes is a
// ParameterError naming the path.
constexpr std::uintmax_t kMaxSceneBytes = 16u << 20;
MpmScene loadScene(const std::string& path);

// Memory of the grid and the particles a scene needs, for an out-of-memory message that names
// grid.cells and the particle count (the solver's own estimate of its arrays).
std::string sceneSizeDescription(const MpmScene& scene);

// Lower and upper corners of the region open to material points (inside the wall layers).
std::array<double, 3> materialRegionLo(const MpmParams& params);
std::array<double, 3> materialRegionHi(const MpmParams& params);

// Material points of all entries (boxes and meshes), in entry order (see "Seeding" above).
ParticleSet seedParticles(const MpmScene& scene);
// The same points held compactly, for MpmSolver::setParticles(ParticleSlices&).
SeededParticles seedParticleSlices(const MpmScene& scene);

const char* backendName(Backend backend);
const char* precisionName(Precision precision);

}  // namespace mpm
}  // namespace mpmsdem
