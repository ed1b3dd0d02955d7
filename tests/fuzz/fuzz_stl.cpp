// libFuzzer target: an STL particle mesh, ASCII or binary (the reader tells them apart by the
// size a binary file's triangle count implies), as a scene's "particles" entry reads it
// (mpm::parseScene: io::readMesh, then mpm::checkSeedMesh's closedness and orientation checks).
#include <cstddef>
#include <cstdint>

#include "FuzzMesh.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  mpmsdem::fuzz::readAndCheckMesh("input.stl", data, size);
  return 0;
}
