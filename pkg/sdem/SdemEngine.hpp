// SdemEngine: block–block contact forces of a set of sphero-polyhedra (paper §2.2, Eqs 5–11;
// docs/physics.md). Broad phase (sort-and-sweep on x over the rounded bodies' AABBs, fixed–fixed
// pairs skipped), narrow phase (Ig2_SpheroPolyhedron_SpheroPolyhedron), pair physics
// (Ip2_SdemMat_SdemMat_BarrierPhys), law (Law2_SdemGeom_BarrierPhys_Coulomb), force and torque
// sums, tangential histories kept across steps.
//
// The engine does not move bodies: YADE's NewtonIntegrator does (through the Python bridge),
// or SdemWorld below in C++ tests and drivers. Bodies are addressed by a dense index
// (0..numBodies()-1, in order of addBody); state and forces also come as flat arrays so a
// bridge can exchange all bodies in one call.
#pragma once
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "common/Terrain.hpp"
#include "sdem/Ig2_SpheroPolyhedron_SpheroPolyhedron.hpp"
#include "sdem/Ig2_SpheroPolyhedron_Terrain.hpp"
#include "sdem/Ip2_SdemMat_SdemMat_BarrierPhys.hpp"
#include "sdem/Law2_SdemGeom_BarrierPhys_Coulomb.hpp"
#include "sdem/SdemMaterial.hpp"

namespace mpmsdem {
namespace sdem {

// The terrain's place in a contact key (bodyB) and record (externalB = -1).
constexpr int kTerrainBody = -2;

// Identity of a contact: the two body indices (bodyA < bodyB; bodyB kTerrainBody for a contact
// with the terrain) and the two core features.
struct ContactKey {
  int bodyA = -1, bodyB = -1;
  FeatureKind kindA = FeatureKind::Vertex, kindB = FeatureKind::Face;
  int indexA = -1, indexB = -1;
  bool operator==(const ContactKey& o) const {
    return bodyA == o.bodyA && bodyB == o.bodyB && kindA == o.kindA && kindB == o.kindB && indexA == o.indexA &&
           indexB == o.indexB;
  }
};

struct ContactKeyHash {
  size_t operator()(const ContactKey& k) const {
    uint64_t h = 1469598103934665603ull;
    const int64_t parts[6] = {k.bodyA, k.bodyB, static_cast<int64_t>(k.kindA), static_cast<int64_t>(k.kindB),
                              k.indexA, k.indexB};
    for (int64_t p : parts) h = (h ^ static_cast<uint64_t>(p)) * 1099511628211ull;
    return static_cast<size_t>(h);
  }
};

// One contact of the last computeForces(), for export.
struct ContactRecord {
  ContactKey key;
  int externalA = -1, externalB = -1;    // externalId of the two bodies
  Vec3 point = Vec3::Zero();             // contact point (midway between sphere surfaces) [m]
  Vec3 normal = Vec3::UnitX();           // unit normal from A to B
  Real normalForce = 0;                  // F_n on B along the normal [N] (>= 0)
  Vec3 tangentialForce = Vec3::Zero();   // F_t on B [N]
  Real overlap = 0;                      // delta [m] (Eq 7)
  Real normalStiffness = 0;              // k_n [N/m]
  bool sliding = false;                  // Coulomb cap reached
};

// The contacts' tangential histories by key, in open addressing with linear probing: once grown
// to the contacts' number, a step's lookups and inserts allocate nothing (a node-based map
// allocated one node per contact and step, a quarter of the blocks' step at 3,000 resting blocks).
// clear() starts a new generation instead of touching the slots.
class ContactHistoryTable {
 public:
  // The history of k, or null.
  const ContactHistory* find(const ContactKey& k) const;
  // Insert k's history, or replace it.
  void put(const ContactKey& k, const ContactHistory& h);
  void clear();
  std::size_t size() const { return size_; }
  void swap(ContactHistoryTable& o) noexcept;
  // f(key, history) for every entry, in slot order.
  template <typename F>
  void forEach(F f) const {
    for (std::size_t i = 0; i < gen_.size(); ++i)
      if (gen_[i] == current_) f(keys_[i], values_[i]);
  }

 private:
  std::size_t slotOf(const ContactKey& k) const;  // k's slot, or the free one where it would go
  void grow();
  std::vector<ContactKey> keys_;
  std::vector<ContactHistory> values_;
  std::vector<std::uint32_t> gen_;  // a slot is in use when it holds the current generation
  std::uint32_t current_ = 1;
  std::size_t size_ = 0;
};

// Tangential history of one contact, for checkpoints.
struct ContactHistoryEntry {
  ContactKey key;
  Vec3 xi = Vec3::Zero();  // elastic tangential force F_el [N]
};

class SdemEngine {
 public:
  // ---- set-up
  // Register a material (validated: ParameterError on a bad one); returns its index.
  int addMaterial(const SdemMaterial& m);
  int numMaterials() const { return static_cast<int>(materials_.size()); }
  const SdemMaterial& material(int k) const;

