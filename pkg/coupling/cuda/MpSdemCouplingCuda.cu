// Host control of the CUDA coupling backend: device copies of the shape table (when it
// grows) or of the LevelSet bodies' grids (when one is added), the blocks, pair physics and bins
// (every step: a few kB), the tangential histories
// (resident; copied to and from the host for checkpoints), the per-block sums (downloaded once
// per step). Particle data never leaves the device.
//
// Block sums in a fixed order: the contacts' shares go to a list, are placed in particle-number
// and contact order by a scan of the particles' contact counts, then sorted stably by block
// alone, and each block's are added in that order by a fixed tree, so two runs give the same
// bits. A step with more contacts than the
// list holds uses sums added atomically (the order of those changes from run to run), and the
// list grows for the next. The step's flags and sums come back in one copy at its end.
#include <cuda_runtime.h>

#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "coupling/CouplingBackend.hpp"
#include "coupling/cuda/MpSdemCouplingKernels.cuh"
#include "common/Error.hpp"
#include "mpm/cuda/CudaCheck.hpp"
#include "mpm/cuda/SortedKeys.cuh"

namespace mpmsdem {
namespace coupling {

namespace {

constexpr int kThreads = 128;

// Memory that grows on demand: device memory (refilled from host data with upload), or pinned
// host memory (kPinned: the source of asynchronous copies).
template <typename U, bool kPinned = false>
struct GrowingArray {
  U* ptr = nullptr;
  std::size_t capacity = 0;
  ~GrowingArray() {
    if (ptr) CUDA_CHECK_NOTHROW(kPinned ? cudaFreeHost(ptr) : cudaFree(ptr));
  }
  void reserve(std::size_t n) {
    if (n <= capacity && ptr) return;
    if (ptr) CUDA_CHECK(kPinned ? cudaFreeHost(ptr) : cudaFree(ptr));
    ptr = nullptr;
    capacity = std::max<std::size_t>(n, 1);
    void** p = reinterpret_cast<void**>(&ptr);
    CUDA_CHECK(kPinned ? cudaMallocHost(p, capacity * sizeof(U)) : cudaMalloc(p, capacity * sizeof(U)));
  }
  void upload(const U* src, std::size_t n) {
    static_assert(!kPinned, "a pinned host array is written directly");
    reserve(n);
    if (n) CUDA_CHECK(cudaMemcpy(ptr, src, n * sizeof(U), cudaMemcpyHostToDevice));
  }
};
template <typename U>
using DeviceArray = GrowingArray<U>;
using PinnedArray = GrowingArray<unsigned char, true>;

// Offsets in the staged tables: every table starts on a 16-byte boundary.
constexpr std::size_t alignUp(std::size_t bytes) { return (bytes + 15) / 16 * 16; }

// Host double data converted to T, then uploaded.
template <typename T>
void uploadAs(DeviceArray<T>& dst, const double* src, std::size_t n) {
  std::vector<T> buf(src, src + n);
  dst.upload(buf.data(), n);
}

template <typename T>
class CouplingCuda : public CouplingDeviceBackend {
 public:
  void resetHistories() override { histCount_ = 0; }

  void downloadHistories(std::vector<long long>& keys, std::vector<double>& xi,
                         std::vector<unsigned>& written) override {
    keys.assign(histCount_, -1);
    xi.assign(3 * histCount_, 0.0);
    written.assign(histParticles_, 0u);
    if (histCount_ == 0) return;
    std::vector<T> buf(3 * histCount_);
    CUDA_CHECK(cudaMemcpy(keys.data(), histKey_.ptr, histCount_ * sizeof(long long), cudaMemcpyDeviceToHost));
    CUDA_CHECK(cudaMemcpy(buf.data(), histXi_.ptr, buf.size() * sizeof(T), cudaMemcpyDeviceToHost));
    CUDA_CHECK(cudaMemcpy(written.data(), histWritten_.ptr, histParticles_ * sizeof(unsigned), cudaMemcpyDeviceToHost));
    for (std::size_t k = 0; k < buf.size(); ++k) xi[k] = static_cast<double>(buf[k]);
  }

