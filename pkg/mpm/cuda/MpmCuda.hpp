// CUDA backend of the MPM solver (host control class). The kernels are in
// MpmCudaKernels.cuh and call the same __host__ __device__ stage functions as the CPU
// backend (MpmKernelsCommon.hpp). T = float or double, picked at run time by makeSolver.
//
// P2G without atomics, in a fixed order: each step the particles are sorted (radix sort) by
// block of stencil bases, base and number, as the CPU backend bins them, and each block's
// nodes gather their sums (p2gBaseKernel), the eight parity colours one launch after another
// (a grid small enough to hold a tile of sums for each block the particles could occupy: every
// block's tile in one launch, then each node adds its tiles in colour order, the same additions).
// A node's sum therefore has one order: two runs of a scene give the same bits, whatever the
// storage order (a restart included), and a node is written once per block instead of taking
// 7 atomic adds per particle. G2P writes each particle into the slot of its sorted place, so
// that the next step reads the particles nearly in turn; a particle keeps its number (id[slot],
// what setParticles/getParticles index by), and its mass and volume0 move with it. Grid work
// follows the particles, as on the CPU: the sort's keys give the step's occupied blocks (P2G
// launches only their work) and the tiles next to them (the only nodes zeroed and updated), so
// a flow filling a few per cent of a long runout box does not pay for the box. Grid memory
// follows the flow as on the CPU: only the node columns (i, j) near the particles are stored
// (GridConst::column), in a pool that grows at a step's end (takeColumns), so a flow in a
// kilometre-wide domain costs its footprint's columns, not the box.
//
// Device memory (T = float, N particles, C stored node columns of nz nodes): particle state
// double-buffered (x, v, stress, J, gammaDotP, mass, volume0: 16 values, phase 1 byte, number 4
// bytes, twice) = 138 bytes/particle; the sort (two keys of 8 bytes, two slots of 4) 24
// bytes/particle; + 12 bytes/particle once external forces are set; kNodeValues (8) values per
// stored node (32 C nz bytes, the pool holding up to half as many columns again); an int per
// node column of the box (the column map), six ints per block of 27 cells (the active lists and
// marks, the blocks' particle ranges and tile places). Double-buffering makes a failed step leave
// the previous state intact at no bandwidth cost.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "mpm/MpmKernelsCommon.hpp"
#include "mpm/StagedSolver.hpp"

namespace mpmsdem {
namespace mpm {
namespace cudak {
struct ActiveLists;
struct BlockGrid;
struct ColumnMap;
}

template <typename T>
class MpmCuda : public StagedSolver {
 public:
  explicit MpmCuda(const MpmParams& params);  // params must have been validated
  ~MpmCuda() override;
  MpmCuda(const MpmCuda&) = delete;
  MpmCuda& operator=(const MpmCuda&) = delete;

  std::string name() const override;
  const MpmParams& params() const override { return params_; }
  void setParticles(const ParticleSet& particles) override;
  using MpmSolver::setParticles;  // slices gathered into a whole set
  void getParticles(ParticleSet& out) override;
  void getParticles(ParticleSet& out, std::size_t first, std::size_t count) override;
  std::size_t numParticles() const override { return n_; }
  void setExternalForces(const std::vector<double>& f) override;
  ParticleView openForceBuffer() override;
  ParticleView extendForceBuffer() override;
  bool queuesSteps() const override { return true; }
  void launchStep(double dt) override;
  void finishStep() override;
  void abandonStep() override;
  double cflTimeStep() override;
  std::size_t memoryBytes() const override;
  void setStageTiming(bool on) override;
  std::vector<std::pair<std::string, double>> stageSeconds() const override;
  bool diagnosticSums(const std::array<double, 3>& gravity, const std::vector<ProbeStation>& stations,
                      DiagnosticSums& sums, std::vector<ProbeSums>& probeSums) override;

 private:
  ParticleView forceView();  // the force buffer and the particles as a coupling sees them
  // The stages of a step (StagedSolver holds their order): queued by launchStep, waited for by
  // finishStep in stageEnd.
  void beforeChecks() override;
  void stageP2G(double dt) override;
  void stageGrid(double dt) override;
  void stageGridVelocity(double dt) override;
  GridView gridView(double dt) override;
  void stageGridBoundaries() override;
  void stageG2P(double dt) override;
  void stageEnd(double dt) override;
  void markStage(int k);  // device event k of the step's stage clock, where timing is on

  struct DeviceState {
    T* x[3] = {};
    T* v[3] = {};
    T* s[6] = {};
    T* J = nullptr;
    T* gdp = nullptr;
    T* mass = nullptr;
    T* vol0 = nullptr;
    std::uint8_t* phase = nullptr;
    int* id = nullptr;  // particle number of each slot
  };
  struct StepFlags {
    unsigned long long firstBad;  // smallest (number << 32 | slot) of a failing particle, or all ones
    unsigned int maxSpeedBits;    // float bits of the largest particle speed (>= 0, so ordered as uint)
    unsigned int columnsMissing;  // non-zero: a tile of this step had a node column not stored
    unsigned int columnsUsed;     // places of the column pool taken (kept from step to step)
  };
  void freeParticles();
  void allocateGrid();  // the grid's arrays, the terrain's heights and the kernels' launch size
  void freeDevice();    // every device array and event (the destructor; a constructor that failed part-way)
  void loadParticles(const ParticleSet& ps);  // allocates and fills the particle arrays for ps
  ParticleIn<T> input() const;
  ParticleOut<T> output() const;
  std::vector<int> numbers() const;  // id of the current state, on the host
  // slot of each particle number on the device (built in the sort's free buffer between steps)
  const int* slotsByNumber();
  // count values of src for the particles numbered [first, first + count), into host dst
  template <typename U, typename H>
  void gatherByNumber(const U* src, std::size_t first, std::size_t count, std::vector<H>& dst, int stride, int offset);
  void beginLists();                 // the last lists' tiles zeroed and slots forgotten, the lists emptied
  void sortParticles();              // sorted_, sortedKeys_ and the active lists for this step
  cudak::ActiveLists activeLists() const;
  cudak::BlockGrid blockGrid() const;
  cudak::ColumnMap columnMap() const;
  // Queues the storing of the node columns near the active tiles (cudak::storeColumnsNearKernel);
  // takeColumns then grows the pool to the count the flags copied back hold (or, where it cannot,
  // takes the places past the pool back and throws).
  void queueColumnsNear();
  void takeColumns(const StepFlags& flags);
  void growColumns(unsigned int needed);  // a pool of at least `needed` columns, the stored ones kept

