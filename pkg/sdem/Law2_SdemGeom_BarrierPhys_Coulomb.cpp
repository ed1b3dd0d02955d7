#include "sdem/Law2_SdemGeom_BarrierPhys_Coulomb.hpp"

#include <cmath>
#include <sstream>

#include "common/Error.hpp"

namespace mpmsdem {
namespace sdem {

// With x = delta/R: ln((R-delta)/R) = log1p(-x) and 1 - R/(R-delta) = -x/(1-x); written this way
// the bracket of Eq 10 has no cancellation near first touch.
Real Law2_SdemGeom_BarrierPhys_Coulomb::normalForce(Real kc, Real R, Real delta) {
  if (delta <= 0) return 0;
  const Real x = delta / R;
  return -kc * delta * (2 * std::log1p(-x) - x / (1 - x));
}

Real Law2_SdemGeom_BarrierPhys_Coulomb::normalStiffness(Real kc, Real R, Real delta) {
  if (delta <= 0) return 0;
  const Real x = delta / R;
  // d/ddelta of -kc [2 delta log1p(-x) - delta x/(1-x)]
  return -kc * (2 * std::log1p(-x) - 3 * x / (1 - x) - x / ((1 - x) * (1 - x)));
}

Real Law2_SdemGeom_BarrierPhys_Coulomb::barrierEnergy(Real kc, Real R, Real delta) {
  if (delta <= 0) return 0;
  return -kc * delta * delta * std::log1p(-delta / R);
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
  const Real len = xi.norm();
  if (len == 0) return;
  const Vec3 proj = xi - xi.dot(n) * n;
  const Real plen = proj.norm();
  xi = plen > 1e-12 * len ? Vec3(proj * (len / plen)) : Vec3::Zero();
}

LawResult Law2_SdemGeom_BarrierPhys_Coulomb::go(const SdemGeom& g, Real R, const BarrierPhys& phys,
                                                const Vec3& relVel, Real meff, Real dt, ContactHistory& h,
                                                int idA, int idB) {
  const Real delta = g.overlap;
  if (!(delta < R)) {
    std::ostringstream os;
    os << "SDEM contact between bodies " << idA << " and " << idB << ": overlap " << delta
       << " m reached the barrier limit R_A + R_B = " << R
       << " m (cores touching); the time step is too large for the barrier stiffness";
    throw RuntimeFailure(os.str());
  }
  const Real kc = phys.barrierStiffness;
  const Vec3& n = g.normal;
  LawResult r;
  r.normalStiffness = normalStiffness(kc, R, delta);
  r.tangentialStiffness = r.normalStiffness / (2 * (1 + phys.poisson));
  r.barrierEnergy = barrierEnergy(kc, R, delta);

  // normal: elastic barrier + optional dashpot; vn > 0 when separating
  const Real vn = relVel.dot(n);
  const Real cn = 2 * phys.normalDamping * std::sqrt(meff * r.normalStiffness);
  const Real fElastic = normalForce(kc, R, delta);
  r.normalForce = std::max(Real(0), fElastic - cn * vn);
  r.dampingDissipation = (r.normalForce - fElastic) * -vn * dt;

  // tangential: incremental spring with history
  const Vec3 vt = relVel - vn * n;
  rotateHistory(h.xi, n);
  h.xi += vt * dt;
  const Real kt = r.tangentialStiffness;
  const Real cap = phys.friction * r.normalForce;
  const Vec3 fSpring = -kt * h.xi;
  const Real fSpringNorm = fSpring.norm();
  if (fSpringNorm > cap) {
    r.sliding = true;
    const Real slip = fSpringNorm > 0 ? h.xi.norm() * (1 - cap / fSpringNorm) : 0;
    h.xi *= fSpringNorm > 0 ? cap / fSpringNorm : 0;
    r.tangentialForce = -kt * h.xi;
    r.frictionDissipation = cap * slip;
  } else {
    const Real ct = 2 * phys.tangentialDamping * std::sqrt(meff * kt);
    Vec3 ft = fSpring - ct * vt;
    const Real ftNorm = ft.norm();
    if (ftNorm > cap) ft *= cap / ftNorm;
    r.tangentialForce = ft;
    r.dampingDissipation += -(ft - fSpring).dot(vt) * dt;
  }
  r.springEnergy = 0.5 * kt * h.xi.squaredNorm();
  return r;
}

}  // namespace sdem
}  // namespace mpmsdem
