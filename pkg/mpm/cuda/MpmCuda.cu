// Host control code of the CUDA backend: memory, transfers, launches, failure checks.
#include <cuda_runtime.h>

#include <cub/device/device_radix_sort.cuh>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <sstream>

#include "mpm/cuda/CudaCheck.hpp"
#include "mpm/cuda/MpmCuda.hpp"
#include "mpm/cuda/MpmCudaKernels.cuh"
#include "mpm/cuda/SortedKeys.cuh"

namespace mpmsdem {
namespace mpm {

namespace {
constexpr int kThreads = 256;
inline int blocksFor(std::size_t n) { return static_cast<int>((n + kThreads - 1) / kThreads); }

template <typename U>
void deviceAlloc(U** ptr, std::size_t count, std::size_t& bytes) {
  CUDA_CHECK(cudaMalloc(reinterpret_cast<void**>(ptr), std::max<std::size_t>(count, 1) * sizeof(U)));
  bytes += std::max<std::size_t>(count, 1) * sizeof(U);
}
template <typename U>
void deviceFree(U*& ptr) {
  if (ptr) CUDA_CHECK_NOTHROW(cudaFree(ptr));
  ptr = nullptr;
}
// Host double array indexed by particle number (stride/offset) -> device T array by slot.
template <typename T>
void uploadByNumber(T* dst, const std::vector<double>& src, const std::vector<int>& id, int stride, int offset,
                    std::vector<T>& buf) {
  const std::size_t n = id.size();
  buf.resize(n);
  for (std::size_t q = 0; q < n; ++q) buf[q] = static_cast<T>(src[stride * static_cast<std::size_t>(id[q]) + offset]);
  if (n) CUDA_CHECK(cudaMemcpy(dst, buf.data(), n * sizeof(T), cudaMemcpyHostToDevice));
}
}  // namespace

template <typename T>
MpmCuda<T>::MpmCuda(const MpmParams& params)
    : params_(params),
      grid_(makeGridConst<T>(params, 0.0)),
      mat_(makeConstitutiveConst<T>(params.material)),
      maxSpeedAllowed_(blowUpSpeed(params)) {
  nColumns_ = grid_.nodes[0] * grid_.nodes[1];
  for (int d = 0; d < 3; ++d) blocks_[d] = blocksAlong(params.cells[d]);
  nBlocks_ = blocks_[0] * blocks_[1] * blocks_[2];
  // What a grid too large for the device allocated is given back (a YADE session that tries a
  // smaller grid next has the whole device), and the error says what the grid needs.
  try {
    allocateGrid();
  } catch (const RuntimeFailure& e) {
    freeDevice();
    const std::size_t map = static_cast<std::size_t>(nColumns_) * sizeof(int);
    const std::size_t lists = static_cast<std::size_t>(nBlocks_) * 6 * sizeof(int);
    std::ostringstream os;
    os << "the CUDA backend's index arrays for the grid of " << params.cells[0] << " x " << params.cells[1] << " x "
       << params.cells[2] << " cells (" << map / 1e9 << " GB of column map, " << lists / 1e9
       << " GB of block lists) did not fit on the device (a smaller grid.cells, or the CPU backend): " << e.what();
    throw RuntimeFailure(os.str());
  }
}

template <typename T>
void MpmCuda<T>::allocateGrid() {
  deviceAlloc(&column_, nColumns_, gridBytes_);
  deviceAlloc(&flags_, 1, gridBytes_);
  CUDA_CHECK(cudaMallocHost(reinterpret_cast<void**>(&flagsHost_), sizeof(StepFlags)));
  cudaEvent_t done;
  CUDA_CHECK(cudaEventCreateWithFlags(&done, cudaEventDisableTiming));
  stepDone_ = done;
  deviceAlloc(&blockStart_, nBlocks_, gridBytes_);
  deviceAlloc(&blockEnd_, nBlocks_, gridBytes_);
  deviceAlloc(&colourBlocks_, nBlocks_, gridBytes_);
  deviceAlloc(&activeTiles_, nBlocks_, gridBytes_);
  deviceAlloc(&listCounts_, kTileLists, gridBytes_);
  deviceAlloc(&tileMark_, nBlocks_, gridBytes_);
  deviceAlloc(&slotOf_, nBlocks_, gridBytes_);
  // no column stored yet (the pool grows as the particles reach columns); no active tile
  CUDA_CHECK(cudaMemset(column_, 0xff, static_cast<std::size_t>(nColumns_) * sizeof(int)));
  CUDA_CHECK(cudaMemset(flags_, 0, sizeof(StepFlags)));
  CUDA_CHECK(cudaMemset(listCounts_, 0, kTileLists * sizeof(int)));
  CUDA_CHECK(cudaMemset(tileMark_, 0, static_cast<std::size_t>(nBlocks_) * sizeof(int)));
  CUDA_CHECK(cudaMemset(slotOf_, 0xff, static_cast<std::size_t>(nBlocks_) * sizeof(int)));
  grid_.column = column_;
  if (params_.terrain.enabled()) {
    const std::vector<T> z(params_.terrain.heights.begin(), params_.terrain.heights.end());
    deviceAlloc(&terrain_, z.size(), gridBytes_);
    CUDA_CHECK(cudaMemcpy(terrain_, z.data(), z.size() * sizeof(T), cudaMemcpyHostToDevice));
    grid_.terrain.z = terrain_;
  }
  // enough blocks to fill the device; the kernels over the active tiles' nodes loop over them
  int device = 0, sms = 1;
  CUDA_CHECK(cudaGetDevice(&device));
  CUDA_CHECK(cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, device));
  gridLaunch_ = std::max(1, std::min(blocksFor(static_cast<std::size_t>(kBlockCells) * nBlocks_), 8 * sms));
  p2gLaunch_ = kP2GBlocksPerSM * sms;
}

template <typename T>
MpmCuda<T>::~MpmCuda() {
  freeDevice();
}

template <typename T>
void MpmCuda<T>::freeDevice() {
  setStageTiming(false);
  freeParticles();
  deviceFree(nodes_);
  deviceFree(column_);
  deviceFree(terrain_);
  deviceFree(flags_);
  if (flagsHost_) CUDA_CHECK_NOTHROW(cudaFreeHost(flagsHost_));
  flagsHost_ = nullptr;
  if (stepDone_) CUDA_CHECK_NOTHROW(cudaEventDestroy(static_cast<cudaEvent_t>(stepDone_)));
  stepDone_ = nullptr;
  deviceFree(blockStart_);
  deviceFree(blockEnd_);
  deviceFree(colourBlocks_);
  deviceFree(activeTiles_);
  deviceFree(listCounts_);
  deviceFree(tileMark_);
  deviceFree(slotOf_);
  deviceFree(diagnostics_);
}

template <typename T>
std::string MpmCuda<T>::name() const {
  return sizeof(T) == sizeof(float) ? "cuda-float" : "cuda-double";
}

template <typename T>
void MpmCuda<T>::freeParticles() {
  for (auto& st : state_) {
    for (auto& a : st.x) deviceFree(a);
    for (auto& a : st.v) deviceFree(a);
    for (auto& a : st.s) deviceFree(a);
    deviceFree(st.J);
    deviceFree(st.gdp);
    deviceFree(st.mass);
    deviceFree(st.vol0);
    deviceFree(st.phase);
    deviceFree(st.id);
  }
  for (auto& a : fext_) deviceFree(a);
  for (auto& a : keys_) deviceFree(a);
  for (auto& a : slots_) deviceFree(a);
  deviceFree(sortScratch_);
  deviceFree(tileScratch_);
  tileCapacity_ = 0;
  sortScratchBytes_ = 0;
  sorted_ = nullptr;
  sortedKeys_ = nullptr;
  bytes_ = 0;
  hasFext_ = false;
  forcesIncomplete_ = false;
}

template <typename T>
void MpmCuda<T>::setParticles(const ParticleSet& ps) {
  const double meanMass = validateParticles(params_, ps);
  if (!ps.fext.empty()) validateExternalForces(ps.fext, ps.size());
  const int numberBits = sortedkeys::bitsFor(ps.size());
  const int keyBits = numberBits + sortedkeys::bitsFor(static_cast<unsigned long long>(nBlocks_) * kBlockCells);
  if (keyBits > 64)
    throw ParameterError(std::to_string(ps.size()) + " particles in a grid of " + std::to_string(nBlocks_) +
                         " blocks of 3x3x3 cells: the CUDA P2G sort key needs " + std::to_string(keyBits) +
                         " bits, at most 64 are supported (fewer particles or cells)");
  grid_.massEps = static_cast<T>(1e-12 * meanMass);
  freeParticles();
  numberBits_ = numberBits;
  keyBits_ = keyBits;
  n_ = 0;  // until every array is allocated and filled: a failure leaves an empty solver
  try {
    loadParticles(ps);
  } catch (...) {
    freeParticles();
    throw;
  }
  n_ = ps.size();
  // the node columns around the particles, so that the first step finds its columns stored
  try {
    beginLists();
    if (n_ > 0) sortParticles();
    queueColumnsNear();
    StepFlags flags;
    CUDA_CHECK(cudaMemcpy(&flags, flags_, sizeof(StepFlags), cudaMemcpyDeviceToHost));
    takeColumns(flags);
  } catch (...) {
    freeParticles();
    n_ = 0;
    throw;
  }
  if (!ps.fext.empty()) setExternalForces(ps.fext);
}

template <typename T>
void MpmCuda<T>::queueColumnsNear() {
  cudak::storeColumnsNearKernel<<<gridLaunch_, kThreads>>>(activeLists(), blockGrid(), columnMap(),
                                                           &flags_->columnsUsed);
  CUDA_CHECK(cudaGetLastError());
}

template <typename T>
void MpmCuda<T>::takeColumns(const StepFlags& flags) {
  if (flags.columnsUsed > columnCapacity_) {
    try {
      growColumns(flags.columnsUsed);
    } catch (const RuntimeFailure&) {
      // the pool keeps what it holds: the places past it are taken back
      const unsigned int capacity = columnCapacity_;
      cudak::unstoreColumnsPastKernel<<<gridLaunch_, kThreads>>>(nColumns_, static_cast<int>(capacity), column_);
      CUDA_CHECK_NOTHROW(cudaGetLastError());
      CUDA_CHECK_NOTHROW(cudaMemcpy(&flags_->columnsUsed, &capacity, sizeof(capacity), cudaMemcpyHostToDevice));
      columnsStored_ = capacity;
      throw;
    }
  }
  columnsStored_ = flags.columnsUsed;
}

template <typename T>
void MpmCuda<T>::growColumns(unsigned int needed) {
  // half as many again as needed: a flow spreading over new ground grows the pool a few times, not every step
  const std::size_t capacity = std::min<std::size_t>(nColumns_, needed + needed / 2);
  const std::size_t column = static_cast<std::size_t>(kNodeValues) * grid_.nodes[2];  // values a column
  T* pool = nullptr;
  std::size_t bytes = 0;
  try {
    deviceAlloc(&pool, capacity * column, bytes);
    if (nodes_)
      CUDA_CHECK(cudaMemcpy(pool, nodes_, columnCapacity_ * column * sizeof(T), cudaMemcpyDeviceToDevice));
    CUDA_CHECK(cudaMemset(pool + columnCapacity_ * column, 0, (capacity - columnCapacity_) * column * sizeof(T)));
  } catch (const RuntimeFailure& e) {
    deviceFree(pool);
    std::ostringstream os;
    os << "the flow has reached " << needed << " node columns of the " << params_.cells[0] << " x "
       << params_.cells[1] << " x " << params_.cells[2] << "-cell grid (" << grid_.nodes[2] << " nodes each, "
       << needed * column * sizeof(T) / 1e9 << " GB of node records in " << name()
       << "); they did not fit on the device beside the rest (fewer cells along z, float, fewer particles, or the "
       << "CPU backend): " << e.what();
    throw RuntimeFailure(os.str());
  }
  deviceFree(nodes_);
  nodes_ = pool;
  gridBytes_ += bytes - columnCapacity_ * column * sizeof(T);
  columnCapacity_ = static_cast<unsigned int>(capacity);
}

template <typename T>
void MpmCuda<T>::loadParticles(const ParticleSet& ps) {
  const std::size_t n = ps.size();
  for (auto& st : state_) {
    for (auto& a : st.x) deviceAlloc(&a, n, bytes_);
    for (auto& a : st.v) deviceAlloc(&a, n, bytes_);
    for (auto& a : st.s) deviceAlloc(&a, n, bytes_);
    deviceAlloc(&st.J, n, bytes_);
    deviceAlloc(&st.gdp, n, bytes_);
    deviceAlloc(&st.mass, n, bytes_);
    deviceAlloc(&st.vol0, n, bytes_);
    deviceAlloc(&st.phase, n, bytes_);
    deviceAlloc(&st.id, n, bytes_);
  }
  for (auto& a : keys_) deviceAlloc(&a, n, bytes_);
  for (auto& a : slots_) deviceAlloc(&a, n, bytes_);
  {
    cub::DoubleBuffer<unsigned long long> k(keys_[0], keys_[1]);
    cub::DoubleBuffer<int> v(slots_[0], slots_[1]);
    CUDA_CHECK(cub::DeviceRadixSort::SortPairs(nullptr, sortScratchBytes_, k, v, static_cast<int>(n), 0, keyBits_));
    deviceAlloc(&sortScratch_, sortScratchBytes_, bytes_);
  }
  const std::size_t tiles = std::min<std::size_t>(n, static_cast<std::size_t>(nBlocks_));
  const std::size_t tileValues = static_cast<std::size_t>(cudak::kTileNodes) * (kNodeVNew + 3);
  if (n > 0 && tiles * tileValues * sizeof(T) <= kTileScratchBytes) {
    try {
      deviceAlloc(&tileScratch_, tiles * tileValues, bytes_);
      tileCapacity_ = static_cast<int>(tiles);
    } catch (const RuntimeFailure&) {
      tileScratch_ = nullptr;  // a device nearly full: the colour launches need no scratch
    }
  }
  cur_ = 0;
  slotOfValid_ = false;
  DeviceState& s = state_[0];
  std::vector<int> id(n);  // a new set: slot = number
  for (std::size_t p = 0; p < n; ++p) id[p] = static_cast<int>(p);
  std::vector<T> buf;
  for (int d = 0; d < 3; ++d) {
    uploadByNumber(s.x[d], ps.x, id, 3, d, buf);
    uploadByNumber(s.v[d], ps.v, id, 3, d, buf);
  }
  for (int k = 0; k < 6; ++k) uploadByNumber(s.s[k], ps.stress, id, 6, k, buf);
  uploadByNumber(s.J, ps.J, id, 1, 0, buf);
  uploadByNumber(s.mass, ps.mass, id, 1, 0, buf);
  uploadByNumber(s.vol0, ps.volume0, id, 1, 0, buf);
  if (ps.gammaDotP.empty())
    CUDA_CHECK(cudaMemset(s.gdp, 0, std::max<std::size_t>(n, 1) * sizeof(T)));
  else
    uploadByNumber(s.gdp, ps.gammaDotP, id, 1, 0, buf);
  if (ps.phase.empty())
    CUDA_CHECK(cudaMemset(s.phase, 0, std::max<std::size_t>(n, 1)));
  else if (n)
    CUDA_CHECK(cudaMemcpy(s.phase, ps.phase.data(), n, cudaMemcpyHostToDevice));
  if (n) CUDA_CHECK(cudaMemcpy(s.id, id.data(), n * sizeof(int), cudaMemcpyHostToDevice));
  maxSpeed_ = 0;
  for (std::size_t p = 0; p < n; ++p)
    maxSpeed_ = std::max(maxSpeed_, std::sqrt(ps.v[3 * p] * ps.v[3 * p] + ps.v[3 * p + 1] * ps.v[3 * p + 1] +
                                              ps.v[3 * p + 2] * ps.v[3 * p + 2]));
}

template <typename T>
std::vector<int> MpmCuda<T>::numbers() const {
  std::vector<int> id(n_);
  if (n_) CUDA_CHECK(cudaMemcpy(id.data(), state_[cur_].id, n_ * sizeof(int), cudaMemcpyDeviceToHost));
  return id;
}

template <typename T>
void MpmCuda<T>::getParticles(ParticleSet& out) {
  getParticles(out, 0, n_);
}

template <typename T>
const int* MpmCuda<T>::slotsByNumber() {
  // slots_ serve the sort within a step only; between steps slots_[0] holds this map
  if (!slotOfValid_) {
    cudak::slotOfKernel<<<blocksFor(n_), kThreads>>>(static_cast<int>(n_), state_[cur_].id, slots_[0]);
    CUDA_CHECK(cudaGetLastError());
    slotOfValid_ = true;
  }
  return slots_[0];
}

template <typename T>
template <typename U, typename H>
void MpmCuda<T>::gatherByNumber(const U* src, std::size_t first, std::size_t count, std::vector<H>& dst, int stride,
                                int offset) {
  // keys_[0] (n 8-byte keys, free between steps) receives the gathered values
  U* gathered = reinterpret_cast<U*>(keys_[0]);
  cudak::gatherByNumberKernel<U><<<blocksFor(count), kThreads>>>(static_cast<int>(count), static_cast<int>(first),
                                                                 slotsByNumber(), src, gathered);
  CUDA_CHECK(cudaGetLastError());
  std::vector<U> buf(count);
  CUDA_CHECK(cudaMemcpy(buf.data(), gathered, count * sizeof(U), cudaMemcpyDeviceToHost));
  for (std::size_t k = 0; k < count; ++k) dst[stride * k + offset] = static_cast<H>(buf[k]);
}

template <typename T>
void MpmCuda<T>::getParticles(ParticleSet& out, std::size_t first, std::size_t count) {
  validateSliceRange("particle slice", first, count, n_);
  const DeviceState& s = state_[cur_];
  out.x.assign(3 * count, 0.0);
  out.v.assign(3 * count, 0.0);
  out.stress.assign(6 * count, 0.0);
  out.mass.assign(count, 0.0);
  out.volume0.assign(count, 0.0);
  out.J.assign(count, 0.0);
  out.gammaDotP.assign(count, 0.0);
  out.phase.assign(count, 0);
  out.fext.assign(3 * count, 0.0);
  if (count == 0) return;
  for (int d = 0; d < 3; ++d) {
    gatherByNumber(s.x[d], first, count, out.x, 3, d);
    gatherByNumber(s.v[d], first, count, out.v, 3, d);
    if (hasFext_) gatherByNumber(fext_[d], first, count, out.fext, 3, d);
  }
  for (int k = 0; k < 6; ++k) gatherByNumber(s.s[k], first, count, out.stress, 6, k);
  gatherByNumber(s.J, first, count, out.J, 1, 0);
  gatherByNumber(s.gdp, first, count, out.gammaDotP, 1, 0);
  gatherByNumber(s.mass, first, count, out.mass, 1, 0);
  gatherByNumber(s.vol0, first, count, out.volume0, 1, 0);
  gatherByNumber(s.phase, first, count, out.phase, 1, 0);
}

template <typename T>
void MpmCuda<T>::setExternalForces(const std::vector<double>& f) {
  validateExternalForces(f, n_);
  forcesIncomplete_ = true;
  const std::vector<int> id = numbers();
  std::vector<T> buf;
  for (int d = 0; d < 3; ++d) {
    if (!fext_[d]) deviceAlloc(&fext_[d], n_, bytes_);
    uploadByNumber(fext_[d], f, id, 3, d, buf);
  }
  hasFext_ = true;
  forcesIncomplete_ = false;
}

template <typename T>
ParticleView MpmCuda<T>::openForceBuffer() {
  forcesIncomplete_ = true;
  for (int d = 0; d < 3; ++d) {
    if (!fext_[d]) deviceAlloc(&fext_[d], n_, bytes_);
    CUDA_CHECK(cudaMemset(fext_[d], 0, std::max<std::size_t>(n_, 1) * sizeof(T)));
  }
  hasFext_ = true;
  forcesIncomplete_ = false;
  return forceView();
}

// The buffer as the first coupling left it: a second one's kernel, queued after the first's on
// the same stream, adds to what it wrote.
template <typename T>
ParticleView MpmCuda<T>::extendForceBuffer() {
  if (!hasFext_) return openForceBuffer();
  return forceView();
}

template <typename T>
ParticleView MpmCuda<T>::forceView() {
  ParticleView v;
  v.precision = sizeof(T) == sizeof(float) ? Precision::Float : Precision::Double;
  v.device = true;
  v.n = n_;
  const DeviceState& s = state_[cur_];
  for (int d = 0; d < 3; ++d) {
    v.x[d] = s.x[d];
    v.v[d] = s.v[d];
    v.force[d] = fext_[d];
  }
  v.id = s.id;
  v.mass = s.mass;
  v.volume0 = s.vol0;
  v.J = s.J;
  return v;
}

template <typename T>
double MpmCuda<T>::cflTimeStep() {
  return params_.cfl * params_.dx / (pWaveSpeed(params_.material) + maxSpeed_);
}

template <typename T>
std::size_t MpmCuda<T>::memoryBytes() const {
  return gridBytes_ + bytes_;
}

template <typename T>
void MpmCuda<T>::setStageTiming(bool on) {
  for (auto& e : events_) {
    if (e) CUDA_CHECK_NOTHROW(cudaEventDestroy(static_cast<cudaEvent_t>(e)));
    e = nullptr;
  }
  for (double& t : stageTotals_) t = 0;
  if (!on) return;
  for (auto& e : events_) {
    cudaEvent_t ev;
    CUDA_CHECK(cudaEventCreate(&ev));
    e = ev;
  }
}

template <typename T>
std::vector<std::pair<std::string, double>> MpmCuda<T>::stageSeconds() const {
  if (!events_[0]) return {};
  static const char* kNames[kStages] = {"lists", "sort", "p2g", "grid", "g2p", "columns"};
  std::vector<std::pair<std::string, double>> out;
  for (int k = 0; k < kStages; ++k) out.emplace_back(kNames[k], stageTotals_[k]);
  return out;
}

template <typename T>
ParticleIn<T> MpmCuda<T>::input() const {
  const DeviceState& s = state_[cur_];
  ParticleIn<T> in;
  for (int d = 0; d < 3; ++d) {
    in.x[d] = s.x[d];
    in.v[d] = s.v[d];
    in.fext[d] = hasFext_ ? fext_[d] : nullptr;
  }
  for (int k = 0; k < 6; ++k) in.s[k] = s.s[k];
  in.J = s.J;
  in.mass = s.mass;
  in.vol0 = s.vol0;
  in.id = s.id;
  return in;
}

template <typename T>
ParticleOut<T> MpmCuda<T>::output() const {
  const DeviceState& s = state_[1 - cur_];
  ParticleOut<T> out;
  for (int d = 0; d < 3; ++d) {
    out.x[d] = s.x[d];
    out.v[d] = s.v[d];
  }
  for (int k = 0; k < 6; ++k) out.s[k] = s.s[k];
  out.J = s.J;
  out.gdp = s.gdp;
  out.phase = s.phase;
  return out;
}

template <typename T>
cudak::ActiveLists MpmCuda<T>::activeLists() const {
  static_assert(kTileLists == cudak::kTilesCount + 1, "a count per colour and one for the tiles");
  return {colourBlocks_, activeTiles_, listCounts_, tileMark_, blockStart_, blockEnd_};
}

template <typename T>
cudak::ColumnMap MpmCuda<T>::columnMap() const {
  return {column_, {grid_.nodes[0], grid_.nodes[1], grid_.nodes[2]}};
}

template <typename T>
cudak::BlockGrid MpmCuda<T>::blockGrid() const {
  return {{blocks_[0], blocks_[1], blocks_[2]}};
}

template <typename T>
void MpmCuda<T>::beginLists() {
  const cudak::BlockGrid bg = blockGrid();
  // Only the last lists' tiles hold non-zero values, and only they and their blocks marks.
  cudak::clearTilesKernel<T><<<gridLaunch_, kThreads>>>(activeLists(), bg, nodes_, grid_);
  CUDA_CHECK(cudaGetLastError());
  // (the tiles' scratch places whether or not this particle set has it: the last one's may have had it)
  cudak::forgetListsKernel<<<gridLaunch_, kThreads>>>(activeLists(), bg, slotOf_);
  CUDA_CHECK(cudaGetLastError());
  CUDA_CHECK(cudaMemsetAsync(listCounts_, 0, kTileLists * sizeof(int)));
}

template <typename T>
void MpmCuda<T>::sortParticles() {
  slotOfValid_ = false;  // the sort takes slots_ back
  const int n = static_cast<int>(n_);
  const ParticleIn<T> in = input();
  const cudak::BlockGrid bg = blockGrid();
  cudak::binKernel<T><<<blocksFor(n_), kThreads>>>(n, in, grid_, bg, numberBits_, keys_[0], slots_[0]);
  CUDA_CHECK(cudaGetLastError());
  cub::DoubleBuffer<unsigned long long> k(keys_[0], keys_[1]);
  cub::DoubleBuffer<int> v(slots_[0], slots_[1]);
  CUDA_CHECK(cub::DeviceRadixSort::SortPairs(sortScratch_, sortScratchBytes_, k, v, n, 0, keyBits_));
  cudak::occupiedBlocksKernel<<<blocksFor(n_), kThreads>>>(n, k.Current(), numberBits_, bg, activeLists(),
                                                            columnMap(), &flags_->columnsMissing);
  CUDA_CHECK(cudaGetLastError());
  sorted_ = v.Current();
  sortedKeys_ = k.Current();
}

template <typename T>
void MpmCuda<T>::launchStep(double dt) {
  runStages(dt);
}

template <typename T>
void MpmCuda<T>::finishStep() {
  endStages(launchedDt_);
}

template <typename T>
void MpmCuda<T>::beforeChecks() {
  if (launched_) throw RuntimeFailure(name() + ": launchStep: the step launched before has not been finished or abandoned");
}

// The device-event marks k of a step bound its timed stages (stageSeconds: sort, p2g, grid, g2p).
template <typename T>
void MpmCuda<T>::markStage(int k) {
  if (events_[k]) CUDA_CHECK(cudaEventRecord(static_cast<cudaEvent_t>(events_[k])));
}

template <typename T>
void MpmCuda<T>::stageP2G(double dt) {
  const T dtT = static_cast<T>(dt);
  const cudak::BlockGrid bg = blockGrid();
  markStage(0);
  beginLists();
  CUDA_CHECK(cudaMemsetAsync(&flags_->firstBad, 0xff, sizeof(flags_->firstBad)));
  static_assert(offsetof(StepFlags, columnsMissing) == offsetof(StepFlags, maxSpeedBits) + sizeof(unsigned int),
                "one memset clears both");
  CUDA_CHECK(cudaMemsetAsync(&flags_->maxSpeedBits, 0, 2 * sizeof(unsigned int)));
  const ParticleIn<T> in = input();
  markStage(1);
  if (n_ > 0) {
    sortParticles();
    markStage(2);
    if (tileScratch_) {
      cudak::p2gTilesKernel<T><<<std::min(tileCapacity_, p2gLaunch_), cudak::kBaseThreads>>>(
          bg, activeLists(), in, sorted_, sortedKeys_, numberBits_, grid_, dtT, tileScratch_, slotOf_);
      CUDA_CHECK(cudaGetLastError());
      cudak::p2gTileSumsKernel<T><<<gridLaunch_, kThreads>>>(activeLists(), bg, tileScratch_, slotOf_, nodes_, grid_);
      CUDA_CHECK(cudaGetLastError());
    } else {
      for (int colour = 0; colour < 8; ++colour) {
        const int count = std::min(bg.colourCapacity(colour), p2gLaunch_);
        if (count == 0) continue;
        cudak::p2gBaseKernel<T><<<count, cudak::kBaseThreads>>>(bg, colour, activeLists(), in, sorted_,
                                                                 sortedKeys_, numberBits_, grid_, dtT, nodes_,
                                                                 &flags_->columnsMissing);
        CUDA_CHECK(cudaGetLastError());
      }
    }
  }
  markStage(3);
}

template <typename T>
void MpmCuda<T>::stageGrid(double dt) {
  cudak::gridKernel<T><<<gridLaunch_, kThreads>>>(activeLists(), blockGrid(), nodes_, grid_, static_cast<T>(dt));
  CUDA_CHECK(cudaGetLastError());
}

template <typename T>
void MpmCuda<T>::stageGridVelocity(double dt) {
  cudak::gridVelocityKernel<T><<<gridLaunch_, kThreads>>>(activeLists(), blockGrid(), nodes_, grid_,
                                                          static_cast<T>(dt));
  CUDA_CHECK(cudaGetLastError());
}

template <typename T>
GridView MpmCuda<T>::gridView(double dt) {
  GridView view = gridViewFrame(dt);
  view.precision = sizeof(T) == sizeof(float) ? Precision::Float : Precision::Double;
  view.device = true;
  view.stride = kNodeValues;
  view.column = column_;
  view.storedNodes = static_cast<long>(columnsStored_) * grid_.nodes[2];
  view.mass = nodes_ + kNodeMass;
  for (int d = 0; d < 3; ++d) view.v[d] = nodes_ + kNodeVNew + d;
  return view;
}

template <typename T>
void MpmCuda<T>::stageGridBoundaries() {
  cudak::gridWallsKernel<T><<<gridLaunch_, kThreads>>>(activeLists(), blockGrid(), nodes_, grid_);
  CUDA_CHECK(cudaGetLastError());
}

template <typename T>
void MpmCuda<T>::stageG2P(double dt) {
  markStage(4);
  StepConst<T> sc;
  sc.dt = static_cast<T>(dt);
  sc.alpha = static_cast<T>(params_.flip.alphaFor(dt, params_.dx));
  sc.maxSpeed = static_cast<T>(maxSpeedAllowed_);
  sc.mat = mat_;
  const DeviceState& next = state_[1 - cur_];
  if (n_ > 0) {
    const cudak::MovedWith<T> moved{next.mass, next.vol0, next.id};
    cudak::g2pKernel<T><<<blocksFor(n_), kThreads>>>(static_cast<int>(n_), input(), output(), moved, sorted_, nodes_,
                                                     grid_, sc, &flags_->firstBad, &flags_->maxSpeedBits,
                                                     &flags_->columnsMissing);
    CUDA_CHECK(cudaGetLastError());
  }
  markStage(5);
  // the columns the next step's particles can reach (they move less than a cell), counted in the
  // copy back of the flags that every step waits for
  queueColumnsNear();
  markStage(6);
  CUDA_CHECK(cudaMemcpyAsync(flagsHost_, flags_, sizeof(StepFlags), cudaMemcpyDeviceToHost));
  CUDA_CHECK(cudaEventRecord(static_cast<cudaEvent_t>(stepDone_)));
  launched_ = true;
  launchedDt_ = dt;
}

template <typename T>
typename MpmCuda<T>::StepFlags MpmCuda<T>::waitForLaunched(const char* what) {
  if (!launched_) throw RuntimeFailure(name() + ": " + what + ": no step was launched (launchStep)");
  launched_ = false;
  CUDA_CHECK(cudaEventSynchronize(static_cast<cudaEvent_t>(stepDone_)));
  return *flagsHost_;
}

template <typename T>
void MpmCuda<T>::abandonStep() {
  const StepFlags res = waitForLaunched("abandonStep");
  // The columns the step stored stay (a superset of what the particles reach). Where the pool
  // cannot grow to them, takeColumns takes them back, and a later step that reaches them says so.
  try {
    takeColumns(res);
  } catch (const RuntimeFailure&) {
  }
}

template <typename T>
void MpmCuda<T>::stageEnd(double dt) {
  const StepFlags res = waitForLaunched("finishStep");
  const ParticleOut<T> out = output();
  takeColumns(res);
  if (res.columnsMissing) {
    std::ostringstream os;
    os << "MPM step " << steps_ + 1 << " (t = " << time_ + dt << " s, " << name()
       << "): material points reached node columns that were not stored: they moved more than three cells "
       << "in one step (the step " << dt << " s is far above the stable step " << stableTimeStep()
       << " s). The particle state is kept at the start of this step, and the columns are stored now.";
    throw RuntimeFailure(os.str());
  }
  if (events_[0] && n_ > 0)
    for (int k = 0; k < kStages; ++k) {
      float ms = 0;
      CUDA_CHECK(cudaEventElapsedTime(&ms, static_cast<cudaEvent_t>(events_[k]), static_cast<cudaEvent_t>(events_[k + 1])));
      stageTotals_[k] += 1e-3 * ms;
    }
  if (res.firstBad != ~0ull) {
    const int p = static_cast<int>(res.firstBad >> 32);
    const int slot = static_cast<int>(res.firstBad & 0xffffffffull);
    T xv[7];
    const T* src[7] = {out.x[0], out.x[1], out.x[2], out.v[0], out.v[1], out.v[2], out.J};
    for (int i = 0; i < 7; ++i) CUDA_CHECK(cudaMemcpy(&xv[i], src[i] + slot, sizeof(T), cudaMemcpyDeviceToHost));
    const double x[3] = {double(xv[0]), double(xv[1]), double(xv[2])};
    const double v[3] = {double(xv[3]), double(xv[4]), double(xv[5])};
    throw RuntimeFailure(badParticleMessage(steps_ + 1, time_ + dt, name(), p, maxSpeedAllowed_, x, v, xv[6],
                                            "The particle state is kept at the start of this step."));
  }
  float vmax;
  std::memcpy(&vmax, &res.maxSpeedBits, sizeof(float));
  maxSpeed_ = vmax;
  cur_ = 1 - cur_;
  hasFext_ = false;
}

template <typename T>
bool MpmCuda<T>::diagnosticSums(const std::array<double, 3>& gravity, const std::vector<ProbeStation>& stations,
                                DiagnosticSums& sums, std::vector<ProbeSums>& probeSums) {
  if (stations.size() > static_cast<std::size_t>(kMaxDeviceProbes)) return false;
  cudak::DiagnosticPartial total;
  total.sums = emptyDiagnosticSums();
  for (auto& q : total.probes) q = emptyProbeSums();
  if (n_ > 0) {
    cudak::DiagnosticInput in{};
    for (int d = 0; d < 3; ++d) in.gravity[d] = gravity[d];
    for (std::size_t k = 0; k < stations.size(); ++k) in.probes[k] = stations[k];
    in.numProbes = static_cast<int>(stations.size());
    if (!diagnostics_) {
      cudak::DiagnosticPartial* p = nullptr;
      deviceAlloc(&p, cudak::kDiagBlocks + 1, gridBytes_);
      diagnostics_ = p;
    }
    auto* partial = static_cast<cudak::DiagnosticPartial*>(diagnostics_);
    cudak::diagnosticsKernel<T><<<cudak::kDiagBlocks, cudak::kDiagThreads>>>(static_cast<int>(n_), input(),
                                                                           state_[cur_].phase, in, partial);
    CUDA_CHECK(cudaGetLastError());
    cudak::diagnosticsTotalKernel<<<1, cudak::kDiagThreads>>>(partial, in.numProbes, partial + cudak::kDiagBlocks);
    CUDA_CHECK(cudaGetLastError());
    CUDA_CHECK(cudaMemcpy(&total, partial + cudak::kDiagBlocks, sizeof(total), cudaMemcpyDeviceToHost));
  }
  sums = total.sums;
  probeSums.assign(total.probes, total.probes + stations.size());
  return true;
}

template class MpmCuda<float>;
template class MpmCuda<double>;

std::unique_ptr<MpmSolver> makeCudaSolver(const MpmParams& params, Precision precision) {
  if (precision == Precision::Float) return std::make_unique<MpmCuda<float>>(params);
  return std::make_unique<MpmCuda<double>>(params);
}

bool cudaDevicePresent() {
  int count = 0;
  const cudaError_t err = cudaGetDeviceCount(&count);
  if (err != cudaSuccess) {
    cudaGetLastError();  // no driver or no device: clear the sticky error and report "absent"
    return false;
  }
  return count > 0;
}

}  // namespace mpm
}  // namespace mpmsdem
