#include "coupling/MpLevelSetCoupling.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "common/Error.hpp"
#include "coupling/CouplingBackend.hpp"
#include "coupling/CpuContactLoop.hpp"

namespace mpmsdem {
namespace coupling {

namespace {
constexpr double kPi = 3.14159265358979323846;

template <typename T>
double smallest(const void* values, std::size_t n) {
  const T* a = static_cast<const T*>(values);
  double m = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) m = std::min(m, static_cast<double>(a[i]));
  return m;
}
}  // namespace

int MpLevelSetCoupling::addBody(int externalId, LevelSetGrid grid, const sdem::BarrierPhys& phys) {
  const std::string what = "LevelSet body " + std::to_string(externalId) + ": ";
  if (!(grid.spacing > 0) || !std::isfinite(grid.spacing))
    throwParameter(what + "grid spacing", grid.spacing, "m", "> 0");
  if (!grid.min.allFinite()) throw ParameterError(what + "grid min: must be finite");
  long long n = 1;
  for (int d = 0; d < 3; ++d) {
    if (grid.nGP[d] < 2) throwParameter(what + "grid nGP[" + std::to_string(d) + "]", grid.nGP[d], "", ">= 2");
    n *= grid.nGP[d];
  }
  if (static_cast<long long>(grid.dist.size()) != n)
    throwParameter(what + "distField size", grid.dist.size(), "",
                   "nGP[0] x nGP[1] x nGP[2] = " + std::to_string(n) + " grid values");
  for (double v : grid.dist)
    if (!std::isfinite(v)) throw ParameterError(what + "distField: every value must be finite");
  checkPairPhys(phys);
  ids_.push_back(externalId);
  distF_.emplace_back(grid.dist.begin(), grid.dist.end());
  grids_.push_back(std::move(grid));
  phys_.push_back({phys.barrierStiffness, phys.friction, phys.poisson, phys.normalDamping, phys.tangentialDamping});
  gridsChanged_ = true;
  bodies_.emplace_back();
  minInertia_.push_back(0);
  stateSet_.push_back(0);
  return numBodies() - 1;
}

Vec3 MpLevelSetCoupling::position(int i) const {
  const BlockState<double>& b = bodies_.at(i);
  return Vec3(b.pos[0], b.pos[1], b.pos[2]);
}

Mat3 MpLevelSetCoupling::rotation(int i) const {
  const BlockState<double>& b = bodies_.at(i);
  Mat3 R;
  for (int d = 0; d < 3; ++d)
    for (int e = 0; e < 3; ++e) R(d, e) = b.rot[3 * d + e];
  return R;
}

void MpLevelSetCoupling::setState(int i, const Vec3& pos, const Quat& ori, const Vec3& vel, const Vec3& angVel,
                                  double mass, double minInertia, bool fixed) {
  if (i < 0 || i >= numBodies()) throwParameter("LevelSet body index", i, "", "in [0, " + std::to_string(numBodies()) + ")");
  const std::string what = "LevelSet body " + std::to_string(ids_[i]) + ": ";
  if (!pos.allFinite() || !ori.coeffs().allFinite() || !vel.allFinite() || !angVel.allFinite())
    throw RuntimeFailure(what + "non-finite position, orientation or velocity (the run blew up?)");
  if (!fixed && !(mass > 0)) throwParameter(what + "mass", mass, "kg", "> 0 for a body that moves");
  BlockState<double>& b = bodies_[i];
  const Mat3 R = ori.normalized().toRotationMatrix();
  for (int d = 0; d < 3; ++d) {
    b.pos[d] = pos[d];
    b.vel[d] = vel[d];
    b.angVel[d] = angVel[d];
    for (int e = 0; e < 3; ++e) b.rot[3 * d + e] = R(d, e);
  }
  const LevelSetGrid& g = grids_[i];
  double reach = 0;  // farthest corner of the grid box from the grid origin
  for (int c = 0; c < 8; ++c) {
    Vec3 corner;
    for (int d = 0; d < 3; ++d) corner[d] = g.min[d] + ((c >> d) & 1 ? (g.nGP[d] - 1) * g.spacing : 0.0);
    reach = std::max(reach, corner.norm());
  }
  b.reach = reach;
  b.mass = mass;
  b.shape = i;
  b.phys = i;
  b.fixed = fixed ? 1 : 0;
  minInertia_[i] = minInertia;
  stateSet_[i] = 1;
}

void MpLevelSetCoupling::checkResolution(double particleRadius) const {
  for (int i = 0; i < numBodies(); ++i) {
    if (grids_[i].spacing <= levelSetSpacingLimit(particleRadius)) continue;
    std::ostringstream os;
    os << "LevelSet body " << ids_[i] << ": grid spacing " << grids_[i].spacing
       << " m is coarser than the material point contact radius R_p0 = " << particleRadius
       << " m: the spacing must be <= R_p0 (near the body's edges and corners the interpolated distance is "
          "off by up to a quarter of the spacing, and the barrier acts only over overlaps up to R_p0); "
          "build the body with a finer spacing";
    throw ParameterError(os.str());
  }
}

void MpLevelSetCoupling::setHistorySlots(int slots) {
  if (slots < 1 || slots > 4) throwParameter("historySlots", slots, "", "in [1, 4]");
  if (slots != slots_) {
    slots_ = slots;
    particleCount_ = 0;  // the histories restart at the next step
  }
}

void MpLevelSetCoupling::pullHistories() {
  if (!historiesOnDevice_ || historiesToDevice_) return;  // the host copies are the current ones
  device_->downloadHistories(key_, xi_, written_);
  floatRun_ = false;  // (downloaded in double)
}

void MpLevelSetCoupling::historiesToHost() {
  pullHistories();
  xiF_.assign(xi_.begin(), xi_.end());  // (downloaded in double; a float step reads these)
  historiesOnDevice_ = false;
  historiesToDevice_ = true;  // (should a later step run on a device)
}

std::vector<long long> MpLevelSetCoupling::historyKeys() const {
  return currentHistoryKeys(key_, written_, historyStep_, slots_);
}

std::vector<double> MpLevelSetCoupling::historyXi() const {
  return floatRun_ ? std::vector<double>(xiF_.begin(), xiF_.end()) : xi_;
}

void MpLevelSetCoupling::setHistories(const std::vector<long long>& keys, const std::vector<double>& xi) {
  checkHistories(keys, xi, slots_);
  particleCount_ = keys.size() / slots_;
  key_ = keys;
  written_.assign(particleCount_, historyStep_);  // current at the next step
  // the next step's precision picks its copy (computeForces keeps the one of its size)
  xi_ = xi;
  xiF_.assign(xi.begin(), xi.end());
  floatRun_ = false;  // historyXi() before the next step: the double copy
  historiesOnDevice_ = false;
  historiesToDevice_ = true;  // for a step on the device
}

void MpLevelSetCoupling::computeForces(const mpm::ParticleView& view, double dt, double stepStart, double safety,
                                       double watch) {
  if (!(dt > 0) || !std::isfinite(dt)) throwParameter("dt", dt, "s", "> 0");
  if (!std::isfinite(stepStart)) throwParameter("stepStart", stepStart, "s", "finite");
  stepStart_ = stepStart;
  for (int i = 0; i < numBodies(); ++i)
    if (!stateSet_[i]) throw RuntimeFailure("LevelSet body " + std::to_string(ids_[i]) + ": no state set before the step");
  const bool isFloat = view.precision == mpm::Precision::Float;
  sums_.assign(static_cast<std::size_t>(kBlockSums) * numBodies(), 0.0);
  minParticleStep_ = minApproachStep_ = std::numeric_limits<double>::infinity();
  contacts_.clear();
  contactsF_.clear();
  barrierEnergy_ = springEnergy_ = 0;
  onDevice_ = false;  // (until a device step: where the histories and contacts are)
  if (numBodies() == 0 || view.n == 0) return;
  if (view.device) return runDevice(view, dt, safety, watch);
  if (historiesOnDevice_) historiesToHost();  // the steps before ran on the device: go on from its histories
  if (view.n != particleCount_ || (isFloat ? xiF_.size() : xi_.size()) != 3 * slots_ * view.n) {
    // a new particle set: no history yet, and its smallest radius may be below the grids'
    const double v0 = isFloat ? smallest<float>(view.volume0, view.n) : smallest<double>(view.volume0, view.n);
    checkResolution(std::cbrt(3 * v0 / (4 * kPi)));
    particleCount_ = view.n;
    key_.assign(slots_ * view.n, -1);
    written_.assign(view.n, historyStep_);
    xi_.assign(isFloat ? 0 : 3 * slots_ * view.n, 0.0);
    xiF_.assign(isFloat ? 3 * slots_ * view.n : 0, 0.0f);
  }
  floatRun_ = isFloat;
  if (isFloat) {
    std::vector<BlockState<float>> B(bodies_.size());
    std::vector<sdem::BarrierCoulombPhys<float>> phys(phys_.size());
    std::vector<LevelSetGridView<float>> G(grids_.size());
    for (std::size_t i = 0; i < bodies_.size(); ++i) {
      B[i] = convertBlock<float>(bodies_[i]);
      phys[i] = convertPhys<float>(phys_[i]);
      const LevelSetGrid& g = grids_[i];
      G[i] = {{float(g.min[0]), float(g.min[1]), float(g.min[2])}, float(g.spacing),
              {g.nGP[0], g.nGP[1], g.nGP[2]}, distF_[i].data()};
    }
    run(view, B.data(), G.data(), phys.data(), xiF_, contactsF_, dt, safety, watch);
    reduce(contactsF_, B.data(), dt);
  } else {
    std::vector<LevelSetGridView<double>> G(grids_.size());
    for (std::size_t i = 0; i < grids_.size(); ++i) {
      const LevelSetGrid& g = grids_[i];
      G[i] = {{g.min[0], g.min[1], g.min[2]}, g.spacing, {g.nGP[0], g.nGP[1], g.nGP[2]}, g.dist.data()};
    }
    run(view, bodies_.data(), G.data(), phys_.data(), xi_, contacts_, dt, safety, watch);
    reduce(contacts_, bodies_.data(), dt);
  }
}

template <typename T>
void MpLevelSetCoupling::run(const mpm::ParticleView& view, const BlockState<T>* B, const LevelSetGridView<T>* G,
                             const sdem::BarrierCoulombPhys<T>* phys, std::vector<T>& xi,
                             std::vector<MpContact<T>>& contacts, double dt, double safety, double watch) {
  const CouplingParticles<T> P = couplingParticles<T>(view);
  const HistoryView<T> H{key_.data(), xi.data(), written_.data(), ++historyStep_, slots_};
  const int nb = numBodies();
  const long n = static_cast<long>(view.n);
  std::vector<std::vector<MpContact<T>>> chunkContacts;
  const ContactLoopTotals t = runContactChunks(
      P, n, chunkContacts,
      [&](int p, auto& sink, int* bad, int* over, T* approach,
          CouplingLoopMemo<T>& memo) __attribute__((always_inline)) {  // inlined: CpuContactLoop.hpp
        return coupleParticleLevelSets(p, P, B, nb, G, phys, H, T(dt), T(safety), T(watch), sink, bad, over, approach,
                                       memo);
      });
  overflow_ += t.overflow;
  minApproachStep_ = t.approach;
  if (t.firstBad < n) centreReached(t.firstBad, t.badBody);
  for (const auto& list : chunkContacts) contacts.insert(contacts.end(), list.begin(), list.end());
  // by particle number, not storage slot: sums that do not depend on the solver's particle order
  std::stable_sort(contacts.begin(), contacts.end(),
                   [](const MpContact<T>& a, const MpContact<T>& b) { return a.particle < b.particle; });
}

void MpLevelSetCoupling::centreReached(long particle, int body) const {
  std::ostringstream os;
  os << "MP-LevelSet coupling: the centre of material point " << particle << " reached the surface of LevelSet body "
     << ids_[body] << " (distance <= 0, overlap >= R_p0); at the first step the particles were seeded inside "
     << "the body, later the time step was too long for the barrier stiffness";
  throw RuntimeFailure(os.str());
}

// The step on the solver's device: the SDEM coupling's backend with the bodies' grids for its
// shape table, launched and collected at once (the flow's step is queued after it).
void MpLevelSetCoupling::runDevice(const mpm::ParticleView& view, double dt, double safety, double watch) {
  if (!device_ || devicePrecision_ != view.precision) {
    if (historiesOnDevice_) historiesToHost();  // the replaced backend's histories go on in the new one
    device_ = makeCouplingDeviceBackend(view.precision);
    if (!device_) throw RuntimeFailure("MP-LevelSet coupling: the solver runs on CUDA but this build has no CUDA coupling");
    device_->recordContacts(true);  // contacts() reads them: those of a few bodies
    devicePrecision_ = view.precision;
    gridsChanged_ = true;
  }
  if (view.n != particleCount_) {  // a new particle set: its smallest radius may be below the grids', no history yet
    checkResolution(std::cbrt(3 * device_->volume0Range(view).first / (4 * kPi)));
    particleCount_ = view.n;
    device_->resetHistories();
    historiesToDevice_ = false;
  }
  if (historiesToDevice_) {
    if (floatRun_) xi_.assign(xiF_.begin(), xiF_.end());  // a float CPU step kept its histories there
    device_->uploadHistories(key_, xi_, written_);
  }
  historiesToDevice_ = false;
  if (gridsChanged_) {
    gridViews_.clear();
    for (const LevelSetGrid& g : grids_)
      gridViews_.push_back({{g.min[0], g.min[1], g.min[2]}, g.spacing, {g.nGP[0], g.nGP[1], g.nGP[2]}, g.dist.data()});
  }
  CouplingStepInput in{};
  in.blocks = &bodies_;
  in.phys = &phys_;
  in.particles = view;
  in.dt = dt;
  in.stepSafety = safety;
  in.historySlots = slots_;
  in.historyStep = ++historyStep_;
  in.levelSets = &gridViews_;
  in.levelSetsChanged = gridsChanged_;
  in.watch = watch;
  CouplingStepOutput out;
  device_->launch(in);
  device_->collect(out);
  gridsChanged_ = false;
  onDevice_ = historiesOnDevice_ = true;
  if (out.badParticle >= 0) centreReached(out.badParticle, out.badBlock);
  overflow_ += out.overflow;
  minApproachStep_ = out.minApproachStep;
  minParticleStep_ = out.minParticleStep;
  sums_ = out.sums;
  takeStepTotals(sums_, numBodies(), dt, stepStart_);
}

template <typename T>
void MpLevelSetCoupling::reduce(const std::vector<MpContact<T>>& contacts, const BlockState<T>* B, double dt) {
  auto add = [](double* slot, double value) { *slot += value; };
  for (const MpContact<T>& ct : contacts) {
    addBlockShare(ct, B[ct.block], sums_.data(), add);
    minParticleStep_ = std::min(minParticleStep_, static_cast<double>(particleStepBound(ct)));
  }
  takeStepTotals(sums_, numBodies(), dt, stepStart_);
}

long MpLevelSetCoupling::totalContacts() const {
  long n = 0;
  for (int i = 0; i < numBodies() && !sums_.empty(); ++i) n += contactCount(i);
  return n;
}

double MpLevelSetCoupling::bodyContactStep(double safety) const {
  double dt = std::numeric_limits<double>::infinity();
  for (int i = 0; i < numBodies() && !sums_.empty(); ++i) {
    if (bodies_[i].fixed) continue;
    const double k = stiffnessSum(i), kr = rotationalStiffnessSum(i);
    if (k > 0) dt = std::min(dt, std::sqrt(bodies_[i].mass / k));
    if (kr > 0 && minInertia_[i] > 0) dt = std::min(dt, std::sqrt(minInertia_[i] / kr));
  }
  return safety * dt;
}

std::vector<MpContactRecord> MpLevelSetCoupling::contacts(int body) const {
  if (onDevice_) return deviceContacts(*device_, body, "MP-LevelSet contacts");
  std::vector<MpContactRecord> out;
  double r[kContactValues];
  auto append = [&](const auto& list) {
    for (const auto& ct : list) {
      if (body >= 0 && ct.block != body) continue;
      contactRecord(ct, r);
      out.push_back(recordOf(r));
    }
  };
  if (floatRun_)
    append(contactsF_);
  else
    append(contacts_);
  return out;
}

}  // namespace coupling
}  // namespace mpmsdem