  void uploadHistories(const std::vector<long long>& keys, const std::vector<double>& xi,
                       const std::vector<unsigned>& written) override {
    histKey_.upload(keys.data(), keys.size());
    uploadAs(histXi_, xi.data(), xi.size());
    histWritten_.upload(written.data(), written.size());
    histCount_ = keys.size();
    histParticles_ = written.size();
  }

  std::pair<double, double> volume0Range(const mpm::ParticleView& v) override {
    std::vector<T> buf(v.n);
    if (v.n) CUDA_CHECK(cudaMemcpy(buf.data(), v.volume0, v.n * sizeof(T), cudaMemcpyDeviceToHost));
    double lo = std::numeric_limits<double>::infinity(), hi = 0;
    for (T x : buf) {
      lo = std::min(lo, static_cast<double>(x));
      hi = std::max(hi, static_cast<double>(x));
    }
    return {lo, hi};
  }

  void setFirstListCapacity(unsigned int capacity) override {
    if (capacity == 0) throw ParameterError("MP-block coupling on CUDA: the contact list's first capacity must be >= 1");
    firstListCapacity_ = capacity;
  }

  void setStageTiming(bool on) override {
    if (on && !events_[0])
      for (auto& e : events_) CUDA_CHECK(cudaEventCreate(&e));
    timing_ = on;
  }

  std::vector<std::pair<std::string, double>> stageSeconds() const override {
    if (!events_[0]) return {};
    return {{"upload", stageTotals_[0]}, {"kernel", stageTotals_[1]}, {"sums", stageTotals_[2]},
            {"host_wait", hostWait_}};
  }

  ~CouplingCuda() override {
    for (auto& e : events_)
      if (e) CUDA_CHECK_NOTHROW(cudaEventDestroy(e));
    if (done_) CUDA_CHECK_NOTHROW(cudaEventDestroy(done_));
  }

  void recordContacts(bool on) override {
    recording_ = on;
    if (on && listCapacity_ > 0) record_.reserve(static_cast<std::size_t>(kContactValues) * listCapacity_);
  }

  bool downloadContacts(std::vector<double>& records) override {
    if (recorded_ < 0) return false;
    records.resize(static_cast<std::size_t>(kContactValues) * recorded_);
    if (recorded_ > 0)
      CUDA_CHECK(cudaMemcpy(records.data(), record_.ptr, records.size() * sizeof(double), cudaMemcpyDeviceToHost));
    return true;
  }

