// CPU backend of the MPM solver, OpenMP, in double or float (T): "cpu-double", "cpu-float".
// Both run the shared stage functions of MpmKernelsCommon.hpp, as CUDA does in the same
// precisions, so the float formulas of the CUDA backend run and are tested here too.
//
// P2G without races: each step the particles are binned (counting sort, O(N)) into blocks of
// 3x3x3 stencil-base cells, by particle number within a block. A particle whose stencil base
// lies in block b touches nodes 3b .. 3b+4 per axis, so two blocks whose indices differ by 2 or
// more along some axis share no node. The blocks are split into 8 colours by index parity; the
// blocks of one colour are scattered in parallel, the colours one after another. A block's
// particles add into a private 5x5x5-node copy (in L1 cache), added to the grid once per block.
// The summation order is fixed, so the result does not depend on the thread count.
//
// Storage order: G2P writes each particle into the slot of its place in that binning, so the
// particles are stored sorted by block and the next step's P2G and G2P read them nearly in turn
// (not through an index scattered over a set that outgrows the caches). A particle keeps its
// number (its index in setParticles/getParticles, id[slot]); its mass and volume0 move with it.
// Blocks are filled by number, so the sums are those of number order: results, snapshots and
// restarts do not depend on the storage order.
//
// Grid work follows the particles, not the box (the active tiles of MpmKernelsCommon.hpp,
// forTilesOfBlock): a step scatters only the occupied blocks and zeroes, updates and
// wall-corrects only the tiles next to them, with results bit-identical to sweeping the whole
// grid; a grid hook still sees the whole grid. A flow filling 5 % of a long runout box then
// costs what it would in a box around it.
//
// The mutable particle state is double-buffered: a step reads buffer `cur_` and writes the
// other one, and only swaps when every particle passed the NaN/blow-up check. After a
// RuntimeFailure, getParticles() returns the state at the start of the failed step.
//
// Precision: every particle and grid array is T. In float the grid sums (P2G node mass and
// momentum) stay float too: a node sums the shares of the 27 ppc points around it, so its
// round-off stays below 27 ppc eps/2 (1e-5 at 8 points per cell, ~1e-6 typically) and does not
// grow with the run; momentum is conserved to that per step; the scatter order is fixed; and
// a double grid would cost 21 B/particle more at 1e6 points, past the 150 B/particle of
// float. The sums over a whole run accumulate in double: the clock (MpmSolver::time()), the
// gate's impulse (Gate), the coupling's block sums (MpSdemCoupling); in float a step's
// increment would be rounded to 1.2e-7 of the total every step.
//
// Memory per particle (memoryBytes()): the state x, v, stress, J, gammaDotP (14 T), phase
// (1 byte) and number (int), twice, plus mass and volume0: 30 T + 10 bytes (250 B in double,
// 130 B in float);
// the binning arrays (block id and sorted order, 8 B); external forces, 3 T, once set or
// opened by a coupling; and the grid, 8 T per node (7 values and a pad that makes a node two
// whole SIMD registers in double; plus a byte and at most an int per tile of 27 nodes for the
// active tiles). Grid memory follows the flow: only the node columns (i, j) the particles
// have reached are stored (GridConst::column; an int per column for the map), so a flow in a
// large domain costs its footprint's columns, not the box.
#pragma once
#include <cstdint>
#include <type_traits>
#include <vector>

#include "mpm/MpmKernelsCommon.hpp"
#include "mpm/StagedSolver.hpp"

namespace mpmsdem {
namespace mpm {

template <typename T>
class MpmCpu : public StagedSolver {
  static_assert(std::is_same_v<T, double> || std::is_same_v<T, float>, "MpmCpu runs in double or float");

 public:
  static constexpr Precision kPrecision = std::is_same_v<T, float> ? Precision::Float : Precision::Double;

  // params must have been validated (makeSolver does it).
  explicit MpmCpu(const MpmParams& params);

