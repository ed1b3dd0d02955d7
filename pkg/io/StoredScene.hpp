// What mpmsdem-run --restart and --flow-from check of the run they go on from, as its mpm.h5
// recorded it (pkg/io/Hdf5Writer.hpp): the scene it was started with (root attribute
// "parameters", its JSON text) and its FLIP/PIC blend ("flip_blend"), against the scene given
// now. The file may come from elsewhere or be damaged: its scene may be any JSON, and every
// refusal is a ParameterError naming the option, the file and what differs or is wrong.
// Builds with HDF5 only (CMakeLists.txt: MPMSDEM_WITH_HDF5).
#pragma once
#include <nlohmann/json.hpp>

#include <string>

#include "scene/MpmScene.hpp"

namespace mpmsdem {
namespace io {

// The scene stored in the mpm.h5 `h5` of an earlier run (its "parameters"), for `option`
// ("--restart", "--flow-from"): text that is not JSON, or nested deeper than a scene may be
// (scenejson::parse), is refused like an absent or unreadable attribute.
nlohmann::json readStoredScene(const std::string& option, const std::string& h5);

// --restart: the scene must be the one stored in `h5` but for the keys a restart may change (how
// long to run and what to write, where, and on which backend), with the blend the run had.
void checkRestartScene(const mpm::MpmScene& scene, const std::string& h5);

// --flow-from: this scene must run the flow of the one stored in `h5` (every key a restart
// keeps but grid cells, which may differ only on a side whose wall is "free": the grid's origin
// and spacing stay, so a point sees the same nodes), and begin with its blocks, in its order,
// with the same materials.
void checkFlowFromScene(const mpm::MpmScene& scene, const std::string& h5);

}  // namespace io
}  // namespace mpmsdem
