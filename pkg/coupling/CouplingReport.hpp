// What a coupling of the flow with rigid bodies reports of its last step, per body (the sums of
// its contacts: kBlockSums doubles a body, CouplingKernelsCommon.hpp) and in all (step bounds,
// history overflow, energies). MpSdemCoupling (SDEM blocks) and MpLevelSetCoupling (YADE
// LevelSet bodies) report through it alike.
#pragma once
#include <limits>
#include <string>
#include <vector>

#include "common/Types.hpp"

namespace mpmsdem {
namespace coupling {

// A checkpoint of a coupling's tangential histories, per particle `slots` keys and 3 x slots
// elastic tangential forces xi [N]: the keys with the slots not written by the last step
// (written[p] != step) set to -1 (empty), and the checks of a set to restore (sizes, finite xi),
// ParameterError naming what is wrong.
std::vector<long long> currentHistoryKeys(const std::vector<long long>& keys, const std::vector<unsigned>& written,
                                          unsigned step, int slots);
void checkHistories(const std::vector<long long>& keys, const std::vector<double>& xi, int slots);

class CouplingReport {
 public:
  // ---- per body index, world frame
  Vec3 force(int body) const;        // force of the flow on the body [N]
  Vec3 torque(int body) const;       // its torque about the body's centroid (SDEM) or position (LevelSet) [N m]
  int contactCount(int body) const;  // number of MP contacts
  double stiffnessSum(int body) const;            // sum max(k_n, K_t) [N/m]
  double rotationalStiffnessSum(int body) const;  // sum k_n |r x n|^2 + K_t |r|^2 [N m]

  // Smallest sqrt(m_p / max(k_n, K_t)) over the MP contacts [s]; +inf without contacts.
  double particleCriticalStep() const { return minParticleStep_; }
  // The longest next step [s] that stays within the contact step of the contacts the last step
  // made (points that did not touch a body at its start but reached its barrier within it):
  // the smallest approachStepBound (CouplingKernelsCommon.hpp) with the time-step safety; +inf
  // when no point did. The contact step itself sees those contacts one step late. Pairs are
  // examined up to the distance they close in the step, at most one grid cell (a particle moves
  // less than a cell per stable MPM step).
  double particleApproachStep() const { return minApproachStep_; }
  long historyOverflow() const { return overflow_; }

  // ---- energies [J]: current barrier and tangential-spring potentials, cumulative slip and
  // dashpot work of MP–body contacts.
  double barrierEnergy() const { return barrierEnergy_; }
  double springEnergy() const { return springEnergy_; }
  double frictionDissipation() const { return frictionWork_; }
  double dampingDissipation() const { return dampingWork_; }
  // The dissipation counters, to continue after a restart [J], each >= 0.
  void setDissipation(double friction, double damping);
  // Whether body i has sums of a last step (a body added since, or before the first step, has none).
  bool reported(int body) const;

  // ---- impulses since the run's start, per body index: the flow's force and torque of every
  // step times its dt, summed [N s], [N m s]. Their difference between two records over the
  // interval is the mean force between them, which no single step's force gives: a contact
  // force swings from step to step, and a record every few hundred steps samples one of them.
  Vec3 impulse(int body) const;
  Vec3 angularImpulse(int body) const;
  // kImpulseValues per body (impulse, then angular impulse), in body order: the counters, to
  // continue after a restart. setImpulses: finite values, kImpulseValues per body (ParameterError).
  static constexpr int kImpulseValues = 6;
  const std::vector<double>& impulses() const { return impulse_; }
  void setImpulses(const std::vector<double>& values);

  // ---- when the flow first touched each body index: the start [s] of the first step whose
  // force on it was not zero (a step's contacts are those of the state it starts from, and the
  // impulse up to then is the one before any contact); NaN before that. A record holds one
  // step's force every record interval, so the first record with a force places the touch only
  // within that interval, and the first blow's windows (counted from the touch) would start up
  // to an interval late. NaN too where it is not known: a run continued from a state that did
  // not keep it (restoreFirstContacts).
  double firstContact(int body) const;
  // Per body index, to continue after a restart: a time >= 0, NaN (not yet) or -inf (touched
  // at a time not kept).
  const std::vector<double>& firstContacts() const { return firstContact_; }
  // At a restart, after setImpulses: the first contacts a state kept for its `bodies` bodies
  // (per body index, a time >= 0 or NaN for none; empty where it kept none). A body without one
  // that the impulses say was touched was touched at a time not kept: it stays NaN, and no later
  // step sets it; so does every body of a state that kept neither (`impulsesKept` false).
  // ParameterError for a time < 0 or infinite.
  void restoreFirstContacts(const std::vector<double>& kept, bool impulsesKept, int bodies);

 protected:
  // indexKey, indexWhat: how a bad body index is named in the ParameterError (the parameter and
  // what it must be, e.g. "block", "a block (SDEM body) index").
  CouplingReport(std::string indexKey, std::string indexWhat)
      : indexKey_(std::move(indexKey)), indexWhat_(std::move(indexWhat)) {}
  virtual ~CouplingReport() = default;
  // The per-body sums of the last step and the number of bodies they were summed for.
  virtual const std::vector<double>& lastSums() const = 0;
  virtual int reportedBodies() const = 0;
  // Body i's sums from `offset`; ParameterError when i is no body of the last step.
  const double* sums(int body, int offset) const;
  // The three sums of body i from `offset` as a vector (force, torque, their face and edge shares).
  Vec3 sumVector(int body, int offset) const;
  // The step's potentials (replaced), dissipations and impulses (added) from its per-body sums,
  // its length dt [s] and the time it starts at [s] (the first contacts).
  void takeStepTotals(const std::vector<double>& sums, int bodies, double dt, double stepStart);

  double minParticleStep_ = std::numeric_limits<double>::infinity();
  double minApproachStep_ = std::numeric_limits<double>::infinity();
  long overflow_ = 0;
  double barrierEnergy_ = 0, springEnergy_ = 0, frictionWork_ = 0, dampingWork_ = 0;

 private:
  // Body i's impulse counters from `offset` (0: impulse, 3: angular impulse); zero for a body
  // no step has reached yet.
  Vec3 impulseVector(int body, int offset) const;
  std::vector<double> impulse_;  // kImpulseValues per body
  std::vector<double> firstContact_;  // per body: time, NaN (not yet) or -inf (not kept)
  std::string indexKey_, indexWhat_;
};

}  // namespace coupling
}  // namespace mpmsdem
