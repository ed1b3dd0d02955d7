// libFuzzer target: an ESRI ASCII grid as a scene's "terrain": {"file": ...} reads it
// (mpm::parseScene: io::readEsriAscii). A raster the reader accepts must be a terrain the solver
// takes: TerrainSpec::validate refusing it would be the reader's fault, so it is not caught.
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>

#include "FuzzInput.hpp"
#include "input/TerrainRaster.hpp"
#include "mpm/MpmTypes.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace mpmsdem;
  const std::string path = fuzz::inputFile("input.asc", data, size);
  io::TerrainRaster r;
  bool read = false;
  fuzz::expectOnlyDocumentedErrors([&] {
    r = io::readEsriAscii(path);
    read = true;
  });
  if (!read) return 0;
  mpmsdem::TerrainSpec t;
  t.nx = r.nx;
  t.ny = r.ny;
  t.x0 = r.x0;
  t.y0 = r.y0;
  t.spacing = r.spacing;
  t.heights = std::move(r.heights);
  t.validate();
  return 0;
}
