// The sanitizer run's filter (test/plain_only_tests.txt) against the binaries CMakeLists.txt
// leaves out of the sanitizer build (ACVO_PLAIN_ONLY_TESTS): a test added to one of those
// binaries that the filter does not name would otherwise run under no sanitizer, and nothing
// would say so.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "test_support.hpp"

namespace acvo {
namespace {

namespace fs = std::filesystem;

// The patterns of test/plain_only_tests.txt joined as a gtest filter ("A.*:B.c").
std::string plainOnlyFilter() {
  std::ifstream in(test::sourceDir() / "test" / "plain_only_tests.txt");
  std::string filter;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    filter += (filter.empty() ? "" : ":") + line;
  }
  return filter;
}

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::istringstream in(text);
  for (std::string part; std::getline(in, part, separator);) {
    if (!part.empty()) parts.push_back(part);
  }
  return parts;
}

// The tests `binary --gtest_list_tests` names under `filter` (gtest's listing: a suite's name at
// the line's start, each of its tests indented by two spaces).
std::vector<std::string> listedTests(const fs::path& binary, const std::string& filter) {
  const std::string command =
      "'" + binary.string() + "' --gtest_list_tests '--gtest_filter=" + filter + "' 2>&1";
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(command.c_str(), "r"), pclose);
  std::vector<std::string> tests;
  if (!pipe) return tests;
  std::string suite, line;
  std::array<char, 512> buffer{};
  while (fgets(buffer.data(), int(buffer.size()), pipe.get())) {
    line = buffer.data();
    if (!line.empty() && line.back() == '\n') line.pop_back();
    if (line.rfind("  ", 0) == 0) {
      tests.push_back(suite + line.substr(2, line.find(' ', 2) - 2));
    } else {
      suite = line;
    }
  }
  return tests;
}

TEST(PlainOnly, TheSanitizerFilterLeavesThePlainOnlyBinariesNothingToRun) {
  const std::string filter = plainOnlyFilter();
  ASSERT_FALSE(filter.empty()) << "test/plain_only_tests.txt names no test";
  const std::vector<std::string> binaries = split(ACVO_PLAIN_ONLY_TESTS, ',');
  ASSERT_FALSE(binaries.empty());
  for (const auto& name : binaries) {
    const fs::path binary = fs::path(ACVO_TESTS_DIR) / name;
    ASSERT_TRUE(fs::exists(binary)) << binary << " is not built";
    // The listing works at all: every test of the binary without a filter.
    EXPECT_FALSE(listedTests(binary, "*").empty()) << name << " lists no test";
    for (const auto& test : listedTests(binary, "-" + filter)) {
      ADD_FAILURE() << name << " is not built under the sanitizers, but its test " << test
                    << " is not in test/plain_only_tests.txt: it would run under no sanitizer."
                    << " Name it there, or move it to a binary the sanitizer build keeps";
    }
  }
}

TEST(PlainOnly, TheFilterKeepsTheTestsItDoesNotName) {
  // The check above cannot pass for a listing that ignores the filter: this binary's own test of
  // the plain-only list is left out by it, and a pattern it does not hold keeps it.
  const fs::path self = fs::path(ACVO_TESTS_DIR) / "test_plain_only";
  EXPECT_TRUE(listedTests(self, "-" + plainOnlyFilter()).empty());
  const auto kept = listedTests(self, "-Sequences.*");
  EXPECT_EQ(kept.size(), 2u);
}

}  // namespace
}  // namespace acvo