  // Add a body; returns its index. shape: non-null; material: a registered index;
  // mass [kg] > 0; principalInertia [kg m^2], all > 0, about the shape's body axes (the body
  // frame of SpheroPolyhedron); externalId: the caller's id (e.g. YADE's body id), reported in
  // contacts and errors. The body starts at rest at the origin with identity orientation.
  int addBody(std::shared_ptr<const SpheroPolyhedron> shape, int material, Real mass, const Vec3& principalInertia,
              int externalId);
  int numBodies() const { return static_cast<int>(shapes_.size()); }

  // A fixed body takes no forces into account for its motion (SdemWorld moves it
  // kinematically with its set velocities) and fixed–fixed pairs are never tested. A body
  // whose six degrees of freedom are blocked is one (SdemWorld::setBlockedDofs, the YADE
  // bridge); its contacts with moving bodies then use the moving body's mass as the
  // effective mass, and it does not limit criticalTimeStep().
  void setFixed(int i, bool fixed);
  bool isFixed(int i) const;

  // A terrain under the blocks (the flow's, common/Terrain.hpp: a height field, linear on the two
  // triangles of each raster cell) with its SDEM material (a registered index): every moving
  // body meets it through Ig2_SpheroPolyhedron_Terrain's contacts (its core vertices against the
  // triangles under them; the crest nodes and convex edges of ridges and peaks against its core,
  // so that relief finer than the core is felt), with the barrier and Coulomb laws of the block
  // pairs (the terrain's own radius 0: overlap R − d). A cube face-down on a plane carries its
  // weight on its 4 corners, edge-down on 2. The cost is each moving body's features against the
  // raster under it, whatever the raster's size. Terrain reaching a core (a vertex at or below
  // the surface, a crest in it) stops the run (RuntimeFailure), as interpenetrating cores do.
  // ParameterError for an invalid terrain (the checks of the flow's) or material.
  void setTerrain(const mpmsdem::TerrainSpec& terrain, int material);
  bool hasTerrain() const { return terrainMaterial_ >= 0; }

  // World-frame state: centroid position [m], orientation (x_world = pos + ori * x_body),
  // velocity [m/s], angular velocity [rad/s] (world frame).
  void setState(int i, const Vec3& pos, const Quat& ori, const Vec3& vel, const Vec3& angVel);
  // All bodies at once from flat arrays (3 n, 4 n as w x y z, 3 n, 3 n values).
  void setStates(const Real* pos, const Real* oriWxyz, const Real* vel, const Real* angVel);

  const Vec3& position(int i) const;
  const Quat& orientation(int i) const;
  const Vec3& velocity(int i) const;
  const Vec3& angularVelocity(int i) const;
  Real mass(int i) const;
  const Vec3& principalInertia(int i) const;
  int externalId(int i) const;
  int materialOf(int i) const;
  const SpheroPolyhedron& shape(int i) const;

  // ---- step
  // Contact forces and torques of the current state. dt [s] > 0 drives the tangential history
  // increment. Throws RuntimeFailure naming the bodies when cores touch or interpenetrate, or
  // when strictTimeStep is set and dt exceeds criticalTimeStep() (else counts a warning).
  void computeForces(Real dt);

  // Sum of contact forces on body i [N] and their torque about its centroid [N m], world
  // frame, from the last computeForces().
  const Vec3& force(int i) const;
  const Vec3& torque(int i) const;
  const std::vector<Vec3>& forces() const { return force_; }
  const std::vector<Vec3>& torques() const { return torque_; }

  const std::vector<ContactRecord>& contacts() const { return records_; }

  // Body pairs whose contact geometry the narrow phase has computed, summed over every
  // computeForces() so far: what the broad phase let through (fixed–fixed pairs never are).
  long narrowPhasePairs() const { return narrowPhasePairs_; }

