// Error checking for CUDA runtime calls (include only from .cu files).
#pragma once
#include <cuda_runtime.h>

#include <cstdio>
#include <sstream>

#include "common/Error.hpp"

// Throws mpmsdem::RuntimeFailure naming the call, the file:line and CUDA's message. The failure
// is also taken off the runtime's last-error slot: CUB reads that slot after its own calls, and
// a failed allocation left there (a grid too large, refused) made CUB's first call of the process
// cache "no device" and every later sort fail with "invalid device ordinal".
#define CUDA_CHECK(call)                                                                          \
  do {                                                                                            \
    const cudaError_t mpmsdemCudaErr_ = (call);                                                   \
    if (mpmsdemCudaErr_ != cudaSuccess) {                                                         \
      cudaGetLastError();                                                                         \
      std::ostringstream mpmsdemOs_;                                                              \
      mpmsdemOs_ << "CUDA error in " #call " at " << __FILE__ << ":" << __LINE__ << ": "          \
                 << cudaGetErrorString(mpmsdemCudaErr_);                                          \
      throw ::mpmsdem::RuntimeFailure(mpmsdemOs_.str());                                          \
    }                                                                                             \
  } while (0)

// For destructors, which must not throw: reports the failure on stderr (and clears it likewise).
#define CUDA_CHECK_NOTHROW(call)                                                                  \
  do {                                                                                            \
    const cudaError_t mpmsdemCudaErr_ = (call);                                                   \
    if (mpmsdemCudaErr_ != cudaSuccess) {                                                         \
      cudaGetLastError();                                                                         \
      std::fprintf(stderr, "mpmsdem: CUDA error in %s at %s:%d: %s\n", #call, __FILE__, __LINE__, \
                   cudaGetErrorString(mpmsdemCudaErr_));                                          \
    }                                                                                             \
  } while (0)
