// Shared by the libFuzzer targets of tests/fuzz (README.md there): the fuzz input as a file for
// the readers that take a path, and the one place that says which exceptions a reader may throw.
#pragma once
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "common/Error.hpp"

namespace mpmsdem {
namespace fuzz {

// A scratch folder of this process (removed at a normal exit), created on first use.
inline const std::filesystem::path& scratchDir() {
  struct Dir {
    std::filesystem::path path;
    Dir() {
      path = std::filesystem::temp_directory_path() / ("mpmsdem-fuzz-" + std::to_string(::getpid()));
      std::filesystem::create_directories(path);
    }
    ~Dir() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  };
  static const Dir dir;
  return dir.path;
}

// Writes the input to <scratch>/<name> (one path per process and name, rewritten each run) and
// returns that path.
inline std::string inputFile(const std::string& name, const std::uint8_t* data, std::size_t size) {
  const std::string path = (scratchDir() / name).string();
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();  // the fuzzing machine's fault, not the reader's
  if (size && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
  return path;
}

// Runs `read`; the readers' documented refusals (common/Error.hpp) are the expected outcome of
// a bad input. Anything else escapes: another exception, a crash, a leak or undefined behaviour
// is a finding.
template <typename F>
void expectOnlyDocumentedErrors(F&& read) {
  try {
    read();
  } catch (const ParameterError&) {
  } catch (const RuntimeFailure&) {
  }
}

}  // namespace fuzz
}  // namespace mpmsdem
