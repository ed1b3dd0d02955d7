// libFuzzer target: a Wavefront OBJ particle mesh as a scene's "particles" entry reads it
// (mpm::parseScene: io::readMesh, then mpm::checkSeedMesh's closedness and orientation checks).
#include <cstddef>
#include <cstdint>

#include "FuzzMesh.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  mpmsdem::fuzz::readAndCheckMesh("input.obj", data, size);
  return 0;
}
