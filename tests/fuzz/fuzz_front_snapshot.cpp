// libFuzzer target: the front snapshot record (front_snapshot.json) as mpmsdem-run --flow-from
// reads it (coupling::readFrontSnapshot).
#include <cstddef>
#include <cstdint>
#include <string>

#include "FuzzInput.hpp"
#include "coupling/CoupledCheckpoint.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace mpmsdem;
  const std::string path = fuzz::inputFile("front_snapshot.json", data, size);
  fuzz::expectOnlyDocumentedErrors([&] { (void)coupling::readFrontSnapshot(path); });
  return 0;
}