  void launch(const CouplingStepInput& in) override {
    if (launched_) throw RuntimeFailure("MP-block coupling on CUDA: a step was launched before the last one was collected");
    if (!done_) CUDA_CHECK(cudaEventCreateWithFlags(&done_, cudaEventDisableTiming));
    const mpm::ParticleView& v = in.particles;
    const sdem::ShapeTableView<double>& s = in.shapes;
    const bool levelSets = in.levelSets != nullptr;
    if (levelSets && (in.levelSetsChanged || lsGridsHeld_ != in.levelSets->size())) uploadLevelSets(*in.levelSets);
    if (!levelSets && (in.shapesChanged || !vertex_.ptr)) {
      const int ns = s.numShapes;
      uploadAs(vertex_, s.vertex, 3 * static_cast<std::size_t>(in.numVertices));
      uploadAs(faceNormal_, s.faceNormal, 3 * static_cast<std::size_t>(in.numFaces));
      uploadAs(faceOffset_, s.faceOffset, in.numFaces);
      faceLoopStart_.upload(s.faceLoopStart, in.numFaces + 1);
      loopVertex_.upload(s.loopVertex, in.numLoopEntries);
      loopEdge_.upload(s.loopEdge, in.numLoopEntries);
      shapeFaceStart_.upload(s.shapeFaceStart, ns + 1);
      shapeVertexStart_.upload(s.shapeVertexStart, ns + 1);
      shapeEdgeStart_.upload(s.shapeEdgeStart, ns + 1);
      uploadAs(sweepRadius_, s.sweepRadius, ns);
      uploadAs(boundingRadius_, s.boundingRadius, ns);
      convex_.upload(s.convex, ns);
      numShapes_ = ns;
    }
    mark(0);
    const std::vector<BlockState<double>>& hb = *in.blocks;
    // What changes every step (blocks, pair physics, the flags' start values) goes in one copy
    // from pinned memory, queued before the kernel without waiting for it; the bin table only
    // when it changed.
    const std::size_t nb = hb.size(), np = in.phys->size();
    const std::size_t offPhys = alignUp(nb * sizeof(BlockState<T>));
    const std::size_t offFlags = offPhys + alignUp(np * sizeof(sdem::BarrierCoulombPhys<T>));
    const std::size_t bytes = offFlags + sizeof(cudak::CouplingFlags);
    staged_.reserve(bytes);
    stagedHost_.reserve(bytes);
    unsigned char* h = stagedHost_.ptr;
    auto* blocksH = reinterpret_cast<BlockState<T>*>(h);
    for (std::size_t i = 0; i < nb; ++i) blocksH[i] = convertBlock<T>(hb[i]);
    auto* physH = reinterpret_cast<sdem::BarrierCoulombPhys<T>*>(h + offPhys);
    for (std::size_t i = 0; i < np; ++i) physH[i] = convertPhys<T>((*in.phys)[i]);
    cudak::CouplingFlags init;
    init.bad = ~0ull;
    const float inf = std::numeric_limits<float>::infinity();
    std::memcpy(&init.minStepBits, &inf, sizeof(float));
    std::memcpy(&init.minApproachBits, &inf, sizeof(float));
    init.overflow = 0;
    init.contacts = 0;
    std::memcpy(h + offFlags, &init, sizeof(init));
    CUDA_CHECK(cudaMemcpyAsync(staged_.ptr, h, bytes, cudaMemcpyHostToDevice));
    if (!levelSets && (in.binsChanged || binsHeld_ != in.numBins)) {
      // The slot of every bin stays on the device: the last table's slots are cleared and the new
      // ones set, so a change costs the bins the blocks reach, not the grid.
      if (binsHeld_ != in.numBins) {
        binSlot_.reserve(in.numBins);
        CUDA_CHECK(cudaMemset(binSlot_.ptr, 0xff, std::max<std::size_t>(in.numBins, 1) * sizeof(int)));
        binsHeld_ = in.numBins;
        slotsHeld_ = 0;
      }
      if (slotsHeld_ > 0) {
        cudak::binSlotsKernel<<<std::min(kPlaceBlocks, (slotsHeld_ + kThreads - 1) / kThreads), kThreads>>>(
            slotsHeld_, slotBins_.ptr, true, binSlot_.ptr);
        CUDA_CHECK(cudaGetLastError());
        // a longer list replaces the array the clearing reads: it must be done first
        if (static_cast<std::size_t>(in.numSlots) > slotBins_.capacity) CUDA_CHECK(cudaStreamSynchronize(0));
      }
      slotBins_.upload(in.slotBins, in.numSlots);
      slotsHeld_ = in.numSlots;
      if (slotsHeld_ > 0) {
        cudak::binSlotsKernel<<<std::min(kPlaceBlocks, (slotsHeld_ + kThreads - 1) / kThreads), kThreads>>>(
            slotsHeld_, slotBins_.ptr, false, binSlot_.ptr);
        CUDA_CHECK(cudaGetLastError());
      }
      binFirst_.upload(in.bins.first, in.numSlots + 1);
      binBlocks_.upload(in.bins.blocks, in.numBinEntries);
    }
    const auto* blocksD = reinterpret_cast<const BlockState<T>*>(staged_.ptr);
    const auto* physD = reinterpret_cast<const sdem::BarrierCoulombPhys<T>*>(staged_.ptr + offPhys);
    auto* flagsD = reinterpret_cast<cudak::CouplingFlags*>(staged_.ptr + offFlags);
    const std::size_t nh = static_cast<std::size_t>(in.historySlots) * v.n;
    if (histCount_ != nh || histParticles_ != v.n) {
      histKey_.reserve(nh);
      histXi_.reserve(3 * nh);
      histWritten_.reserve(v.n);
      CUDA_CHECK(cudaMemset(histKey_.ptr, 0xff, std::max<std::size_t>(nh, 1) * sizeof(long long)));
      CUDA_CHECK(cudaMemset(histWritten_.ptr, 0, std::max<std::size_t>(v.n, 1) * sizeof(unsigned)));
      CUDA_CHECK(cudaMemset(histXi_.ptr, 0, std::max<std::size_t>(3 * nh, 1) * sizeof(T)));
      histCount_ = nh;
      histParticles_ = v.n;
    }
    const int numBlocks = static_cast<int>(hb.size());
    const int numberBits = sortedkeys::bitsFor(v.n);
    const int keyBits = sortedkeys::bitsFor(static_cast<unsigned long long>(numBlocks)) + numberBits;
    if (keyBits > 64)
      throw ParameterError("MP-block coupling on CUDA: " + std::to_string(numBlocks) + " blocks and " +
                           std::to_string(v.n) + " particles need a contact key of " + std::to_string(keyBits) +
                           " bits, at most 64 are supported");
    if (listCapacity_ == 0) growList(firstListCapacity_);
    const std::size_t numSums = static_cast<std::size_t>(kBlockSums) * nb;
    sums_.reserve(numSums);
    CUDA_CHECK(cudaMemsetAsync(sums_.ptr, 0, std::max<std::size_t>(numSums, 1) * sizeof(double)));
    if (counted_ != v.n) {  // every particle writes its count each step: no clearing
      count_.reserve(v.n);
      first_.reserve(v.n);
      std::size_t scanBytes = 0;
      CUDA_CHECK(cub::DeviceScan::ExclusiveSum(nullptr, scanBytes, count_.ptr, first_.ptr, static_cast<int>(v.n)));
      scanScratch_.reserve(scanBytes);
      counted_ = v.n;
    }
    const cudak::ContactList list{share_.ptr,  key_.ptr, entry_.ptr, count_.ptr, recording_ ? record_.ptr : nullptr,
                                  listCapacity_, numberBits};

    const CouplingParticles<T> P = couplingParticles<T>(v);
    const sdem::ShapeTableView<T> S{numShapes_,          vertex_.ptr,         faceNormal_.ptr,
                                    faceOffset_.ptr,     faceLoopStart_.ptr,  loopVertex_.ptr,
                                    loopEdge_.ptr,       shapeFaceStart_.ptr, shapeVertexStart_.ptr,
                                    shapeEdgeStart_.ptr, sweepRadius_.ptr,    boundingRadius_.ptr,
                                    convex_.ptr};
    BinGridView bins = in.bins;
    bins.slot = binSlot_.ptr;
    bins.first = binFirst_.ptr;
    bins.blocks = binBlocks_.ptr;
    const HistoryView<T> H{histKey_.ptr, histXi_.ptr, histWritten_.ptr, in.historyStep, in.historySlots};
    const int n = static_cast<int>(v.n);
    mark(1);
    if (n > 0 && levelSets) {
      const cudak::LevelSetBodies<T> bodies{lsGrids_.ptr, numBlocks, static_cast<T>(in.watch)};
      cudak::coupleKernel<T><<<(n + kThreads - 1) / kThreads, kThreads>>>(
          n, P, blocksD, bodies, physD, H, static_cast<T>(in.dt), static_cast<T>(in.stepSafety), sums_.ptr, flagsD,
          list);
      CUDA_CHECK(cudaGetLastError());
    } else if (n > 0) {
      cudak::coupleKernel<T><<<(n + kThreads - 1) / kThreads, kThreads>>>(
          n, P, blocksD, cudak::BlockBodies<T>{S, bins}, physD, H, static_cast<T>(in.dt),
          static_cast<T>(in.stepSafety), sums_.ptr, flagsD, list);
      CUDA_CHECK(cudaGetLastError());
    }
    mark(2);
    // The contact count stays on the device: the placing and the sums read it there (a step
    // that overflowed the list takes the atomic way in blockSumsKernel), and the host learns
    // it with the sums.
    if (n > 0 && numBlocks > 0) {
      std::size_t scanBytes = scanScratch_.capacity;
      CUDA_CHECK(cub::DeviceScan::ExclusiveSum(scanScratch_.ptr, scanBytes, count_.ptr, first_.ptr, n));
      cudak::placeKernel<<<kPlaceBlocks, kThreads>>>(flagsD, listCapacity_, key_.ptr, entry_.ptr, first_.ptr,
                                                     numberBits, order_.ptr);
      CUDA_CHECK(cudaGetLastError());
      // each block's contacts side by side, in that order: a stable sort of the whole list's places
      // (the count is on the device) by the few bits of the block
      const unsigned long long blockValues = static_cast<unsigned long long>(numBlocks) + 1;  // and the end mark
      cudak::blockKeysKernel<<<kPlaceBlocks, kThreads>>>(flagsD, listCapacity_, key_.ptr, order_.ptr, numberBits,
                                                         static_cast<unsigned long long>(numBlocks), blockKey_[0].ptr,
                                                         share_.ptr, sums_.ptr);
      CUDA_CHECK(cudaGetLastError());
      const int blockBits = sortedkeys::bitsFor(blockValues);
      std::size_t sortBytes = 0;
      CUDA_CHECK(cub::DeviceRadixSort::SortPairs(nullptr, sortBytes, blockKey_[0].ptr, blockKey_[1].ptr, order_.ptr,
                                                 byBlock_.ptr, static_cast<int>(listCapacity_), 0, blockBits));
      sortScratch_.reserve(sortBytes);
      sortBytes = sortScratch_.capacity;
      CUDA_CHECK(cub::DeviceRadixSort::SortPairs(sortScratch_.ptr, sortBytes, blockKey_[0].ptr, blockKey_[1].ptr,
                                                 order_.ptr, byBlock_.ptr, static_cast<int>(listCapacity_), 0,
                                                 blockBits));
      const int chunks = std::max(1, std::min(kMaxSumChunks, kSumChunksInAll / numBlocks));
      partial_.reserve(static_cast<std::size_t>(kBlockSums) * numBlocks * chunks);
      cudak::blockSumsKernel<<<numBlocks * chunks, cudak::kSumThreads>>>(flagsD, listCapacity_, share_.ptr,
                                                                         blockKey_[1].ptr, byBlock_.ptr, chunks,
                                                                         partial_.ptr);
      CUDA_CHECK(cudaGetLastError());
      const int totals = numBlocks * kBlockSums;
      cudak::blockTotalsKernel<<<std::min(kPlaceBlocks, (totals + kThreads - 1) / kThreads), kThreads>>>(
          flagsD, listCapacity_, numBlocks, chunks, partial_.ptr, sums_.ptr);
      CUDA_CHECK(cudaGetLastError());
    }
    mark(3);
    const std::size_t sumBytes = numSums * sizeof(double);
    resultHost_.reserve(alignUp(sizeof(cudak::CouplingFlags)) + sumBytes);
    CUDA_CHECK(cudaMemcpyAsync(resultHost_.ptr, flagsD, sizeof(cudak::CouplingFlags), cudaMemcpyDeviceToHost));
    if (sumBytes)
      CUDA_CHECK(cudaMemcpyAsync(resultHost_.ptr + alignUp(sizeof(cudak::CouplingFlags)), sums_.ptr, sumBytes,
                                 cudaMemcpyDeviceToHost));
    // what the host waits for: the work queued after it (the flow's step) goes on meanwhile
    CUDA_CHECK(cudaEventRecord(done_));
    launched_ = true;
    launchedSums_ = numSums;
  }

