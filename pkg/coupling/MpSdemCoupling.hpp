// MpSdemCoupling: contact between the material points of an MPM solver and the blocks of an
// SdemEngine (paper §2.3, Eqs 12–18), on the backend the solver runs on (CPU, or CUDA with
// no host round trip of particle data), in the solver's precision: a float solver's particles
// meet float copies of the shapes, blocks and pair physics (the CUDA float path's formulas,
// also on the CPU), while the block sums accumulate in double on both.
//
// Each step (computeForces):
//  1. blocks in: pose, velocity of every SDEM body (block index = SdemEngine body index);
//     bodies added since the last step join the shape table;
//  2. broad phase: uniform bins over the MPM grid list the blocks whose rounded-body box,
//     grown by the largest MP radius and a grid cell, touches them; a particle tests only its
//     bin's blocks, so the cost follows the particles near blocks, not particles x blocks;
//  3. narrow phase and law per (particle, block): CouplingKernelsCommon.hpp;
//  4. forces: into the solver's external-force buffer (spread to the grid by the next MPM
//     step with the P2G weights, Eq 14) and, opposite, onto the blocks (force, torque about
//     the centroid, split into face-interior F_f and edge/vertex F_e, §3.2.3).
// Because the B-spline weights sum to one, the impulse the grid receives equals minus the
// impulse the blocks receive (Eqs 17–18).
//
// Block sums are reduced in a fixed order on the CPU (results do not depend on the thread
// count) and on the GPU (by particle number; atomics only in a step whose contacts overflow the
// device's contact list).
#pragma once
#include <array>
#include <chrono>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "coupling/CouplingBackend.hpp"
#include "coupling/CouplingReport.hpp"
#include "mpm/MpmSolver.hpp"
#include "sdem/SdemEngine.hpp"
#include "sdem/ShapeTable.hpp"

namespace mpmsdem {
namespace coupling {

// One MP–block contact of the last coupling step (MpSdemCoupling::contacts()).
struct MpContactRecord {
  int particle = -1;      // the material point's number (its index in MpmSolver::setParticles)
  int block = -1;         // SDEM body index
  int featureKind = 0;    // feature of the block's core nearest the point: sdem::kFeatureFace / Edge / Vertex
  Vec3 point;             // contact point, midway between the two sphere surfaces [m]
  Vec3 normal;            // unit, from the block towards the point
  Vec3 force;             // the flow's force on the block through this contact [N]; the point takes -force
  double normalForce = 0; // F_n of the barrier law (Eq 10) [N]
  double overlap = 0;     // delta (Eq 12) [m]
};

// ParameterError naming the first parameter of flow-body contact physics out of its range
// (MpSdemCoupling::setPair lists them).
void checkPairPhys(const sdem::BarrierPhys& phys);

// The record of a contact written by contactRecord (kContactValues doubles).
MpContactRecord recordOf(const double* r);

// The contacts of the last step that `device` ran and recorded (CouplingDeviceBackend::
// recordContacts), those of body `block` or all (block < 0), in the CPU loop's order: by particle
// number, then in the order each particle made them. RuntimeFailure, `what` first, when that step
// had more contacts than the device's list held.
std::vector<MpContactRecord> deviceContacts(CouplingDeviceBackend& device, int block, const char* what);

class MpSdemCoupling : public CouplingReport {
 public:
  explicit MpSdemCoupling(const sdem::SdemEngine& sdem);
  ~MpSdemCoupling();

  // Contact physics between the flow and blocks of SDEM material `sdemMaterial` (YADE's Ip2
  // role for the pair "granular flow, block material"): barrier stiffness k_c [N/m] (> 0),
  // friction mu (>= 0), Poisson ratio (in (-1, 0.5)) for K_t, normal and tangential damping
  // (fractions of critical, >= 0). A block whose material has no pair stops the first step
  // with a ParameterError naming the material.
  void setPair(int sdemMaterial, const sdem::BarrierPhys& phys);
  bool hasPair(int sdemMaterial) const { return pairs_.count(sdemMaterial) > 0; }

  // Tangential-history slots per particle: how many simultaneous block contacts keep their
  // memory (a point in the corner between a block and the bed needs 2). In [1, 4], default 2.
  void setHistorySlots(int slots);
  int historySlots() const { return slots_; }

