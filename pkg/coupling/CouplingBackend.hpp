// What a coupling backend receives and returns for one step (host side), and the interface of
// the CUDA backend. Kept free of Eigen so that the CUDA sources include only plain headers.
#pragma once
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "coupling/CouplingKernelsCommon.hpp"
#include "coupling/LevelSetKernelsCommon.hpp"
#include "mpm/MpmSolver.hpp"

namespace mpmsdem {
namespace coupling {

struct CouplingStepInput {
  // The bodies are SDEM blocks (shapes, bins) or, where levelSets is set, LevelSet bodies
  // (MpLevelSetCoupling: each body's BlockState::shape is its grid's index; shapes and bins unused).
  sdem::ShapeTableView<double> shapes;  // host arrays
  int numVertices, numFaces, numLoopEntries;
  bool shapesChanged;                   // the table grew since the last step
  const std::vector<BlockState<double>>* blocks;
  const std::vector<sdem::BarrierCoulombPhys<double>>* phys;
  BinGridView bins;                     // host arrays
  int numBins, numBinEntries;
  const int* slotBins;                  // the bin of each slot (numSlots): where bins.slot is not -1
  int numSlots;
  bool binsChanged;                     // the bin table differs from the last step's
  mpm::ParticleView particles;
  double dt;
  double stepSafety;                    // the SDEM time-step safety factor (approachStepBound)
  int historySlots;
  unsigned historyStep;                 // HistoryView::step of this step
  const std::vector<LevelSetGridView<double>>* levelSets = nullptr;  // host arrays
  bool levelSetsChanged = false;        // a body was added since the last step
  double watch = 0;                     // LevelSet bodies: how far beyond contact closing pairs are examined [m]
};

// The particles of the solver's view as the coupling reads them, in the view's precision T.
template <typename T>
CouplingParticles<T> couplingParticles(const mpm::ParticleView& v) {
  CouplingParticles<T> P;
  for (int d = 0; d < 3; ++d) {
    P.x[d] = static_cast<const T*>(v.x[d]);
    P.v[d] = static_cast<const T*>(v.v[d]);
    P.force[d] = static_cast<T*>(v.force[d]);
  }
  P.mass = static_cast<const T*>(v.mass);
  P.vol0 = static_cast<const T*>(v.volume0);
  P.id = v.id;
  return P;
}

// What a step leaves; the defaults are a step without contact or failure.
struct CouplingStepOutput {
  std::vector<double> sums;   // kBlockSums per block
  // min over contacts of sqrt(m_p / max(k_n, K_t)) [s] (inf: none)
  double minParticleStep = std::numeric_limits<double>::infinity();
  // min of approachStepBound over closing pairs not in contact [s] (inf: none)
  double minApproachStep = std::numeric_limits<double>::infinity();
  long overflow = 0;          // contacts without a free history slot
  int badParticle = -1;       // -1, or a particle whose centre reached block badBlock's core
  int badBlock = -1;
};

// The CUDA side (pkg/coupling/cuda): device copies of the tables and histories, the kernel.
class CouplingDeviceBackend {
 public:
  virtual ~CouplingDeviceBackend() = default;
  // One step in two halves: launch queues the uploads, the contact kernel, the ordered sums and
  // their copy back, and returns; collect waits for that copy alone (work queued after launch,
  // such as the flow's step, goes on) and fills `out`'s sums and flags. Each launch is collected
  // before the next.
  virtual void launch(const CouplingStepInput& in) = 0;
  virtual void collect(CouplingStepOutput& out) = 0;
  virtual void resetHistories() = 0;
  // The tangential histories (HistoryView: keys and 3 xi per slot, the step each particle's
  // were written) to and from the host, for checkpoints; xi in double either way.
  virtual void downloadHistories(std::vector<long long>& keys, std::vector<double>& xi,
                                 std::vector<unsigned>& written) = 0;
  virtual void uploadHistories(const std::vector<long long>& keys, const std::vector<double>& xi,
                               const std::vector<unsigned>& written) = 0;
  // The contacts the device's list holds before it first grows (default 65,536). A step with
  // more adds its block sums atomically, in an order that changes from run to run, and the list
  // grows to twice its contacts for the next step. Tests set a small one to reach that step.
  virtual void setFirstListCapacity(unsigned int capacity) = 0;
  // Time the step's parts from now on (on: device events around the uploads, the contact
  // kernel and the ordered sums, a few microseconds a step; host clocks around the waits for
  // the device) and add them up: stageSeconds() by name, in seconds.
  virtual void setStageTiming(bool on) = 0;
  virtual std::vector<std::pair<std::string, double>> stageSeconds() const = 0;
  // Smallest and largest initial particle volume of the view [m^3].
  virtual std::pair<double, double> volume0Range(const mpm::ParticleView& v) = 0;
  // Keep each step's contacts on the device from the next step on (kContactValues doubles,
  // 120 B, per contact), for downloadContacts().
  virtual void recordContacts(bool on) = 0;
  // The last step's contact records (contactRecord, kContactValues each) in the device list's
  // order; false when that step recorded none: recording off, or more contacts than the list
  // held (it holds them from the next step on).
  virtual bool downloadContacts(std::vector<double>& records) = 0;
};
// Null when this build has no CUDA.
std::unique_ptr<CouplingDeviceBackend> makeCouplingDeviceBackend(mpm::Precision precision);

}  // namespace coupling
}  // namespace mpmsdem
