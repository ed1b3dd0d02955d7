// Inputs from elsewhere that crashed or fooled the coupling's readers (the blocks of a scene,
// the restart checkpoint, the front snapshot record), found by the libFuzzer targets of
// tests/fuzz or while writing them (docs/extremes.md, "Fuzzing"): each is now a ParameterError
// naming the file or key and what is wrong. The same inputs are in tests/fuzz/corpus/.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>

#include "../ReaderRefusal.hpp"
#include "common/Error.hpp"
#include "coupling/CoupledCheckpoint.hpp"
#include "coupling/CoupledScene.hpp"

using namespace mpmsdem;
using mpmsdem::testutil::expectRefused;
using mpmsdem::testutil::writeFile;
using namespace mpmsdem::coupling;

namespace {

nlohmann::json checkpoint() {
  return nlohmann::json::parse(R"({"format": "mpmsdem-driver-coupled-1", "snapshot": 3, "step": 1200, "time": 0.012,
    "world_time": 0.012, "last_dt": 1e-5, "contact_step": 2.5e-5, "contact_step_low": [2e-5, 0.011],
    "particle_approach_step": null,
    "bodies": [{"pos": [0.1, 0.2, 0.3], "ori": [1, 0, 0, 0], "vel": [0.5, 0, 0], "ang_vel": [0, 0, 1], "ang_mom": null}],
    "sdem_histories": [[0, -2, 0, 2, 3, 5, 1e-6, -2e-6, 0]], "sdem_dissipation": [0.01, 0.002], "history_slots": 4,
    "history_particles": 1000, "coupling_histories": [[17, 456, 0, 2e-7, 0]], "coupling_dissipation": [0.003, 0.0004],
    "coupling_impulse": [[0.001, 0, -2e-4, 0, 1e-6, 0]], "coupling_first_contact": [0.0105],
    "reference_orientations": [[1, 0, 0, 0]]})");
}

}  // namespace

// snapshot 1.8e19 (a JSON integer beyond long) or 1e300 (a double) was converted to long: undefined
// behaviour (UBSan), in practice any snapshot number. Every field is now checked for its type
// and the range of the C++ field it goes to.
TEST(ReaderRegressions, CheckpointFieldsOutOfRangeAreRefusedByName) {
  const std::string path = writeFile("mpmsdem_regression_checkpoint.json", checkpoint().dump());
  const CoupledCheckpoint c = readCheckpoint(path);
  EXPECT_EQ(c.snapshot, 3);
  EXPECT_EQ(c.sdemHistories.at(0).key.bodyB, -2);  // the terrain
  EXPECT_EQ(c.historyKey.at(0), 456);
  auto refused = [&](const char* pointer, const nlohmann::json& value, const std::string& words) {
    nlohmann::json j = checkpoint();
    j[nlohmann::json::json_pointer(pointer)] = value;
    std::ofstream(path) << j.dump();
    expectRefused([&] { readCheckpoint(path); }, {path, words});
  };
  refused("/snapshot", nlohmann::json::parse("18446744073709551615"), "snapshot = 18446744073709551615: must be an integer");
  refused("/step", 1e300, "step = 1e+300: must be an integer");
  refused("/step", -1, "step = -1: must be an integer in [0, ");
  refused("/history_slots", 4294967296LL, "history_slots = 4294967296");
  refused("/sdem_histories/0/2", 7, "sdem_histories[0][2] = 7: must be an integer in [0, 2]");
  refused("/sdem_histories/0/4", 2147483648LL, "sdem_histories[0][4]");
  refused("/sdem_histories/0", nlohmann::json::array({0, 1}), "sdem_histories[0] = 2 values: must be an array of 9");
  refused("/coupling_histories/0/0", -1, "coupling_histories[0][0] = -1");
  refused("/bodies/0/pos", nlohmann::json::array({1, 2}), "bodies[0].pos = 2 values: must be an array of 3 values");
  refused("/bodies/0/vel/1", "fast", "bodies[0].vel[1] = a JSON string: must be a number");
  refused("/time", true, "time = a JSON boolean: must be a number");
  refused("/bodies", 5, "bodies = 5: must be an array");
  refused("/coupling_impulse/0", nlohmann::json::array({1, 2}), "coupling_impulse[0] = 2 values: must be an array of 6");
  refused("/coupling_impulse/0/4", "large", "coupling_impulse[0][4] = a JSON string: must be a number");
  refused("/coupling_impulse", nlohmann::json::array(), "coupling_impulse = 0 entries: must be one per block of");
  refused("/coupling_first_contact/0", -0.5, "coupling_first_contact[0] = -0.5 s: must be >= 0 or null");
  refused("/coupling_first_contact/0", "soon", "coupling_first_contact[0] = a JSON string: must be a number");
  refused("/coupling_first_contact", nlohmann::json::array({0.01, 0.02}),
          "coupling_first_contact = 2 values: must be an array of 1 values");
  // a checkpoint written before the impulse was kept: read, the impulse counting from the restart
  nlohmann::json old = checkpoint();
  old.erase("coupling_impulse");
  std::ofstream(path) << old.dump();
  EXPECT_TRUE(readCheckpoint(path).couplingImpulse.empty());
  EXPECT_EQ(c.couplingImpulse, (std::vector<double>{0.001, 0, -2e-4, 0, 1e-6, 0}));
  // ... and before the first contacts were: none read (restoreCheckpoint tells touched blocks by
  // their impulse); a block not touched yet is null
  EXPECT_EQ(c.couplingFirstContact, (std::vector<double>{0.0105}));
  old = checkpoint();
  old.erase("coupling_first_contact");
  std::ofstream(path) << old.dump();
  EXPECT_TRUE(readCheckpoint(path).couplingFirstContact.empty());
  old = checkpoint();
  old["coupling_first_contact"][0] = nullptr;
  std::ofstream(path) << old.dump();
  EXPECT_TRUE(std::isnan(readCheckpoint(path).couplingFirstContact.at(0)));
  std::remove(path.c_str());
}

