// acvo_compare end to end on a small synthetic sequence: the table's columns and rows (a row
// per method and setting, the best peer setting named), the speed ratio's reference row, the
// JSON beside it, threads, repeats and starts, and the errors for bad arguments. Whether the
// peers are set up right is test_peers' question.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "acvo/cloud/camera.hpp"
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

// The table's rows as words; the comment line above the header ("# ...") is left out.
std::vector<std::vector<std::string>> words(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind('#', 0) == 0) continue;
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

TEST_F(CompareTool, PrintsOneRowPerMethodAndSettingAndTheJsonBesideIt) {
  const fs::path out = dir_ / "table.txt", json = dir_ / "table.json";
  ASSERT_EQ(runTool("acvo_compare",
                    "'" + (dir_ / "room").string() + "' --json '" + json.string() + "'", out),
            0);
  const std::string text = readText(out);
  EXPECT_EQ(text.rfind("# acvo on 1_thread;", 0), 0u) << "the header says acvo's threads";
  const auto rows = words(out);
  // acvo on one thread; each OpenCV odometry at 4 m and 10 m, without and with the last motion
  // as its initial guess, and its best setting again.
  std::vector<std::pair<std::string, std::string>> expected = {{"acvo", "1_thread"}};
  for (const std::string peer : {"rgbd", "icp", "rgbd_icp"}) {
    for (const char* setting : {"4m", "4m_guess", "10m", "10m_guess"}) {
      expected.emplace_back(peer, setting);
    }
    expected.emplace_back(peer + "_best", "");
  }
  ASSERT_EQ(rows.size(), expected.size() + 1) << text;
  const std::vector<std::string> header = {
      "dataset", "method", "setting",   "rpe_t_m/s", "rpe_r_deg/s", "ate_m",
      "lost",    "median_ms", "cpu_ms", "spread_%",  "vs_rgbd"};
  EXPECT_EQ(rows[0], header);
  for (std::size_t k = 0; k < expected.size(); ++k) {
    const auto& row = rows[k + 1];
    ASSERT_EQ(row.size(), header.size()) << text;
    EXPECT_EQ(row[0], "room");
    EXPECT_EQ(row[1], expected[k].first);
    if (!expected[k].second.empty()) {
      EXPECT_EQ(row[2], expected[k].second);
    }
    for (std::size_t c = 3; c < row.size(); ++c) {
      EXPECT_TRUE(std::isfinite(std::stod(row[c]))) << row[1] << " " << header[c];
      EXPECT_GE(std::stod(row[c]), 0.0) << row[1] << " " << header[c];
    }
    EXPECT_EQ(row[6].find('.'), std::string::npos) << "lost is a count: " << row[6];
    EXPECT_EQ(row[9], "0.0") << "one run: no spread";
  }
  // A best row repeats one of its method's settings, figure for figure.
  for (std::size_t k : {5u, 10u, 15u}) {
    const auto& best = rows[k + 1];
    bool repeats = false;
    for (std::size_t s = k - 3; s <= k; ++s) {
      repeats = repeats || std::equal(best.begin() + 2, best.end(), rows[s].begin() + 2);
    }
    EXPECT_TRUE(repeats) << best[1];
  }
  // The speed reference: the best RgbdOdometry setting, 1.00.
  EXPECT_EQ(rows[6][10], "1.00");
  // acvo tracks this room closely (measured about 0.01 m/s, 0.2 deg/s over 40 frames).
  EXPECT_LT(std::stod(rows[1][3]), 0.03);
  EXPECT_LT(std::stod(rows[1][4]), 0.6);
  EXPECT_EQ(rows[1][6], "0");

  const std::string j = readText(json);
  EXPECT_EQ(count(j, "\"method\":"), 16) << j;
  EXPECT_EQ(count(j, "\"best\": true"), 3) << j;
  for (const char* key : {"\"rpe_trans\":", "\"rpe_rot_deg\":", "\"ate\":", "\"lost\":",
                          "\"median_ms\":", "\"cpu_median_ms\":", "\"median_ms_runs\":",
                          "\"spread_percent\":", "\"median_vs_rgbd\": ", "\"setting\":"}) {
    EXPECT_EQ(count(j, key), 16) << key;
  }
}

