// Host control of the gate on a CUDA grid: accumulator memory and the kernel launch.
#include <cuda_runtime.h>

#include "mpm/cuda/CudaCheck.hpp"
#include "mpm/cuda/GateCuda.hpp"
#include "mpm/cuda/MpmCudaKernels.cuh"

namespace mpmsdem {
namespace mpm {

namespace {
constexpr int kThreads = 256;  // a multiple of the warp size (the kernel reduces per warp)

template <typename T>
void launch(const GridView& g, const GateBand& b, int count, double friction, double* impulse) {
  const int blocks = (count + kThreads - 1) / kThreads;
  cudak::gateKernel<T><<<blocks, kThreads>>>(b, count, g.stride, g.column, static_cast<const T*>(g.mass),
                                             static_cast<T*>(g.v[0]), static_cast<T*>(g.v[1]),
                                             static_cast<T*>(g.v[2]), static_cast<T>(friction), impulse);
  CUDA_CHECK(cudaGetLastError());
}
}  // namespace

void applyGateCuda(const GridView& g, const GateBand& b, double friction, double** impulse) {
  const int count = gateBandSize(b);
  if (count == 0) return;
  if (!*impulse) {
    CUDA_CHECK(cudaMalloc(reinterpret_cast<void**>(impulse), 3 * sizeof(double)));
    CUDA_CHECK(cudaMemset(*impulse, 0, 3 * sizeof(double)));
  }
  if (g.precision == Precision::Float)
    launch<float>(g, b, count, friction, *impulse);
  else
    launch<double>(g, b, count, friction, *impulse);
}

std::array<double, 3> downloadGateImpulse(const double* impulse) {
  std::array<double, 3> out{};
  CUDA_CHECK(cudaMemcpy(out.data(), impulse, 3 * sizeof(double), cudaMemcpyDeviceToHost));
  return out;
}

void freeGateImpulse(double* impulse) {
  if (impulse) CUDA_CHECK_NOTHROW(cudaFree(impulse));
}

}  // namespace mpm
}  // namespace mpmsdem
