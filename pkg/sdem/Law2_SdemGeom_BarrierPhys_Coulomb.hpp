// Law2_SdemGeom_BarrierPhys_Coulomb: contact law of two sphero-polyhedra (paper Eqs 9–11,
// with Eq 10 read as a force, docs/physics.md).
//
// Normal: log barrier b(d) = -k_c (d - R)^2 ln(d / R) on the core gap d = R - delta,
// R = R_A + R_B, whose force is Eq 10:
//   F_n(delta) = -db/dd = -k_c delta [2 ln((R - delta)/R) - R/(R - delta) + 1]   [N],
// ~ 3 k_c delta^2 / R near first touch and unbounded as delta -> R. Tangent stiffness
// k_n = dF_n/ddelta. Optional normal dashpot c_n = 2 zeta_n sqrt(m_eff k_n); the total normal
// force is clamped at >= 0 (no adhesion).
// Tangential: incremental (hypoelastic) spring whose history is the elastic tangential force
// F_el (Eq 9): each step F_el is rotated into the current tangent plane keeping its length and
// incremented by -K_t v_t dt, K_t = k_n / (2 (1 + nu)) (Eq 11), so a change of k_n with delta
// alone leaves the force unchanged (storing a displacement instead would make it jump and create
// energy). F_t = F_el - c_t v_t, c_t = 2 zeta_t sqrt(m_eff K_t). If |F_el| > mu F_n the contact
// slips: F_el is rescaled to mu F_n and F_t = F_el (the dashpot is off while slipping);
// otherwise the damped force is capped at mu F_n in magnitude. Spring energy |F_el|^2 / (2 K_t).
// Forces are those exerted ON B (A receives the opposite).
#pragma once
#include "sdem/Ig2_SpheroPolyhedron_SpheroPolyhedron.hpp"
#include "sdem/Ip2_SdemMat_SdemMat_BarrierPhys.hpp"

namespace mpmsdem {
namespace sdem {

// State kept by a contact across steps.
struct ContactHistory {
  Vec3 xi = Vec3::Zero();  // elastic tangential force F_el on B [N] (Eq 9), not a displacement
};

// What the law produced for one contact in one step.
struct LawResult {
  Real normalForce = 0;             // F_n >= 0 along the normal, on B [N] (elastic + damping)
  Vec3 tangentialForce = Vec3::Zero();  // F_t on B [N], perpendicular to the normal
  Real normalStiffness = 0;         // k_n = dF_n/ddelta [N/m]
  Real tangentialStiffness = 0;     // K_t [N/m]
  Real barrierEnergy = 0;           // b(d) [J]
  Real springEnergy = 0;            // |F_el|^2 / (2 K_t) after the step [J]
  Real frictionDissipation = 0;     // energy dissipated by slip in this step [J]
  Real dampingDissipation = 0;      // energy dissipated by the dashpots in this step [J]
  bool sliding = false;             // the Coulomb cap was reached
};

class Law2_SdemGeom_BarrierPhys_Coulomb {
 public:
  // Elastic normal force F_n(delta) of Eq 10 [N]. kc [N/m] > 0, R = R_A + R_B [m] > 0,
  // 0 <= delta < R [m]. Returns 0 for delta <= 0.
  static Real normalForce(Real kc, Real R, Real delta);
  // Tangent stiffness k_n = dF_n/ddelta [N/m] (0 for delta <= 0).
  static Real normalStiffness(Real kc, Real R, Real delta);
  // Barrier potential b(d), d = R - delta [J] (0 for delta <= 0); F_n = db/ddelta.
  static Real barrierEnergy(Real kc, Real R, Real delta);
  // Overlap delta at which F_n(delta) = force [m] (force >= 0), by safeguarded Newton.
  static Real overlapForForce(Real kc, Real R, Real force);

  // Rotate the history (elastic tangential force) into the plane perpendicular to the unit
  // normal n, keeping its length.
  static void rotateHistory(Vec3& xi, const Vec3& n);

  // Apply the law to contact `g` between bodies with ids idA, idB (used in error messages).
  //  R:       R_A + R_B [m]
  //  relVel:  velocity of B's material point at the contact minus A's [m/s]
  //  meff:    effective mass of the pair [kg] (m_A m_B / (m_A + m_B), or the moving body's
  //           mass against a fixed one), used only by the dashpots
  //  dt:      time step [s] (> 0)
  // Throws RuntimeFailure naming the bodies and coreContactRemedy() when delta >= R (cores touching).
  static LawResult go(const SdemGeom& g, Real R, const BarrierPhys& phys, const Vec3& relVel, Real meff, Real dt,
                      ContactHistory& history, int idA, int idB);
};

// What to change when a contact reaches its cores, for every path that detects it (block-block
// law and narrow phase, MP-block coupling). The barrier's force is unbounded only as the gap
// closes continuously; a step carries the cores across the last of the gap when the approach is
// fast for dt, or when a load does more work than the barrier stores at any gap a double can
// hold, and then no smaller step helps: only a stiffer or thicker barrier or a gentler load do.
inline const char* coreContactRemedy() {
  return "a step carried the cores across the barrier gap. Remedies: a smaller time step if the approach was "
         "fast (keep v dt well below the gap; the critical step shrinks as the gap closes), a stiffer barrier "
         "(larger k_c) or thicker one (larger sweep radius R), or a gentler load (a load that does more work "
         "than the barrier can store is stopped by no step)";
}

}  // namespace sdem
}  // namespace mpmsdem
