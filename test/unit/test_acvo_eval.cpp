// acvo_eval end to end: the built tool on the hand-checkable fixtures.
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "acvo/dataset/tum.hpp"
#include "clock_fixtures.hpp"
#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;

struct ToolRun {
  int status = -1;
  std::string output;  // stdout only
  std::string lastLine() const {
    std::istringstream lines(output);
    std::string line, last;
    while (std::getline(lines, line)) {
      if (!line.empty()) last = line;
    }
    return last;
  }
};

// Runs a shell command; stdout and the exit status.
ToolRun runCommand(const std::string& command) {
  ToolRun run;
  FILE* pipe = popen((command + " 2>/dev/null").c_str(), "r");
  if (!pipe) return run;
  char buffer[4096];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0;) {
    run.output.append(buffer, n);
  }
  const int status = pclose(pipe);
  run.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return run;
}

ToolRun runTool(const std::string& arguments, const std::string& environment = "") {
  const fs::path tool = acvo::test::toolsDir() / "acvo_eval";
  if (!fs::exists(tool)) {
    ADD_FAILURE() << tool << " is not built";
    return {};
  }
  return runCommand(environment + " '" + tool.string() + "' " + arguments);
}

std::string fixtureArgs(const std::string& gt, const std::string& est) {
  const fs::path dir = acvo::test::sourceDir() / "test/data/eval";
  return "--groundtruth '" + (dir / gt).string() + "' --estimate '" + (dir / est).string() + "'";
}

// The figure after "key=" in the summary line.
double figure(const std::string& line, const std::string& key) {
  const auto at = line.find(key + "=");
  if (at == std::string::npos) {
    ADD_FAILURE() << "no " << key << " in '" << line << "'";
    return NAN;
  }
  return std::stod(line.substr(at + key.size() + 1));
}

TEST(AcvoEval, SummaryLineCarriesTheFigures) {
  // line_drift: 10 % too fast along a straight line (test/data/eval/README.md).
  const ToolRun run = runTool(fixtureArgs("line_gt.txt", "line_drift.txt"));
  ASSERT_EQ(run.status, 0) << run.output;
  const std::string last = run.lastLine();
  EXPECT_EQ(last.rfind("rpe_trans_rmse=", 0), 0u) << last;
  EXPECT_NEAR(figure(last, "rpe_trans_rmse"), 0.05, 1e-6);
  EXPECT_NEAR(figure(last, "rpe_rot_rmse_deg"), 0.0, 1e-5);
  EXPECT_NEAR(figure(last, "ate_rmse"), 0.005 * std::sqrt(80.0), 1e-6);
  EXPECT_EQ(figure(last, "pairs"), 20.0);
  EXPECT_NE(run.output.find("translational_error.rmse 0.050000 m"), std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("absolute_translational_error.max 0.075000 m"), std::string::npos)
      << run.output;
}

TEST(AcvoEval, DeltaUnitAndJson) {
  const fs::path json = acvo::test::tempDir("acvo_eval_json") / "eval.json";
  const ToolRun run = runTool(fixtureArgs("spin_gt.txt", "spin_drift.txt") +
                              " --delta 10 --delta-unit deg --json '" + json.string() + "'");
  ASSERT_EQ(run.status, 0) << run.output;
  EXPECT_NEAR(figure(run.lastLine(), "rpe_rot_rmse_deg"), 0.035 * 180.0 / M_PI, 1e-6);
  EXPECT_EQ(figure(run.lastLine(), "pairs"), 23.0);
  std::ifstream in(json);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find("\"delta_unit\": \"deg\""), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("\"pairs\": 23"), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("\"alignment\""), std::string::npos) << text.str();
}

