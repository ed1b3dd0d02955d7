// Host control of the CUDA coupling backend: device copies of the shape table (when it
// grows), the blocks, pair physics and bins (every step: a few kB), the tangential histories
// (resident), the per-block sums (downloaded once per step). Particle data never leaves the
// device.
#include <cuda_runtime.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <vector>

#include "coupling/CouplingBackend.hpp"
#include "coupling/cuda/MpSdemCouplingKernels.cuh"
#include "mpm/cuda/CudaCheck.hpp"

namespace mpmsdem {
namespace coupling {

namespace {

constexpr int kThreads = 128;

// A device array that grows on demand and is refilled from host data.
template <typename U>
struct DeviceArray {
  U* ptr = nullptr;
  std::size_t capacity = 0;
  ~DeviceArray() {
    if (ptr) CUDA_CHECK_NOTHROW(cudaFree(ptr));
  }
  void reserve(std::size_t n) {
    if (n <= capacity && ptr) return;
    if (ptr) CUDA_CHECK(cudaFree(ptr));
    ptr = nullptr;
    capacity = std::max<std::size_t>(n, 1);
    CUDA_CHECK(cudaMalloc(reinterpret_cast<void**>(&ptr), capacity * sizeof(U)));
  }
  void upload(const U* src, std::size_t n) {
    reserve(n);
    if (n) CUDA_CHECK(cudaMemcpy(ptr, src, n * sizeof(U), cudaMemcpyHostToDevice));
  }
};

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

  double maxVolume0(const mpm::ParticleView& v) override {
    std::vector<T> buf(v.n);
    if (v.n) CUDA_CHECK(cudaMemcpy(buf.data(), v.volume0, v.n * sizeof(T), cudaMemcpyDeviceToHost));
    double m = 0;
    for (T x : buf) m = std::max(m, static_cast<double>(x));
    return m;
  }

  void run(const CouplingStepInput& in, CouplingStepOutput& out) override {
    const mpm::ParticleView& v = in.particles;
    const sdem::ShapeTableView<double>& s = in.shapes;
    if (in.shapesChanged || !vertex_.ptr) {
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
    const std::vector<BlockState<double>>& hb = *in.blocks;
    std::vector<BlockState<T>> blocks(hb.size());
    for (std::size_t i = 0; i < hb.size(); ++i) blocks[i] = convertBlock<T>(hb[i]);
    blocks_.upload(blocks.data(), blocks.size());
    std::vector<sdem::BarrierCoulombPhys<T>> phys;
    for (const auto& p : *in.phys) phys.push_back(convertPhys<T>(p));
    phys_.upload(phys.data(), phys.size());
    binStart_.upload(in.bins.start, in.numBins + 1);
    binBlocks_.upload(in.bins.blocks, in.numBinEntries);
    const std::size_t nh = static_cast<std::size_t>(in.historySlots) * v.n;
    if (histCount_ != nh) {
      histKey_.reserve(nh);
      histXi_.reserve(3 * nh);
      histWritten_.reserve(v.n);
      CUDA_CHECK(cudaMemset(histKey_.ptr, 0xff, std::max<std::size_t>(nh, 1) * sizeof(long long)));
      CUDA_CHECK(cudaMemset(histWritten_.ptr, 0, std::max<std::size_t>(v.n, 1) * sizeof(unsigned)));
      CUDA_CHECK(cudaMemset(histXi_.ptr, 0, std::max<std::size_t>(3 * nh, 1) * sizeof(T)));
      histCount_ = nh;
    }
    sums_.reserve(out.sums.size());
    CUDA_CHECK(cudaMemset(sums_.ptr, 0, std::max<std::size_t>(out.sums.size(), 1) * sizeof(double)));
    cudak::CouplingFlags init;
    init.bad = ~0ull;
    const float inf = std::numeric_limits<float>::infinity();
    std::memcpy(&init.minStepBits, &inf, sizeof(float));
    std::memcpy(&init.minApproachBits, &inf, sizeof(float));
    init.overflow = 0;
    flags_.upload(&init, 1);

    const CouplingParticles<T> P = couplingParticles<T>(v);
    const sdem::ShapeTableView<T> S{numShapes_,          vertex_.ptr,         faceNormal_.ptr,
                                    faceOffset_.ptr,     faceLoopStart_.ptr,  loopVertex_.ptr,
                                    loopEdge_.ptr,       shapeFaceStart_.ptr, shapeVertexStart_.ptr,
                                    shapeEdgeStart_.ptr, sweepRadius_.ptr,    boundingRadius_.ptr,
                                    convex_.ptr};
    BinGridView bins = in.bins;
    bins.start = binStart_.ptr;
    bins.blocks = binBlocks_.ptr;
    const HistoryView<T> H{histKey_.ptr, histXi_.ptr, histWritten_.ptr, in.historyStep, in.historySlots};
    const int n = static_cast<int>(v.n);
    if (n > 0) {
      cudak::coupleKernel<T><<<(n + kThreads - 1) / kThreads, kThreads>>>(
          n, P, blocks_.ptr, S, phys_.ptr, bins, H, static_cast<T>(in.dt), static_cast<T>(in.stepSafety), sums_.ptr,
          flags_.ptr);
      CUDA_CHECK(cudaGetLastError());
    }
    cudak::CouplingFlags res;
    CUDA_CHECK(cudaMemcpy(&res, flags_.ptr, sizeof(res), cudaMemcpyDeviceToHost));
    if (!out.sums.empty())
      CUDA_CHECK(cudaMemcpy(out.sums.data(), sums_.ptr, out.sums.size() * sizeof(double), cudaMemcpyDeviceToHost));
    float minStep;
    std::memcpy(&minStep, &res.minStepBits, sizeof(float));
    out.minParticleStep = minStep;
    std::memcpy(&minStep, &res.minApproachBits, sizeof(float));
    out.minApproachStep = minStep;
    out.overflow = static_cast<long>(res.overflow);
    if (res.bad != ~0ull) {
      out.badParticle = static_cast<int>(res.bad >> 32);
      out.badBlock = static_cast<int>(res.bad & 0xffffffffull);
    }
  }

 private:
  int numShapes_ = 0;
  DeviceArray<T> vertex_, faceNormal_, faceOffset_, sweepRadius_, boundingRadius_;
  DeviceArray<int> faceLoopStart_, loopVertex_, loopEdge_, shapeFaceStart_, shapeVertexStart_, shapeEdgeStart_;
  DeviceArray<std::uint8_t> convex_;
  DeviceArray<BlockState<T>> blocks_;
  DeviceArray<sdem::BarrierCoulombPhys<T>> phys_;
  DeviceArray<int> binStart_, binBlocks_;
  DeviceArray<long long> histKey_;
  DeviceArray<T> histXi_;
  DeviceArray<unsigned> histWritten_;
  std::size_t histCount_ = 0;
  DeviceArray<double> sums_;
  DeviceArray<cudak::CouplingFlags> flags_;
};

}  // namespace

std::unique_ptr<CouplingDeviceBackend> makeCouplingDeviceBackend(mpm::Precision precision) {
  if (precision == mpm::Precision::Float) return std::make_unique<CouplingCuda<float>>();
  return std::make_unique<CouplingCuda<double>>();
}

}  // namespace coupling
}  // namespace mpmsdem
