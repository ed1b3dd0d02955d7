#include "sdem/SdemEngine.hpp"

#include <algorithm>
#include <cstring>
#include <cmath>
#include <sstream>
#include <string>

#include "common/Error.hpp"
#include "sdem/Bo1_SpheroPolyhedron_Aabb.hpp"

namespace mpmsdem {
namespace sdem {

// ------------------------------------------------------------------ contact histories

std::size_t ContactHistoryTable::slotOf(const ContactKey& k) const {
  const std::size_t mask = gen_.size() - 1;
  std::size_t i = ContactKeyHash()(k) & mask;
  while (gen_[i] == current_ && !(keys_[i] == k)) i = (i + 1) & mask;
  return i;
}

const ContactHistory* ContactHistoryTable::find(const ContactKey& k) const {
  if (size_ == 0) return nullptr;
  const std::size_t i = slotOf(k);
  return gen_[i] == current_ ? &values_[i] : nullptr;
}

void ContactHistoryTable::put(const ContactKey& k, const ContactHistory& h) {
  if (2 * (size_ + 1) > gen_.size()) grow();  // at most half full: short probes
  const std::size_t i = slotOf(k);
  if (gen_[i] != current_) {
    gen_[i] = current_;
    keys_[i] = k;
    ++size_;
  }
  values_[i] = h;
}

void ContactHistoryTable::clear() {
  size_ = 0;
  if (++current_ == 0) {  // the generations wrapped: no slot may look current
    std::fill(gen_.begin(), gen_.end(), 0u);
    current_ = 1;
  }
}

void ContactHistoryTable::swap(ContactHistoryTable& o) noexcept {
  keys_.swap(o.keys_);
  values_.swap(o.values_);
  gen_.swap(o.gen_);
  std::swap(current_, o.current_);
  std::swap(size_, o.size_);
}

void ContactHistoryTable::grow() {
  ContactHistoryTable bigger;
  const std::size_t n = std::max<std::size_t>(64, 2 * gen_.size());
  bigger.keys_.resize(n);
  bigger.values_.resize(n);
  bigger.gen_.assign(n, 0u);
  forEach([&bigger](const ContactKey& k, const ContactHistory& h) { bigger.put(k, h); });
  swap(bigger);
}

// ------------------------------------------------------------------ set-up

int SdemEngine::addMaterial(const SdemMaterial& m) {
  m.validate();
  materials_.push_back(m);
  const size_t n = materials_.size();
  std::vector<BarrierPhys> phys(n * n);
  for (size_t a = 0; a < n; ++a)
    for (size_t b = 0; b < n; ++b) phys[a * n + b] = Ip2_SdemMat_SdemMat_BarrierPhys::go(materials_[a], materials_[b]);
  pairPhys_.swap(phys);
  return static_cast<int>(n - 1);
}

const SdemMaterial& SdemEngine::material(int k) const {
  if (k < 0 || k >= numMaterials())
    throwParameter("material", k, "", "a registered material index in [0, " + std::to_string(numMaterials()) + ")");
  return materials_[k];
}

int SdemEngine::addBody(std::shared_ptr<const SpheroPolyhedron> shape, int material, Real mass,
                        const Vec3& principalInertia, int externalId) {
  if (!shape) throw ParameterError("shape = null: must be a SpheroPolyhedron");
  if (shape->vertices.empty() || !(shape->sweepRadius > 0))
    throwParameter("shape.sweepRadius", shape->sweepRadius, "m", "> 0 on a shape with a core");
  if (material < 0 || material >= numMaterials())
    throwParameter("material", material, "",
                   "a registered material index in [0, " + std::to_string(numMaterials()) + ")");
  if (!(mass > 0) || !std::isfinite(mass)) throwParameter("mass", mass, "kg", "> 0");
  for (int k = 0; k < 3; ++k)
    if (!(principalInertia[k] > 0) || !std::isfinite(principalInertia[k]))
      throwParameter("principalInertia[" + std::to_string(k) + "]", principalInertia[k], "kg m^2", "> 0");
  shapes_.push_back(std::move(shape));
  material_.push_back(material);
  external_.push_back(externalId);
  mass_.push_back(mass);
  inertia_.push_back(principalInertia);
  fixed_.push_back(0);
  pos_.push_back(Vec3::Zero());
  ori_.push_back(Quat::Identity());
  vel_.push_back(Vec3::Zero());
  angVel_.push_back(Vec3::Zero());
  posed_.emplace_back();
  poseStale_.push_back(1);
  force_.push_back(Vec3::Zero());
  torque_.push_back(Vec3::Zero());
  sumK_.push_back(0);
  sumKr_.push_back(0);
  return numBodies() - 1;
}

void SdemEngine::checkBody(int i, const char* what) const {
  if (i < 0 || i >= numBodies())
    throwParameter(what, i, "", "a body index in [0, " + std::to_string(numBodies()) + ")");
}

void SdemEngine::setFixed(int i, bool fixed) {
  checkBody(i, "body");
  fixed_[i] = fixed;
}

bool SdemEngine::isFixed(int i) const {
  checkBody(i, "body");
  return fixed_[i];
}

void SdemEngine::setState(int i, const Vec3& pos, const Quat& ori, const Vec3& vel, const Vec3& angVel) {
  checkBody(i, "body");
  if (!pos.allFinite() || !vel.allFinite() || !angVel.allFinite() || !ori.coeffs().allFinite() ||
      !(ori.norm() > 0)) {
    std::ostringstream os;
    os << "state of body " << external_[i] << ": position, orientation, velocity and angular velocity must be finite"
       << " (orientation non-zero)";
    throw ParameterError(os.str());
  }
  if (pos != pos_[i] || !ori.coeffs().isApprox(ori_[i].coeffs(), 0.0)) poseStale_[i] = 1;
  pos_[i] = pos;
  ori_[i] = ori.normalized();
  vel_[i] = vel;
  angVel_[i] = angVel;
}

void SdemEngine::setStates(const Real* pos, const Real* q, const Real* vel, const Real* angVel) {
  for (int i = 0; i < numBodies(); ++i)
    setState(i, Vec3(pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]),
             Quat(q[4 * i], q[4 * i + 1], q[4 * i + 2], q[4 * i + 3]),
             Vec3(vel[3 * i], vel[3 * i + 1], vel[3 * i + 2]),
             Vec3(angVel[3 * i], angVel[3 * i + 1], angVel[3 * i + 2]));
}

const Vec3& SdemEngine::position(int i) const { return checkBody(i, "body"), pos_[i]; }
const Quat& SdemEngine::orientation(int i) const { return checkBody(i, "body"), ori_[i]; }
const Vec3& SdemEngine::velocity(int i) const { return checkBody(i, "body"), vel_[i]; }
const Vec3& SdemEngine::angularVelocity(int i) const { return checkBody(i, "body"), angVel_[i]; }
Real SdemEngine::mass(int i) const { return checkBody(i, "body"), mass_[i]; }
const Vec3& SdemEngine::principalInertia(int i) const { return checkBody(i, "body"), inertia_[i]; }
int SdemEngine::externalId(int i) const { return checkBody(i, "body"), external_[i]; }
int SdemEngine::materialOf(int i) const { return checkBody(i, "body"), material_[i]; }
const SpheroPolyhedron& SdemEngine::shape(int i) const { return checkBody(i, "body"), *shapes_[i]; }
const Vec3& SdemEngine::force(int i) const { return checkBody(i, "body"), force_[i]; }
const Vec3& SdemEngine::torque(int i) const { return checkBody(i, "body"), torque_[i]; }

void SdemEngine::setTimeStepSafety(Real c) {
  if (!(c > 0) || !std::isfinite(c)) throwParameter("timeStepSafety", c, "", "> 0");
  safety_ = c;
}

void SdemEngine::setTimeStepCheckFactor(Real f) {
  if (!(f >= 1 && f <= 2)) throwParameter("timeStepCheckFactor", f, "", "in [1, 2]");
  checkFactor_ = f;
}

Real SdemEngine::pointSpeedBound(int i) const {
  checkBody(i, "body");
  return vel_[i].norm() + angVel_[i].norm() * shapes_[i]->boundingRadius;
}

Real SdemEngine::approachTimeStep(int* body) const {
  Real dt = std::numeric_limits<Real>::infinity();
  if (body) *body = -1;
  for (int i = 0; i < numBodies(); ++i) {
    const Real speed = pointSpeedBound(i);
    if (speed > 0 && shapes_[i]->sweepRadius / speed < dt) {
      dt = shapes_[i]->sweepRadius / speed;
      if (body) *body = i;
    }
  }
  return dt;
}

Real autoTimeStep(Real factor, Real critical, Real approach, Real lastDt) {
  if (!(factor > 0 && factor <= 1)) throwParameter("dt factor", factor, "", "in (0, 1]");
  Real dt = std::min(factor * critical, kApproachFraction * approach);
  if (lastDt > 0) dt = std::min(dt, kAutoStepGrowth * lastDt);
  return dt;
}

// ------------------------------------------------------------------ step

void SdemEngine::broadPhase() {
  pairs_.clear();
  const int n = numBodies();
  order_.resize(n);
  for (int i = 0; i < n; ++i) order_[i] = i;
  boxLo_.resize(n);
  boxHi_.resize(n);
  for (int i = 0; i < n; ++i) Bo1_SpheroPolyhedron_Aabb::go(posed_[i], boxLo_[i], boxHi_[i]);
  auto lo = [&](int i, int k) { return boxLo_[i][k]; };
  auto hi = [&](int i, int k) { return boxHi_[i][k]; };
  std::sort(order_.begin(), order_.end(), [&](int a, int b) { return lo(a, 0) < lo(b, 0); });
  for (int s = 0; s < n; ++s) {
    const int i = order_[s];
    const Real xmax = hi(i, 0);
    for (int t = s + 1; t < n; ++t) {
      const int j = order_[t];
      if (lo(j, 0) > xmax) break;
      if (fixed_[i] && fixed_[j]) continue;
      if (lo(j, 1) > hi(i, 1) || lo(i, 1) > hi(j, 1) || lo(j, 2) > hi(i, 2) || lo(i, 2) > hi(j, 2)) continue;
      pairs_.emplace_back(std::min(i, j), std::max(i, j));
    }
  }
  std::sort(pairs_.begin(), pairs_.end());  // deterministic order of force summation
}

void SdemEngine::computeForces(Real dt) {
  if (!(dt > 0) || !std::isfinite(dt)) throwParameter("dt", dt, "s", "> 0");
  const int n = numBodies();
  for (int i = 0; i < n; ++i) {
    if (poseStale_[i]) posed_[i].update(*shapes_[i], pos_[i], ori_[i]);
    poseStale_[i] = 0;
    force_[i].setZero();
    torque_[i].setZero();
    sumK_[i] = 0;
    sumKr_[i] = 0;
  }
  broadPhase();
  records_.clear();
  nextHistory_.clear();
  barrierEnergy_ = 0;
  springEnergy_ = 0;
  const int nm = numMaterials();
  narrowPhasePairs_ += static_cast<long>(pairs_.size());
  for (const auto& [a, b] : pairs_) {
    geoms_.clear();
    if (!Ig2_SpheroPolyhedron_SpheroPolyhedron::go(posed_[a], posed_[b], geoms_)) {
      std::ostringstream os;
      os << "SDEM bodies " << external_[a] << " and " << external_[b]
         << ": cores interpenetrate; " << coreContactRemedy();
      throw RuntimeFailure(os.str());
    }
    if (geoms_.empty()) continue;
    const BarrierPhys& phys = pairPhys_[material_[a] * nm + material_[b]];
    const Real R = shapes_[a]->sweepRadius + shapes_[b]->sweepRadius;
    const Real meff = fixed_[a] ? mass_[b] : fixed_[b] ? mass_[a] : mass_[a] * mass_[b] / (mass_[a] + mass_[b]);
    for (const SdemGeom& g : geoms_) addContact(a, b, g, phys, R, meff, dt);
  }
  if (hasTerrain()) terrainContacts(dt);
  history_.swap(nextHistory_);
  if (dt > checkFactor_ * criticalTimeStep()) {
    if (strict_) {
      std::ostringstream os;
      os << "dt = " << dt << " s: must be <= ";
      if (checkFactor_ != 1) os << checkFactor_ << " x ";
      os << "the SDEM critical time step " << criticalTimeStep() << " s";
      throw RuntimeFailure(os.str());
    }
    ++warnings_;
  }
}

void SdemEngine::addContact(int a, int b, const SdemGeom& g, const BarrierPhys& phys, Real R, Real meff, Real dt) {
  const bool terrain = b == kTerrainBody;
  ContactKey key{a, b, g.kindA, g.kindB, g.indexA, g.indexB};
  ContactHistory h;
  if (const ContactHistory* old = history_.find(key)) h = *old;
  const Vec3 ra = g.contactPoint - pos_[a];
  const Vec3 rb = terrain ? Vec3::Zero() : Vec3(g.contactPoint - pos_[b]);
  const Vec3 velB = terrain ? Vec3::Zero() : Vec3(vel_[b] + angVel_[b].cross(rb));
  const Vec3 relVel = velB - (vel_[a] + angVel_[a].cross(ra));
  const int externalB = terrain ? -1 : external_[b];
  const LawResult r = Law2_SdemGeom_BarrierPhys_Coulomb::go(g, R, phys, relVel, meff, dt, h, external_[a], externalB);
  nextHistory_.put(key, h);
  const Vec3 f = r.normalForce * g.normal + r.tangentialForce;  // on B
  force_[a] -= f;
  torque_[a] -= ra.cross(f);
  const Real kmax = std::max(r.normalStiffness, r.tangentialStiffness);
  sumK_[a] += kmax;
  sumKr_[a] += r.normalStiffness * ra.cross(g.normal).squaredNorm() + r.tangentialStiffness * ra.squaredNorm();
  if (!terrain) {
    force_[b] += f;
    torque_[b] += rb.cross(f);
    sumK_[b] += kmax;
    sumKr_[b] += r.normalStiffness * rb.cross(g.normal).squaredNorm() + r.tangentialStiffness * rb.squaredNorm();
  }
  barrierEnergy_ += r.barrierEnergy;
  springEnergy_ += r.springEnergy;
  frictionWork_ += r.frictionDissipation;
  dampingWork_ += r.dampingDissipation;
  ContactRecord rec;
  rec.key = key;
  rec.externalA = external_[a];
  rec.externalB = externalB;
  rec.point = g.contactPoint;
  rec.normal = g.normal;
  rec.normalForce = r.normalForce;
  rec.tangentialForce = r.tangentialForce;
  rec.overlap = g.overlap;
  rec.normalStiffness = r.normalStiffness;
  rec.sliding = r.sliding;
  records_.push_back(rec);
}

void SdemEngine::setTerrain(const mpmsdem::TerrainSpec& terrain, int material) {
  if (material < 0 || material >= numMaterials())
    throwParameter("terrain material", material, "",
                   "a registered material index in [0, " + std::to_string(numMaterials()) + ")");
  if (!terrain.enabled()) throw ParameterError("terrain.heights: empty: a terrain has nx * ny >= 4 heights");
  terrain.validate();
  terrainGeom_.setTerrain(terrain);
  terrainMaterial_ = material;
}

// Every moving body against the terrain (Ig2_SpheroPolyhedron_Terrain).
void SdemEngine::terrainContacts(Real dt) {
  const int nm = numMaterials();
  std::string what;
  for (int i = 0; i < numBodies(); ++i) {
    if (fixed_[i]) continue;
    geoms_.clear();
    if (!terrainGeom_.go(posed_[i], geoms_, what)) {
      std::ostringstream os;
      os << "SDEM body " << external_[i] << ": " << what << "; " << coreContactRemedy();
      throw RuntimeFailure(os.str());
    }
    const BarrierPhys& phys = pairPhys_[material_[i] * nm + terrainMaterial_];
    for (const SdemGeom& g : geoms_) addContact(i, kTerrainBody, g, phys, shapes_[i]->sweepRadius, mass_[i], dt);
  }
}

Real SdemEngine::criticalTimeStep() const {
  Real dt = std::numeric_limits<Real>::infinity();
  for (int i = 0; i < numBodies(); ++i) {
    if (fixed_[i]) continue;
    if (sumK_[i] > 0) dt = std::min(dt, std::sqrt(mass_[i] / sumK_[i]));
    if (sumKr_[i] > 0) dt = std::min(dt, std::sqrt(inertia_[i].minCoeff() / sumKr_[i]));
  }
  return safety_ * dt;
}

// ------------------------------------------------------------------ checkpoint

void SdemEngine::setDissipation(Real friction, Real damping) {
  if (!(std::isfinite(friction) && friction >= 0)) throwParameter("friction dissipation", friction, "J", ">= 0, finite");
  if (!(std::isfinite(damping) && damping >= 0)) throwParameter("damping dissipation", damping, "J", ">= 0, finite");
  frictionWork_ = friction;
  dampingWork_ = damping;
}

std::vector<ContactHistoryEntry> SdemEngine::contactHistories() const {
  std::vector<ContactHistoryEntry> out;
  out.reserve(history_.size());
  history_.forEach([&out](const ContactKey& k, const ContactHistory& h) { out.push_back({k, h.xi}); });
  return out;
}

void SdemEngine::setContactHistories(const std::vector<ContactHistoryEntry>& entries) {
  ContactHistoryTable h;
  for (const ContactHistoryEntry& e : entries) {
    checkBody(e.key.bodyA, "contact history bodyA");
    if (e.key.bodyB == kTerrainBody && !hasTerrain())
      throw ParameterError("contact history bodyB = the terrain: this engine has no terrain (setTerrain first)");
    if (e.key.bodyB != kTerrainBody) checkBody(e.key.bodyB, "contact history bodyB");
    if (e.key.bodyB != kTerrainBody && !(e.key.bodyA < e.key.bodyB))
      throwParameter("contact history bodyB", e.key.bodyB, "", "> bodyA = " + std::to_string(e.key.bodyA));
    if (!e.xi.allFinite()) throw ParameterError("contact history xi: must be finite");
    ContactHistory v;
    v.xi = e.xi;
    h.put(e.key, v);
  }
  history_.swap(h);
}

// ------------------------------------------------------------------ SdemWorld

namespace {
constexpr char kDofLetters[] = "xyzXYZ";
constexpr unsigned kRotationDofs = 070;
constexpr unsigned kAllDofs = 077;

// Turn q by the rotation vector omega dt (YADE's rotation of spherical and DOF-blocked bodies).
Quat advance(const Quat& q, const Vec3& omega, Real dt) {
  const Real angle = omega.norm() * dt;
  if (angle == 0) return q;
  return (Quat(Eigen::AngleAxis<Real>(angle, omega.normalized())) * q).normalized();
}
// q + s dq/dt with dq/dt = q (0, w_body) / 2, component-wise (not normalised).
Quat addRate(const Quat& q, const Quat& base, const Vec3& wBody, Real s) {
  const Quat r = base * Quat(0, wBody.x(), wBody.y(), wBody.z());
  return Quat(q.w() + 0.5 * s * r.w(), q.x() + 0.5 * s * r.x(), q.y() + 0.5 * s * r.y(), q.z() + 0.5 * s * r.z());
}
}  // namespace

void SdemWorld::setBlockedDofs(int i, const std::string& dofs) {
  if (i < 0 || i >= engine.numBodies())
    throwParameter("body", i, "", "in [0, " + std::to_string(engine.numBodies()) + ")");
  unsigned mask = 0;
  for (char c : dofs) {
    const char* at = std::strchr(kDofLetters, c);
    if (c == '\0' || !at) throwParameter("blockedDOFs", "'" + dofs + "'", "", "letters among x y z X Y Z");
    mask |= 1u << (at - kDofLetters);
  }
  blocked_.resize(engine.numBodies(), 0);
  fixedByDofs_.resize(engine.numBodies(), 0);
  blocked_[i] = mask;
  // A body that nothing can move is fixed: the broad phase then skips its pairs with other
  // fixed bodies. Its motion is the same either way (kinematic, with its set velocities).
  if (mask == kAllDofs && !engine.isFixed(i)) {
    engine.setFixed(i, true);
    fixedByDofs_[i] = 1;
  } else if (mask != kAllDofs && fixedByDofs_[i]) {
    engine.setFixed(i, false);
    fixedByDofs_[i] = 0;
  }
}

std::string SdemWorld::blockedDofs(int i) const {
  std::string s;
  const unsigned mask = i >= 0 && i < static_cast<int>(blocked_.size()) ? blocked_[i] : 0;
  for (int k = 0; k < 6; ++k)
    if (mask & (1u << k)) s += kDofLetters[k];
  return s;
}

void SdemWorld::step(Real dt, const std::vector<Vec3>* extraForce, const std::vector<Vec3>* extraTorque) {
  const int n = engine.numBodies();
  for (const std::vector<Vec3>* extra : {extraForce, extraTorque})
    if (extra && static_cast<int>(extra->size()) != n)
      throwParameter("extra force/torque count", extra->size(), "", "the number of bodies, " + std::to_string(n));
  engine.computeForces(dt);
  angMom_.resize(n, Vec3::Zero());
  lastAngVel_.resize(n, Vec3::Constant(std::numeric_limits<Real>::quiet_NaN()));
  blocked_.resize(n, 0);
  for (int i = 0; i < n; ++i) {
    const Quat& q = engine.orientation(i);
    Vec3 v = engine.velocity(i), w = engine.angularVelocity(i);
    Vec3 x = engine.position(i);
    Quat qn;
    if (engine.isFixed(i)) {
      x += dt * v;
      qn = advance(q, w, dt);
    } else {
      const unsigned mask = blocked_[i];
      const Vec3& I = engine.principalInertia(i);
      const Vec3 T = engine.torque(i) + (extraTorque ? (*extraTorque)[i] : Vec3::Zero());
      if (mask & kRotationDofs) {
        for (int k = 0; k < 3; ++k)
          if (!(mask & (8u << k))) w[k] += dt * T[k] / I[k];
        qn = advance(q, w, dt);
      } else {
        // angular velocity changed from outside since our last step: re-derive L from it
        if (!(w.array() == lastAngVel_[i].array()).all()) angMom_[i] = q * Vec3(I.cwiseProduct(q.conjugate() * w));
        const Mat3 toBody = q.conjugate().toRotationMatrix();
        const Vec3 wNow = (toBody * (angMom_[i] + 0.5 * dt * T)).cwiseQuotient(I);  // body frame, at t
        const Quat qHalf = addRate(q, q, wNow, 0.5 * dt);
        angMom_[i] += dt * T;  // L(t + dt/2)
        const Vec3 wHalf = (toBody * angMom_[i]).cwiseQuotient(I);
        qn = addRate(q, qHalf, wHalf, dt);
        w = qn * wHalf;
        qn.normalize();
      }
      const Vec3 F = engine.force(i) + (extraForce ? (*extraForce)[i] : Vec3::Zero());
      for (int k = 0; k < 3; ++k)
        if (!(mask & (1u << k))) v[k] += dt * (F[k] / engine.mass(i) + gravity[k]);
      x += dt * v;
      if (!x.allFinite() || !v.allFinite() || !w.allFinite()) {
        std::ostringstream os;
        os << "SdemWorld: body " << engine.externalId(i) << " got a non-finite state at t = " << time_ << " s";
        throw RuntimeFailure(os.str());
      }
    }
    engine.setState(i, x, qn, v, w);
    lastAngVel_[i] = w;
  }
  time_ += dt;
}

bool SdemWorld::angularMomentum(int i, Vec3& L) const {
  const Vec3& w = engine.angularVelocity(i);  // checks i
  const std::size_t k = static_cast<std::size_t>(i);
  if (k >= angMom_.size() || (k < blocked_.size() && (blocked_[k] & kRotationDofs)) ||
      !(w.array() == lastAngVel_[k].array()).all())
    return false;
  L = angMom_[k];
  return true;
}

void SdemWorld::restoreAngularMomentum(int i, const Vec3& L) {
  const Vec3& w = engine.angularVelocity(i);  // checks i
  if (!L.allFinite()) throw ParameterError("angular momentum of body " + std::to_string(i) + ": must be finite");
  const std::size_t n = static_cast<std::size_t>(engine.numBodies());
  angMom_.resize(n, Vec3::Zero());
  lastAngVel_.resize(n, Vec3::Constant(std::numeric_limits<Real>::quiet_NaN()));
  angMom_[i] = L;
  lastAngVel_[i] = w;
}

void SdemWorld::setTime(Real t) {
  if (!(std::isfinite(t) && t >= 0)) throwParameter("time", t, "s", ">= 0, finite");
  time_ = t;
}

Real SdemWorld::kineticEnergy() const {
  Real e = 0;
  for (int i = 0; i < engine.numBodies(); ++i) {
    if (engine.isFixed(i)) continue;
    const Quat& q = engine.orientation(i);
    const Vec3 wb = q.conjugate() * engine.angularVelocity(i);
    e += 0.5 * engine.mass(i) * engine.velocity(i).squaredNorm() +
         0.5 * wb.dot(engine.principalInertia(i).cwiseProduct(wb));
  }
  return e;
}

Real SdemWorld::gravityEnergy() const {
  Real e = 0;
  for (int i = 0; i < engine.numBodies(); ++i)
    if (!engine.isFixed(i)) e -= engine.mass(i) * gravity.dot(engine.position(i));
  return e;
}

}  // namespace sdem
}  // namespace mpmsdem