TEST(AcvoEval, AClockOffsetGivenOrFound) {
  // A 100 Hz reference and 30 Hz frames whose poses are those 12.3 ms after their stamps.
  const fs::path dir = acvo::test::tempDir("acvo_eval_offset");
  const std::string gt = (dir / "gt.txt").string(), est = (dir / "est.txt").string();
  acvo::writeTrajectory(gt, acvo::test::sampledCamera(100.0, 6.0, 0.0), "reference");
  acvo::writeTrajectory(est, acvo::test::sampledCamera(30.0, 6.0, 0.0123, 0.05), "frames");
  const std::string args = "--groundtruth '" + gt + "' --estimate '" + est + "'";
  const ToolRun plain = runTool(args);
  ASSERT_EQ(plain.status, 0) << plain.output;
  EXPECT_EQ(figure(plain.lastLine(), "offset"), 0.0);
  const ToolRun found = runTool(args + " --offset auto");
  ASSERT_EQ(found.status, 0) << found.output;
  EXPECT_NEAR(figure(found.lastLine(), "offset"), 0.0123, 2e-4);
  EXPECT_NE(found.output.find("# clock offset, from "), std::string::npos) << found.output;
  EXPECT_NE(found.output.find("turn_error_rms_at_offset "), std::string::npos) << found.output;
  EXPECT_LT(figure(found.lastLine(), "rpe_rot_rmse_deg"),
            0.5 * figure(plain.lastLine(), "rpe_rot_rmse_deg"));
  const ToolRun given = runTool(args + " --offset 0.0123");
  ASSERT_EQ(given.status, 0) << given.output;
  EXPECT_EQ(figure(given.lastLine(), "offset"), 0.0123);
  EXPECT_EQ(given.output.find("# clock offset"), std::string::npos) << given.output;
  // A reference of one pose per frame has no clock of its own to find; a bad value is refused.
  EXPECT_EQ(runTool(fixtureArgs("arc_gt.txt", "arc_drift.txt") + " --offset auto").status, 2);
  EXPECT_EQ(runTool(args + " --offset soon").status, 2);
  EXPECT_EQ(runTool(args + " --offset 20").status, 2);
}

TEST(AcvoEval, BadInputExitsWithTwo) {
  EXPECT_EQ(runTool(fixtureArgs("line_gt.txt", "absent.txt")).status, 2);
  EXPECT_EQ(runTool("--estimate x").status, 2);
  EXPECT_EQ(runTool(fixtureArgs("line_gt.txt", "line_drift.txt") + " --delta-unit km").status, 2);
  const fs::path bad = acvo::test::tempDir("acvo_eval_bad") / "bad.txt";
  std::ofstream(bad) << "1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 1\n";
  const fs::path dir = acvo::test::sourceDir() / "test/data/eval";
  EXPECT_EQ(runTool("--groundtruth '" + (dir / "line_gt.txt").string() + "' --estimate '" +
                    bad.string() + "'")
                .status,
            2);
  const ToolRun help = runTool("--help");
  EXPECT_EQ(help.status, 0);
  EXPECT_NE(help.output.find("Usage: acvo_eval"), std::string::npos);
}

