// Error checking for CUDA runtime calls (include only from .cu files).
#pragma once
#include <cuda_runtime.h>

#include <cstdio>
#include <sstream>

#include "common/Error.hpp"

// Throws mpmsdem::RuntimeFailure naming the call, the file:line and CUDA's message.
#define CUDA_CHECK(call)                                                                          \
  do {                                                                                            \
    const cudaError_t mpmsdemCudaErr_ = (call);                                                   \
    if (mpmsdemCudaErr_ != cudaSuccess) {                                                         \
      std::ostringstream mpmsdemOs_;                                                              \
      mpmsdemOs_ << "CUDA error in " #call " at " << __FILE__ << ":" << __LINE__ << ": "          \
                 << cudaGetErrorString(mpmsdemCudaErr_);                                          \
      throw ::mpmsdem::RuntimeFailure(mpmsdemOs_.str());                                          \
    }                                                                                             \
  } while (0)

// For destructors, which must not throw: reports the failure on stderr.
#define CUDA_CHECK_NOTHROW(call)                                                                  \
  do {                                                                                            \
    const cudaError_t mpmsdemCudaErr_ = (call);                                                   \
    if (mpmsdemCudaErr_ != cudaSuccess)                                                           \
      std::fprintf(stderr, "mpmsdem: CUDA error in %s at %s:%d: %s\n", #call, __FILE__, __LINE__, \
                   cudaGetErrorString(mpmsdemCudaErr_));                                          \
  } while (0)
