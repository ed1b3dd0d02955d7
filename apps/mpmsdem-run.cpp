// mpmsdem-run: plain C++ driver (no YADE, no Python) for JSON-described MPM scenes, and coupled
// MPM–SDEM scenes when the scene has "blocks" (pkg/coupling/CoupledScene.hpp): the command line
// of the run layer (pkg/run/RunScene.hpp), which runs the scene.
//
//   mpmsdem-run scene.json [--backend cpu|cuda] [--precision float|double] [--out DIR]
//                          [--steps N] [--restart | --flow-from DIR|FILE] [--bench]
//
// The scene schema is documented in pkg/scene/MpmScene.hpp (flow), pkg/coupling/CoupledScene.hpp
// (blocks) and examples/scenes/README.md.
// Options override the scene's "run" settings:
//   --backend, --precision   solver backend and precision (either precision on either backend)
//   --out DIR                output folder (run.output_dir)
//   --steps N                run exactly N steps (N >= 1) instead of run.duration
//   --restart                continue from the last snapshot of the output folder's mpm.h5
//                            (its particles, time and step), appending to its outputs as
//                            they were at that snapshot (mpm.h5.restart, coupled.h5.restart);
//                            --steps then counts the steps of this run. The scene must be
//                            the one the run was started with (the file's "parameters"),
//                            except for kRestartFree (pkg/io/StoredScene.cpp; exit 2 naming what changed).
//                            With blocks, from the snapshot that coupled.checkpoint.json
//                            names (pkg/coupling/CoupledCheckpoint.hpp): the same run, bit
//                            for bit, on the CPU and on CUDA (whose sums have a fixed order)
//   --flow-from DIR|FILE     start from the flow of the run in DIR, at the state it saved when
//                            its front reached run.snapshot_when_front_at (DIR/front_snapshot.json,
//                            or the record FILE, e.g. DIR/front_snapshot_2.json for a list of x):
//                            a scene of the same flow with blocks that the flow had not reached
//                            (pkg/run/RunScene.hpp). Needs a fixed run.dt, the same in both, and
//                            no flow_probes; --steps counts the steps of this run
//   --bench                  write no files, take no diagnostics; print one JSON line on
//                            stdout at the end: speed, memory, and with blocks what the moving
//                            blocks did (its fields: pkg/run/BenchRun.hpp)
//   --device-stages          with --bench on CUDA: time the MPM step's stages on the device
//                            (events; lists, sort, p2g, grid, g2p, columns) and add device_stage_seconds to
//                            the JSON line; in a coupled run also the coupling's parts
//                            (coupling_stage_seconds: MpSdemCoupling::setStageTiming)
// Outputs (not with --bench), in the output folder: mpm.h5, the ParaView series, and with blocks
// coupled.h5, scene.pvd and coupled.checkpoint.json, flow_probes.json and the front snapshots
// (pkg/run/OutputRun.hpp). Progress lines go to stdout (stderr with --bench) every 5 % of the run
// and at least every run.progress_every seconds of wall time (pkg/run/Progress.hpp). SIGINT or
// SIGTERM ends the run after the step in progress with the state saved; a second SIGINT ends the
// process at once (pkg/run/StopSignal.hpp).
// Exit status: 0 done; 2 bad parameters or command line (a scene too large for the memory
// included); 3 run failure (NaN, blow-up, step above the stable one), after writing the last
// good state as a final snapshot (with "keep_last_good_state": false, naming the last snapshot
// written as the last good state); 4 stopped by a signal, the state saved; 1 other errors (e.g.
// I/O).
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <new>
#include <optional>
#include <string>

#include "common/Error.hpp"
#include "coupling/CoupledScene.hpp"
#ifdef MPMSDEM_WITH_HDF5
#include "io/Hdf5Writer.hpp"
#endif
#include "scene/MpmScene.hpp"
#include "run/RunScene.hpp"

using namespace mpmsdem;
using namespace mpmsdem::mpm;