TEST(AcvoEval, PlotWritesAPng) {
  if (std::system("/usr/bin/python3 -c 'import matplotlib' >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "/usr/bin/python3 with matplotlib is not available";
  }
  const fs::path png = acvo::test::tempDir("acvo_eval_plot") / "plot.png";
  const ToolRun run =
      runTool(fixtureArgs("arc_gt.txt", "arc_drift.txt") + " --plot '" + png.string() + "'");
  ASSERT_EQ(run.status, 0) << run.output;
  EXPECT_EQ(run.lastLine().rfind("rpe_trans_rmse=", 0), 0u);
  std::ifstream in(png, std::ios::binary);
  char signature[8] = {};
  in.read(signature, 8);
  EXPECT_EQ(std::string(signature + 1, 3), "PNG");
  EXPECT_GT(fs::file_size(png), 10000u);
}

TEST(AcvoEval, FailedPlotStillReportsAndExitsWithThree) {
  const fs::path png = acvo::test::tempDir("acvo_eval_no_plot") / "plot.png";
  const ToolRun run =
      runTool(fixtureArgs("line_gt.txt", "line_drift.txt") + " --plot '" + png.string() + "'",
              "ACVO_PLOT_SCRIPT=/nonexistent/plot_trajectories.py");
  EXPECT_EQ(run.status, 3);
  EXPECT_NEAR(figure(run.lastLine(), "rpe_trans_rmse"), 0.05, 1e-6);
  EXPECT_FALSE(fs::exists(png));
}

// scripts/window_errors on a camera turning about its y axis at 20 deg/s while moving along it
// at 0.1 m/s, against an estimate that turns 10% less and travels 20% further: over 1 s windows
// the turn ratio is 0.9, the travel ratio 1.2, the translation error 0.02 m per window, all of it
// a bias along y; an estimate with no stamp in common with the reference is refused.
TEST(WindowErrors, TurnAndTravelAgainstTheReference) {
  if (std::system("/usr/bin/python3 -c 'import numpy' >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "/usr/bin/python3 with numpy is not available";
  }
  const fs::path dir = acvo::test::tempDir("window_errors");
  const double kPi = 3.14159265358979323846;
  auto write = [&](const fs::path& path, double turn, double travel) {
    std::ofstream out(path);
    out.precision(12);
    for (int i = 0; i <= 60; ++i) {
      const double t = i / 30.0, half = 0.5 * turn * (20.0 * kPi / 180.0) * t;
      out << 100.0 + t << " 0 " << travel * 0.1 * t << " 0 0 " << std::sin(half) << " 0 "
          << std::cos(half) << "\n";
    }
  };
  write(dir / "gt.txt", 1.0, 1.0);
  write(dir / "est.txt", 0.9, 1.2);
  const std::string script = "'" + (acvo::test::sourceDir() / "scripts/window_errors").string() +
                             "' '" + (dir / "gt.txt").string() + "' ";
  const ToolRun run = runCommand(script + "'" + (dir / "est.txt").string() + "'");
  ASSERT_EQ(run.status, 0) << run.output;
  EXPECT_NE(run.output.find("windows 31, reference turn 20.00 deg"), std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("rotation error rms 2.0000 deg, turn / reference 0.900"),
            std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("translation error rms 0.0200 m, travel / reference 1.200, mean "
                            "error (x y z) +0.0000 +0.0200 +0.0000 m"),
            std::string::npos)
      << run.output;
  std::ofstream(dir / "elsewhen.txt") << "5.0 0 0 0 0 0 0 1\n6.0 0 0 0 0 0 0 1\n";
  EXPECT_EQ(runCommand(script + "'" + (dir / "elsewhen.txt").string() + "'").status, 2);
}

// The three-cornered hat of scripts/window_errors: the reference drifts 0.01 m/s along x, one
// estimate turns 10% less and travels 20% further (0.02 m per window along y), the other drifts
// 0.03 m/s along z. Their errors are orthogonal over every window, so each pair's differences
// have a mean square of exactly the sum of the two's, and the split gives each its own.
TEST(WindowErrors, SplitsTheErrorsAmongTheReferenceAndTheEstimates) {
  if (std::system("/usr/bin/python3 -c 'import numpy' >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "/usr/bin/python3 with numpy is not available";
  }
  const fs::path dir = acvo::test::tempDir("window_errors_split");
  const double kPi = 3.14159265358979323846;
  auto write = [&](const fs::path& path, double turn, double travel, double drift_x,
                   double drift_z) {
    std::ofstream out(path);
    out.precision(12);
    for (int i = 0; i <= 60; ++i) {
      const double t = i / 30.0, half = 0.5 * turn * (20.0 * kPi / 180.0) * t;
      out << 100.0 + t << " " << drift_x * t << " " << travel * 0.1 * t << " " << drift_z * t
          << " 0 " << std::sin(half) << " 0 " << std::cos(half) << "\n";
    }
  };
  write(dir / "gt.txt", 1.0, 1.0, 0.01, 0.0);
  write(dir / "a.txt", 0.9, 1.2, 0.0, 0.0);
  write(dir / "b.txt", 1.0, 1.0, 0.0, 0.03);
  const std::string script = "'" + (acvo::test::sourceDir() / "scripts/window_errors").string() +
                             "' '" + (dir / "gt.txt").string() + "' ";
  const ToolRun run =
      runCommand(script + "'" + (dir / "a.txt").string() + "' '" + (dir / "b.txt").string() + "'");
  ASSERT_EQ(run.status, 0) << run.output;
  EXPECT_NE(run.output.find("the reference: rotation 0.0000 deg, translation 0.0100 m"),
            std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("a.txt: rotation 2.0000 deg, translation 0.0200 m"), std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("b.txt: rotation 0.0000 deg, translation 0.0300 m"), std::string::npos)
      << run.output;
  // One estimate alone gives no split: two sources cannot be told apart.
  const ToolRun one = runCommand(script + "'" + (dir / "a.txt").string() + "'");
  ASSERT_EQ(one.status, 0) << one.output;
  EXPECT_EQ(one.output.find("three-cornered hat"), std::string::npos) << one.output;
}

}  // namespace
