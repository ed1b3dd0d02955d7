#include "sdem/Law2_SdemGeom_BarrierPhys_Coulomb.hpp"

#include <cmath>
#include <sstream>

#include "common/Error.hpp"
#include "sdem/SdemKernelsCommon.hpp"

namespace mpmsdem {
namespace sdem {

// The formulas are the shared ones of SdemKernelsCommon.hpp (also run by the coupling on CPU
// and GPU).
Real Law2_SdemGeom_BarrierPhys_Coulomb::normalForce(Real kc, Real R, Real delta) { return barrierForce(kc, R, delta); }

Real Law2_SdemGeom_BarrierPhys_Coulomb::normalStiffness(Real kc, Real R, Real delta) {
  return barrierStiffness(kc, R, delta);
}

Real Law2_SdemGeom_BarrierPhys_Coulomb::barrierEnergy(Real kc, Real R, Real delta) {
  return barrierPotential(kc, R, delta);
}

Real Law2_SdemGeom_BarrierPhys_Coulomb::overlapForForce(Real kc, Real R, Real force) {
  if (force <= 0) return 0;
  Real lo = 0, hi = R;
  Real d = std::min(std::sqrt(force * R / (3 * kc)), 0.5 * R);
  for (int it = 0; it < 200; ++it) {
    const Real f = normalForce(kc, R, d) - force;
    if (f > 0)
      hi = d;
    else
      lo = d;
    Real next = d - f / normalStiffness(kc, R, d);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    if (std::abs(next - d) <= 1e-15 * R) return next;
    d = next;
  }
  return d;
}

void Law2_SdemGeom_BarrierPhys_Coulomb::rotateHistory(Vec3& xi, const Vec3& n) {
  Real x[3] = {xi[0], xi[1], xi[2]};
  rotateTangentialHistory(x, mpmsdem::Vec3T<Real>{n[0], n[1], n[2]});
  xi = Vec3(x[0], x[1], x[2]);
}

LawResult Law2_SdemGeom_BarrierPhys_Coulomb::go(const SdemGeom& g, Real R, const BarrierPhys& phys,
                                                const Vec3& relVel, Real meff, Real dt, ContactHistory& h,
                                                int idA, int idB) {
  const Real delta = g.overlap;
  if (!(delta < R)) {
    std::ostringstream os;
    os << "SDEM contact between bodies " << idA << " and " << idB << ": overlap " << delta
       << " m reached the barrier limit R_A + R_B = " << R << " m (cores touching) at a normal approach speed of "
       << std::abs(relVel.dot(g.normal)) << " m/s (dt = " << dt << " s); " << coreContactRemedy();
    throw RuntimeFailure(os.str());
  }
  const BarrierCoulombPhys<Real> ph{phys.barrierStiffness, phys.friction, phys.poisson, phys.normalDamping,
                                    phys.tangentialDamping};
  Real xi[3] = {h.xi[0], h.xi[1], h.xi[2]};
  const BarrierCoulombResult<Real> b =
      barrierCoulomb(ph, R, delta, mpmsdem::Vec3T<Real>{g.normal[0], g.normal[1], g.normal[2]},
                     mpmsdem::Vec3T<Real>{relVel[0], relVel[1], relVel[2]}, meff, dt, xi);
  h.xi = Vec3(xi[0], xi[1], xi[2]);
  LawResult r;
  r.normalForce = b.normalForce;
  r.tangentialForce = Vec3(b.tangential.x, b.tangential.y, b.tangential.z);
  r.normalStiffness = b.kn;
  r.tangentialStiffness = b.kt;
  r.barrierEnergy = b.barrierEnergy;
  r.springEnergy = b.springEnergy;
  r.frictionDissipation = b.frictionWork;
  r.dampingDissipation = b.dampingWork;
  r.sliding = b.sliding;
  return r;
}

}  // namespace sdem
}  // namespace mpmsdem
