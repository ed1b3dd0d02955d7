// Runs with outputs through the run layer's entry point: the outputs of a run by steps, a
// restart that continues it bit for bit (its flow probes too), a front snapshot, and a restart
// refused.
#include <gtest/gtest.h>

#ifdef MPMSDEM_WITH_HDF5  // runs with outputs need HDF5 (CMakeLists.txt)
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "common/Error.hpp"
#include "coupling/CoupledCheckpoint.hpp"
#include "coupling/CoupledScene.hpp"
#include "io/Hdf5Writer.hpp"
#include "scene/MpmScene.hpp"
#include "run/RunScene.hpp"
#include "SandBox.hpp"

namespace fs = std::filesystem;
using namespace mpmsdem;
using namespace mpmsdem::run;

namespace {

fs::path scratchDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("mpmsdem_test_run_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(dir);
  return dir;
}

// The sand collapsing, a fixed step of 5e-5 s: a snapshot every 5 steps, a series record every step.
mpm::MpmScene collapse(const fs::path& out, const std::string& extraRun = "") {
  return testing_scenes::sandInABox(
      R"({"duration": 1.0, "dt": 5e-5, "output_every": 2.5e-4, "series_every": 5e-5, "vtk": "raw",
          "output_dir": ")" + out.string() + "\"" + extraRun + "}");
}

RunEnd runSteps(const mpm::MpmScene& scene, long steps, bool restart = false) {
  RunRequest request;
  request.steps = steps;
  request.restart = restart;
  return runScene(scene, coupling::SceneBlocks{}, request);
}

// The last snapshot of the run in dir: its particles, time and step.
struct LastSnapshot {
  explicit LastSnapshot(const fs::path& dir) {
    const std::string h5 = (dir / "mpm.h5").string();
    io::readSnapshot(h5, io::readNumSnapshots(h5) - 1, particles, &time, &step);
  }
  mpm::ParticleSet particles;
  double time = 0;
  long step = 0;
};

}  // namespace

TEST(OutputRun, RunsByStepsWithItsOutputs) {
  const fs::path dir = scratchDir("steps");
  EXPECT_EQ(runSteps(collapse(dir), 12), RunEnd::Done);
  const std::string h5 = (dir / "mpm.h5").string();
  EXPECT_EQ(io::readNumSnapshots(h5), 4);  // the start, steps 5 and 10, and the end at step 12
  EXPECT_EQ(io::readSeries(h5, "time").size(), 13u);
  const LastSnapshot last(dir);
  EXPECT_EQ(last.step, 12);
  EXPECT_TRUE(fs::exists(dir / "particles.pvd"));
  EXPECT_TRUE(fs::exists(dir / "vtk" / "particles_000003.vtp"));
  EXPECT_TRUE(fs::exists(dir / "mpm.h5.restart"));
  EXPECT_FALSE(fs::exists(dir / "flow_probes.json"));  // no probes
  fs::remove_all(dir);
}

TEST(OutputRun, ARestartContinuesTheRunBitForBit) {
  const fs::path whole = scratchDir("whole"), parts = scratchDir("parts");
  ASSERT_EQ(runSteps(collapse(whole), 20), RunEnd::Done);
  ASSERT_EQ(runSteps(collapse(parts), 12), RunEnd::Done);
  ASSERT_EQ(runSteps(collapse(parts), 8, true), RunEnd::Done);  // from step 12's snapshot
  const LastSnapshot a(whole), b(parts);
  EXPECT_EQ(a.step, 20);
  EXPECT_EQ(b.step, 20);
  EXPECT_EQ(a.time, b.time);
  EXPECT_EQ(a.particles.x, b.particles.x);
  EXPECT_EQ(a.particles.v, b.particles.v);
  EXPECT_EQ(a.particles.stress, b.particles.stress);
  for (const char* name : {"time", "step", "dt", "kinetic_energy", "front_x"})
    EXPECT_EQ(io::readSeries((whole / "mpm.h5").string(), name), io::readSeries((parts / "mpm.h5").string(), name))
        << name;
  EXPECT_EQ(io::readNumSnapshots((whole / "mpm.h5").string()), io::readNumSnapshots((parts / "mpm.h5").string()) - 1)
      << "the restarted run has the snapshot at step 12 besides those at multiples of 5 steps";
  fs::remove_all(whole);
  fs::remove_all(parts);
}

// The collapse with a flow probe at the block's downstream face: the flow is there from the
// first record (its arrival is t = 0) and the means run over 15 steps, across a restart at step
// 12. The restarted run must report what the whole run does, not an arrival at its restart.
TEST(OutputRun, ARestartKeepsTheProbesRecords) {
  const fs::path whole = scratchDir("probe_whole"), parts = scratchDir("probe_parts");
  auto scene = [](const fs::path& out) {
    mpm::MpmScene s = collapse(out);
    s.probes.push_back({0.06, 0.005, 0.02, 4, 7.5e-4});
    return s;
  };
  ASSERT_EQ(runSteps(scene(whole), 20), RunEnd::Done);
  ASSERT_EQ(runSteps(scene(parts), 12), RunEnd::Done);
  ASSERT_EQ(runSteps(scene(parts), 8, true), RunEnd::Done);
  const nlohmann::json a = nlohmann::json::parse(std::ifstream(whole / "flow_probes.json"));
  const nlohmann::json b = nlohmann::json::parse(std::ifstream(parts / "flow_probes.json"));
  ASSERT_EQ(a["probes"].size(), 1u);
  EXPECT_EQ(a["probes"][0]["arrival"], 0.0);
  EXPECT_EQ(a["probes"][0]["records"], 21);
  EXPECT_GT(a["probes"][0]["h_f"].get<double>(), 0.03);  // the block's 0.04 m less its first slump
  for (const char* key : {"arrival", "h_f", "v_f", "Fr", "records", "complete"})
    EXPECT_EQ(a["probes"][0][key], b["probes"][0][key]) << key;
  EXPECT_EQ(a["front_still_since"], b["front_still_since"]);
  // a run whose records hold another number of probes is not the one the scene describes
  mpm::MpmScene two = scene(parts);
  two.probes.push_back(two.probes[0]);
  try {
    runSteps(two, 2, true);
    ADD_FAILURE() << "expected ParameterError";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("flow_probes"), std::string::npos) << e.what();
  }
  fs::remove_all(whole);
  fs::remove_all(parts);
}

TEST(OutputRun, TheFrontReachingAnXIsSaved) {
  const fs::path dir = scratchDir("front");
  ASSERT_EQ(runSteps(collapse(dir, R"(, "snapshot_when_front_at": 0.01)"), 3), RunEnd::Done);
  ASSERT_TRUE(fs::exists(dir / "front_snapshot.json"));
  const coupling::FrontSnapshot f = coupling::readFrontSnapshot((dir / "front_snapshot.json").string());
  EXPECT_EQ(f.snapshot, 0);  // the front is past x = 0.01 m from the start
  EXPECT_EQ(f.step, 0);
  EXPECT_EQ(f.x, 0.01);
  fs::remove_all(dir);
}

TEST(OutputRun, ARestartWithoutARestartPointIsRefused) {
  const fs::path dir = scratchDir("empty");
  fs::create_directories(dir);
  try {
    runSteps(collapse(dir), 5, true);
    ADD_FAILURE() << "expected ParameterError";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("--restart"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("restart point"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

#endif  // MPMSDEM_WITH_HDF5
