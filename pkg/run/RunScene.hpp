// The run layer's entry point: a scene read and checked (mpm::loadScene, coupling::parseBlocks)
// run from its start, from the last restart point of its output folder, or from the flow of
// another run, as a benchmark or with outputs. mpmsdem-run (apps/mpmsdem-run.cpp) is its
// command line.
//
// Where a run starts:
//   from the scene's start: the particles seeded from it, the blocks where it puts them.
//   restart: from the last snapshot of the output folder's mpm.h5 (its particles, time and step),
//            appending to its outputs as they were at that snapshot (mpm.h5.restart,
//            coupled.h5.restart). The scene must be the one the run was started with (the file's
//            "parameters"), except for kRestartFree (pkg/io/StoredScene.cpp). With blocks, from
//            the snapshot that coupled.checkpoint.json names (pkg/coupling/CoupledCheckpoint.hpp):
//            the same run, bit for bit, on the CPU and on CUDA (whose sums have a fixed order).
//            A scene with flow_probes is not restarted (its probe records are not kept).
//   flowFrom: from the state the run in that folder saved when its front reached
//            run.snapshot_when_front_at (DIR/front_snapshot.json, or the record given, e.g.
//            DIR/front_snapshot_2.json for a list of x): a scene of the same flow
//            (io::checkFlowFromScene: the keys a restart keeps, but for grid cells added on free
//            sides) with blocks that the flow had not reached, its own fixed blocks first (a bed).
//            The other blocks take their steps before that state alone, so the run is the one
//            this scene would give from the start, bit for bit, without computing the flow's way
//            to them again (coupling::startFromFlow). Needs a fixed run.dt, the same in both, and
//            no flow_probes.
// At load, a block faster than run.max_block_speed or more than 100 grid diagonals from the grid
// is refused (ParameterError); one that lies wholly outside the grid is a warning on stderr and
// in the outputs' "warnings" attribute. A fixed run.dt above the flow's stable step is refused.
// Without HDF5 (CMakeLists.txt) only benchmarks run.
#pragma once

#include <optional>
#include <string>

#include "coupling/CoupledScene.hpp"
#include "scene/MpmScene.hpp"
#include "run/RunLoop.hpp"

namespace mpmsdem {
namespace run {

// How to run a scene; the scene's "run" settings say the rest.
struct RunRequest {
  long steps = 0;        // run exactly this many steps (>= 1) from where the run starts; 0: to run.duration
  bool restart = false;  // continue from the output folder's last restart point
  std::optional<std::string> flowFrom;  // start from the flow of this run: its folder or a front record
  bool bench = false;         // a benchmark (pkg/run/BenchRun.hpp): no files, no diagnostics
  bool deviceStages = false;  // time the device's stages (a benchmark on CUDA)
};

// Run `scene` with its blocks as `request` asks. ParameterError: a request or a start state
// that does not fit the scene (naming what); RuntimeFailure: a failure before the step loop;
// failures in the step loop end the run with RunEnd::Failure, the last good state saved.
RunEnd runScene(const mpm::MpmScene& scene, const coupling::SceneBlocks& blocks, const RunRequest& request);

}  // namespace run
}  // namespace mpmsdem
