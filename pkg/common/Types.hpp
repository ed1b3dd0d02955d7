// Common scalar/vector types of the host (CPU) code. Everything is SI.
// GPU-shareable math lives in common/MathHD.hpp (no Eigen in device code).
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace mpmsdem {
using Real = double;
using Vec3 = Eigen::Matrix<Real, 3, 1>;
using Mat3 = Eigen::Matrix<Real, 3, 3>;
using Quat = Eigen::Quaternion<Real>;
}  // namespace mpmsdem