  std::string name() const override { return kPrecision == Precision::Float ? "cpu-float" : "cpu-double"; }
  const MpmParams& params() const override { return params_; }
  void setParticles(const ParticleSet& particles) override;
  void setParticles(ParticleSlices& particles) override;
  void getParticles(ParticleSet& out) override;
  void getParticles(ParticleSet& out, std::size_t first, std::size_t count) override;
  std::size_t numParticles() const override { return n_; }
  void setExternalForces(const std::vector<double>& f) override;
  ParticleView openForceBuffer() override;
  ParticleView extendForceBuffer() override;
  double cflTimeStep() override;
  std::size_t memoryBytes() const override;

 private:
  // The stages of a step (StagedSolver holds their order).
  void stageP2G(double dt) override;
  void stageGrid(double dt) override;
  void stageGridVelocity(double dt) override;
  GridView gridView(double dt) override;
  void stageGridBoundaries() override;
  void stageG2P(double dt) override;
  void stageEnd(double dt) override;
  long g2pFirstBad_ = 0;  // G2P's first failing particle number, or the particle count: none
  T g2pMaxSpeed_ = 0;     // G2P's largest particle speed [m/s]

  void load(ParticleSlices& particles, bool checked);
  struct State {
    // mass and volume0 never change; they are kept by slot like the rest, so that a step reads
    // them in turn and not scattered by particle number.
    std::vector<T> x[3], v[3], s[6], J, gdp, mass, vol0;
    std::vector<std::uint8_t> phase;
    std::vector<int> id;  // particle number of each slot
    void resize(std::size_t n);
  };
  ParticleIn<T> input() const;
  ParticleOut<T> output();
  // One copy (keepLastGoodState off): put the particles in the order of order_.
  void reorder();
  void scatter(T dt, const ParticleIn<T>& in);
  // Binning and the active tiles of the current particle positions.
  void bin(const ParticleIn<T>& in);
  template <typename F>
  void forActiveNodes(F&& f);

  MpmParams params_;
  GridConst<T> grid_{};
  ConstitutiveConst<T> mat_{};
  double maxSpeedAllowed_;
  std::size_t n_ = 0;
  // The state a step reads and, unless params_.keepLastGoodState is off (then state_[1] stays
  // empty and G2P updates state_[0] in place), the one it writes.
  State state_[2];
  int cur_ = 0;
  std::vector<T> scratch_;   // one copy: the buffer reorder() gathers into
  int stepsSinceReorder_ = 0;
  std::vector<T> fext_[3];
  bool hasFext_ = false;
  ParticleView forceView();  // the particles with fext_ as their force buffer
  // The grid's node records, column by column (GridConst::column): a column of nodes[2] records
  // is added when the particles first reach it (an active tile covers it), and kept.
  std::vector<T> nodes_;
  std::vector<int> column_;  // stored column of each (i, j), -1 until reached
  int columns_ = 0;          // columns stored
  void allocateColumns();    // a column for each (i, j) of this step's active tiles
  std::vector<T> terrainZ_;  // the terrain's heights (grid_.terrain.z), empty without one
  double maxSpeed_ = 0;   // largest particle speed of the current state [m/s]
  // P2G colouring and the active grid
  int blocks_[3];
  int tiles_[3];
  std::vector<int> colourBlocks_[8];   // occupied block ids of each colour, this step
  // The binning: each occupied block's first place in order_ and its particle count (entries
  // of other blocks are stale or zero: only occupied_ is read), the occupied blocks ascending.
  std::vector<int> blockFirst_, blockCount_;
  std::vector<int> occupied_;
  std::vector<int> order_;             // slots sorted by block, within a block by stencil base, then number
  std::vector<int> cellOf_;           // stencil base of each particle (27 x block + base in the block)
  std::vector<int> slotOf_;            // slot of each particle number, for output slices; emptied by step()
  std::vector<int> activeTiles_;       // tiles that may hold non-zero grid values
  std::vector<std::uint8_t> tileMark_; // scratch, all zero between steps
};

extern template class MpmCpu<double>;
extern template class MpmCpu<float>;

}  // namespace mpm
}  // namespace mpmsdem