namespace {

const char* const kUsage =
    "usage: mpmsdem-run scene.json [--backend cpu|cuda] [--precision float|double] [--out DIR] [--steps N] "
    "[--restart | --flow-from DIR|FILE] [--bench [--device-stages]]\n";

struct Options {
  std::string scene;
  std::optional<Backend> backend;
  std::optional<Precision> precision;
  std::optional<std::string> out;
  run::RunRequest request;  // --steps, --restart, --flow-from, --bench, --device-stages
};

Options parseArgs(int argc, char** argv) {
  Options o;
  run::RunRequest& r = o.request;
  auto value = [&](int& i, const char* flag) -> std::string {
    if (i + 1 >= argc) throw ParameterError(std::string(flag) + ": missing value\n" + kUsage);
    return argv[++i];
  };
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--backend") {
      const std::string v = value(i, "--backend");
      if (v != "cpu" && v != "cuda") throwParameter("--backend", v, "", "cpu or cuda");
      o.backend = v == "cuda" ? Backend::Cuda : Backend::Cpu;
    } else if (a == "--precision") {
      const std::string v = value(i, "--precision");
      if (v != "float" && v != "double") throwParameter("--precision", v, "", "float or double");
      o.precision = v == "float" ? Precision::Float : Precision::Double;
    } else if (a == "--out") {
      o.out = value(i, "--out");
    } else if (a == "--steps") {
      const std::string v = value(i, "--steps");
      char* end = nullptr;
      r.steps = std::strtol(v.c_str(), &end, 10);
      if (v.empty() || *end != '\0' || r.steps < 1) throwParameter("--steps", v, "", "an integer >= 1");
    } else if (a == "--restart") {
      r.restart = true;
    } else if (a == "--flow-from") {
      r.flowFrom = value(i, "--flow-from");
    } else if (a == "--bench") {
      r.bench = true;
    } else if (a == "--device-stages") {
      r.deviceStages = true;
    } else if (a == "-h" || a == "--help") {
      std::cout << kUsage;
      std::exit(0);
    } else if (!a.empty() && a[0] == '-') {
      throw ParameterError("unknown option '" + a + "'\n" + kUsage);
    } else if (o.scene.empty()) {
      o.scene = a;
    } else {
      throw ParameterError("more than one scene file given ('" + o.scene + "', '" + a + "')\n" + kUsage);
    }
  }
  if (o.scene.empty()) throw ParameterError(std::string("no scene file given\n") + kUsage);
  if (r.restart && r.bench) throw ParameterError("--restart and --bench: choose one (a benchmark writes no files)");
  if (r.restart && r.flowFrom)
    throw ParameterError("--restart and --flow-from: choose one (a run started from another's flow is restarted from "
                         "its own outputs, with --restart alone)");
  if (r.deviceStages && !r.bench) throw ParameterError(std::string("--device-stages: only with --bench\n") + kUsage);
  return o;
}

// The exit status of a run that ended without an exception.
int exitStatus(run::RunEnd end) {
  switch (end) {
    case run::RunEnd::Done:
      return 0;
    case run::RunEnd::Failure:
      return 3;
    case run::RunEnd::Stopped:
      return 4;
  }
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
#ifdef MPMSDEM_WITH_HDF5
  io::skipHdf5CleanupAtExit();  // a failed write (a full disk) must end with its message, not a crash at exit
#endif
  std::string sceneSize;  // for an out-of-memory message
  try {
    const Options opt = parseArgs(argc, argv);
    MpmScene scene = loadScene(opt.scene);
    sceneSize = sceneSizeDescription(scene);
    if (opt.backend) scene.run.backend = *opt.backend;
    if (opt.precision) scene.run.precision = *opt.precision;
    if (opt.out) scene.run.outputDir = *opt.out;
    const coupling::SceneBlocks blocks = coupling::parseBlocks(scene.sourceJson);
    if (opt.request.deviceStages && scene.run.backend != Backend::Cuda)
      throw ParameterError("--device-stages: times the CUDA step; this run is on the " +
                           std::string(backendName(scene.run.backend)) + " backend (--backend cuda)");
    return exitStatus(run::runScene(scene, blocks, opt.request));
  } catch (const ParameterError& e) {
    std::fprintf(stderr, "mpmsdem-run: parameter error: %s\n", e.what());
    return 2;
  } catch (const RuntimeFailure& e) {
    std::fprintf(stderr, "mpmsdem-run: failure: %s\n", e.what());
    return 3;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "mpmsdem-run: parameter error: out of memory for %s: reduce grid.cells (a coarser dx or "
                         "a smaller domain) or the particles per cell (ppc)\n",
                 sceneSize.empty() ? "the scene" : sceneSize.c_str());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mpmsdem-run: error: %s\n", e.what());
    return 1;
  }
}