// --threads gives one acvo row per value, with the same trajectory (the reduction order does not
// depend on the threads); --repeat times every run; one --peer-max-depth and one --peer-guess
// give one setting, and no best row.
TEST_F(CompareTool, ThreadsRepeatAndOneDepth) {
  const fs::path out = dir_ / "threads.txt", traj = dir_ / "traj";
  fs::create_directories(traj);
  ASSERT_EQ(runTool("acvo_compare",
                    "'" + (dir_ / "room").string() +
                        "' --methods acvo,rgbd --threads 1,0 --repeat 2 --peer-max-depth 4 "
                        "--peer-guess last "
                        "--frames 20 --trajectories '" + traj.string() + "'",
                    out),
            0);
  const std::string text = readText(out);
  EXPECT_EQ(text.rfind("# acvo on 1_thread,all_cores;", 0), 0u) << text;
  EXPECT_NE(text.find("median of 2 runs"), std::string::npos) << text;
  const auto rows = words(out);
  ASSERT_EQ(rows.size(), 4u) << text;
  EXPECT_EQ(rows[1][2], "1_thread");
  EXPECT_EQ(rows[2][2], "all_cores");
  EXPECT_EQ(rows[3][1], "rgbd");
  EXPECT_EQ(rows[3][2], "4m_guess");
  EXPECT_EQ(rows[3][10], "1.00");
  for (std::size_t c = 3; c < 7; ++c) EXPECT_EQ(rows[1][c], rows[2][c]) << "column " << c;
  const auto poses_1 = words(traj / "room-acvo-1_thread.txt");
  EXPECT_EQ(poses_1.size(), 20u);
  EXPECT_EQ(poses_1, words(traj / "room-acvo-all_cores.txt"));
  EXPECT_TRUE(fs::exists(traj / "room-rgbd-4m_guess.txt"));
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
  EXPECT_EQ(rows[1][10], "nan");  // no RgbdOdometry row to compare the speed with
}

// --offset: a given one is named in the header line and reaches the JSON; auto refuses a
// reference of one pose per frame (the synthetic sequence's, which shares the frames' clock) and
// says so below the table, the figures then at offset 0.
TEST_F(CompareTool, AClockOffsetGivenOrRefused) {
  const std::string room = "'" + (dir_ / "room").string() + "' --methods acvo --frames 20";
  const fs::path plain = dir_ / "offset_plain.txt", given = dir_ / "offset_given.txt";
  const fs::path json = dir_ / "offset_given.json", automatic = dir_ / "offset_auto.txt";
  const fs::path auto_json = dir_ / "offset_auto.json";
  ASSERT_EQ(runTool("acvo_compare", room, plain), 0);
  ASSERT_EQ(runTool("acvo_compare", room + " --offset 0.01 --json '" + json.string() + "'", given),
            0);
  ASSERT_EQ(runTool("acvo_compare", room + " --offset auto --json '" + auto_json.string() + "'",
                    automatic),
            0);
  EXPECT_EQ(count(readText(plain), "against the reference's"), 0);
  EXPECT_EQ(count(readText(given), "the frames' stamps +10.0 ms against the reference's"), 1);
  EXPECT_EQ(count(readText(json), "\"offset_s\": 0.01, \"offset_found\": false"), 1);
  EXPECT_EQ(count(readText(auto_json),
                  "\"offset_found\": false, \"offset_refused\": \"clock offset: the reference"),
            1);
  const std::string text = readText(automatic);
  EXPECT_EQ(count(text, "# room: evaluated at offset 0: clock offset: the reference is sampled"),
            1)
      << text;
  const auto a = words(automatic), p = words(plain);
  ASSERT_EQ(a.size(), 2u);
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(a[1][3], p[1][3]);  // the translation error, at offset 0 both
  EXPECT_EQ(a[1][4], p[1][4]);
}

// --stride 3 uses frames 0, 3, 6, ...: the trajectory has their stamps (--frames counts the
// frames used), and the dataset is named for the stride.
TEST_F(CompareTool, StrideUsesEveryKthFrame) {
  const fs::path out = dir_ / "stride.txt", traj = dir_ / "traj_stride";
  fs::create_directories(traj);
  ASSERT_EQ(runTool("acvo_compare",
                    "'" + (dir_ / "room").string() +
                        "' --methods acvo --stride 3 --frames 10 --trajectories '" +
                        traj.string() + "'",
                    out),
            0);
  const auto rows = words(out);
  ASSERT_EQ(rows.size(), 2u) << readText(out);
  EXPECT_EQ(rows[1][0], "room_every3");
  EXPECT_EQ(rows[1][6], "0");  // lost frames: a tenth of a second apart is well within the basin
  const auto poses = words(traj / "room_every3-acvo.txt");
  const auto stamps = words(dir_ / "room" / "rgb.txt");
  std::vector<std::string> expected;
  for (const auto& line : stamps) {
    if (!line.empty() && line[0][0] != '#') expected.push_back(line[0]);
  }
  ASSERT_EQ(poses.size(), 10u);
  ASSERT_GE(expected.size(), 28u);
  for (std::size_t i = 0; i < poses.size(); ++i) EXPECT_EQ(poses[i][0], expected[3 * i]) << i;
  EXPECT_EQ(runTool("acvo_compare", "'" + (dir_ / "room").string() + "' --stride 0", out), 2);
}

