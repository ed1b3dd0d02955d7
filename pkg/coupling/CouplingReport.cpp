#include "coupling/CouplingReport.hpp"

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