  void collect(CouplingStepOutput& out) override {
    if (!launched_) throw RuntimeFailure("MP-block coupling on CUDA: no step was launched to collect");
    launched_ = false;
    waited([&] { CUDA_CHECK(cudaEventSynchronize(done_)); });
    const std::size_t sumBytes = launchedSums_ * sizeof(double);
    out.sums.resize(launchedSums_);
    cudak::CouplingFlags res;
    std::memcpy(&res, resultHost_.ptr, sizeof(res));
    if (sumBytes) std::memcpy(out.sums.data(), resultHost_.ptr + alignUp(sizeof(cudak::CouplingFlags)), sumBytes);
    recorded_ = recording_ && res.contacts <= listCapacity_ ? static_cast<long>(res.contacts) : -1;
    if (res.contacts > listCapacity_) growList(2ull * res.contacts);  // this step's sums were atomic
    if (timing_) {
      CUDA_CHECK(cudaEventSynchronize(events_[kStages]));
      for (int k = 0; k < kStages; ++k) {
        float ms = 0;
        CUDA_CHECK(cudaEventElapsedTime(&ms, events_[k], events_[k + 1]));
        stageTotals_[k] += 1e-3 * ms;
      }
    }
    float minStep;
    std::memcpy(&minStep, &res.minStepBits, sizeof(float));
    out.minParticleStep = minStep;
    std::memcpy(&minStep, &res.minApproachBits, sizeof(float));
    out.minApproachStep = minStep;
    out.overflow = static_cast<long>(res.overflow);
    const bool failed = res.bad != ~0ull;  // written either way: an output reused keeps no earlier failure
    out.badParticle = failed ? static_cast<int>(res.bad >> 32) : -1;
    out.badBlock = failed ? static_cast<int>(res.bad & 0xffffffffull) : -1;
  }

