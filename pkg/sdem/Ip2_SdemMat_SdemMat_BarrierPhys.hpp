// Ip2_SdemMat_SdemMat_BarrierPhys: pair physics of a block–block contact from the two
// blocks' materials (YADE's Ip2 role). Paper §2.2, Eqs 9–11.
#pragma once
#include "sdem/SdemMaterial.hpp"

namespace mpmsdem {
namespace sdem {

// Parameters of one contact pair, consumed by Law2_SdemGeom_BarrierPhys_Coulomb.
struct BarrierPhys {
  Real barrierStiffness = 1e4;   // k_c [N/m] (Eq 10)
  Real friction = 0.5;           // mu [-] (Eq 9)
  Real poisson = 0.3;            // nu [-] (Eq 11)
  Real normalDamping = 0.0;      // zeta_n, fraction of critical [-]
  Real tangentialDamping = 0.1;  // zeta_t, fraction of critical [-]
};

class Ip2_SdemMat_SdemMat_BarrierPhys {
 public:
  // Combination rules (both materials are validated first; ParameterError on bad input):
  //  - friction: the smaller of the two (the weaker surface limits sliding resistance);
  //  - barrierStiffness: harmonic mean 2 k1 k2 / (k1 + k2), i.e. two barriers in series with
  //    half the gap each; equal materials give back k_c;
  //  - poisson, normalDamping, tangentialDamping: arithmetic means.
  static BarrierPhys go(const SdemMaterial& a, const SdemMaterial& b);
};

}  // namespace sdem
}  // namespace mpmsdem