TEST(ReaderRegressions, FrontSnapshotFieldsOutOfRangeAreRefusedByName) {
  const nlohmann::json good = {{"format", "mpmsdem-front-snapshot-1"}, {"x", 0.5}, {"front_x", 0.51}, {"snapshot", 2},
                               {"time", 0.3}, {"step", 3000}, {"checkpoint", nullptr}};
  const std::string path = writeFile("mpmsdem_regression_front.json", good.dump());
  EXPECT_EQ(readFrontSnapshot(path).step, 3000);
  auto refused = [&](const char* key, const nlohmann::json& value, const std::string& words) {
    nlohmann::json j = good;
    j[key] = value;
    std::ofstream(path) << j.dump();
    expectRefused([&] { readFrontSnapshot(path); }, {"--flow-from", path, words});
  };
  refused("step", nlohmann::json::parse("92233720368547758080"), "step = 9.22");
  refused("snapshot", 2.5, "snapshot = 2.5: must be an integer");
  refused("checkpoint", 7, "checkpoint = 7: must be null or the name of a checkpoint file");
  refused("checkpoint", "", "checkpoint = a JSON string: must be null or the name");
  std::remove(path.c_str());
}

// A core face's vertex index 4294967297 was read as int: it wrapped into vertex 1, and a
// corrupt table became another shape without a word.
TEST(ReaderRegressions, CoreFaceIndicesBeyondIntAreRefused) {
  const std::string scene = R"({"block_materials": {"m": {"density": 2500, "flow": {"friction": 0.2}}},
    "blocks": [{"material": "m", "sweep_radius": 0.01, "position": [0, 0, 0],
                "core": {"vertices": [[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.1]],
                         "faces": [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, FACE]]}}]})";
  auto with = [&](const std::string& face) { return std::string(scene).replace(scene.find("FACE"), 4, face); };
  EXPECT_EQ(parseBlocks(with("3")).blocks.size(), 1u);
  expectRefused([&] { parseBlocks(with("4294967299")); }, {"blocks[0]", "core.faces[3][2] = 4294967299", "an integer vertex index"});
  expectRefused([&] { parseBlocks(with("-4294967293")); }, {"core.faces[3][2] = -4294967293"});
  // and the blocks' reader refuses a deeply nested scene as the flow's does
  const std::string deep = R"({"blocks": )" + std::string(100000, '[') + std::string(100000, ']') + "}";
  expectRefused([&] { parseBlocks(deep); }, {"nested more than 64 levels"});
}
