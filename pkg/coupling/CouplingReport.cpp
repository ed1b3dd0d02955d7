#include "coupling/CouplingReport.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/Error.hpp"
#include "coupling/CouplingKernelsCommon.hpp"

namespace mpmsdem {
namespace coupling {

const double* CouplingReport::sums(int i, int offset) const {
  const int n = reportedBodies();
  const std::vector<double>& s = lastSums();
  if (i < 0 || i >= n || s.size() < static_cast<std::size_t>(kBlockSums) * n)
    throwParameter(indexKey_, i, "", indexWhat_ + " in [0, " + std::to_string(n) + ") of the last coupling step");
  return s.data() + kBlockSums * i + offset;
}

Vec3 CouplingReport::sumVector(int i, int offset) const {
  const double* s = sums(i, offset);
  return Vec3(s[0], s[1], s[2]);
}
bool CouplingReport::reported(int i) const {
  return i >= 0 && i < reportedBodies() && lastSums().size() >= static_cast<std::size_t>(kBlockSums) * (i + 1);
}

void CouplingReport::setDissipation(double friction, double damping) {
  if (!(friction >= 0) || !(damping >= 0)) throwParameter("dissipation", friction < 0 ? friction : damping, "J", ">= 0");
  frictionWork_ = friction;
  dampingWork_ = damping;
}

Vec3 CouplingReport::impulseVector(int i, int offset) const {
  if (i < 0 || i >= reportedBodies())
    throwParameter(indexKey_, i, "", indexWhat_ + " in [0, " + std::to_string(reportedBodies()) +
                                         ") of the last coupling step");
  const std::size_t at = static_cast<std::size_t>(kImpulseValues) * i + offset;
  if (at + 3 > impulse_.size()) return Vec3::Zero();
  return Vec3(impulse_[at], impulse_[at + 1], impulse_[at + 2]);
}
Vec3 CouplingReport::impulse(int i) const { return impulseVector(i, 0); }
Vec3 CouplingReport::angularImpulse(int i) const { return impulseVector(i, 3); }

void CouplingReport::setImpulses(const std::vector<double>& values) {
  if (values.size() % kImpulseValues != 0)
    throwParameter("impulses", values.size(), "", "6 values per body (impulse [N s], angular impulse [N m s])");
  for (double v : values)
    if (!std::isfinite(v)) throwParameter("impulses", v, "N s", "finite");
  impulse_ = values;
}

double CouplingReport::firstContact(int i) const {
  if (i < 0 || i >= reportedBodies())
    throwParameter(indexKey_, i, "", indexWhat_ + " in [0, " + std::to_string(reportedBodies()) +
                                         ") of the last coupling step");
  const double t = static_cast<std::size_t>(i) < firstContact_.size() ? firstContact_[i]
                                                                      : std::numeric_limits<double>::quiet_NaN();
  return std::isinf(t) ? std::numeric_limits<double>::quiet_NaN() : t;
}

void CouplingReport::restoreFirstContacts(const std::vector<double>& kept, bool impulsesKept, int bodies) {
  for (double v : kept)
    if (!(std::isnan(v) || (std::isfinite(v) && v >= 0)))
      throwParameter("first contacts", v, "s", ">= 0, or NaN (not touched yet, or not kept)");
  const double notKept = -std::numeric_limits<double>::infinity();
  const std::size_t withImpulse = impulse_.size() / kImpulseValues,
                    n = std::max(static_cast<std::size_t>(bodies), withImpulse);
  if (kept.empty() && !impulsesKept) {
    firstContact_.assign(n, notKept);
    return;
  }
  firstContact_ = kept;
  if (firstContact_.size() < n) firstContact_.resize(n, std::numeric_limits<double>::quiet_NaN());
  for (std::size_t b = 0; b < withImpulse; ++b)
    for (int k = 0; k < kImpulseValues && std::isnan(firstContact_[b]); ++k)
      if (impulse_[kImpulseValues * b + k] != 0) firstContact_[b] = notKept;
}

std::vector<long long> currentHistoryKeys(const std::vector<long long>& keys, const std::vector<unsigned>& written,
                                          unsigned step, int slots) {
  std::vector<long long> out = keys;
  for (std::size_t h = 0; h < written.size() && slots * (h + 1) <= out.size(); ++h)
    if (written[h] != step) std::fill_n(out.begin() + slots * h, slots, -1LL);
  return out;
}

void checkHistories(const std::vector<long long>& keys, const std::vector<double>& xi, int slots) {
  if (xi.size() != 3 * keys.size()) throwParameter("history xi size", xi.size(), "", "3 x the number of keys");
  if (keys.size() % slots != 0)
    throwParameter("history keys size", keys.size(), "", "a multiple of historySlots = " + std::to_string(slots));
  for (double v : xi)
    if (!std::isfinite(v)) throw ParameterError("history xi: must be finite");
}

Vec3 CouplingReport::force(int i) const { return sumVector(i, kSumForce); }
Vec3 CouplingReport::torque(int i) const { return sumVector(i, kSumTorque); }
int CouplingReport::contactCount(int i) const { return static_cast<int>(*sums(i, kSumCount)); }
double CouplingReport::stiffnessSum(int i) const { return *sums(i, kSumK); }
double CouplingReport::rotationalStiffnessSum(int i) const { return *sums(i, kSumKr); }

void CouplingReport::takeStepTotals(const std::vector<double>& sums, int bodies, double dt, double stepStart) {
  barrierEnergy_ = springEnergy_ = 0;
  if (impulse_.size() < static_cast<std::size_t>(kImpulseValues) * bodies) impulse_.resize(kImpulseValues * bodies, 0.0);
  if (firstContact_.size() < static_cast<std::size_t>(bodies))
    firstContact_.resize(bodies, std::numeric_limits<double>::quiet_NaN());
  for (int b = 0; b < bodies; ++b) {
    const double* s = sums.data() + kBlockSums * b;
    barrierEnergy_ += s[kSumBarrier];
    springEnergy_ += s[kSumSpring];
    frictionWork_ += s[kSumFriction];
    dampingWork_ += s[kSumDamping];
    double* j = impulse_.data() + kImpulseValues * b;
    for (int d = 0; d < 3; ++d) {
      j[d] += s[kSumForce + d] * dt;
      j[3 + d] += s[kSumTorque + d] * dt;
    }
    if (std::isnan(firstContact_[b]) && (s[kSumForce] != 0 || s[kSumForce + 1] != 0 || s[kSumForce + 2] != 0))
      firstContact_[b] = stepStart;
  }
}

}  // namespace coupling
}  // namespace mpmsdem
