// SIGINT and SIGTERM during the step loop (Ctrl-C, `timeout`, a batch system's end of
// allocation): the output run (pkg/run/OutputRun.hpp) ends after the step in progress and saves
// the state as a snapshot with its coupled checkpoint, so that --restart continues the same run.
// A second SIGINT (Ctrl-C twice) ends the process at once (the outputs are then those of the
// last snapshot, as after a kill); more SIGTERMs change nothing, so that a runner may pass one
// on to a driver that had its own. Before the step loop has begun, and in a benchmark (which
// does not catch them), either signal ends the process at once.
#pragma once

namespace mpmsdem {
namespace run {

// From now on, a SIGINT or SIGTERM is recorded (stopSignal) instead of ending the process; a
// SIGINT then gets its default action back, so that a second Ctrl-C ends a run whose saving hangs.
void catchStopSignals();
// The number of the first SIGINT or SIGTERM caught (0: none).
int stopSignal();
// "SIGINT", "SIGTERM", or "a signal" for another number.
const char* signalName(int sig);

}  // namespace run
}  // namespace mpmsdem
