// Contact geometry shared by the law tests: two bodies touching along +z.
#pragma once
#include "sdem/Law2_SdemGeom_BarrierPhys_Coulomb.hpp"

namespace mpmsdem {
namespace sdem {
namespace testing_geometry {

// A contact of normal +z at overlap delta, for sweep-radius sum R [m]: gap R - delta from the cores.
inline SdemGeom geomAlongZ(Real R, Real delta) {
  SdemGeom g;
  g.normal = Vec3::UnitZ();
  g.overlap = delta;
  g.distance = R - delta;
  return g;
}

}  // namespace testing_geometry
}  // namespace sdem
}  // namespace mpmsdem
