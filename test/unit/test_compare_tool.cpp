// acvo_compare end to end on a small synthetic sequence: the table's columns and rows, the
// speed ratio's reference row, the JSON beside it, and the errors for bad arguments.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "test_support.hpp"

namespace acvo {
namespace {

namespace fs = std::filesystem;

// Runs a tool of the package with `arguments`, stdout to `output`; returns its exit status.
int runTool(const std::string& tool, const std::string& arguments, const fs::path& output) {
  const std::string command = "'" + (test::toolsDir() / tool).string() + "' " + arguments + " > '" +
                              output.string() + "' 2>/dev/null";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::vector<std::vector<std::string>> words(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    std::istringstream w(line);
    rows.emplace_back();
    for (std::string s; w >> s;) rows.back().push_back(s);
  }
  return rows;
}

std::string readText(const fs::path& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

class CompareTool : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = test::tempDir("compare_tool");
    const fs::path log = dir_ / "synth.log";
    ASSERT_EQ(runTool("acvo_synth", "'" + (dir_ / "room").string() + "' --frames 40", log), 0);
  }
  static fs::path dir_;
};
fs::path CompareTool::dir_;

TEST_F(CompareTool, PrintsOneRowPerMethodAndTheJsonBesideIt) {
  const fs::path out = dir_ / "table.txt", json = dir_ / "table.json";
  ASSERT_EQ(runTool("acvo_compare",
                    "'" + (dir_ / "room").string() + "' --json '" + json.string() + "'", out),
            0);
  const auto rows = words(out);
  ASSERT_EQ(rows.size(), 5u) << readText(out);
  const std::vector<std::string> header = {"dataset",     "method", "rpe_t_m/s",
                                           "rpe_r_deg/s", "ate_m",  "lost",
                                           "median_ms",   "p90_ms", "vs_rgbd"};
  EXPECT_EQ(rows[0], header);
  const std::vector<std::string> methods = {"acvo", "rgbd", "icp", "rgbd_icp"};
  for (std::size_t k = 0; k < methods.size(); ++k) {
    const auto& row = rows[k + 1];
    ASSERT_EQ(row.size(), header.size()) << methods[k];
    EXPECT_EQ(row[0], "room");
    EXPECT_EQ(row[1], methods[k]);
    for (std::size_t c = 2; c < row.size(); ++c) {
      EXPECT_TRUE(std::isfinite(std::stod(row[c]))) << methods[k] << " " << header[c];
      EXPECT_GE(std::stod(row[c]), 0.0) << methods[k] << " " << header[c];
    }
    EXPECT_EQ(row[5].find('.'), std::string::npos) << "lost is a count: " << row[5];
  }
  EXPECT_EQ(rows[2][8], "1.00");  // the reference of the speed ratio
  // acvo tracks this room closely (measured about 0.01 m/s, 0.2 deg/s over 40 frames).
  EXPECT_LT(std::stod(rows[1][2]), 0.03);
  EXPECT_LT(std::stod(rows[1][3]), 0.6);
  EXPECT_EQ(rows[1][5], "0");

  const std::string j = readText(json);
  EXPECT_EQ(count(j, "\"method\":"), 4) << j;
  for (const auto& m : methods) EXPECT_EQ(count(j, "\"method\": \"" + m + "\""), 1) << m;
  for (const char* key : {"\"rpe_trans\":", "\"rpe_rot_deg\":", "\"ate\":", "\"lost\":",
                          "\"median_ms\":", "\"p90_ms\":", "\"median_vs_rgbd\": "}) {
    EXPECT_EQ(count(j, key), 4) << key;
  }
  EXPECT_EQ(count(j, "\"median_vs_rgbd\": 1,") + count(j, "\"median_vs_rgbd\": 1}"), 1) << j;
}

TEST_F(CompareTool, ASubsetOfMethodsAndItsLabel) {
  const fs::path out = dir_ / "subset.txt";
  ASSERT_EQ(runTool("acvo_compare",
                    "'" + (dir_ / "room").string() + "' --methods acvo --label paper --config '" +
                        (test::sourceDir() / "config" / "paper.yaml").string() + "' --frames 20",
                    out),
            0);
  const auto rows = words(out);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[1][1], "paper");
  EXPECT_EQ(rows[1][8], "nan");  // no RgbdOdometry row to compare the speed with
}

TEST_F(CompareTool, BadArgumentsExitWithStatusTwo) {
  const fs::path out = dir_ / "bad.txt";
  const std::string room = "'" + (dir_ / "room").string() + "'";
  EXPECT_EQ(runTool("acvo_compare", "", out), 2);
  EXPECT_EQ(runTool("acvo_compare", room + " --methods acvo,dvo", out), 2);
  EXPECT_EQ(runTool("acvo_compare", room + " --set solver.no_such_key=1", out), 2);
  EXPECT_EQ(runTool("acvo_compare", "'" + (dir_ / "missing").string() + "'", out), 2);
}

}  // namespace
}  // namespace acvo
