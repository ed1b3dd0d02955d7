#include "sdem/Ip2_SdemMat_SdemMat_BarrierPhys.hpp"

#include <algorithm>

namespace mpmsdem {
namespace sdem {

BarrierPhys Ip2_SdemMat_SdemMat_BarrierPhys::go(const SdemMaterial& a, const SdemMaterial& b) {
  a.validate();
  b.validate();
  BarrierPhys p;
  p.friction = std::min(a.friction, b.friction);
  p.barrierStiffness = 2.0 * a.barrierStiffness * b.barrierStiffness / (a.barrierStiffness + b.barrierStiffness);
  p.poisson = 0.5 * (a.poisson + b.poisson);
  p.normalDamping = 0.5 * (a.normalDamping + b.normalDamping);
  p.tangentialDamping = 0.5 * (a.tangentialDamping + b.tangentialDamping);
  return p;
}

}  // namespace sdem
}  // namespace mpmsdem
