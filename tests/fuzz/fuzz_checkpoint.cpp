// libFuzzer target: the coupled restart checkpoint (coupled.checkpoint.json) as
// mpmsdem-run --restart and --flow-from read it (coupling::readCheckpoint).
#include <cstddef>
#include <cstdint>
#include <string>

#include "FuzzInput.hpp"
#include "coupling/CoupledCheckpoint.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace mpmsdem;
  const std::string path = fuzz::inputFile("coupled.checkpoint.json", data, size);
  fuzz::expectOnlyDocumentedErrors([&] { (void)coupling::readCheckpoint(path); });
  return 0;
}
