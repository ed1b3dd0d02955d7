// Progress of a run in wall time: the clock the step loop is timed with, when a progress line
// is due, the ETA's format, and where a coupled run's step loop spent its time.
//
// A progress line comes every 5 % of the run and at least every run.progress_every seconds of
// wall time (10), on stdout (stderr with --bench, whose stdout is its JSON line), with the step
// and what sets it (the flow's CFL step, a contact, a block's approach naming the block). A
// coupled run ends with the split of the step loop's wall time (MPM step, MP-block coupling,
// blocks, the rest).
#pragma once

#include <chrono>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "coupling/CoupledWorld.hpp"

namespace mpmsdem {
namespace run {

using Clock = std::chrono::steady_clock;
// Wall time since t0 [s]
inline double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// A duration for an ETA [s]: "42s", "3.5min" (from 2 min), "2.1h" (from 2 h).
std::string formatDuration(double s);

// A flow probe as a run that stops when every probe's record is complete (run.stop_when_probed)
// sees it: where the front arrives (its station less its half width) and how long after the
// arrival its record lasts [m, s], and the arrival once the front has come [s].
struct ProbeProgress {
  double arriveAt = 0, window = 0;
  std::optional<double> arrival;
};

// The simulated time [s] such a run has left at time t, read from its front at x = front moving
// at frontSpeed [m/s]: a probe the front has not reached needs it to cover the distance at that
// speed, then the probe's window; a reached one what is left of its window. The largest over
// the probes; none while a probe is not reached and the front does not advance. An estimate: a
// front that speeds up (a collapsing column) arrives sooner.
std::optional<double> probesTimeLeft(double t, double front, double frontSpeed,
                                     const std::vector<ProbeProgress>& probes);

// When the next progress line is due: at the first multiple of 5 % of the run above the fraction
// of the last line, or when progress_every seconds of wall time have passed since it.
class ProgressSchedule {
 public:
  // next: the first fraction of the run (0 to 1) that is due; everySeconds: run.progress_every [s], > 0
  ProgressSchedule(double next, double everySeconds) : next_(next), every_(everySeconds), last_(Clock::now()) {}
  // The first 5 % mark above fraction f
  static double markAfter(double f) { return std::floor(f / 0.05 + 1) * 0.05; }
  // Whether a line is due at fraction f; force: due anyway (the run's last step)
  bool due(double f, bool force = false) const { return f >= next_ || force || since(last_) >= every_; }
  // A line was written at fraction f
  void reported(double f) {
    next_ = markAfter(f);
    last_ = Clock::now();
  }

 private:
  double next_;
  double every_;
  Clock::time_point last_;
};

// Where the step loop's wall time went in a coupled run: "MPM step 71.2 %, ...". The records
// (diagnostics read from every particle, series, progress) and the snapshots are timed by the
// loop; the rest is the time-step control. All times in seconds of wall time.
std::string stageSplit(const coupling::CoupledWorld& world, double loopSeconds, double recordSeconds,
                       double snapshotSeconds);

}  // namespace run
}  // namespace mpmsdem
