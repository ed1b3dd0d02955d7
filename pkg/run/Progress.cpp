#include "run/Progress.hpp"

#include <algorithm>
#include <cstdio>

namespace mpmsdem {
namespace run {

std::string formatDuration(double s) {
  char buf[32];
  if (s < 120)
    std::snprintf(buf, sizeof buf, "%.0fs", s);
  else if (s < 7200)
    std::snprintf(buf, sizeof buf, "%.1fmin", s / 60);
  else
    std::snprintf(buf, sizeof buf, "%.1fh", s / 3600);
  return buf;
}

std::optional<double> probesTimeLeft(double t, double front, double frontSpeed,
                                     const std::vector<ProbeProgress>& probes) {
  double left = 0;
  for (const ProbeProgress& p : probes) {
    if (p.arrival) {
      left = std::max(left, *p.arrival + p.window - t);
    } else {
      if (!(frontSpeed > 0)) return std::nullopt;
      left = std::max(left, std::max(0.0, p.arriveAt - front) / frontSpeed + p.window);
    }
  }
  return left;
}

std::string stageSplit(const coupling::CoupledWorld& world, double loopSeconds, double recordSeconds,
                       double snapshotSeconds) {
  const auto& s = world.stageSeconds();
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "MPM step %.1f %%, MP-block coupling %.1f %%, blocks %.1f %%, records %.1f %%, snapshots %.1f %%, "
                "time-step control %.1f %%",
                100 * s.mpm / loopSeconds, 100 * s.coupling / loopSeconds, 100 * s.blocks / loopSeconds,
                100 * recordSeconds / loopSeconds, 100 * snapshotSeconds / loopSeconds,
                100 * (loopSeconds - s.mpm - s.coupling - s.blocks - recordSeconds - snapshotSeconds) / loopSeconds);
  return buf;
}

}  // namespace run
}  // namespace mpmsdem
