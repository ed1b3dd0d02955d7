// When records of one kind are due in simulated time: the series every run.series_every and the
// snapshots every run.output_every (pkg/run/OutputRun.hpp) come at the multiples of their
// interval, each taken once, the first after the time the run starts from (a restart continues
// the cadence of the run it restarts). The relative slack of 1e-12 keeps a multiple that a
// step's round-off puts a hair off the step's time from being missed or taken twice.
#pragma once

#include <cmath>

namespace mpmsdem {
namespace run {

class OutputCadence {
 public:
  // every: the interval [s], > 0 (parseScene checks it); start: the run's start time [s], >= 0
  OutputCadence(double every, double start)
      : every_(every), next_((std::floor(start / every * (1 + 1e-12)) + 1) * every) {}
  // Whether a record is due at time t [s]
  bool due(double t) const { return t >= next_ * (1 - 1e-12); }
  // A record was taken at time t [s]: the next is the first multiple after it
  void passed(double t) {
    while (next_ <= t * (1 + 1e-12)) next_ += every_;
  }
  double next() const { return next_; }  // [s]

 private:
  double every_;
  double next_;
};

}  // namespace run
}  // namespace mpmsdem
