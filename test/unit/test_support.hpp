// Helpers shared by the unit tests: where the repository and the shared data live.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

namespace acvo::test {

// The repository's root (for test/data fixtures and config/).
inline std::filesystem::path sourceDir() { return ACVO_SOURCE_DIR; }

// ../shared/data beside the repository, or ACVO_SHARED_DATA when set. Empty when absent:
// tests that need it call GTEST_SKIP() with a reason, as a user's machine has no such folder.
// With ACVO_REQUIRE_SHARED_DATA=1 (.ci/run) an absent folder is also a failure of the test that
// asked: CI can never pass with the real-data tests quietly skipped.
inline std::filesystem::path sharedDataDir() {
  std::filesystem::path p = ACVO_SHARED_DATA_DIR;
  if (const char* env = std::getenv("ACVO_SHARED_DATA")) p = env;
  if (std::filesystem::is_directory(p)) return p;
  const char* require = std::getenv("ACVO_REQUIRE_SHARED_DATA");
  if (require && std::string(require) == "1") {
    ADD_FAILURE() << "ACVO_REQUIRE_SHARED_DATA=1 and the shared data folder " << p
                  << " is absent: this test needs its real frames";
  }
  return {};
}

// Folder of the built tools (acvo_synth, acvo_tum, acvo_eval).
inline std::filesystem::path toolsDir() { return ACVO_TOOLS_DIR; }

// A fresh temporary folder for one test.
inline std::filesystem::path tempDir(const std::string& name) {
  auto p = std::filesystem::temp_directory_path() / ("acvo_test_" + name);
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p;
}

inline void writeText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
}

// The message of the std::runtime_error `f` throws (fails the test when it throws none).
template <typename F>
std::string errorOf(F f) {
  try {
    f();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no std::runtime_error thrown";
  return {};
}

}  // namespace acvo::test