// --camera reaches every method: the room's own camera with its focal length 5% longer turns
// acvo's error of a fraction of a millimetre per second into centimetres (0.0002 -> 0.0363 m/s
// when written) and ICPOdometry's to over four times its own (0.0118 -> 0.0551). The header and
// the JSON name the camera; one that is neither a file nor a known name is a bad argument.
TEST_F(CompareTool, ACameraGivenReachesEveryMethod) {
  const fs::path room = dir_ / "room", camera = dir_ / "focal_5_percent_long.yaml";
  Camera long_focal = loadCameraYaml((room / "camera.yaml").string());
  long_focal.fx *= 1.05;
  long_focal.fy *= 1.05;
  saveCameraYaml(camera.string(), long_focal);
  const std::string common = "'" + room.string() + "' --methods acvo,icp --peer-max-depth 10 --peer-guess none";
  const fs::path own = dir_ / "own_camera.txt", given = dir_ / "given_camera.txt";
  const fs::path json = dir_ / "given_camera.json";
  ASSERT_EQ(runTool("acvo_compare", common, own), 0);
  ASSERT_EQ(runTool("acvo_compare",
                    common + " --camera '" + camera.string() + "' --json '" + json.string() + "'",
                    given),
            0);
  const auto a = words(own), b = words(given);
  ASSERT_EQ(a.size(), 3u) << readText(own);
  ASSERT_EQ(b.size(), 3u) << readText(given);
  ASSERT_EQ(b[1][1], "acvo");
  ASSERT_EQ(b[2][1], "icp");
  EXPECT_GT(std::stod(b[1][3]), 10.0 * std::max(std::stod(a[1][3]), 1e-4));
  EXPECT_GT(std::stod(b[1][3]), 0.01);
  EXPECT_GT(std::stod(b[2][3]), 2.0 * std::stod(a[2][3]));
  const std::string given_text = readText(given);
  const std::string header = given_text.substr(0, given_text.find('\n'));
  EXPECT_NE(header.find("; camera: " + camera.string()), std::string::npos) << header;
  EXPECT_EQ(readText(own).find("camera:"), std::string::npos);
  EXPECT_NE(readText(json).find("\"camera\": \"" + camera.string() + "\""), std::string::npos);
  EXPECT_EQ(runTool("acvo_compare", common + " --camera '" + (dir_ / "none.yaml").string() + "'",
                    given),
            2);
}

// Colour taken 10 ms after the depth: acvo's poses carry the colour's stamps, ICPOdometry's (of
// depth alone) the depth's; each is evaluated against the truth at its own stamps.
TEST_F(CompareTool, APoseOfDepthAloneCarriesTheDepthsStamp) {
  const fs::path data = dir_ / "colour_later", out = dir_ / "later.txt",
                 traj = dir_ / "traj_later";
  fs::create_directories(traj);
  ASSERT_EQ(runTool("acvo_synth",
                    "'" + data.string() +
                        "' --frames 12 --width 160 --height 120 --colour-delay 0.01",
                    dir_ / "synth_later.log"),
            0);
  ASSERT_EQ(runTool("acvo_compare",
                    "'" + data.string() +
                        "' --methods acvo,icp --peer-max-depth 10 --peer-guess none --trajectories '" +
                        traj.string() + "'",
                    out),
            0)
      << readText(out);
  const auto assoc = words(data / "associations.txt");
  const auto acvo = words(traj / "colour_later-acvo.txt");
  const auto icp = words(traj / "colour_later-icp-10m.txt");
  ASSERT_EQ(assoc.size(), 12u);
  ASSERT_EQ(acvo.size(), 12u);
  ASSERT_EQ(icp.size(), 12u);
  for (std::size_t i = 0; i < assoc.size(); ++i) {
    EXPECT_EQ(acvo[i][0], assoc[i][0]) << i;  // the colour's stamp
    EXPECT_EQ(icp[i][0], assoc[i][2]) << i;   // the depth's
  }
}

// The first number after `"key": ` (or after its list's "[") in the JSON, from `from` on.
double jsonNumberAfter(const std::string& json, const std::string& key, std::size_t from = 0) {
  auto at = json.find("\"" + key + "\": ", from);
  if (at == std::string::npos) return NAN;
  at += key.size() + 4;
  if (json[at] == '[') ++at;
  return std::stod(json.substr(at));
}

