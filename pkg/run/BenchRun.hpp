// A benchmark run (mpmsdem-run --bench): the step loop with no files and no diagnostics, and at
// the end one JSON line on stdout: backend, precision, solver, particles, steps, seconds (step
// loop wall time), particle_updates_per_s (over the steps after the first kBenchWarmupSteps,
// which sort the particles from their seeded order and first touch the second state buffer;
// their time is warmup_seconds), warmup_steps, bytes_per_particle (solver memoryBytes() /
// particles), threads, flip_blend, blocks; with the device's stage timing (--device-stages)
// device_stage_seconds; with blocks also time, stage_seconds, coupling_stage_seconds (with
// --device-stages), contact_step_min(_time) (null while nothing touched), moving_blocks
// (BlockRecord), narrow_phase_pairs (block pairs the narrow phase computed, all steps) and
// block_contacts (the blocks' contacts with blocks and terrain after the last step). Progress
// lines go to stderr (pkg/run/Progress.hpp). A benchmark takes no records, so it ignores the
// flow probes and the stop rules run.stop_when_probed and run.stop_when_front_still.
#pragma once

#include <nlohmann/json.hpp>

#include <vector>

#include "common/Types.hpp"
#include "coupling/CoupledWorld.hpp"
#include "scene/MpmScene.hpp"
#include "run/RunLoop.hpp"
#include "sdem/SdemEngine.hpp"

namespace mpmsdem {
namespace run {

// What a benchmark run did to each moving block, so that backends and precisions can be
// compared on physics as well as speed without output files: the start and end of its centroid,
// its end velocity, the angle it turned, and the largest flow force on it (|F| and the x
// component, the downstream force in a flume's frame) with when it came (null: no such force).
class BlockRecord {
 public:
  explicit BlockRecord(const sdem::SdemEngine& e);
  // After every step: the peaks of the flow forces
  void afterStep(const coupling::CoupledWorld& w);
  // One entry per moving block: block, start, end, velocity, rotation_deg, peak_flow_force(_time),
  // peak_flow_force_x(_time) [m, m/s, degrees, N, s]
  nlohmann::json summary(const sdem::SdemEngine& e) const;

 private:
  struct Block {
    int index;
    Vec3 pos0;
    Quat ori0;
    double peak = 0, peakTime = 0, peakX = 0, peakXTime = 0;
  };
  std::vector<Block> blocks_;
};

// Steps at the start of a benchmark that are timed apart: as many as a peer's warm-up
// (scripts/bench/peers: one step per copy of the particles), so that both rates are of the
// steps a long run repeats.
constexpr long kBenchWarmupSteps = 2;

// Run the benchmark to maxSteps (0: to run.duration) and print its JSON line.
void runBench(Stepper& st, const mpm::MpmScene& scene, long maxSteps);

}  // namespace run
}  // namespace mpmsdem
