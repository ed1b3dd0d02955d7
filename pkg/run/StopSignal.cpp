#include "run/StopSignal.hpp"

#include <csignal>

namespace mpmsdem {
namespace run {

namespace {

// The number of the SIGINT or SIGTERM that asked the step loop to stop (0: none).
volatile std::sig_atomic_t gStopSignal = 0;

extern "C" void onStopSignal(int sig) {
  if (!gStopSignal) gStopSignal = sig;
  if (sig == SIGINT) std::signal(sig, SIG_DFL);
}

}  // namespace

void catchStopSignals() {
  std::signal(SIGINT, onStopSignal);
  std::signal(SIGTERM, onStopSignal);
}

int stopSignal() { return gStopSignal; }

const char* signalName(int sig) { return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : "a signal"; }

}  // namespace run
}  // namespace mpmsdem