  // ---- time step control
  // c * min over non-fixed bodies of sqrt(m_i / sum k_i) and sqrt(I_min,i / sum k_r,i) [s], with
  // sum k_i = sum over its contacts of max(k_n, K_t) and sum k_r,i = sum of
  // k_n |r x n|^2 + K_t |r|^2 (r: centroid -> contact point). For one spring the leapfrog is
  // stable up to 2 sqrt(m/k): c = 1 reports half the stability limit. +infinity when no body
  // has a contact. Uses the stiffnesses of the last computeForces() (the barrier stiffens
  // fast with the overlap: keep a margin).
  Real criticalTimeStep() const;
  // The per-body sums behind criticalTimeStep(), from the last computeForces(): sum of
  // max(k_n, K_t) [N/m] and of k_n |r x n|^2 + K_t |r|^2 [N m]. A coupling adds its own
  // contacts' sums to these for the combined critical step.
  Real stiffnessSum(int i) const { return checkBody(i, "body"), sumK_[i]; }
  Real rotationalStiffnessSum(int i) const { return checkBody(i, "body"), sumKr_[i]; }
  // Safety factor c [-] in criticalTimeStep(). Valid: > 0. Default 1.
  void setTimeStepSafety(Real c);
  Real timeStepSafety() const { return safety_; }
  // Strict: computeForces(dt) throws RuntimeFailure when dt > checkFactor * criticalTimeStep().
  // Not strict (default): it counts the step in timeStepWarnings().
  void setStrictTimeStep(bool strict) { strict_ = strict; }
  bool strictTimeStep() const { return strict_; }
  long timeStepWarnings() const { return warnings_; }
  // The factor on criticalTimeStep() that the check above allows [-]. Valid: in [1, 2].
  // Default 1, for a step the user fixes. A step chosen automatically from the contacts of the
  // step before cannot see a contact that starts within it (a block landing): 2, the leapfrog's
  // own stability limit for c = 1, lets that step through, and the next step shrinks.
  void setTimeStepCheckFactor(Real f);
  Real timeStepCheckFactor() const { return checkFactor_; }

  // The step in which a point of a moving body travels its own sweep radius [s]: min over
  // bodies of R_i / (|v_i| + |w_i| rho_i), rho_i its bounding radius about the centroid, from
  // the state last set (a fixed body moved with a set velocity counts); +infinity when nothing
  // moves. Within f times this step no body moves by more than f R_i, so two bodies apart
  // enter their barrier by at most f (R_i + R_j) in one step, and none crosses another (cores
  // are R_i + R_j apart at first touch). Not a stability limit: criticalTimeStep() sees only the
  // contacts there are, and a body about to land has none; autoTimeStep() takes both. With
  // `body`, the index of the body that sets it (-1 when nothing moves).
  Real approachTimeStep(int* body = nullptr) const;
  // |v_i| + |w_i| rho_i [m/s]: no point of body i moves faster (rho_i its bounding radius).
  Real pointSpeedBound(int i) const;

  // ---- energies [J]
  Real barrierEnergy() const { return barrierEnergy_; }          // sum of b(d), current
  Real tangentialEnergy() const { return springEnergy_; }        // sum of |F_el|^2 / (2 K_t), current
  Real frictionDissipation() const { return frictionWork_; }     // cumulative slip work
  Real dampingDissipation() const { return dampingWork_; }       // cumulative dashpot work
  // Continue the cumulative counters of a checkpointed run (finite, >= 0: ParameterError).
  void setDissipation(Real friction, Real damping);

  // ---- checkpoint of the contact histories
  std::vector<ContactHistoryEntry> contactHistories() const;
  // Replace all histories (ParameterError on a key naming a body index out of range).
  void setContactHistories(const std::vector<ContactHistoryEntry>& h);

 private:
  void checkBody(int i, const char* what) const;
  void broadPhase();
  void terrainContacts(Real dt);
  // The law on one contact geometry g of bodies a and b (b = kTerrainBody: the terrain, at rest),
  // its forces, stiffness sums, energies, history and record.
  void addContact(int a, int b, const SdemGeom& g, const BarrierPhys& phys, Real R, Real meff, Real dt);

  std::vector<SdemMaterial> materials_;
  std::vector<BarrierPhys> pairPhys_;  // numMaterials^2, row-major

  std::vector<std::shared_ptr<const SpheroPolyhedron>> shapes_;
  std::vector<int> material_, external_;
  std::vector<Real> mass_;
  std::vector<Vec3> inertia_;
  std::vector<char> fixed_;
  std::vector<Vec3> pos_, vel_, angVel_;
  std::vector<Quat> ori_;
  std::vector<PosedSpheroPolyhedron> posed_;
  std::vector<char> poseStale_;

  std::vector<Vec3> force_, torque_;
  std::vector<Real> sumK_, sumKr_;
  std::vector<Vec3> boxLo_, boxHi_;  // rounded-body boxes of the current step (broad phase)
  std::vector<std::pair<int, int>> pairs_;
  std::vector<int> order_;
  std::vector<SdemGeom> geoms_;
  std::vector<ContactRecord> records_;
  ContactHistoryTable history_, nextHistory_;
  Ig2_SpheroPolyhedron_Terrain terrainGeom_;
  int terrainMaterial_ = -1;

