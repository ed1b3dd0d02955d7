// libFuzzer target: the driver's JSON scene as mpmsdem-run reads it (apps/mpmsdem-run.cpp):
// mpm::parseScene (what loadScene calls with the file's text: grid, material, particles with
// their mesh files, terrain given inline or as an ESRI ASCII file, flow probes, run keys), what
// the driver derives from it before the solver exists (sceneSizeDescription, the blend's
// description), then coupling::parseBlocks on the scene as parsed (block materials, boxes and
// core tables, terrain_material). Relative mesh and terrain paths are taken from
// tests/fuzz/data (block.obj, block.stl, block_binary.stl, ground.asc).
#include <cstddef>
#include <cstdint>
#include <string>

#include "FuzzInput.hpp"
#include "coupling/CoupledScene.hpp"
#include "scene/MpmScene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace mpmsdem;
  const std::string text(reinterpret_cast<const char*>(data), size);
  fuzz::expectOnlyDocumentedErrors([&] {
    const mpm::MpmScene scene = mpm::parseScene(text, "scene.json", MPMSDEM_FUZZ_DATA);
    (void)mpm::sceneSizeDescription(scene);
    (void)scene.params.flip.describe(scene.params.dx);
    (void)coupling::parseBlocks(scene.sourceJson);
  });
  return 0;
}