  MpmParams params_;
  GridConst<T> grid_{};
  ConstitutiveConst<T> mat_{};
  double maxSpeedAllowed_;
  int nNodes_;
  std::size_t n_ = 0;
  DeviceState state_[2];
  int cur_ = 0;
  T* fext_[3] = {};
  bool hasFext_ = false;
  // The stored node columns: column_ (device, an int per (i, j), -1 where none) gives each its
  // place in nodes_, a pool of columnCapacity_ columns of nodes[2] records, columnsStored_ taken.
  int* column_ = nullptr;
  int nColumns_ = 0;
  unsigned int columnCapacity_ = 0;
  unsigned int columnsStored_ = 0;
  T* nodes_ = nullptr;
  T* terrain_ = nullptr;  // the terrain's heights (grid_.terrain.z); null without one
  StepFlags* flags_ = nullptr;
  // A launched step (launchStep): its flags come back into flagsHost_ (pinned) before the event
  // stepDone_ (a cudaEvent_t without timing), which finishStep and abandonStep wait for.
  StepFlags* flagsHost_ = nullptr;
  void* stepDone_ = nullptr;
  bool launched_ = false;
  double launchedDt_ = 0;
  StepFlags waitForLaunched(const char* what);  // waits for the launched step's flags; launched_ off
  // P2G order: blocks of stencil bases, the sort's double buffers and its scratch space.
  int blocks_[3];
  int nBlocks_;
  int* blockStart_ = nullptr;  // an occupied block b's particles: sorted places [blockStart_[b], blockEnd_[b])
  int* blockEnd_ = nullptr;
  // The step's occupied blocks by colour and active tiles (cudak::ActiveLists); between steps
  // only the active tiles' nodes may be non-zero.
  int* colourBlocks_ = nullptr;
  int* activeTiles_ = nullptr;
  static constexpr int kTileLists = 9;
  // kTileLists: 8 colours, then the active tiles. Reset only by beginLists, after the last lists'
  // tiles are cleared and their marks forgotten: a mark left would keep its tile out of every list.
  int* listCounts_ = nullptr;
  int* tileMark_ = nullptr;
  int gridLaunch_ = 1;  // CUDA blocks of the kernels over the active tiles' nodes
  // CUDA blocks of a P2G colour launch at most: more than the device holds at once (the kernel's
  // shared arrays allow a few per SM), so that a colour with fewer occupied blocks still gets one
  // CUDA block each, and a colour with more loops over them
  static constexpr int kP2GBlocksPerSM = 16;
  int p2gLaunch_ = 1;
  // P2G in one launch with a tile of sums per occupied block (p2gTilesKernel, p2gTileSumsKernel),
  // where a tile for each block that particles could occupy (min(particles, blocks)) fits in
  // kTileScratchBytes; null: the colour launches. slotOf_: each block's place in it this step.
  static constexpr std::size_t kTileScratchBytes = std::size_t(512) << 20;
  T* tileScratch_ = nullptr;
  int tileCapacity_ = 0;
  int* slotOf_ = nullptr;
  int numberBits_ = 0;
  int keyBits_ = 0;
  unsigned long long* keys_[2] = {};
  int* slots_[2] = {};
  const int* sorted_ = nullptr;  // slot of each sorted place, this step
  const unsigned long long* sortedKeys_ = nullptr;  // their keys
  bool slotOfValid_ = false;      // slots_[0] holds slotsByNumber() of the current state
  unsigned char* sortScratch_ = nullptr;
  std::size_t sortScratchBytes_ = 0;
  // Stage timing (setStageTiming): events at the step's start and after each stage, and the sums.
  // "lists" clears the last step's tiles and marks, "columns" stores the columns near the flow:
  // the work the grid stored by columns adds to the four stages of the step.
  static constexpr int kStages = 6;  // lists, sort, p2g, grid, g2p, columns
  void* events_[kStages + 1] = {};
  double stageTotals_[kStages] = {};
  double maxSpeed_ = 0;
  void* diagnostics_ = nullptr;  // the diagnostics' per-block results and total (allocated at first use)
  std::size_t gridBytes_ = 0;  // the grid's arrays, the column pool and the diagnostics' (kept by setParticles)
  std::size_t bytes_ = 0;      // the particles' arrays
};

// Build a CUDA solver in the given precision (params validated by the caller).
std::unique_ptr<MpmSolver> makeCudaSolver(const MpmParams& params, Precision precision);
// True when the CUDA runtime finds at least one device.
bool cudaDevicePresent();

}  // namespace mpm
}  // namespace mpmsdem