 private:
  unsigned int firstListCapacity_ = 1u << 16;

  // The placing kernel's grid: it loops over the step's contacts, whose number the device holds.
  static constexpr int kPlaceBlocks = 264;
  // The block sums in runs (blockSumsKernel): about this many CUDA blocks in all, so that a scene
  // of a few blocks spreads their contacts over the device, and at most this many runs a block.
  static constexpr int kSumChunksInAll = 264;
  static constexpr int kMaxSumChunks = 32;

  // The bodies' grids side by side in one device array, and their views into it.
  void uploadLevelSets(const std::vector<LevelSetGridView<double>>& grids) {
    std::vector<std::size_t> start(grids.size() + 1, 0);
    for (std::size_t b = 0; b < grids.size(); ++b) {
      const LevelSetGridView<double>& g = grids[b];
      start[b + 1] = start[b] + static_cast<std::size_t>(g.nGP[0]) * g.nGP[1] * g.nGP[2];
    }
    std::vector<T> dist(start.back());
    for (std::size_t b = 0; b < grids.size(); ++b)
      std::copy(grids[b].dist, grids[b].dist + (start[b + 1] - start[b]), dist.begin() + start[b]);
    lsDist_.upload(dist.data(), dist.size());
    std::vector<LevelSetGridView<T>> views(grids.size());
    for (std::size_t b = 0; b < grids.size(); ++b) {
      const LevelSetGridView<double>& g = grids[b];
      views[b] = {{T(g.min[0]), T(g.min[1]), T(g.min[2])}, T(g.spacing), {g.nGP[0], g.nGP[1], g.nGP[2]},
                  lsDist_.ptr + start[b]};
    }
    lsGrids_.upload(views.data(), views.size());
    lsGridsHeld_ = grids.size();
  }