  // One coupling step at the current SDEM state and the solver's current particles: adds the
  // particles' forces into solver.openForceBuffer() and computes the blocks' share. Without
  // blocks or without particles it only zeroes the results (the solver's force buffer is not
  // opened: a flow alone costs what the MPM step costs). Throws
  // RuntimeFailure when a particle centre reaches a block core (names both; at the first step
  // this means particles were seeded inside a block), ParameterError for a missing pair.
  void computeForces(mpm::MpmSolver& solver, double dt);
  // computeForces in two halves, for a caller with device work to queue behind the contacts
  // (CoupledWorld queues the flow's step there on CUDA): launchForces does the host part and
  // queues the device part (on the CPU it does all the work), collectForces waits for the block
  // sums alone and ends the step, with computeForces' failures. The results below are those of
  // the last collected step; a launch left uncollected (a step that failed between the two) is
  // waited for and dropped by the next launch.
  void launchForces(mpm::MpmSolver& solver, double dt);
  void collectForces();

  // ---- results of the last computeForces, per SDEM body index (world frame): force, torque,
  // contactCount, stiffness sums, step bounds and energies of CouplingReport, and
  // force(i) and torque(i) of every block of the last step, numBlocks() of each (the SDEM
  // engine's bodies at that step), as the rigid-body update takes them.
  void blockForces(std::vector<Vec3>& force, std::vector<Vec3>& torque) const;
  Vec3 faceForce(int block) const;    // share through face interiors, F_f [N]
  Vec3 edgeForce(int block) const;    // share through edges and vertices, F_e [N]
  int numBlocks() const { return static_cast<int>(blocks_.size()); }
  long totalContacts() const;
  // The contacts behind these sums, by particle number (a point's contacts in the order it
  // made them): where on each block the flow pressed, and how hard (§3.2.3's F_f and F_e, point
  // by point). Empty before the first step and after a step that had no blocks or no
  // particles. On CUDA the contacts stay on the device unless setRecordContacts(true) was
  // called before the step (RuntimeFailure otherwise, or when the step had more contacts than
  // the device list held: it holds them from the next step on). Those of SDEM body index
  // `block` only, or all for block < 0.
  std::vector<MpContactRecord> contacts(int block = -1) const;
  // CUDA: keep each step's contacts on the device (120 B per contact) for contacts(). The CPU
  // backends always have them (the loop's own list).
  void setRecordContacts(bool on);
  bool recordContacts() const { return recordContacts_; }
  // Time the parts of each step from now on and add them up (host clocks; on CUDA also device
  // events): stageSeconds() gives, in seconds, force_buffer (opening the solver's force
  // buffer), setup (blocks, tables and histories), bins, contacts (the contact loop, on CUDA
  // the whole device call) and on CUDA device_upload, device_kernel, device_sums (device time)
  // and device_host_wait (host time blocked on the device); empty while timing is off.
  void setStageTiming(bool on);
  std::vector<std::pair<std::string, double>> stageSeconds() const;
  // CUDA: the contacts the device's list holds before it first grows (default 65,536; >= 1). A
  // step with more sums its block forces with atomics, in an order that changes from run to run,
  // and grows the list to twice its contacts. Set before the first step.
  void setDeviceListCapacity(unsigned int capacity);
  // contacts() can answer for the last step (false on CUDA without recording).
  bool contactsAvailable() const { return contactsIn_ != ContactsIn::Device || recordContacts_; }
  // The value a checkpointed run's last step left (> 0, inf for none), until the next step.
  void restoreParticleApproachStep(double s);

  // ---- checkpoint of the tangential histories: per particle `slots` keys and 3 x slots xi
  // values, elastic tangential forces [N] (a float run's converted to double). On CUDA they
  // live on the device: pullHistories() brings them to the host before these are read (a no-op
  // on the CPU), and setHistories() sends them to the device at the next step.
  void pullHistories();
  std::vector<long long> historyKeys() const;
  std::vector<double> historyXi() const;
  // Component d of historyXi() for history slot k, without copying them all [N].
  double historyXiAt(std::size_t k, int d) const {
    return hostFloatRun_ ? double(hostFloat_.xi[3 * k + d]) : hostDouble_.xi[3 * k + d];
  }
  void setHistories(const std::vector<long long>& keys, const std::vector<double>& xi);

  // Bin edge of the broad phase [m] (set on the first step from the grid spacing).
  double binSize() const { return binSize_; }
  // The blocks (SDEM body indices, ascending) the broad phase of the last step lists for a point
  // at x: those whose box, grown by the largest particle radius and a grid cell, reaches its bin.
  std::vector<int> binnedBlocks(const Vec3& x) const;

