// The blocks of a coupled driver scene: the "block_materials" and "blocks" keys of the JSON
// scene that pkg/scene/MpmScene.hpp describes for the flow. SI units; an unknown key is a
// ParameterError naming it, as for the rest of the scene; "(req)" marks required keys. The
// unit, default and range of each key are its entry in coupling/BlockParameters, which the reader
// checks against (docs/parameters.md is generated from it); this is the shape of the blocks:
//
//   "block_materials": {            (req with "blocks") materials by name
//     "copper": {
//       "density": 8900,            (req) block mass = density x rounded volume
//       "friction": 0.5,            block–block Coulomb friction (Eq 9)
//       "poisson": 0.3,             for K_t = k_n / (2 (1 + nu)) (Eq 11)
//       "barrier_stiffness": 1e4,   k_c of Eq 10
//       "normal_damping": 0,        fractions of critical
//       "tangential_damping": 0.1,
//       "flow": {                   (req) contact of the material points with blocks of this
//         "friction": 0.21,         (req)   material (paper Eq 12; the pair's own physics)
//         "barrier_stiffness": 1e4, "poisson": 0.3, "normal_damping": 0, "tangential_damping": 0.1
//       }
//     }
//   },
//   "blocks": [                     rigid sphero-polyhedra (paper §2.2), moved by the driver's
//     {                             rigid-body update (sdem::SdemWorld, as YADE's NewtonIntegrator)
//       "material": "copper",       (req) a key of block_materials
//       "box": [hx, hy, hz],        OUTER half-extents [m] (box of side 2 hx x 2 hy x 2 hz), or
//       "core": {                   a shape table, as mpmsdem.driver.writeScene writes it from
//         "vertices": [[x, y, z], ...],   any SDEM shape (convex hulls and meshes need CGAL to
//         "faces": [[i, j, k, ...], ...], build, not to run): core vertices [m], faces as vertex
//         "convex": true                  loops counter-clockwise seen from outside
//       },
//       "outer": {"vertices": [...], "triangles": [[i, j, k], ...]}   with "core": the outer
//                                   shape, for display only (default: the core)
//       "sweep_radius": 0.001,      (req) R [m] (Eq 7): for a box in (0, min half-extent)
//       "position": [x, y, z],      (req) [m]: where the shape's own origin goes (the centroid for
//                                   a box and for tables written in the body frame)
//       "orientation": [w, x, y, z], unit quaternion, default [1, 0, 0, 0]
//       "velocity": [0, 0, 0],      [m/s], "angular_velocity": [0, 0, 0] [rad/s] (world frame)
//       "fixed": false,             moves only with its set velocities (a flume bed)
//       "blocked_dofs": "",         YADE's blockedDOFs: letters among x y z X Y Z
//       "id": 0                     label in the outputs, an integer >= 0, unique; default its
//     }                             position in the list
//   ],
//   "terrain_material": {           (req with "terrain" and moving blocks) the blocks' contact
//     "friction": 0.5, "poisson": 0.3,   with the flow's terrain (sdem::SdemEngine::setTerrain):
//     "barrier_stiffness": 1e4,          the keys of a block material but "flow" (its laws mix
//     "normal_damping": 0, "tangential_damping": 0.1   with each block's, as a block pair's)
//   }
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "coupling/CoupledWorld.hpp"
#include "sdem/Ip2_SdemMat_SdemMat_BarrierPhys.hpp"
#include "sdem/SdemMaterial.hpp"
#include "sdem/SpheroPolyhedron.hpp"

namespace mpmsdem {
namespace coupling {

struct BlockMaterialSpec {
  std::string name;
  sdem::SdemMaterial material;
  sdem::BarrierPhys flow;  // MP–block pair
};

struct BlockSpec {
  int id = 0;
  int material = 0;  // index into SceneBlocks::materials
  std::shared_ptr<const sdem::SpheroPolyhedron> shape;
  Vec3 position = Vec3::Zero();  // of the shape's input frame origin [m]
  Quat orientation = Quat::Identity();
  Vec3 velocity = Vec3::Zero(), angularVelocity = Vec3::Zero();
  bool fixed = false;
  std::string blockedDofs;
};

struct SceneBlocks {
  std::vector<BlockMaterialSpec> materials;
  std::vector<BlockSpec> blocks;
  std::shared_ptr<const sdem::SdemMaterial> terrainMaterial;  // null: no terrain contacts
  bool empty() const { return blocks.empty(); }
};

// Parse and validate the blocks of a scene (the whole scene's JSON text; the flow keys are
// MpmScene's business). No "blocks" key, or an empty list: no blocks.
SceneBlocks parseBlocks(const std::string& sceneJson);

// Register the materials and pairs and add the bodies to `world`, in scene order (SDEM body
// index = position in `blocks`), with their states, fixed flags and blocked DOFs.
void addBlocks(const SceneBlocks& scene, CoupledWorld& world);

// ParameterError naming the block (`name`) and the limit's key when body i moves faster than
// maxSpeed [m/s] (|v| + |w| times its bounding radius).
void checkBlockSpeed(const sdem::SdemEngine& engine, int i, double maxSpeed, const std::string& name,
                     const std::string& key);
// How far the bounding sphere of body i lies outside the MPM grid box [m] (<= 0: it reaches
// into it), and the warning for one that lies wholly outside ("can never touch the flow: ...").
double distanceFromGrid(const sdem::SdemEngine& engine, int i, const mpm::MpmParams& p);
std::string outsideGridMessage(const sdem::SdemEngine& engine, int i, const mpm::MpmParams& p);

// States no physical scene starts from, checked once the blocks are in `world`: a ParameterError
// for a block faster than maxBlockSpeed [m/s] (|v| + |w| times its bounding radius; the scene's
// run.max_block_speed) or whose bounding sphere lies more than 100 grid diagonals away from
// the grid box. Returns a warning for each block whose bounding sphere lies wholly outside the
// grid box: it can never touch the flow (legal: blocks may meet only blocks).
std::vector<std::string> checkBlockStates(const SceneBlocks& scene, CoupledWorld& world, double maxBlockSpeed);

}  // namespace coupling
}  // namespace mpmsdem
