#include "coupling/BlockParameters.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "sdem/Ip2_SdemMat_SdemMat_BarrierPhys.hpp"
#include "sdem/SdemParameters.hpp"

namespace mpmsdem {
namespace coupling {

namespace {

// The defaults are the structs' (sdem::BarrierPhys); a block material's own keys (density,
// friction, ...) are sdem::materialParameter.table(), which SdemMaterial::validate checks against.
ParameterTable ownTable() {
  using namespace parameter_entries;
  const sdem::BarrierPhys f{};
  // key, python, kind, unit, default, default in words, lo, hi, lo and hi allowed, range in
  // words, equation, meaning
  return {
      {"blocks", "", K::kObject, "", kNone, "none", 0, 0, false, false, "a list of blocks", "§2.2",
       "rigid sphero-polyhedra moved by the driver's rigid-body update (as YADE's NewtonIntegrator); in Python the "
       "bodies of the SDEM engine, written by mpmsdem.driver.writeScene"},
      {"block_materials", "", K::kObject, "", kNone, "required with blocks", 0, 0, false, false,
       "materials by name", "",
       "the blocks' materials; in Python mpmsdem.material(...) and the pairs of CoupledEngine"},
      {"terrain_material", "", K::kObject, "", kNone, "required with terrain and moving blocks", 0, 0, false, false,
       "the keys of a block material but flow", "",
       "the blocks' contact with the flow's terrain (its laws mix with each block's, as a block pair's)"},

      {"block_materials.<name>.flow", "pairs", K::kObject, "", kNone, kRequired, 0, 0, false, false, "", "Eq 12",
       "the contact of the material points with blocks of this material (the pair's own physics)"},

      {"block_materials.<name>.flow.friction", "friction", K::kNumber, "", kNone, kRequired, 0, kInf, true, false, "",
       "Eq 12", "material point-block Coulomb friction coefficient"},
      {"block_materials.<name>.flow.barrier_stiffness", "barrierStiffness", K::kNumber, "N/m", f.barrierStiffness, "",
       0, kInf, false, false, "", "Eq 10", "k_c of the material point-block barrier"},
      {"block_materials.<name>.flow.poisson", "poisson", K::kNumber, "", f.poisson, "", -1, 0.5, false, false, "",
       "Eq 11", "nu of the pair's tangential stiffness"},
      {"block_materials.<name>.flow.normal_damping", "normalDamping", K::kNumber, "", f.normalDamping, "", 0, kInf,
       true, false, "", "", "normal viscous damping, a fraction of critical"},
      {"block_materials.<name>.flow.tangential_damping", "tangentialDamping", K::kNumber, "", f.tangentialDamping, "",
       0, kInf, true, false, "", "", "tangential viscous damping, a fraction of critical"},

      {"blocks[].material", "", K::kText, "", kNone, kRequired, 0, 0, false, false, "a key of block_materials", "",
       "the block's material"},
      {"blocks[].box", "", K::kVector, "m", kNone, "", 0, 0, false, false, "[hx, hy, hz], each > sweep_radius", "",
       "outer half-extents of a box (give box or core)"},
      {"blocks[].core", "", K::kObject, "", kNone, "", 0, 0, false, false, "{vertices, faces, convex}", "",
       "a shape table: core vertices [m], faces as vertex loops counter-clockwise seen from outside"},
      {"blocks[].outer", "", K::kObject, "", kNone, "the core", 0, 0, false, false, "{vertices, triangles}", "",
       "with core: the outer shape, for display only"},
      {"blocks[].sweep_radius", "sweepRadius", K::kNumber, "m", kNone, kRequired, 0, kInf, false, false,
       "(0, min half-extent) for a box", "Eq 7", "R, the radius swept around the core"},
      {"blocks[].position", "state.pos", K::kVector, "m", kNone, kRequired, 0, 0, false, false, "", "",
       "where the shape's own origin goes (the centroid for a box and for tables written in the body frame)"},
      {"blocks[].orientation", "state.ori", K::kVector, "", kNone, "[1, 0, 0, 0]", 0, 0, false, false,
       "a unit quaternion [w, x, y, z]", "", "orientation"},
      {"blocks[].velocity", "state.vel", K::kVector, "m/s", kNone, "[0, 0, 0]", 0, 0, false, false, "", "",
       "velocity (world frame)"},
      {"blocks[].angular_velocity", "state.angVel", K::kVector, "rad/s", kNone, "[0, 0, 0]", 0, 0, false, false, "",
       "", "angular velocity (world frame)"},
      {"blocks[].fixed", "", K::kBoolean, "", kNone, "false", 0, 0, false, false, "", "",
       "moves only with its set velocities (a flume bed); in YADE a body that is not dynamic"},
      {"blocks[].blocked_dofs", "state.blockedDOFs", K::kText, "", kNone, "\"\"", 0, 0, false, false,
       "a string of letters among x y z X Y Z", "", "YADE's blockedDOFs"},
      {"blocks[].id", "", K::kInteger, "", kNone, "its position in the list", 0, 2147483647, true, true, "", "",
       "label in the outputs, unique (in Python the body's id)"},
  };
}

}  // namespace

// The blocks, their materials' objects, a material's own keys (from pkg/sdem), then the flow pair's
// and the blocks' keys, in the order docs/parameters.md shows them.
ParameterTable listBlockParameters() {
  const ParameterTable own = ownTable(), &material = sdem::materialParameter.table();
  const auto flow = std::find_if(own.begin(), own.end(), [](const ParameterSpec& e) {
    return std::strcmp(e.key, "block_materials.<name>.flow") == 0;
  });
  ParameterTable table(own.begin(), flow);
  table.insert(table.end(), material.begin(), material.end());
  table.insert(table.end(), flow, own.end());
  return table;
}

}  // namespace coupling
}  // namespace mpmsdem
