// Bound functor (YADE naming: Bo1 = one shape -> bound): world-frame axis-aligned bounding
// box of a rounded sphero-polyhedron at a given pose.
#pragma once
#include "common/Types.hpp"
#include "sdem/Ig2_SpheroPolyhedron_SpheroPolyhedron.hpp"
#include "sdem/SpheroPolyhedron.hpp"

namespace mpmsdem {
namespace sdem {

struct Bo1_SpheroPolyhedron_Aabb {
  // pos: world position of the body-frame origin [m]; ori: rotation body -> world (unit).
  // lo/hi [m]: the tight box of the rounded body = box of the rotated core vertices grown by
  // the sweep radius R on every side (exact, since the rounded body is core (+) ball(R)).
  static void go(const SpheroPolyhedron& shape, const Vec3& pos, const Quat& ori, Vec3& lo, Vec3& hi);
  // The same box for a shape already placed in the world (its core box is known).
  static void go(const PosedSpheroPolyhedron& posed, Vec3& lo, Vec3& hi);
};

}  // namespace sdem
}  // namespace mpmsdem