 private:
  const std::vector<double>& lastSums() const override { return last_.sums; }
  int reportedBodies() const override { return numBlocks(); }
  void syncBlocks();
  void buildBins(const mpm::MpmParams& grid);
  BinGridView binView() const;  // the host's bin table
  // What the CPU loop writes in precision T: the tangential forces xi of the histories (3 x slots
  // per particle, keys in key_) and the contacts of each particle chunk.
  template <typename T>
  struct HostSide {
    std::vector<T> xi;
    std::vector<std::vector<MpContact<T>>> chunkContacts;
    std::vector<const MpContact<T>*> sorted;  // the contacts by particle number
  };
  template <typename T>
  void runCpu(const CouplingStepInput& in, const sdem::ShapeTableView<T>& shapes, const BlockState<T>* blocks,
              const sdem::BarrierCoulombPhys<T>* phys, HostSide<T>& side, CouplingStepOutput& out);
  void syncFloatTables();

  const sdem::SdemEngine& sdem_;
  std::map<int, sdem::BarrierPhys> pairs_;
  int slots_ = 2;

  sdem::ShapeTable shapes_;
  std::map<const sdem::SpheroPolyhedron*, int> shapeIndex_;
  std::vector<int> blockShape_;
  bool shapesChanged_ = true;
  std::vector<BlockState<double>> blocks_;
  std::vector<sdem::BarrierCoulombPhys<double>> phys_;  // per SDEM material

  double maxParticleRadius_ = -1;  // [m], from the particles' initial volumes
  std::size_t particleCount_ = 0;
  double binSize_ = 0;
  double binWatch_ = 0;  // growth of the block boxes beyond the largest particle radius [m]
  double binOrigin_[3] = {0, 0, 0};
  int binDims_[3] = {0, 0, 0};
  // The bin table (BinGridView): a slot per bin some block's box reaches, their blocks, and the
  // bin of each slot (the slots a rebuild clears, so that it costs the slots, not the grid).
  std::vector<int> binSlot_, binFirst_, binBlocks_, slotBins_;
  std::vector<std::array<int, 6>> binRanges_, binRangesNew_;  // bins of each block's box (last built, this step)
  bool binsChanged_ = true;  // the last buildBins() changed the table

  std::size_t heldKeys_ = 0;       // history slots of the current particle set (host or device)
  std::vector<long long> key_;     // CPU histories (HistoryView)
  std::vector<unsigned> written_;  // per particle
  unsigned historyStep_ = 0;       // the last step's HistoryView::step
  HostSide<double> hostDouble_;
  HostSide<float> hostFloat_;
  bool hostFloatRun_ = false;  // the last host step ran in float (hostFloat_.xi is current)
  // Where the last step's contacts are: none (no step yet, nothing could touch, or the step
  // failed), one of the host sides, or the device.
  enum class ContactsIn { None, HostDouble, HostFloat, Device } contactsIn_ = ContactsIn::None;
  bool recordContacts_ = false;
  unsigned int deviceListCapacity_ = 0;  // 0: the backend's default
  enum { kStageForceBuffer, kStageSetup, kStageBins, kStageContacts, kHostStages };
  bool stageTiming_ = false;
  double hostStage_[kHostStages] = {};
  // host seconds since lapStart_ into hostStage_[stage] when timing, and the clock restarted
  void lap(int stage);
  std::chrono::steady_clock::time_point lapStart_;
  // What launchForces left for collectForces: nothing (no step, or nothing could touch), the
  // host loop's results in last_, or the device's to wait for.
  enum class Pending { None, Host, Device } pending_ = Pending::None;
  double pendingDt_ = 0, pendingStart_ = 0;  // the launched step's dt and start [s] (its impulses, first contacts)
  template <typename T>
  static void appendContacts(const HostSide<T>& side, int block, std::vector<MpContactRecord>& out);
  bool historiesToDevice_ = false;  // setHistories() since the last step: the device takes them
  // Float copies for a float host solver: the shape table's real arrays (its index arrays are
  // shared), the blocks and the pair physics of the step.
  std::vector<float> vertexF_, faceNormalF_, faceOffsetF_, sweepRadiusF_, boundingRadiusF_;
  std::vector<BlockState<float>> blocksF_;
  std::vector<sdem::BarrierCoulombPhys<float>> physF_;
  std::unique_ptr<CouplingDeviceBackend> device_;
  mpm::Precision devicePrecision_ = mpm::Precision::Double;

  CouplingStepOutput last_;
};

}  // namespace coupling
}  // namespace mpmsdem
