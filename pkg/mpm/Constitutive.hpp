// Hypoelastic mu(I) model of the paper's Appendix B with the two corrections of docs/physics.md
// (xi = I_0/(d sqrt(rho_s)); alpha_1 = xi G dt sqrt(p_tr)). Shared by CPU and CUDA code.
// Sign convention: Cauchy stress, tension positive; pressure p = -tr(sigma)/3 > 0 in compression.
#pragma once
#include <cstdint>

#include "common/MathHD.hpp"

namespace mpmsdem {
namespace mpm {

// Phase codes stored in ParticleSet::phase.
enum : std::uint8_t { kPhaseElastic = 0, kPhasePlastic = 1, kPhaseGasified = 2 };

// Material constants in the form the stress update needs (built from GranularMaterial).
template <typename T>
struct ConstitutiveConst {
  T lambda;  // first Lame constant  E nu / ((1+nu)(1-2nu)) [Pa]
  T G;       // shear modulus E / (2(1+nu)) [Pa]
  T muS;     // mu_s, Eq B.2 [-]
  T mu2;     // mu_2, Eq B.2 [-]
  T xi;      // rate parameter I_0 / (d sqrt(rho_s)) [1/(s sqrt(Pa))] (corrected B.3)
  T rhoC;    // critical density rho_c: stress-free below it [kg/m^3]
};

// Invariants of a symmetric stress: p = -tr/3 (compression positive), tau = sqrt(s0:s0 / 2).
template <typename T>
MPM_HD_INLINE void stressInvariants(const Sym6T<T>& s, T& p, T& tau) {
  p = -s.trace() / T(3);
  Sym6T<T> d = s;
  d.s[0] += p;
  d.s[1] += p;
  d.s[2] += p;
  tau = hdSqrt(T(0.5) * ddot(d, d));
}

// Smaller root of tau^2 - B tau + H = 0 (Eq B.8/B.9 with corrected alpha_1), written in the
// cancellation-free form 2H / (B + sqrt(B^2 - 4H)). Inputs: S0 = mu_s p_tr, S2 = mu_2 p_tr,
// trial shear stress tauTr and alpha1 = xi G dt sqrt(p_tr), all in Pa.
template <typename T>
MPM_HD_INLINE T returnMapShear(T S0, T S2, T tauTr, T alpha1) {
  const T B = S2 + tauTr + alpha1;
  const T H = S2 * tauTr + S0 * alpha1;
  T disc = B * B - T(4) * H;
  // disc = (tauTr - S2 + alpha1)^2 + 4 alpha1 (S2 - S0) >= 0 analytically; guard round-off.
  if (disc < T(0)) disc = T(0);
  return T(2) * H / (B + hdSqrt(disc));
}

// One stress update (Eqs B.4-B.11). sigma: stress at the start of the step, replaced by the
// new one; L: velocity gradient of the step [1/s]; rho: density at the end of the step.
// Returns the phase; gammaDotP receives the equivalent plastic shear rate (Eq B.10) [1/s].
template <typename T>
MPM_HD_INLINE std::uint8_t updateStress(Sym6T<T>& sigma, const Mat3T<T>& L, T dt, T rho, const ConstitutiveConst<T>& c,
                                        T& gammaDotP) {
  gammaDotP = T(0);
  if (rho < c.rhoC) {
    sigma = Sym6T<T>::zero();
    return kPhaseGasified;
  }
  const Sym6T<T> D = symPart(L);
  Mat3T<T> W;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) W.m[i][j] = T(0.5) * (L.m[i][j] - L.m[j][i]);
  // Trial stress, Eq B.5: sigma + dt (lambda tr(D) I + 2 G D) + dt (W sigma - sigma W).
  const Sym6T<T> rot = jaumannTerm(W, sigma);
  const T lt = c.lambda * D.trace();
  Sym6T<T> tr;
  for (int k = 0; k < 6; ++k) tr.s[k] = sigma.s[k] + dt * (T(2) * c.G * D.s[k] + rot.s[k]);
  tr.s[0] += dt * lt;
  tr.s[1] += dt * lt;
  tr.s[2] += dt * lt;

  T pTr, tauTr;
  stressInvariants(tr, pTr, tauTr);
  if (!(pTr > T(0))) {
    sigma = Sym6T<T>::zero();
    return kPhaseGasified;
  }
  const T S0 = c.muS * pTr;
  if (tauTr <= S0) {
    sigma = tr;
    return kPhaseElastic;
  }
  const T S2 = c.mu2 * pTr;
  const T alpha1 = c.xi * c.G * dt * hdSqrt(pTr);
  const T tau = returnMapShear(S0, S2, tauTr, alpha1);
  gammaDotP = (tauTr - tau) / (c.G * dt);
  // Eq B.11: scale the trial deviator, keep the trial pressure.
  const T scale = tau / tauTr;
  for (int k = 0; k < 6; ++k) sigma.s[k] = scale * tr.s[k];
  for (int k = 0; k < 3; ++k) sigma.s[k] += (scale - T(1)) * pTr;
  return kPhasePlastic;
}

}  // namespace mpm
}  // namespace mpmsdem
