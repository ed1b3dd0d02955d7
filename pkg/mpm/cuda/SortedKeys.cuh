// Helpers of the radix-sorted keys of the CUDA backends (the MPM step's particles by block cell,
// the coupling's contacts by block): how many bits a key field needs, and the range each value
// of a key's high part holds in the sorted keys.
#pragma once
#include <cuda_runtime.h>

namespace mpmsdem {
namespace sortedkeys {

// Bits that hold 0 .. values - 1.
inline int bitsFor(unsigned long long values) {
  int b = 0;
  while (b < 64 && (1ull << b) < values) ++b;
  return b;
}

// [start[c], end[c]): the places of the sorted keys whose bits from `shift` up equal c (start and
// end left as the caller cleared them for the values that do not occur). static: each
// translation unit that includes this header has its own copy.
static __global__ void rangesKernel(int n, const unsigned long long* key, int shift, int* start, int* end) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  const int c = static_cast<int>(key[i] >> shift);
  if (i == 0 || static_cast<int>(key[i - 1] >> shift) != c) start[c] = i;
  if (i == n - 1 || static_cast<int>(key[i + 1] >> shift) != c) end[c] = i + 1;
}

}  // namespace sortedkeys
}  // namespace mpmsdem
