#include "sdem/Bo1_SpheroPolyhedron_Aabb.hpp"

#include <limits>

namespace mpmsdem {
namespace sdem {

void Bo1_SpheroPolyhedron_Aabb::go(const SpheroPolyhedron& shape, const Vec3& pos, const Quat& ori, Vec3& lo,
                                   Vec3& hi) {
  const Mat3 rot = ori.toRotationMatrix();
  lo = Vec3::Constant(std::numeric_limits<Real>::infinity());
  hi = -lo;
  for (const Vec3& v : shape.vertices) {
    const Vec3 w = rot * v;
    lo = lo.cwiseMin(w);
    hi = hi.cwiseMax(w);
  }
  const Vec3 r = Vec3::Constant(shape.sweepRadius);
  lo += pos - r;
  hi += pos + r;
}

void Bo1_SpheroPolyhedron_Aabb::go(const PosedSpheroPolyhedron& posed, Vec3& lo, Vec3& hi) {
  const Vec3 r = Vec3::Constant(posed.shape->sweepRadius);
  lo = posed.coreLo - r;
  hi = posed.coreHi + r;
}

}  // namespace sdem
}  // namespace mpmsdem
