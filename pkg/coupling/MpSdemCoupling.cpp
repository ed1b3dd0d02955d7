#include "coupling/MpSdemCoupling.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

#include "common/Error.hpp"
#include "coupling/CpuContactLoop.hpp"
#include "sdem/Bo1_SpheroPolyhedron_Aabb.hpp"
#include "sdem/Law2_SdemGeom_BarrierPhys_Coulomb.hpp"

namespace mpmsdem {
namespace coupling {

namespace {
constexpr double kPi = 3.14159265358979323846;
// Upper bound of the number of bins: the bin edge grows until the grid box fits.
constexpr double kMaxBins = 1 << 22;

template <typename T>
double largest(const void* values, std::size_t n) {
  const T* a = static_cast<const T*>(values);
  double m = 0;
  for (std::size_t i = 0; i < n; ++i) m = std::max(m, static_cast<double>(a[i]));
  return m;
}

}  // namespace

#if !defined(MPMSDEM_WITH_CUDA)
std::unique_ptr<CouplingDeviceBackend> makeCouplingDeviceBackend(mpm::Precision) { return nullptr; }
#endif

MpSdemCoupling::MpSdemCoupling(const sdem::SdemEngine& sdem)
    : CouplingReport("block", "a block (SDEM body) index"), sdem_(sdem) {}
MpSdemCoupling::~MpSdemCoupling() = default;

void MpSdemCoupling::setPair(int material, const sdem::BarrierPhys& p) {
  sdem_.material(material);  // throws for an unknown index
  checkPairPhys(p);
  pairs_[material] = p;
}

void checkPairPhys(const sdem::BarrierPhys& p) {
  if (!(p.barrierStiffness > 0) || !std::isfinite(p.barrierStiffness))
    throwParameter("coupling barrierStiffness", p.barrierStiffness, "N/m", "> 0");
  if (!(p.friction >= 0) || !std::isfinite(p.friction)) throwParameter("coupling friction", p.friction, "", ">= 0");
  if (!(p.poisson > -1 && p.poisson < 0.5)) throwParameter("coupling poisson", p.poisson, "", "in (-1, 0.5)");
  if (!(p.normalDamping >= 0) || !std::isfinite(p.normalDamping))
    throwParameter("coupling normalDamping", p.normalDamping, "", ">= 0 (fraction of critical)");
  if (!(p.tangentialDamping >= 0) || !std::isfinite(p.tangentialDamping))
    throwParameter("coupling tangentialDamping", p.tangentialDamping, "", ">= 0 (fraction of critical)");
}

void MpSdemCoupling::setHistorySlots(int slots) {
  if (slots < 1 || slots > 4) throwParameter("historySlots", slots, "", "in [1, 4]");
  if (slots != slots_) {
    slots_ = slots;
    heldKeys_ = 0;
    key_.clear();
    hostDouble_.xi.clear();
    hostFloat_.xi.clear();
    if (device_) device_->resetHistories();
  }
}

void MpSdemCoupling::setHistories(const std::vector<long long>& keys, const std::vector<double>& xi) {
  checkHistories(keys, xi, slots_);
  heldKeys_ = keys.size();
  key_ = keys;
  written_.assign(keys.size() / slots_, historyStep_);  // current at the next step
  hostDouble_.xi = xi;
  hostFloat_.xi.assign(xi.begin(), xi.end());
  particleCount_ = keys.size() / slots_;
  historiesToDevice_ = true;
}

void MpSdemCoupling::pullHistories() {
  if (!device_ || historiesToDevice_) return;  // the host copies are the current ones
  device_->downloadHistories(key_, hostDouble_.xi, written_);
  hostFloatRun_ = false;
}

void MpSdemCoupling::restoreParticleApproachStep(double s) {
  if (!(s > 0)) throwParameter("particle approach step", s, "s", "> 0 (inf: no particle closing on a block)");
  minApproachStep_ = s;
}

std::vector<long long> MpSdemCoupling::historyKeys() const {
  return currentHistoryKeys(key_, written_, historyStep_, slots_);
}

std::vector<double> MpSdemCoupling::historyXi() const {
  if (hostFloatRun_) return std::vector<double>(hostFloat_.xi.begin(), hostFloat_.xi.end());
  return hostDouble_.xi;
}

// Blocks in: shapes of new bodies join the table; pose and motion of every body.
void MpSdemCoupling::syncBlocks() {
  const int n = sdem_.numBodies();
  for (int i = static_cast<int>(blockShape_.size()); i < n; ++i) {
    const sdem::SpheroPolyhedron* s = &sdem_.shape(i);
    auto it = shapeIndex_.find(s);
    if (it == shapeIndex_.end()) {
      it = shapeIndex_.emplace(s, shapes_.add(*s)).first;
      shapesChanged_ = true;
    }
    blockShape_.push_back(it->second);
  }
  phys_.assign(sdem_.numMaterials(), sdem::BarrierCoulombPhys<double>{0, 0, 0, 0, 0});
  for (const auto& [m, p] : pairs_)
    phys_[m] = {p.barrierStiffness, p.friction, p.poisson, p.normalDamping, p.tangentialDamping};
  blocks_.resize(n);
  for (int i = 0; i < n; ++i) {
    const int mat = sdem_.materialOf(i);
    if (!pairs_.count(mat))
      throwParameter("coupling pair for SDEM material " + std::to_string(mat) + " (body " +
                         std::to_string(sdem_.externalId(i)) + ")",
                     "missing", "", "set with setPair(material, phys): the flow-block friction and stiffness");
    BlockState<double>& b = blocks_[i];
    const Vec3& p = sdem_.position(i);
    const Mat3 R = sdem_.orientation(i).toRotationMatrix();
    for (int d = 0; d < 3; ++d) {
      b.pos[d] = p[d];
      b.vel[d] = sdem_.velocity(i)[d];
      b.angVel[d] = sdem_.angularVelocity(i)[d];
      for (int e = 0; e < 3; ++e) b.rot[3 * d + e] = R(d, e);
    }
    b.mass = sdem_.mass(i);
    b.reach = sdem_.shape(i).boundingRadius;
    b.shape = blockShape_[i];
    b.phys = mat;
    b.fixed = sdem_.isFixed(i) ? 1 : 0;
  }
}

// Bins over the grid box; each lists the blocks whose rounded-body box grown by the largest
// particle radius and the approach watch (a grid cell) touches it.
void MpSdemCoupling::buildBins(const mpm::MpmParams& g) {
  if (binSize_ == 0) {
    binWatch_ = g.dx;
    binSize_ = 2 * g.dx;
    for (;;) {
      double count = 1;
      for (int d = 0; d < 3; ++d) count *= std::ceil(g.cells[d] * g.dx / binSize_);
      if (count <= kMaxBins) break;
      binSize_ *= 2;
    }
    for (int d = 0; d < 3; ++d) {
      binOrigin_[d] = g.origin[d];
      binDims_[d] = std::max(1, static_cast<int>(std::ceil(g.cells[d] * g.dx / binSize_)));
    }
  }
  const int nb = binDims_[0] * binDims_[1] * binDims_[2];
  std::vector<std::array<int, 6>>& range = binRangesNew_;
  range.resize(blocks_.size());
  for (std::size_t i = 0; i < blocks_.size(); ++i) {
    Vec3 lo, hi;
    sdem::Bo1_SpheroPolyhedron_Aabb::go(sdem_.shape(static_cast<int>(i)), sdem_.position(static_cast<int>(i)),
                                        sdem_.orientation(static_cast<int>(i)), lo, hi);
    bool outside = false;
    for (int d = 0; d < 3; ++d) {
      const double a = (lo[d] - maxParticleRadius_ - binWatch_ - binOrigin_[d]) / binSize_;
      const double b = (hi[d] + maxParticleRadius_ + binWatch_ - binOrigin_[d]) / binSize_;
      if (b < 0 || a >= binDims_[d]) outside = true;  // no particle can reach it
      range[i][d] = std::clamp(static_cast<int>(std::floor(a)), 0, binDims_[d] - 1);
      range[i][3 + d] = std::clamp(static_cast<int>(std::floor(b)), 0, binDims_[d] - 1);
    }
    if (outside) range[i] = {0, 0, 0, -1, -1, -1};
  }
  // The table only changes when a block's box enters or leaves a bin (for a block that moves
  // less than a bin per step, every few hundred steps): otherwise it is kept, and the CUDA
  // coupling keeps its copy.
  binsChanged_ = range != binRanges_ || binSlot_.size() != static_cast<std::size_t>(nb);
  if (!binsChanged_) return;
  binRanges_.swap(range);
  const std::vector<std::array<int, 6>>& ranges = binRanges_;
  if (binSlot_.size() != static_cast<std::size_t>(nb)) {
    binSlot_.assign(nb, -1);
    slotBins_.clear();
  }
  for (int bin : slotBins_) binSlot_[bin] = -1;
  slotBins_.clear();
  auto forEachBin = [&](const std::array<int, 6>& r, auto&& fn) {
    for (int a = r[0]; a <= r[3]; ++a)
      for (int b = r[1]; b <= r[4]; ++b)
        for (int c = r[2]; c <= r[5]; ++c) fn((a * binDims_[1] + b) * binDims_[2] + c);
  };
  // slots in the order the blocks first reach their bins, each slot's blocks in ascending order
  std::vector<int>& count = binFirst_;
  count.clear();
  for (const auto& r : ranges)
    forEachBin(r, [&](int bin) {
      int& s = binSlot_[bin];
      if (s < 0) {
        s = static_cast<int>(slotBins_.size());
        slotBins_.push_back(bin);
        count.push_back(0);
      }
      ++count[s];
    });
  int total = 0;
  for (int& c : count) {
    const int n = c;
    c = total;
    total += n;
  }
  count.push_back(total);
  binBlocks_.resize(total);
  std::vector<int> fill(binFirst_.begin(), binFirst_.end() - 1);
  for (std::size_t i = 0; i < ranges.size(); ++i)
    forEachBin(ranges[i], [&](int bin) { binBlocks_[fill[binSlot_[bin]]++] = static_cast<int>(i); });
}

BinGridView MpSdemCoupling::binView() const {
  return BinGridView{{binOrigin_[0], binOrigin_[1], binOrigin_[2]},
                     1.0 / binSize_,
                     {binDims_[0], binDims_[1], binDims_[2]},
                     binSlot_.data(),
                     binFirst_.data(),
                     binBlocks_.data(),
                     binWatch_};
}

std::vector<int> MpSdemCoupling::binnedBlocks(const Vec3& x) const {
  std::vector<int> out;
  if (binSlot_.empty()) return out;
  const BinGridView bins = binView();
  const int s = bins.slot[binOf(bins, x[0], x[1], x[2])];
  if (s >= 0) out.assign(binBlocks_.begin() + binFirst_[s], binBlocks_.begin() + binFirst_[s + 1]);
  return out;
}

void MpSdemCoupling::computeForces(mpm::MpmSolver& solver, double dt) {
  launchForces(solver, dt);
  collectForces();
}

void MpSdemCoupling::lap(int stage) {
  if (!stageTiming_) return;
  const auto now = std::chrono::steady_clock::now();
  hostStage_[stage] += std::chrono::duration<double>(now - lapStart_).count();
  lapStart_ = now;
}

void MpSdemCoupling::launchForces(mpm::MpmSolver& solver, double dt) {
  if (!(dt > 0) || !std::isfinite(dt)) throwParameter("dt", dt, "s", "> 0");
  if (pending_ == Pending::Device) device_->collect(last_);  // (its results are dropped)
  pending_ = Pending::None;
  const mpm::MpmParams& g = solver.params();
  contactsIn_ = ContactsIn::None;
  syncBlocks();
  if (blocks_.empty() || solver.numParticles() == 0) {
    // Nothing can touch: no bins, no particle loop, and the force buffer stays closed (the MPM
    // step then adds no external force, as it would add an open buffer's zeros).
    last_.sums.assign(static_cast<std::size_t>(kBlockSums) * blocks_.size(), 0.0);
    minParticleStep_ = minApproachStep_ = std::numeric_limits<double>::infinity();
    barrierEnergy_ = springEnergy_ = 0;
    return;
  }
  lapStart_ = std::chrono::steady_clock::now();
  mpm::ParticleView view = solver.openForceBuffer();
  lap(kStageForceBuffer);
  if (view.device && !device_) {
    device_ = makeCouplingDeviceBackend(view.precision);
    devicePrecision_ = view.precision;
    if (!device_) throw RuntimeFailure("MpSdemCoupling: the solver runs on CUDA but this build has no CUDA coupling");
    device_->recordContacts(recordContacts_);
    if (deviceListCapacity_ > 0) device_->setFirstListCapacity(deviceListCapacity_);
    device_->setStageTiming(stageTiming_);
  }
  const bool hostFloat = !view.device && view.precision == mpm::Precision::Float;
  if (maxParticleRadius_ < 0) {
    double vmax = 0;
    if (view.device)
      vmax = device_->volume0Range(view).second;
    else
      vmax = hostFloat ? largest<float>(view.volume0, view.n) : largest<double>(view.volume0, view.n);
    maxParticleRadius_ = std::cbrt(3 * vmax / (4 * kPi));
  }
  const std::size_t xiSize = hostFloat ? hostFloat_.xi.size() : hostDouble_.xi.size();
  if (view.n != particleCount_ || heldKeys_ != slots_ * view.n ||
      (!view.device && xiSize != 3 * heldKeys_)) {  // a new particle set: no history yet
    particleCount_ = view.n;
    heldKeys_ = slots_ * view.n;
    key_.clear();
    written_.clear();
    hostDouble_.xi.clear();
    hostFloat_.xi.clear();
    if (!view.device) {  // (the device backend holds its own)
      key_.assign(heldKeys_, -1);
      written_.assign(view.n, historyStep_);
      if (hostFloat)
        hostFloat_.xi.assign(3 * heldKeys_, 0.0f);
      else
        hostDouble_.xi.assign(3 * heldKeys_, 0.0);
    }
    if (device_) device_->resetHistories();
    historiesToDevice_ = false;
  }
  if (view.device && historiesToDevice_) device_->uploadHistories(key_, hostDouble_.xi, written_);
  historiesToDevice_ = false;
  if (!view.device) hostFloatRun_ = hostFloat;
  lap(kStageSetup);
  buildBins(g);
  lap(kStageBins);
  CouplingStepInput in;
  in.shapes = shapes_.view();
  in.numVertices = static_cast<int>(shapes_.vertex.size() / 3);
  in.numFaces = static_cast<int>(shapes_.faceOffset.size());
  in.numLoopEntries = static_cast<int>(shapes_.loopVertex.size());
  in.shapesChanged = shapesChanged_;
  in.blocks = &blocks_;
  in.phys = &phys_;
  in.bins = binView();
  in.numBins = binDims_[0] * binDims_[1] * binDims_[2];
  in.numBinEntries = static_cast<int>(binBlocks_.size());
  in.slotBins = slotBins_.data();
  in.numSlots = static_cast<int>(slotBins_.size());
  in.binsChanged = binsChanged_;
  in.particles = view;
  in.dt = dt;
  pendingDt_ = dt;
  pendingStart_ = solver.time();
  in.stepSafety = sdem_.timeStepSafety();
  in.historySlots = slots_;
  in.historyStep = ++historyStep_;
  CouplingStepOutput& out = last_;
  out = CouplingStepOutput{std::move(out.sums)};  // a step without contact or failure; the sums' buffer kept
  out.sums.assign(static_cast<std::size_t>(kBlockSums) * blocks_.size(), 0.0);
  if (view.device) {
    device_->launch(in);
  } else if (hostFloat) {
    syncFloatTables();
    const sdem::ShapeTableView<double> d = shapes_.view();
    const sdem::ShapeTableView<float> S{d.numShapes,        vertexF_.data(),      faceNormalF_.data(),
                                        faceOffsetF_.data(), d.faceLoopStart,      d.loopVertex,
                                        d.loopEdge,          d.shapeFaceStart,     d.shapeVertexStart,
                                        d.shapeEdgeStart,    sweepRadiusF_.data(), boundingRadiusF_.data(),
                                        d.convex};
    runCpu(in, S, blocksF_.data(), physF_.data(), hostFloat_, out);
  } else {
    runCpu(in, shapes_.view(), blocks_.data(), phys_.data(), hostDouble_, out);
  }
  lap(kStageContacts);
  shapesChanged_ = false;
  pending_ = view.device ? Pending::Device : Pending::Host;
  contactsIn_ = view.device ? ContactsIn::Device : hostFloat ? ContactsIn::HostFloat : ContactsIn::HostDouble;
}

void MpSdemCoupling::collectForces() {
  if (pending_ == Pending::None) return;
  const bool onDevice = pending_ == Pending::Device;
  pending_ = Pending::None;
  const ContactsIn where = contactsIn_;
  contactsIn_ = ContactsIn::None;  // until this step's results are in
  CouplingStepOutput& out = last_;
  if (onDevice) {
    lapStart_ = std::chrono::steady_clock::now();
    device_->collect(out);
    lap(kStageContacts);
  }
  if (out.badParticle >= 0) {
    std::ostringstream os;
    os << "MP-SDEM coupling: the centre of material point " << out.badParticle << " reached the core of block "
       << sdem_.externalId(out.badBlock)
       << " (overlap >= R_p0 + R); at the first step the particles were seeded inside the block, later "
       << sdem::coreContactRemedy();
    throw RuntimeFailure(os.str());
  }
  contactsIn_ = where;
  minParticleStep_ = out.minParticleStep;
  minApproachStep_ = out.minApproachStep;
  overflow_ += out.overflow;
  takeStepTotals(out.sums, numBlocks(), pendingDt_, pendingStart_);
}

// Float copies of what a float host step reads: the shape table when it grew, the blocks and
// the pair physics every step (a few values per block).
void MpSdemCoupling::syncFloatTables() {
  if (shapesChanged_ || sweepRadiusF_.size() != shapes_.sweepRadius.size()) {
    vertexF_.assign(shapes_.vertex.begin(), shapes_.vertex.end());
    faceNormalF_.assign(shapes_.faceNormal.begin(), shapes_.faceNormal.end());
    faceOffsetF_.assign(shapes_.faceOffset.begin(), shapes_.faceOffset.end());
    sweepRadiusF_.assign(shapes_.sweepRadius.begin(), shapes_.sweepRadius.end());
    boundingRadiusF_.assign(shapes_.boundingRadius.begin(), shapes_.boundingRadius.end());
  }
  blocksF_.resize(blocks_.size());
  for (std::size_t i = 0; i < blocks_.size(); ++i) blocksF_[i] = convertBlock<float>(blocks_[i]);
  physF_.resize(phys_.size());
  for (std::size_t i = 0; i < phys_.size(); ++i) physF_[i] = convertPhys<float>(phys_[i]);
}

template <typename T>
void MpSdemCoupling::runCpu(const CouplingStepInput& in, const sdem::ShapeTableView<T>& S, const BlockState<T>* B,
                            const sdem::BarrierCoulombPhys<T>* phys, HostSide<T>& side, CouplingStepOutput& out) {
  const mpm::ParticleView& v = in.particles;
  const CouplingParticles<T> P = couplingParticles<T>(v);
  const HistoryView<T> H{key_.data(), side.xi.data(), written_.data(), in.historyStep, slots_};
  const T dt = static_cast<T>(in.dt);
  const T safety = static_cast<T>(in.stepSafety);
  const long n = static_cast<long>(v.n);
  const ContactLoopTotals t = runContactChunks(
      P, n, side.chunkContacts,
      [&](int p, auto& sink, int* bad, int* over, T* approach,
          CouplingLoopMemo<T>& memo) __attribute__((always_inline)) {  // inlined: CpuContactLoop.hpp
        return coupleParticle(p, P, B, S, phys, in.bins, H, dt, safety, sink, bad, over, approach, memo);
      });
  out.overflow = t.overflow;
  out.minApproachStep = t.approach;
  if (t.firstBad < n) {
    out.badParticle = static_cast<int>(t.firstBad);
    out.badBlock = t.badBody;
    return;
  }
  // The solver may store its particles in an order of its own: the block sums go by particle
  // number, so they do not depend on that order (a restart continues bit for bit).
  std::vector<const MpContact<T>*>& all = side.sorted;
  all.clear();
  for (const auto& list : side.chunkContacts)
    for (const MpContact<T>& ct : list) all.push_back(&ct);
  std::stable_sort(all.begin(), all.end(),
                   [](const MpContact<T>* a, const MpContact<T>* b) { return a->particle < b->particle; });
  auto add = [](double* slot, double value) { *slot += value; };
  for (const MpContact<T>* ct : all) {
    addBlockShare(*ct, B[ct->block], out.sums.data(), add);
    out.minParticleStep = std::min(out.minParticleStep, static_cast<double>(particleStepBound(*ct)));
  }
}

// ------------------------------------------------------------------ results

void MpSdemCoupling::blockForces(std::vector<Vec3>& force, std::vector<Vec3>& torque) const {
  const int n = numBlocks();
  force.resize(n);
  torque.resize(n);
  for (int i = 0; i < n; ++i) {
    force[i] = this->force(i);
    torque[i] = this->torque(i);
  }
}
Vec3 MpSdemCoupling::faceForce(int i) const { return sumVector(i, kSumFace); }
Vec3 MpSdemCoupling::edgeForce(int i) const { return sumVector(i, kSumEdge); }
MpContactRecord recordOf(const double* r) {
  MpContactRecord c;
  c.particle = static_cast<int>(r[kRecParticle]);
  c.block = static_cast<int>(r[kRecBlock]);
  c.featureKind = static_cast<int>(r[kRecFeature]);
  for (int d = 0; d < 3; ++d) {
    c.point[d] = r[kRecPoint + d];
    c.normal[d] = r[kRecNormal + d];
    c.force[d] = r[kRecForce + d];
  }
  c.normalForce = r[kRecNormalForce];
  c.overlap = r[kRecOverlap];
  return c;
}

template <typename T>
void MpSdemCoupling::appendContacts(const HostSide<T>& side, int block, std::vector<MpContactRecord>& out) {
  double r[kContactValues];
  for (const MpContact<T>* ct : side.sorted) {
    if (block >= 0 && ct->block != block) continue;
    contactRecord(*ct, r);
    out.push_back(recordOf(r));
  }
}

void MpSdemCoupling::setStageTiming(bool on) {
  stageTiming_ = on;
  if (device_) device_->setStageTiming(on);
}

std::vector<std::pair<std::string, double>> MpSdemCoupling::stageSeconds() const {
  if (!stageTiming_) return {};
  std::vector<std::pair<std::string, double>> out = {{"force_buffer", hostStage_[kStageForceBuffer]},
                                                     {"setup", hostStage_[kStageSetup]},
                                                     {"bins", hostStage_[kStageBins]},
                                                     {"contacts", hostStage_[kStageContacts]}};
  if (device_)
    for (const auto& [name, sec] : device_->stageSeconds()) out.emplace_back("device_" + name, sec);
  return out;
}

void MpSdemCoupling::setRecordContacts(bool on) {
  recordContacts_ = on;
  if (device_) device_->recordContacts(on);
}

void MpSdemCoupling::setDeviceListCapacity(unsigned int capacity) {
  if (capacity == 0) throw ParameterError("MpSdemCoupling: deviceListCapacity must be >= 1 (got 0)");
  if (device_) throw ParameterError("MpSdemCoupling: deviceListCapacity is set before the first step");
  deviceListCapacity_ = capacity;
}

std::vector<MpContactRecord> deviceContacts(CouplingDeviceBackend& device, int block, const char* what) {
  std::vector<double> rec;
  if (!device.downloadContacts(rec))
    throw RuntimeFailure(std::string(what) +
                         ": the last step had more contacts than the device's list held, so it recorded none; the list "
                         "has room from the next step on");
  // the device list holds them in the order the threads reached it: put them in the CPU loop's
  // order, by particle number and then in the order each particle made them
  const std::size_t n = rec.size() / kContactValues;
  std::vector<std::size_t> order(n);
  std::size_t kept = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (block < 0 || rec[kContactValues * i + kRecBlock] == block) order[kept++] = i;
  order.resize(kept);
  auto at = [&rec](std::size_t i, int k) { return rec[kContactValues * i + k]; };
  std::sort(order.begin(), order.end(), [&at](std::size_t a, std::size_t b) {
    return at(a, kRecParticle) != at(b, kRecParticle) ? at(a, kRecParticle) < at(b, kRecParticle)
                                                      : at(a, kRecOrder) < at(b, kRecOrder);
  });
  std::vector<MpContactRecord> out;
  out.reserve(kept);
  for (std::size_t i : order) out.push_back(recordOf(rec.data() + kContactValues * i));
  return out;
}

std::vector<MpContactRecord> MpSdemCoupling::contacts(int block) const {
  std::vector<MpContactRecord> out;
  switch (contactsIn_) {
    case ContactsIn::None:
      break;
    case ContactsIn::HostDouble:
      appendContacts(hostDouble_, block, out);
      break;
    case ContactsIn::HostFloat:
      appendContacts(hostFloat_, block, out);
      break;
    case ContactsIn::Device: {
      std::vector<double> rec;
      if (!recordContacts_)
        throw RuntimeFailure(
            "MP-block contacts: the CUDA backend keeps a step's contacts on the device; turn their recording on "
            "before the step (recordContacts, 120 B per contact on the device) or run the CPU backend");
      out = deviceContacts(*device_, block, "MP-block contacts");
      break;
    }
  }
  return out;
}

long MpSdemCoupling::totalContacts() const {
  long n = 0;
  for (int i = 0; i < numBlocks(); ++i) n += contactCount(i);
  return n;
}

}  // namespace coupling
}  // namespace mpmsdem