// --starts 0,6 runs every row from frame 0 and again from frame 6 (34 frames each: RPE over 1 s
// needs 31): each error is the mean of the two runs' (each as a run from that start alone gives
// it), the JSON keeps both, the trajectories are written per start, and the times of both runs
// are pooled.
TEST_F(CompareTool, SeveralStartsGiveTheMeanOfTheirRuns) {
  const std::string room = "'" + (dir_ / "room").string() +
                           "' --methods acvo,rgbd --peer-max-depth 4 --peer-guess none --frames 34";
  const fs::path both = dir_ / "starts.txt", json = dir_ / "starts.json";
  const fs::path traj = dir_ / "traj_starts";
  fs::create_directories(traj);
  std::vector<std::string> single(2);
  for (std::size_t k = 0; k < 2; ++k) {
    const fs::path j = dir_ / ("start" + std::to_string(k) + ".json");
    ASSERT_EQ(runTool("acvo_compare",
                      room + " --starts " + (k ? "6" : "0") + " --json '" + j.string() + "'",
                      dir_ / ("start" + std::to_string(k) + ".txt")),
              0);
    single[k] = readText(j);
  }
  const std::string header = readText(dir_ / "start1.txt");
  EXPECT_NE(header.substr(0, header.find('\n')).find("; from frame 6"), std::string::npos)
      << header;
  ASSERT_EQ(runTool("acvo_compare",
                    room + " --starts 0,6 --json '" + json.string() + "' --trajectories '" +
                        traj.string() + "'",
                    both),
            0);
  const std::string text = readText(both), j = readText(json);
  EXPECT_NE(text.find("errors: the mean over the runs from frames 0,6, lost: their sum"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("median of 2 runs"), std::string::npos) << text;
  const auto rows = words(both);
  ASSERT_EQ(rows.size(), 3u) << text;
  EXPECT_EQ(rows[1][0], "room");
  EXPECT_EQ(j.find("\"starts\": [0, 6]"), j.find("\"starts\":")) << j;
  for (const std::string key : {"rpe_trans", "rpe_rot_deg", "ate"}) {
    const double a = jsonNumberAfter(single[0], key), b = jsonNumberAfter(single[1], key);
    ASSERT_TRUE(std::isfinite(a) && std::isfinite(b)) << key;
    EXPECT_NE(a, b) << key << ": the two starts are different runs";
    EXPECT_NEAR(jsonNumberAfter(j, key), 0.5 * (a + b), 1e-5 * (a + b)) << key;
    EXPECT_NEAR(jsonNumberAfter(j, key + "_starts"), a, 1e-6 * a) << key;
  }
  EXPECT_EQ(jsonNumberAfter(j, "frames"), 68.0);
  EXPECT_EQ(count(j, "\"vs_rgbd_runs\": [1, 1]"), 1) << "the yardstick, once per start";
  const auto from0 = words(traj / "room-acvo-from0.txt");
  const auto from6 = words(traj / "room-acvo-from6.txt");
  ASSERT_EQ(from0.size(), 34u);
  ASSERT_EQ(from6.size(), 34u);
  EXPECT_EQ(from6[0][0], from0[6][0]) << "the run from frame 6 begins at its stamp";
  EXPECT_EQ(runTool("acvo_compare", room + " --starts 0,1000", both), 2) << "no frames there";
}

TEST_F(CompareTool, BadArgumentsExitWithStatusTwo) {
  const fs::path out = dir_ / "bad.txt";
  const std::string room = "'" + (dir_ / "room").string() + "'";
  EXPECT_EQ(runTool("acvo_compare", "", out), 2);
  EXPECT_EQ(runTool("acvo_compare", room + " --methods acvo,dvo", out), 2);
  EXPECT_EQ(runTool("acvo_compare", room + " --set solver.no_such_key=1", out), 2);
  EXPECT_EQ(runTool("acvo_compare", room + " --threads -1", out), 2);
  EXPECT_EQ(runTool("acvo_compare", room + " --repeat 0", out), 2);
  EXPECT_EQ(runTool("acvo_compare", room + " --peer-max-depth 0", out), 2);
  EXPECT_EQ(runTool("acvo_compare", room + " --peer-guess previous", out), 2);
  EXPECT_EQ(runTool("acvo_compare", room + " --offset soon", out), 2);
  EXPECT_EQ(runTool("acvo_compare", room + " --starts -1", out), 2);
  EXPECT_EQ(runTool("acvo_compare", room + " --starts ,", out), 2);
  EXPECT_EQ(runTool("acvo_compare", "'" + (dir_ / "missing").string() + "'", out), 2);
}

}  // namespace
}  // namespace acvo
