// What the reader-regression tests of tests/cpp/mpm and tests/cpp/coupling share: a file of
// given bytes to read, and the check that a reader refuses it with a message naming the fault.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>

#include <unistd.h>

#include "common/Error.hpp"

namespace mpmsdem {
namespace testutil {

// `bytes` written to a file of the temporary folder; the process id in its name keeps test
// processes that ctest runs side by side (or two build folders' tests) off each other's files.
inline std::string writeFile(const std::string& name, const std::string& bytes) {
  const std::string path =
      (std::filesystem::temp_directory_path() / (std::to_string(::getpid()) + "_" + name)).string();
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

// `read` must throw an `Error` (a ParameterError unless named, e.g. the RuntimeFailure the HDF5
// readers refuse a file with) whose message holds every one of `words`.
template <typename Error = ParameterError, typename F>
void expectRefused(F&& read, std::initializer_list<std::string> words) {
  try {
    read();
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    for (const std::string& w : words) EXPECT_NE(std::string(e.what()).find(w), std::string::npos) << e.what();
  }
}

}  // namespace testutil
}  // namespace mpmsdem
