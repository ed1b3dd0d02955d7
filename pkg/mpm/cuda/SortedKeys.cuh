// Helper of the radix-sorted keys of the CUDA backends (the MPM step's particles by block cell,
// the coupling's contacts by block): how many bits a key field needs.
#pragma once

namespace mpmsdem {
namespace sortedkeys {

// Bits that hold 0 .. values - 1.
inline int bitsFor(unsigned long long values) {
  int b = 0;
  while (b < 64 && (1ull << b) < values) ++b;
  return b;
}

}  // namespace sortedkeys
}  // namespace mpmsdem
