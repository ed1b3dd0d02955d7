// The CPU contact loop shared by the couplings with SDEM blocks and with LevelSet bodies: the
// particles in chunks of kContactChunk slots that the threads take in turn, each chunk's contacts
// in a list of its own (in slot order: the caller sorts them by particle number, so that the sums
// do not depend on the thread count or the solver's particle order).
#pragma once
#include <algorithm>
#include <limits>
#include <vector>

#include "coupling/CouplingKernelsCommon.hpp"

namespace mpmsdem {
namespace coupling {

constexpr long kContactChunk = 4096;

struct ContactLoopTotals {
  long overflow = 0;  // contacts without a free history slot
  double approach = std::numeric_limits<double>::infinity();  // smallest approach bound [s]
  long firstBad;      // smallest number of a particle that failed (reached a body), or n: none
  int badBody = -1;   // the body it reached
};

// couple(p, sink, &bad, &overflow, &approach, memo) runs one particle slot p (coupleParticle or
// coupleParticleLevelSets with the caller's tables) and returns kCoupleOk or a failure with the
// body in bad. A failing particle does not stop the loop: it goes on to name the smallest
// particle number, as the CUDA kernel does. Pass it as a lambda marked
// __attribute__((always_inline)): left to itself the compiler keeps its ~10 kB body out of the
// loop and calls it per particle, reloading the captured tables each time (the coupling stage of
// the coarse §3.2 flume 1.2-1.3 times as long: docs/benchmarks.md).
template <typename T, typename Couple>
ContactLoopTotals runContactChunks(const CouplingParticles<T>& P, long n,
                                   std::vector<std::vector<MpContact<T>>>& chunkContacts, Couple&& couple) {
  const long nChunks = (n + kContactChunk - 1) / kContactChunk;
  chunkContacts.resize(nChunks);
  long overflow = 0;
  double approach = std::numeric_limits<double>::infinity();
  ContactLoopTotals t;
  t.firstBad = n;
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : overflow) reduction(min : approach)
  for (long c = 0; c < nChunks; ++c) {
    std::vector<MpContact<T>>& list = chunkContacts[c];
    list.clear();
    auto sink = [&list](const MpContact<T>& ct) { list.push_back(ct); };
    int over = 0;
    T chunkApproach = std::numeric_limits<T>::infinity();
    CouplingLoopMemo<T> memo;
    for (long p = c * kContactChunk; p < std::min(n, (c + 1) * kContactChunk); ++p) {
      int bad = -1;
      if (couple(static_cast<int>(p), sink, &bad, &over, &chunkApproach, memo) != kCoupleOk) {
        const long number = particleNumber(P, static_cast<int>(p));
#pragma omp critical(coupling_first_bad)
        if (number < t.firstBad) {
          t.firstBad = number;
          t.badBody = bad;
        }
      }
    }
    overflow += over;
    approach = std::min(approach, static_cast<double>(chunkApproach));
  }
  t.overflow = overflow;
  t.approach = approach;
  return t;
}

}  // namespace coupling
}  // namespace mpmsdem
