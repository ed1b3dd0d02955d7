// SdemMaterial: the contact material of a sphero-polyhedron block (paper §2.2, Eqs 9–11;
// docs/physics.md). Pair properties are derived from two materials by
// Ip2_SdemMat_SdemMat_BarrierPhys.
#pragma once
#include "common/Types.hpp"

namespace mpmsdem {
namespace sdem {

struct SdemMaterial {
  // Mass density of the block [kg/m^3]. Valid: > 0. Used by the factories that turn a shape's
  // volume into a mass; the engine itself takes masses explicitly.
  Real density = 1000.0;

  // Coulomb friction coefficient mu [-] (Eq 9: |F_t| <= mu F_n). Valid: >= 0. Default 0.5.
  Real friction = 0.5;

  // Poisson's ratio nu [-] setting the tangential stiffness K_t = k_n / (2 (1 + nu)) (Eq 11).
  // Valid: (-1, 0.5). Default 0.3.
  Real poisson = 0.3;

  // Barrier stiffness k_c [N/m] of the log-barrier normal law (Eq 10, read as a force:
  // F_n = -k_c delta [2 ln((R-delta)/R) - R/(R-delta) + 1]). Valid: > 0. Default 1e4 N/m,
  // the paper's value (Tables 1 and 2).
  Real barrierStiffness = 1e4;

  // Normal viscous damping as a fraction of critical [-]: c_n = 2 zeta_n sqrt(m_eff k_n).
  // Valid: >= 0. Default 0: an elastic barrier, as in the paper.
  Real normalDamping = 0.0;

  // Tangential viscous damping as a fraction of critical [-]: c_t = 2 zeta_t sqrt(m_eff K_t)
  // (the c_t of Eq 9). Valid: >= 0. Default 0.1: the tangential spring of Eq 9 is otherwise
  // undamped and a block at rest keeps ringing on it forever; 10 % of critical kills that
  // ringing within a few periods while taking a negligible share of the energy of an impact
  // (the dashpot acts only while the contact sticks, never during slip).
  Real tangentialDamping = 0.1;

  // Throw ParameterError naming the first parameter out of its valid range (the ranges of
  // sdem/SdemParameters, docs/parameters.md).
  void validate() const;
};

}  // namespace sdem
}  // namespace mpmsdem