  void growList(unsigned long long capacity) {
    // (places are ints)
    const auto n = static_cast<unsigned int>(std::min<unsigned long long>(capacity, (1ull << 31) - 1));
    try {
      share_.reserve(static_cast<std::size_t>(kBlockSums) * n);
      key_.reserve(n);
      entry_.reserve(n);
      order_.reserve(n);
      byBlock_.reserve(n);
      for (auto& k : blockKey_) k.reserve(n);
      if (recording_) record_.reserve(static_cast<std::size_t>(kContactValues) * n);
    } catch (...) {
      listCapacity_ = 0;  // some arrays are smaller or gone: the next step sizes them again
      throw;
    }
    listCapacity_ = n;
  }

  void mark(int k) {
    if (timing_) CUDA_CHECK(cudaEventRecord(events_[k]));
  }
  template <typename F>
  void waited(F&& copy) {
    const auto start = std::chrono::steady_clock::now();
    copy();
    if (timing_) hostWait_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }

  // Stage timing: events before the uploads, the kernel, the ordered sums and after them.
  static constexpr int kStages = 3;  // upload, kernel, sums
  bool timing_ = false;
  cudaEvent_t events_[kStages + 1] = {};
  double stageTotals_[kStages] = {};
  double hostWait_ = 0;  // host time blocked in the step's copy back [s]
  // A launched step (launch): its flags and sums come back into resultHost_ before done_.
  cudaEvent_t done_ = nullptr;
  bool launched_ = false;
  std::size_t launchedSums_ = 0;
  int numShapes_ = 0;
  DeviceArray<T> vertex_, faceNormal_, faceOffset_, sweepRadius_, boundingRadius_;
  DeviceArray<int> faceLoopStart_, loopVertex_, loopEdge_, shapeFaceStart_, shapeVertexStart_, shapeEdgeStart_;
  DeviceArray<std::uint8_t> convex_;
  DeviceArray<T> lsDist_;  // the LevelSet bodies' distances, body after body
  DeviceArray<LevelSetGridView<T>> lsGrids_;
  std::size_t lsGridsHeld_ = 0;  // the bodies lsGrids_ holds
  DeviceArray<unsigned char> staged_;  // this step's blocks, pair physics and flags
  // the bin table (BinGridView), changed when the host's changes; the bin of each slot
  DeviceArray<int> binSlot_, binFirst_, binBlocks_, slotBins_;
  int binsHeld_ = -1;  // the bins binSlot_ covers
  int slotsHeld_ = 0;  // the slots set in it
  PinnedArray stagedHost_;
  PinnedArray resultHost_;  // the step's flags and block sums, copied back together
  DeviceArray<long long> histKey_;
  DeviceArray<T> histXi_;
  DeviceArray<unsigned> histWritten_;
  std::size_t histCount_ = 0;
  std::size_t histParticles_ = 0;
  DeviceArray<double> sums_;
  unsigned int listCapacity_ = 0;
  DeviceArray<double> share_;
  bool recording_ = false;
  long recorded_ = -1;         // contacts the last step recorded, -1: none
  DeviceArray<double> record_;  // kContactValues per list entry while recording
  DeviceArray<unsigned long long> key_;
  DeviceArray<int> entry_, order_;
  // the places of order_ sorted stably by block (byBlock_), their blocks before and after the sort
  DeviceArray<int> byBlock_;
  DeviceArray<unsigned long long> blockKey_[2];
  DeviceArray<double> partial_;  // blockSumsKernel's sum of each run of a block's contacts
  DeviceArray<unsigned char> sortScratch_;
  std::size_t counted_ = ~std::size_t(0);  // the particles count_ and first_ are sized for
  DeviceArray<int> count_, first_;          // per particle number: contacts, and the scan of them
  DeviceArray<unsigned char> scanScratch_;
};

}  // namespace

std::unique_ptr<CouplingDeviceBackend> makeCouplingDeviceBackend(mpm::Precision precision) {
  if (precision == mpm::Precision::Float) return std::make_unique<CouplingCuda<float>>();
  return std::make_unique<CouplingCuda<double>>();
}

}  // namespace coupling
}  // namespace mpmsdem
