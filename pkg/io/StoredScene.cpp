#include "io/StoredScene.hpp"

// (A build without HDF5 has no mpm.h5 to go on from and no reader of it: CMakeLists.txt.)
#ifdef MPMSDEM_WITH_HDF5

#include <algorithm>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include "common/Error.hpp"
#include "common/SceneJson.hpp"
#include "io/Hdf5Writer.hpp"

namespace mpmsdem {
namespace io {

namespace {

using nlohmann::json;

// Scene keys a restart may change: how long to run and what to write, where, and on which
// backend. Everything else (grid, material, particles, gravity, walls, the FLIP/PIC blend, cfl,
// run.dt, run.dt_factor) defines the run being continued: changing it would silently glue
// two different simulations into one output.
const char* const kRestartFree[] = {"description", "run.duration", "run.output_every", "run.series_every",
                                    "run.output_dir", "run.vtk", "run.backend", "run.precision"};

// Scene keys a run started from another's flow (--flow-from) may have changed besides those:
// the stop rules, probes and snapshots of the run it starts from, its blocks (checked apart:
// that run's blocks come first), and grid cells (checked apart: added on free sides only).
const char* const kFlowFromFree[] = {"run.stop_when_probed", "run.stop_when_front_still", "run.snapshot_when_front_at",
                                     "run.max_block_speed",  "run.progress_every",          "flow_probes",
                                     "blocks",               "block_materials",             "grid.cells"};

// j[key] where j is an object holding key, else null. The stored scene is whatever JSON the file
// holds, and nlohmann-json's const operator[] is undefined behaviour for a key that is not there.
const json& member(const json& j, const std::string& key) {
  static const json absent;
  if (!j.is_object()) return absent;
  const auto it = j.find(key);
  return it == j.end() ? absent : *it;
}

// j[i] where j is an array that long, else null (the same for an index).
const json& element(const json& j, std::size_t i) {
  static const json absent;
  return j.is_array() && i < j.size() ? j[i] : absent;
}

// Key paths where two scenes differ (objects compared key by key, anything else as a whole),
// but for the paths in `free`; a stored scene that is no JSON object differs as a whole.
void sceneDifferences(const json& a, const json& b, const std::string& path, const std::vector<std::string>& free,
                      std::vector<std::string>& out) {
  if (std::find(free.begin(), free.end(), path) != free.end()) return;
  if (a.is_object() && b.is_object()) {
    std::vector<std::string> keys;
    for (auto it = a.begin(); it != a.end(); ++it) keys.push_back(it.key());
    for (auto it = b.begin(); it != b.end(); ++it)
      if (!a.contains(it.key())) keys.push_back(it.key());
    for (const std::string& k : keys)
      sceneDifferences(member(a, k), member(b, k), path.empty() ? k : path + "." + k, free, out);
    return;
  }
  if (a != b) out.push_back(path.empty() ? "the whole scene" : path);
}

std::string joined(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& i : items) out += (out.empty() ? "" : ", ") + i;
  return out;
}

// Root string attribute `name` of `h5`, nothing when absent; one of another kind is the file's
// fault, said as the option's.
std::optional<std::string> readOptionalString(const std::string& option, const std::string& h5, const char* name) {
  try {
    return readOptionalStringAttribute(h5, name);
  } catch (const RuntimeFailure& e) {
    throw ParameterError(option + ": " + e.what());
  }
}

// The same scene text means the same blend only if the defaults are the same: a file from
// before the blend was recorded ran the per-step default when its scene named none.
void checkSameBlend(const std::string& option, const mpm::MpmScene& scene, const std::string& h5) {
  const std::string blend = readOptionalString(option, h5, "flip_blend")
                                .value_or("(not recorded: written before the FLIP/PIC blend became per unit time)");
  const std::string ours = scene.params.flip.describe(scene.params.dx);
  if (blend != ours)
    throw ParameterError(option + ": the run in " + h5 + " blended FLIP/PIC as " + blend + ", this scene as " + ours +
                         ": going on from it would glue two different flows into one. Start a new run.");
}

}  // namespace

json readStoredScene(const std::string& option, const std::string& h5) {
  const std::optional<std::string> text = readOptionalString(option, h5, "parameters");
  if (!text) throwParameter(option, h5, "", "an mpm.h5 written by mpmsdem-run (it has no \"parameters\" attribute)");
  return scenejson::parse(*text, option + ": " + h5 + ", root attribute parameters");
}

void checkRestartScene(const mpm::MpmScene& scene, const std::string& h5) {
  const std::vector<std::string> free(std::begin(kRestartFree), std::end(kRestartFree));
  std::vector<std::string> diff;
  sceneDifferences(readStoredScene("--restart", h5), json::parse(scene.sourceJson), "", free, diff);
  if (diff.empty()) return checkSameBlend("--restart", scene, h5);
  throw ParameterError("--restart: the scene differs from the one the run in " + h5 + " was started with (changed: " +
                       joined(diff) + "). A restart continues that run: only " + joined(free) +
                       " may change. Undo the change, or start a new run in another output folder (--out).");
}

void checkFlowFromScene(const mpm::MpmScene& scene, const std::string& h5) {
  const json stored = readStoredScene("--flow-from", h5), ours = json::parse(scene.sourceJson);
  std::vector<std::string> free(std::begin(kRestartFree), std::end(kRestartFree));
  free.insert(free.end(), std::begin(kFlowFromFree), std::end(kFlowFromFree));
  std::vector<std::string> diff;
  sceneDifferences(stored, ours, "", free, diff);
  const auto cells = [](const json& j, int d) -> const json& { return element(member(member(j, "grid"), "cells"), d); };
  const auto wall = [](const json& j, const std::string& side) -> const json& {
    return member(member(j, "walls"), side);
  };
  for (int d = 0; d < 3; ++d) {
    const std::string side = std::string("+") + "xyz"[d];
    if (cells(stored, d) != cells(ours, d) && (wall(stored, side) != "free" || wall(ours, side) != "free"))
      diff.push_back("grid.cells[" + std::to_string(d) + "] (the " + side + " wall is not \"free\" in both)");
  }
  const json& theirs = member(stored, "blocks");
  const json& mine = member(ours, "blocks");
  if (!theirs.is_null() && !theirs.is_array()) diff.push_back("blocks (not a list in the run started from)");
  for (std::size_t i = 0; theirs.is_array() && i < theirs.size(); ++i) {
    if (!mine.is_array() || i >= mine.size() || theirs[i] != mine[i]) {
      diff.push_back("blocks[" + std::to_string(i) + "] (the run started from had it as this scene's block " +
                     std::to_string(i) + ")");
      continue;
    }
    const json& material = member(theirs[i], "material");
    const std::string m = material.is_string() ? material.get<std::string>() : "";
    if (member(member(stored, "block_materials"), m) != member(member(ours, "block_materials"), m))
      diff.push_back("block_materials." + m);
  }
  if (diff.empty()) return checkSameBlend("--flow-from", scene, h5);
  throw ParameterError("--flow-from: this scene's flow is not the one of the run in " + h5 + " (changed: " + joined(diff) +
                       "). It must differ only by " + joined(free) +
                       ", grid cells added on free sides, and blocks after that run's own.");
}

}  // namespace io
}  // namespace mpmsdem

#endif  // MPMSDEM_WITH_HDF5
