#include "mpm/MpmCpu.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "common/Error.hpp"

namespace mpmsdem {
namespace mpm {

namespace {
// With one copy of the particles, G2P leaves them where they are; they are put back in block
// order every this many steps, before they have drifted far from it (docs/benchmarks.md).
constexpr int kReorderEvery = 8;
constexpr int kG2PBatch = 32;  // particles per vector loop of the G2P update
// Particles of one stencil base whose G2P grid sums share vector instructions: 8 in float, 4 in
// double (one AVX2 register; wider groups ran slower, from register spills and half-empty groups
// at 8 particles per cell).
template <typename T>
constexpr int kG2PGroup = 32 / static_cast<int>(sizeof(T));

// The G2P update of a batch of m particles whose values g2pGather put at a[c * kG2PBatch + l],
// as one vector loop. The particles go to slot[l] of out; unless kScattered, these slots are
// consecutive and the loop stores whole vectors. out, g and sc come by value, so the loop's
// stores cannot change the array addresses or the constants it reads. The phase comes back as
// an int: a byte-wide result would set the vector length to 64 lanes, more than a batch.
template <bool kScattered, typename T>
void g2pUpdateBatch(const T* a, int m, const int* slot, const int* id, ParticleOut<T> out, const GridConst<T> g,
                    const StepConst<T> sc, int* phase, long& firstBad, T& vmax) {
  if (!kScattered) {
    const long q0 = slot[0];
    for (int d = 0; d < 3; ++d) out.x[d] += q0, out.v[d] += q0;
    for (int k = 0; k < 6; ++k) out.s[k] += q0;
    out.J += q0;
    out.gdp += q0;
  }
  long bad = firstBad;
  T fastest = vmax;
#pragma omp simd reduction(min : bad) reduction(max : fastest)
  for (int l = 0; l < m; ++l) {
    T speed;
    const bool ok = g2pUpdate(a + l, kG2PBatch, kScattered ? slot[l] : l, out, g, sc, speed, phase[l]);
    if (!ok && id[l] < bad) bad = id[l];
    fastest = speed > fastest ? speed : fastest;
  }
  firstBad = bad;
  vmax = fastest;
}

// Sort the m slots a[] of one block by grid cell, then by particle number: by (cell[x], id[x]).
// The slots come from the previous step's order, in which they were sorted, so only the few
// particles that changed cell are out of place: insertion sort then costs O(m) per misplaced
// particle; a block with many (the first step after setParticles in an unsorted order) is
// sorted in O(m log m).
void sortByCellAndNumber(int* a, int m, const int* cell, const int* id) {
  auto before = [cell, id](int x, int y) { return cell[x] < cell[y] || (cell[x] == cell[y] && id[x] < id[y]); };
  int descents = 0;
  for (int i = 1; i < m; ++i) descents += before(a[i], a[i - 1]);
  if (descents == 0) return;
  if (descents > 8) {
    std::sort(a, a + m, before);
    return;
  }
  for (int i = 1; i < m; ++i) {
    const int v = a[i];
    int j = i;
    for (; j > 0 && before(v, a[j - 1]); --j) a[j] = a[j - 1];
    a[j] = v;
  }
}
}  // namespace

template <typename T>
void MpmCpu<T>::State::resize(std::size_t n) {
  for (auto& a : x) a.assign(n, T(0));
  for (auto& a : v) a.assign(n, T(0));
  for (auto& a : s) a.assign(n, T(0));
  J.assign(n, T(1));
  gdp.assign(n, T(0));
  mass.assign(n, T(0));
  vol0.assign(n, T(0));
  phase.assign(n, 0);
  id.assign(n, 0);
}

template <typename T>
MpmCpu<T>::MpmCpu(const MpmParams& params)
    : params_(params),
      grid_(makeGridConst<T>(params, 0.0)),
      mat_(makeConstitutiveConst<T>(params.material)),
      maxSpeedAllowed_(blowUpSpeed(params)) {
  column_.assign(static_cast<std::size_t>(grid_.nodes[0]) * grid_.nodes[1], -1);
  grid_.column = column_.data();
  for (int d = 0; d < 3; ++d) {
    blocks_[d] = blocksAlong(params.cells[d]);
    tiles_[d] = (grid_.nodes[d] + 2) / 3;
  }
  blockFirst_.assign(static_cast<std::size_t>(blocks_[0]) * blocks_[1] * blocks_[2], 0);
  blockCount_.assign(blockFirst_.size(), 0);
  tileMark_.assign(static_cast<std::size_t>(tiles_[0]) * tiles_[1] * tiles_[2], 0);
  if (params.terrain.enabled()) {
    terrainZ_.assign(params.terrain.heights.begin(), params.terrain.heights.end());
    grid_.terrain.z = terrainZ_.data();
  }
}

template <typename T>
void MpmCpu<T>::setParticles(const ParticleSet& ps) {
  validateParticles(params_, ps);  // a bad set leaves the solver as it was
  WholeParticleSet whole(ps);
  load(whole, true);
}

template <typename T>
void MpmCpu<T>::setParticles(ParticleSlices& particles) {
  load(particles, false);
}

// Slice by slice: the state is allocated once, then each slice is checked (unless `checked`:
// the caller did) and loaded; a bad particle leaves the solver without particles.
template <typename T>
void MpmCpu<T>::load(ParticleSlices& particles, bool checked) {
  n_ = 0;
  const std::size_t n = particles.size();
  std::vector<int>().swap(slotOf_);
  state_[0].resize(n);
  if (params_.keepLastGoodState)
    state_[1].resize(n);
  else
    scratch_.assign(n, T(0));
  cur_ = 0;
  stepsSinceReorder_ = kReorderEvery - 1;  // given by number: sorted after the first step
  partlyAdvanced_ = false;
  State& s = state_[0];
  maxSpeed_ = 0;
  double massSum = 0;
  hasFext_ = false;
  forcesIncomplete_ = false;
  for (auto& a : fext_) std::vector<T>().swap(a);
  forEachSlice(particles, [&](std::size_t first, const ParticleSet& ps) {
    const std::size_t count = ps.size();
    if (checked)
      for (std::size_t i = 0; i < count; ++i) massSum += ps.mass[i];
    else
      validateParticleSlice(params_, ps, first, massSum);
    for (std::size_t i = 0; i < count; ++i) {
      const std::size_t p = first + i;
      s.mass[p] = static_cast<T>(ps.mass[i]);
      s.vol0[p] = static_cast<T>(ps.volume0[i]);
      for (int d = 0; d < 3; ++d) {
        s.x[d][p] = static_cast<T>(ps.x[3 * i + d]);
        s.v[d][p] = static_cast<T>(ps.v[3 * i + d]);
      }
      for (int k = 0; k < 6; ++k) s.s[k][p] = static_cast<T>(ps.stress[6 * i + k]);
      s.J[p] = static_cast<T>(ps.J[i]);
      s.gdp[p] = ps.gammaDotP.empty() ? T(0) : static_cast<T>(ps.gammaDotP[i]);
      s.phase[p] = ps.phase.empty() ? static_cast<std::uint8_t>(kPhaseElastic) : ps.phase[i];
      s.id[p] = static_cast<int>(p);
      const double vx = s.v[0][p], vy = s.v[1][p], vz = s.v[2][p];
      maxSpeed_ = std::max(maxSpeed_, std::sqrt(vx * vx + vy * vy + vz * vz));
    }
    // All-zero forces (every seeded set has them) load as none: P2G adds the same +0 either
    // way, and no force buffer is held until a coupling opens one. The buffer starts at the
    // first slice with a force; the slices before it held zeros.
    if (!hasFext_ && std::any_of(ps.fext.begin(), ps.fext.end(), [](double f) { return f != 0; })) {
      for (int d = 0; d < 3; ++d) fext_[d].assign(n, T(0));
      hasFext_ = true;
    }
    for (std::size_t i = 0; hasFext_ && !ps.fext.empty() && i < count; ++i)
      for (int d = 0; d < 3; ++d) {
        const double f = ps.fext[3 * i + d];
        if (!std::isfinite(f))
          throwParameter("externalForces[" + std::to_string(3 * (first + i) + d) + "]", f, "N", "finite");
        fext_[d][first + i] = static_cast<T>(f);
      }
  });
  grid_.massEps = static_cast<T>(1e-12 * (n ? massSum / static_cast<double>(n) : 1.0));
  n_ = n;
  order_.assign(n_, 0);
  cellOf_.assign(n_, 0);
}

template <typename T>
void MpmCpu<T>::getParticles(ParticleSet& out) {
  getParticles(out, 0, n_);
}

// The slots are in the solver's order, the numbers anywhere: a slice looks its particles up in
// slotOf_, built at the first slice after a step (4 B per particle until the next step), the
// whole set is written in one pass over the slots.
template <typename T>
void MpmCpu<T>::getParticles(ParticleSet& out, std::size_t first, std::size_t count) {
  requireLastGoodState("getParticles");
  validateSliceRange("particle slice", first, count, n_);
  const State& s = state_[cur_];
  const bool whole = first == 0 && count == n_;
  if (!whole && slotOf_.size() != n_) {
    slotOf_.resize(n_);
    for (std::size_t q = 0; q < n_; ++q) slotOf_[s.id[q]] = static_cast<int>(q);
  }
  out.x.resize(3 * count);
  out.v.resize(3 * count);
  out.stress.resize(6 * count);
  out.mass.resize(count);
  out.volume0.resize(count);
  out.J.resize(count);
  out.gammaDotP.resize(count);
  out.phase.resize(count);
  out.fext.assign(3 * count, 0.0);
  for (std::size_t k = 0; k < count; ++k) {
    const std::size_t q = whole ? k : static_cast<std::size_t>(slotOf_[first + k]);
    const std::size_t p = whole ? static_cast<std::size_t>(s.id[q]) : k;
    for (int d = 0; d < 3; ++d) {
      out.x[3 * p + d] = s.x[d][q];
      out.v[3 * p + d] = s.v[d][q];
      if (hasFext_) out.fext[3 * p + d] = fext_[d][q];
    }
    for (int k = 0; k < 6; ++k) out.stress[6 * p + k] = s.s[k][q];
    out.mass[p] = s.mass[q];
    out.volume0[p] = s.vol0[q];
    out.J[p] = s.J[q];
    out.gammaDotP[p] = s.gdp[q];
    out.phase[p] = s.phase[q];
  }
}

template <typename T>
void MpmCpu<T>::setExternalForces(const std::vector<double>& f) {
  validateExternalForces(f, n_);
  forcesIncomplete_ = true;
  for (int d = 0; d < 3; ++d) fext_[d].resize(n_);
  const std::vector<int>& id = state_[cur_].id;
  for (std::size_t q = 0; q < n_; ++q)
    for (int d = 0; d < 3; ++d) fext_[d][q] = static_cast<T>(f[3 * id[q] + d]);
  hasFext_ = true;
  forcesIncomplete_ = false;
}

template <typename T>
ParticleView MpmCpu<T>::openForceBuffer() {
  requireLastGoodState("openForceBuffer");
  forcesIncomplete_ = true;
  for (int d = 0; d < 3; ++d) fext_[d].assign(n_, T(0));
  hasFext_ = true;
  forcesIncomplete_ = false;
  return forceView();
}

template <typename T>
ParticleView MpmCpu<T>::extendForceBuffer() {
  requireLastGoodState("extendForceBuffer");
  if (!hasFext_) return openForceBuffer();
  return forceView();
}

template <typename T>
ParticleView MpmCpu<T>::forceView() {
  ParticleView v;
  v.precision = kPrecision;
  v.device = false;
  v.n = n_;
  const State& s = state_[cur_];
  v.id = s.id.data();
  for (int d = 0; d < 3; ++d) {
    v.x[d] = s.x[d].data();
    v.v[d] = s.v[d].data();
    v.force[d] = fext_[d].data();
  }
  v.mass = s.mass.data();
  v.volume0 = s.vol0.data();
  v.J = s.J.data();
  return v;
}

template <typename T>
double MpmCpu<T>::cflTimeStep() { return params_.cfl * params_.dx / (pWaveSpeed(params_.material) + maxSpeed_); }

template <typename T>
std::size_t MpmCpu<T>::memoryBytes() const {
  std::size_t b = 0;
  auto add = [&b](const auto& v) { b += v.capacity() * sizeof(typename std::decay_t<decltype(v)>::value_type); };
  for (const auto& st : state_) {
    for (const auto& a : st.x) add(a);
    for (const auto& a : st.v) add(a);
    for (const auto& a : st.s) add(a);
    add(st.J);
    add(st.gdp);
    add(st.mass);
    add(st.vol0);
    add(st.phase);
    add(st.id);
  }
  add(scratch_);
  for (const auto& a : fext_) add(a);
  add(nodes_);
  add(column_);
  add(terrainZ_);
  add(blockFirst_);
  add(blockCount_);
  add(occupied_);
  add(order_);
  add(cellOf_);
  for (const auto& c : colourBlocks_) add(c);
  add(activeTiles_);
  add(tileMark_);
  return b;
}

template <typename T>
ParticleIn<T> MpmCpu<T>::input() const {
  const State& s = state_[cur_];
  ParticleIn<T> in;
  for (int d = 0; d < 3; ++d) {
    in.x[d] = s.x[d].data();
    in.v[d] = s.v[d].data();
    in.fext[d] = hasFext_ ? fext_[d].data() : nullptr;
  }
  for (int k = 0; k < 6; ++k) in.s[k] = s.s[k].data();
  in.J = s.J.data();
  in.mass = s.mass.data();
  in.vol0 = s.vol0.data();
  in.id = s.id.data();
  return in;
}

template <typename T>
ParticleOut<T> MpmCpu<T>::output() {
  State& s = state_[params_.keepLastGoodState ? 1 - cur_ : cur_];
  ParticleOut<T> out;
  for (int d = 0; d < 3; ++d) {
    out.x[d] = s.x[d].data();
    out.v[d] = s.v[d].data();
  }
  for (int k = 0; k < 6; ++k) out.s[k] = s.s[k].data();
  out.J = s.J.data();
  out.gdp = s.gdp.data();
  out.phase = s.phase.data();
  return out;
}

template <typename T>
void MpmCpu<T>::reorder() {
  State& s = state_[cur_];
  const long n = static_cast<long>(n_);
  const int* order = order_.data();
  auto gather = [n, order](const auto* from, auto* to) {
#pragma omp parallel for schedule(static)
    for (long q = 0; q < n; ++q) to[q] = from[order[q]];
  };
  auto permute = [&](std::vector<T>& a) {
    gather(a.data(), scratch_.data());
    a.swap(scratch_);
  };
  for (auto& a : s.x) permute(a);
  for (auto& a : s.v) permute(a);
  for (auto& a : s.s) permute(a);
  permute(s.J);
  permute(s.gdp);
  permute(s.mass);
  permute(s.vol0);
  // cellOf_ is free until the next binning: the numbers are gathered into it.
  gather(s.id.data(), cellOf_.data());
  s.id.swap(cellOf_);
  auto* bytes = reinterpret_cast<std::uint8_t*>(scratch_.data());
  gather(s.phase.data(), bytes);
  std::copy(bytes, bytes + n_, s.phase.begin());
}

template <typename T>
void MpmCpu<T>::bin(const ParticleIn<T>& in) {
  const long n = static_cast<long>(n_);
  // Bin the particles by their stencil base node (computed in T exactly as Stencil::compute
  // does): cellOf_[p] = 27 b + c for the c-th base of the 3x3x3 block b.
#pragma omp parallel for schedule(static)
  for (long p = 0; p < n; ++p) {
    T g[3];
    gridCoordinate(in, static_cast<int>(p), grid_, g);
    cellOf_[p] = blockCellOf(g, blocks_);
  }
  // Counting sort over the occupied blocks alone: a domain far larger than its flow has millions
  // of empty blocks, which no pass visits. The counts left by the last binning are cleared
  // first, then each block is listed when its first particle arrives; the offsets go in
  // ascending block order, as a prefix sum over every block would give them.
  for (int b : occupied_) blockCount_[b] = 0;
  occupied_.clear();
  for (long p = 0; p < n; ++p) {
    const int b = cellOf_[p] / kBlockCells;
    if (blockCount_[b]++ == 0) occupied_.push_back(b);
  }
  std::sort(occupied_.begin(), occupied_.end());
  int offset = 0;
  for (int b : occupied_) {
    blockFirst_[b] = offset;  // the fill's cursor first, its first place again below
    offset += blockCount_[b];
  }
  for (long p = 0; p < n; ++p) order_[blockFirst_[cellOf_[p] / kBlockCells]++] = static_cast<int>(p);
  for (int b : occupied_) blockFirst_[b] -= blockCount_[b];
  // Within a block the particles go by stencil base, so that the particles of one base are
  // neighbours for G2P's groups, and then by number, so that the P2G sums and hence the
  // results do not depend on the storage order (a restart from a snapshot, which holds the
  // particles by number, continues bit for bit).
  const long nOccupied = static_cast<long>(occupied_.size());
#pragma omp parallel for schedule(dynamic, 64)
  for (long i = 0; i < nOccupied; ++i) {
    const int b = occupied_[i];
    sortByCellAndNumber(order_.data() + blockFirst_[b], blockCount_[b], cellOf_.data(), in.id);
  }
  for (auto& c : colourBlocks_) c.clear();
  activeTiles_.clear();
  for (int b : occupied_) {
    int bc[3];
    blockCoordsOf(b, blocks_, bc);
    colourBlocks_[blockColourOf(bc)].push_back(b);
    forTilesOfBlock(bc, tiles_, [this](int t) {
      if (tileMark_[t]) return;
      tileMark_[t] = 1;
      activeTiles_.push_back(t);
    });
  }
  std::sort(activeTiles_.begin(), activeTiles_.end());
  for (int t : activeTiles_) tileMark_[t] = 0;
  allocateColumns();
}

template <typename T>
void MpmCpu<T>::allocateColumns() {
  const int* nodes = grid_.nodes;
  const int before = columns_;
  int last = -1;  // the (t0, t1) of the previous tile: the tiles go in index order, t2 fastest
  for (int t : activeTiles_) {
    int tc[3];
    blockCoordsOf(t, tiles_, tc);
    const int pair = tc[0] * tiles_[1] + tc[1];
    if (pair == last) continue;
    last = pair;
    for (int a = 3 * tc[0]; a < std::min(3 * tc[0] + 3, nodes[0]); ++a)
      for (int b = 3 * tc[1]; b < std::min(3 * tc[1] + 3, nodes[1]); ++b) {
        int& c = column_[static_cast<std::size_t>(a) * nodes[1] + b];
        if (c < 0) c = columns_++;
      }
  }
  if (columns_ > before) nodes_.resize(static_cast<std::size_t>(kNodeValues) * columns_ * nodes[2], T(0));
}

template <typename T>
template <typename F>
void MpmCpu<T>::forActiveNodes(F&& f) {
  const long nt = static_cast<long>(activeTiles_.size());
  const int* nodes = grid_.nodes;
#pragma omp parallel for schedule(static)
  for (long i = 0; i < nt; ++i) {
    int tc[3];
    blockCoordsOf(activeTiles_[i], tiles_, tc);
    for (int a = 3 * tc[0]; a < std::min(3 * tc[0] + 3, nodes[0]); ++a)
      for (int b = 3 * tc[1]; b < std::min(3 * tc[1] + 3, nodes[1]); ++b)
        for (int c = 3 * tc[2]; c < std::min(3 * tc[2] + 3, nodes[2]); ++c) f((a * nodes[1] + b) * nodes[2] + c);
  }
}

template <typename T>
void MpmCpu<T>::scatter(T dt, const ParticleIn<T>& in) {
  T* gridData = nodes_.data();
  const GridConst<T>& g = grid_;
  for (int c = 0; c < 8; ++c) {
    const std::vector<int>& list = colourBlocks_[c];
    const long nb = static_cast<long>(list.size());
#pragma omp parallel for schedule(dynamic, 4)
    for (long i = 0; i < nb; ++i) {
      const int b = list[i];
      int b0[3];
      blockCoordsOf(b, blocks_, b0);
      for (int& x : b0) x *= 3;  // the block's first stencil-base node
      // The block's particles add into a private copy of the nodes they reach (in L1), which
      // is then added to the grid once: the grid is touched once per block, not per particle.
      T loc[kBlockNodes][kBlockNodes][kBlockNodes][kNodeValues] = {};
      // The next particle is prepared before this one is added: its coefficients, written
      // value by value, are then in the cache when they are read as whole vectors (read right
      // after being written, the reads waited for the writes).
      const int q0 = blockFirst_[b], q1 = q0 + blockCount_[b];
      P2GParticle<T> prepared[2];
      if (q0 < q1) p2gPrepare(order_[q0], in, g, dt, prepared[0]);
      for (int q = q0; q < q1; ++q) {
        if (q + 1 < q1) p2gPrepare(order_[q + 1], in, g, dt, prepared[(q + 1 - q0) & 1]);
        const P2GParticle<T>& a = prepared[(q - q0) & 1];
        const int o0 = a.st.base[0] - b0[0], o1 = a.st.base[1] - b0[1], o2 = a.st.base[2] - b0[2];
        auto add = [&loc, o0, o1, o2](int di, int dj, int dk, const T* r) {
          T* l = loc[o0 + di][o1 + dj][o2 + dk];
          MPM_SIMD
          for (int v = 0; v < kNodeValues; ++v) l[v] += r[v];
        };
        p2gStencil(a, add);
      }
      const int e0 = std::min(kBlockNodes, g.nodes[0] - b0[0]), e1 = std::min(kBlockNodes, g.nodes[1] - b0[1]),
                e2 = std::min(kBlockNodes, g.nodes[2] - b0[2]);
      for (int a = 0; a < e0; ++a)
        for (int bb = 0; bb < e1; ++bb) {
          T* r = gridData + kNodeValues * nodeRecordAt(g, b0[0] + a, b0[1] + bb, b0[2]);
          const T* l = loc[a][bb][0];
          MPM_SIMD
          for (int v = 0; v < kNodeValues * e2; ++v) r[v] += l[v];
        }
    }
  }
}

template <typename T>
void MpmCpu<T>::stageP2G(double dt) {
  std::vector<int>().swap(slotOf_);  // the particles move in storage
  const ParticleIn<T> in = input();
  {
    // Only the previous step's active tiles hold non-zero values.
    T* gridData = nodes_.data();
    const GridConst<T>& g = grid_;
    forActiveNodes([gridData, &g](int node) {
      T* r = gridData + kNodeValues * nodeRecord(g, node);
      for (int c = 0; c < kNodeValues; ++c) r[c] = T(0);
    });
  }
  bin(in);  // stores the columns the particles newly reach
  scatter(static_cast<T>(dt), in);
}

template <typename T>
void MpmCpu<T>::stageGrid(double dt) {
  T* gridData = nodes_.data();
  const GridConst<T> g = grid_;
  const T dtT = static_cast<T>(dt);
  forActiveNodes([gridData, &g, dtT](int node) { gridNodeUpdate(node, gridData, g, dtT); });
}

template <typename T>
void MpmCpu<T>::stageGridVelocity(double dt) {
  T* gridData = nodes_.data();
  const GridConst<T> g = grid_;
  const T dtT = static_cast<T>(dt);
  forActiveNodes([gridData, &g, dtT](int node) { gridNodeVelocity(node, gridData, g, dtT); });
}

template <typename T>
GridView MpmCpu<T>::gridView(double dt) {
  GridView view = gridViewFrame(dt);
  view.precision = kPrecision;
  view.device = false;
  view.stride = kNodeValues;
  view.mass = nodes_.data() + kNodeMass;
  for (int d = 0; d < 3; ++d) view.v[d] = nodes_.data() + kNodeVNew + d;
  view.column = column_.data();
  view.storedNodes = static_cast<long>(columns_) * grid_.nodes[2];
  return view;
}

template <typename T>
void MpmCpu<T>::stageGridBoundaries() {
  T* gridData = nodes_.data();
  const GridConst<T> g = grid_;
  forActiveNodes([gridData, &g](int node) { gridNodeWalls(node, gridData, g); });
}

template <typename T>
void MpmCpu<T>::stageG2P(double dt) {
  const ParticleIn<T> in = input();
  const ParticleOut<T> out = output();
  T* gridData = nodes_.data();
  const GridConst<T> g = grid_;
  StepConst<T> sc;
  sc.dt = static_cast<T>(dt);
  sc.alpha = static_cast<T>(params_.flip.alphaFor(dt, params_.dx));
  sc.maxSpeed = static_cast<T>(maxSpeedAllowed_);
  sc.mat = mat_;
  const long n = static_cast<long>(n_);
  long firstBad = n;
  T vmax = 0;
  // G2P writes the particles in their block order, where the next step reads them (nearly) in
  // turn; with one copy it updates them in their slots, and reorder() sorts them now and then.
  const bool inPlace = !params_.keepLastGoodState;
  const int* order = order_.data();
  const int* cellOf = cellOf_.data();
  State& next = state_[inPlace ? cur_ : 1 - cur_];
  int* outId = next.id.data();
  T* outMass = next.mass.data();
  T* outVol0 = next.vol0.data();
  // The particles go in batches: the grid sums of a batch one stencil base at a time, then the
  // update of the batch as one vector loop (the update is the same arithmetic for every
  // particle, so several particles share each vector instruction).
  const long batches = (n + kG2PBatch - 1) / kG2PBatch;
#pragma omp parallel for schedule(static) reduction(min : firstBad) reduction(max : vmax)
  for (long b = 0; b < batches; ++b) {
    alignas(64) T a[kG2PValues * kG2PBatch];
    int slot[kG2PBatch], id[kG2PBatch];
    int phase[kG2PBatch];
    const long q0 = b * kG2PBatch;
    const int m = static_cast<int>(std::min<long>(kG2PBatch, n - q0));
    for (int l = 0; l < m;) {
      // The next run of up to kG2PGroup particles with one stencil base.
      const int* ps = order + q0 + l;
      int count = 1;
      while (count < kG2PGroup<T> && l + count < m && cellOf[ps[count]] == cellOf[ps[0]]) ++count;
      g2pGatherGroup<kG2PGroup<T>>(ps, count, in, gridData, g, a + l, kG2PBatch);
      for (int e = l + count; l < e; ++l) {
        const int p = order[q0 + l];
        slot[l] = inPlace ? p : static_cast<int>(q0 + l);
        id[l] = in.id[p];
      }
    }
    if (inPlace)
      g2pUpdateBatch<true>(a, m, slot, id, out, g, sc, phase, firstBad, vmax);
    else
      g2pUpdateBatch<false>(a, m, slot, id, out, g, sc, phase, firstBad, vmax);
    if (g.terrain.z)
      for (int l = 0; l < m; ++l) liftAboveTerrain(out.x[0][slot[l]], out.x[1][slot[l]], out.x[2][slot[l]], g.terrain);
    for (int l = 0; l < m; ++l) {
      out.phase[slot[l]] = static_cast<std::uint8_t>(phase[l]);
      if (inPlace) continue;
      outId[q0 + l] = id[l];
      outMass[q0 + l] = a[kG2PMass * kG2PBatch + l];
      outVol0[q0 + l] = a[kG2PVol0 * kG2PBatch + l];
    }
  }
  g2pFirstBad_ = firstBad;
  g2pMaxSpeed_ = vmax;
}

template <typename T>
void MpmCpu<T>::stageEnd(double dt) {
  const bool inPlace = !params_.keepLastGoodState;
  const long n = static_cast<long>(n_);
  if (g2pFirstBad_ < n) {
    partlyAdvanced_ = inPlace;
    const ParticleOut<T> out = output();
    const int* outId = state_[inPlace ? cur_ : 1 - cur_].id.data();
    const long p = std::find(outId, outId + n, static_cast<int>(g2pFirstBad_)) - outId;  // its slot
    const double x[3] = {double(out.x[0][p]), double(out.x[1][p]), double(out.x[2][p])};
    const double v[3] = {double(out.v[0][p]), double(out.v[1][p]), double(out.v[2][p])};
    throw RuntimeFailure(badParticleMessage(
        steps_ + 1, time_ + dt, name(), g2pFirstBad_, maxSpeedAllowed_, x, v, out.J[p],
        inPlace ? "The particles are partly advanced (keepLastGoodState is off): the last good state is the last "
                  "one saved."
                : "The particle state is kept at the start of this step."));
  }
  if (!inPlace)
    cur_ = 1 - cur_;
  else if (++stepsSinceReorder_ == kReorderEvery) {
    reorder();
    stepsSinceReorder_ = 0;
  }
  maxSpeed_ = g2pMaxSpeed_;
  hasFext_ = false;
}

template class MpmCpu<double>;
template class MpmCpu<float>;

}  // namespace mpm
}  // namespace mpmsdem