  Real safety_ = 1.0;
  Real checkFactor_ = 1.0;
  bool strict_ = false;
  long warnings_ = 0;
  long narrowPhasePairs_ = 0;
  Real barrierEnergy_ = 0, springEnergy_ = 0, frictionWork_ = 0, dampingWork_ = 0;
};

// The next step of automatic time stepping [s]: the smaller of factor * critical (factor in
// (0, 1]) and kApproachFraction * approach (approachTimeStep()), and at most kAutoStepGrowth
// times lastDt when lastDt > 0. A body thus enters a barrier by at most a tenth of its sweep
// radius in one step: the first step of a contact skips the barrier's work up to that overlap
// (~k_c delta^3 / R), which at half the radius made a cube landing face-down on an elastic
// barrier leave with 43 % more energy than it came with. The growth cap is there because YADE's
// NewtonIntegrator, which SdemWorld follows, kicks the velocity with the new step where a
// leapfrog with changing steps needs the mean of the steps on either side of the position, so
// a step that changes during a contact adds or takes a share of its work; a shrinking step is
// never held back (stability first). Measured with both (test_engine.cpp): -0.24 % of the
// energy face-down, -2.5 % for a cube landing edge-first while it spins; a fixed step keeps
// the same impacts to 1e-6.
constexpr Real kAutoStepGrowth = 1.01;
constexpr Real kApproachFraction = 0.1;
Real autoTimeStep(Real factor, Real critical, Real approach, Real lastDt);

// Minimal rigid-body world for C++ tests and the driver, integrating as YADE's
// NewtonIntegrator does (damping 0, exactAsphericalRot), so that a scene run by the driver and
// by YADE gives the same trajectories (tests/python/test_driver_blocks.py):
//  - translation, leapfrog: v(t+dt/2) = v(t-dt/2) + dt (F/m + g), x(t+dt) = x(t) + dt v(t+dt/2);
//    a blocked translational DOF keeps its velocity (neither force nor gravity acts on it);
//  - rotation with no rotational DOF blocked: world angular momentum L(t+dt/2) = L(t-dt/2) + dt T;
//    body-frame rates at t (from L(t) = L(t-dt/2) + dt T/2) and at t+dt/2 (both through the
//    orientation at t) drive a half-step and a full-step update of the quaternion components
//    (q' = q + dt/2 q (0, w_body)), which is then normalised;
//  - rotation with a rotational DOF blocked: omega += dt T / I per world axis, blocked axes
//    kept, orientation turned by |omega| dt about omega (YADE's choice for such bodies);
//  - fixed bodies move kinematically with their set velocities.
// YADE ignores an angular velocity set on an aspherical body (its angular momentum rules);
// here a velocity set from outside (setState) re-derives the angular momentum from it.
class SdemWorld {
 public:
  SdemEngine engine;
  Vec3 gravity = Vec3(0, 0, -9.81);  // [m/s^2]

  // One step. extraForce/extraTorque (world frame, one per body, or null): forces from outside
  // the engine (a coupling) added to the contact forces of this step.
  void step(Real dt, const std::vector<Vec3>* extraForce = nullptr, const std::vector<Vec3>* extraTorque = nullptr);
  Real time() const { return time_; }
  // Degrees of freedom of body i that forces do not change, YADE's blockedDOFs: a string of
  // letters among x y z (translations) and X Y Z (rotations about world axes), "" for none.
  // All six make the body fixed in the engine (as YADE's `dynamic = False`) until a later call
  // unblocks one of them; a body fixed with SdemEngine::setFixed stays fixed either way.
  void setBlockedDofs(int i, const std::string& dofs);
  std::string blockedDofs(int i) const;
  // Translational + rotational kinetic energy of the non-fixed bodies [J].
  Real kineticEnergy() const;
  // Gravitational potential energy -sum m g . x of the non-fixed bodies [J].
  Real gravityEnergy() const;

  // ---- checkpoint: what a step carries to the next besides the engine's state
  // World angular momentum L(t - dt/2) of body i [N m s] that the rotation update carries;
  // false when there is none (before its first step, or its angular velocity was set since,
  // or a rotational DOF is blocked): the next step derives it from the angular velocity.
  bool angularMomentum(int i, Vec3& L) const;
  // Carry L for body i into the next step, as if this world had taken the steps before: its
  // angular velocity (set with engine.setState) must be the one those steps left.
  void restoreAngularMomentum(int i, const Vec3& L);
  // Clock of a restored run [s] (finite, >= 0).
  void setTime(Real t);

 private:
  std::vector<Vec3> angMom_, lastAngVel_;
  std::vector<unsigned> blocked_;  // bit k: DOF "xyzXYZ"[k] blocked
  std::vector<char> fixedByDofs_;  // made fixed by setBlockedDofs (all six), not by setFixed
  Real time_ = 0;
};

}  // namespace sdem
}  // namespace mpmsdem
