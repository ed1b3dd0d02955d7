#include "coupling/CouplingReport.hpp"

#include <algorithm>
#include <cmath>

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

void CouplingReport::takeEnergies(const std::vector<double>& sums, int bodies) {
  barrierEnergy_ = springEnergy_ = 0;
  for (int b = 0; b < bodies; ++b) {
    const double* s = sums.data() + kBlockSums * b;
    barrierEnergy_ += s[kSumBarrier];
    springEnergy_ += s[kSumSpring];
    frictionWork_ += s[kSumFriction];
    dampingWork_ += s[kSumDamping];
  }
}

}  // namespace coupling
}  // namespace mpmsdem
