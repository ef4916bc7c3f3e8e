// acvo_compare: acvo against OpenCV contrib's RGB-D odometries (RgbdOdometry, ICPOdometry,
// RgbdICPOdometry) on TUM-format folders, the same frames in the same run: RPE over 1 s, ATE,
// lost frames and time per frame, as one table (and JSON).
//
// The peers run as a user would run them: OpenCV's default parameters, the dataset's
// intrinsics, depth in metres, the previous frame's motion as the initial guess, and each
// frame's pyramids built once and reused when it becomes the previous frame.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/eigen.hpp>  // after Eigen's headers
#include <opencv2/imgproc.hpp>
#include <opencv2/rgbd.hpp>

#include "acvo/evaluation.hpp"
#include "acvo/odometry.hpp"
#include "acvo/params.hpp"
#include "acvo/tum.hpp"
#include "tool_support.hpp"

namespace {

constexpr const char* kDescription =
    R"(Runs acvo and OpenCV contrib's RgbdOdometry, ICPOdometry and RgbdICPOdometry over TUM RGB-D
folders (rgb.txt, depth.txt, associations.txt, groundtruth.txt, camera.yaml) and prints one
table: RPE over 1 s (translation m/s, rotation deg/s), ATE (m), lost frames, median and 90th
percentile milliseconds per frame, and the median time as a ratio of RgbdOdometry's.
Every method sees the same decoded frames; times cover the odometry call only (acvo: cloud
building and registration; OpenCV: grey conversion, pyramids and registration).
)";

constexpr const char* kFooter = "Exit status: 0 success, 2 bad arguments or input.";

struct Options {
  std::vector<std::string> datasets, methods{"acvo", "rgbd", "icp", "rgbd_icp"}, sets;
  std::string config, label = "acvo", json, trajectories;
  long frames = -1;
};

// The command line into `o`; nullopt to go on, else the exit status.
std::optional<int> parseOptions(CLI::App& app, Options& o, int argc, char** argv) {
  acvo::tools::setUpCommandLine(app, kFooter);
  app.add_option("DATASET_DIR", o.datasets, "TUM RGB-D folders")->type_name("")->required();
  app.add_option("--methods", o.methods, "comma-separated subset of acvo,rgbd,icp,rgbd_icp")
      ->type_name("LIST")
      ->delimiter(',')
      ->allow_extra_args(false)
      ->default_str("all")
      ->check(CLI::IsMember({"acvo", "rgbd", "icp", "rgbd_icp"}).description(""));
  app.add_option("--config", o.config, "acvo parameters (default: built in, as config/acvo.yaml)")
      ->type_name("FILE");
  app.add_option("--set", o.sets, "override one acvo parameter (repeatable)")
      ->type_name("SECTION.KEY=VALUE")
      ->allow_extra_args(false);
  app.add_option("--label", o.label, "name of the acvo row")
      ->type_name("NAME")
      ->capture_default_str();
  app.add_option("--frames", o.frames, "use the first N frames of each dataset")
      ->type_name("N")
      ->check(
          acvo::tools::numberIn(0L, std::numeric_limits<long>::max(), "a non-negative integer"));
  app.add_option("--json", o.json, "write every figure as JSON")->type_name("FILE");
  app.add_option("--trajectories", o.trajectories,
                 "write each estimate as DIR/<dataset>-<method>.txt")
      ->type_name("DIR");
  if (const auto status = acvo::tools::parseCommandLine(app, argc, argv)) return status;
  // --methods "" or ",": CLI11 leaves the list empty.
  if (o.methods.empty()) return acvo::tools::usageError(app, "--methods is empty");
  return std::nullopt;
}

// One method's run over one dataset.
struct Run {
  std::string dataset, method;
  acvo::Trajectory trajectory;
  std::vector<double> ms;  // per registered frame
  long lost = 0;
  double rpe_trans = NAN, rpe_rot = NAN, ate = NAN;
};

// A frame-to-frame odometry: returns false when the frame is lost; `pose` is the camera pose.
using Step = std::function<bool(const acvo::Frame&, Eigen::Isometry3d& pose)>;

Step acvoStep(const acvo::Params& params, const Eigen::Isometry3d& start) {
  auto odometry = std::make_shared<acvo::Odometry>(params);
  odometry->reset(start);
  return [odometry](const acvo::Frame& f, Eigen::Isometry3d& pose) {
    const acvo::OdometryResult r = odometry->process(f);
    pose = r.pose;
    return r.tracking != acvo::Tracking::kLost && r.tracking != acvo::Tracking::kBadFrame;
  };
}

cv::Ptr<cv::rgbd::Odometry> makePeer(const std::string& method, const acvo::Camera& c) {
  const cv::Mat K = (cv::Mat_<float>(3, 3) << c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
  if (method == "rgbd") return cv::rgbd::RgbdOdometry::create(K);
  if (method == "icp") return cv::rgbd::ICPOdometry::create(K);
  return cv::rgbd::RgbdICPOdometry::create(K);
}

// OpenCV's odometry: compute(src = previous, dst = current) gives Rt with dst_p = Rt src_p,
// so the current camera's pose is pose_prev * Rt^-1; the previous Rt is the guess.
Step peerStep(const std::string& method, const acvo::Camera& camera,
              const Eigen::Isometry3d& start) {
  struct State {
    cv::Ptr<cv::rgbd::Odometry> odometry;
    cv::Ptr<cv::rgbd::OdometryFrame> previous;
    cv::Mat guess = cv::Mat::eye(4, 4, CV_64FC1);
    Eigen::Isometry3d pose;
  };
  auto s = std::make_shared<State>();
  s->odometry = makePeer(method, camera);
  s->pose = start;
  return [s](const acvo::Frame& f, Eigen::Isometry3d& pose) {
    cv::Mat grey;
    const int code = f.order == acvo::ColorOrder::kRgb ? cv::COLOR_RGB2GRAY : cv::COLOR_BGR2GRAY;
    if (f.order == acvo::ColorOrder::kGray) {
      grey = f.color;
    } else {
      cv::cvtColor(f.color, grey, code);
    }
    cv::Ptr<cv::rgbd::OdometryFrame> current = cv::rgbd::OdometryFrame::create(grey, f.depth);
    bool ok = true;
    if (s->previous) {
      cv::Mat Rt;
      ok = s->odometry->compute(s->previous, current, Rt, s->guess);
      if (ok && !Rt.empty()) {
        Eigen::Matrix4d m;
        cv::cv2eigen(Rt, m);
        s->pose = s->pose * Eigen::Isometry3d(m).inverse();
        s->guess = Rt;
      } else {
        ok = false;
        s->guess = cv::Mat::eye(4, 4, CV_64FC1);
      }
    }
    s->previous = current;
    pose = s->pose;
    return ok;
  };
}

// The first pose: the ground truth nearest the first frame, identity without one.
Eigen::Isometry3d startPose(const acvo::TumDataset& data, double stamp) {
  const acvo::StampedPose* p =
      data.groundtruth() ? acvo::tools::nearestPose(*data.groundtruth(), stamp) : nullptr;
  return p ? p->pose : Eigen::Isometry3d::Identity();
}

std::string baseName(std::string path) {
  while (path.size() > 1 && path.back() == '/') path.pop_back();
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

std::string jsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{kDescription, "acvo_compare"};
  Options opt;
  if (const auto status = parseOptions(app, opt, argc, argv)) return *status;
  try {
    acvo::Params params;
    try {
      params = acvo::tools::loadToolParams(opt.config, opt.sets);
    } catch (const std::exception& e) {  // a malformed --set, an unknown key, a bad config
      return acvo::tools::usageError(app, e.what());
    }
    std::vector<Run> runs;
    for (const auto& folder : opt.datasets) {
      const acvo::TumDataset data(folder);
      const std::size_t n =
          opt.frames < 0 ? data.size() : std::min(data.size(), std::size_t(opt.frames));
      std::vector<acvo::Frame> frames;
      frames.reserve(n);
      for (std::size_t i = 0; i < n; ++i) frames.push_back(data.loadFrame(i));
      if (frames.empty()) throw std::runtime_error(folder + ": no frames");
      const Eigen::Isometry3d start = startPose(data, frames.front().stamp);
      for (const auto& method : opt.methods) {
        Run run{baseName(folder), method == "acvo" ? opt.label : method, {}, {}, 0};
        Step step =
            method == "acvo" ? acvoStep(params, start) : peerStep(method, data.camera(), start);
        for (std::size_t i = 0; i < n; ++i) {
          Eigen::Isometry3d pose;
          const auto t0 = std::chrono::steady_clock::now();
          const bool ok = step(frames[i], pose);
          const double ms =
              std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                  .count();
          if (i > 0) run.ms.push_back(ms);
          if (!ok && i > 0) ++run.lost;
          const auto& entry = data.frames()[i].rgb;
          run.trajectory.push_back({entry.stamp_text, entry.stamp, pose});
        }
        if (data.groundtruth()) {
          try {
            const acvo::RpeResult rpe = acvo::computeRpe(*data.groundtruth(), run.trajectory);
            run.rpe_trans = rpe.trans.rmse;
            run.rpe_rot = rpe.rot_deg.rmse;
            run.ate = acvo::computeAte(*data.groundtruth(), run.trajectory).trans.rmse;
          } catch (const std::exception& e) {
            std::cerr << "acvo_compare: " << run.dataset << " " << run.method
                      << ": no evaluation: " << e.what() << "\n";
          }
        }
        if (!opt.trajectories.empty()) {
          acvo::writeTrajectory(opt.trajectories + "/" + run.dataset + "-" + run.method + ".txt",
                                run.trajectory, run.method + " on " + folder);
        }
        runs.push_back(std::move(run));
      }
    }

    // Speed as a ratio of RgbdOdometry's median on the same dataset in this run.
    std::map<std::string, double> rgbd_median;
    for (const auto& r : runs) {
      if (r.method == "rgbd") rgbd_median[r.dataset] = acvo::tools::percentile(r.ms, 0.5);
    }
    std::printf("%-20s %-10s %10s %10s %8s %5s %9s %8s %8s\n", "dataset", "method", "rpe_t_m/s",
                "rpe_r_deg/s", "ate_m", "lost", "median_ms", "p90_ms", "vs_rgbd");
    for (const auto& r : runs) {
      const double median = acvo::tools::percentile(r.ms, 0.5);
      const auto it = rgbd_median.find(r.dataset);
      const double ratio = it != rgbd_median.end() && it->second > 0 ? median / it->second : NAN;
      std::printf("%-20s %-10s %10.4f %10.3f %8.4f %5ld %9.2f %8.2f %8.2f\n", r.dataset.c_str(),
                  r.method.c_str(), r.rpe_trans, r.rpe_rot, r.ate, r.lost, median,
                  acvo::tools::percentile(r.ms, 0.9), ratio);
    }
    if (!opt.json.empty()) {
      std::ofstream out(opt.json);
      if (!out) throw std::runtime_error("cannot write " + opt.json);
      out << "{\"rpe_delta_s\": 1, \"runs\": [";
      for (std::size_t k = 0; k < runs.size(); ++k) {
        const Run& r = runs[k];
        const double median = acvo::tools::percentile(r.ms, 0.5);
        const auto it = rgbd_median.find(r.dataset);
        out << (k ? ",\n  " : "\n  ") << "{\"dataset\": \"" << r.dataset << "\", \"method\": \""
            << r.method << "\", \"frames\": " << r.trajectory.size()
            << ", \"rpe_trans\": " << jsonNumber(r.rpe_trans)
            << ", \"rpe_rot_deg\": " << jsonNumber(r.rpe_rot) << ", \"ate\": " << jsonNumber(r.ate)
            << ", \"lost\": " << r.lost << ", \"median_ms\": " << jsonNumber(median)
            << ", \"p90_ms\": " << jsonNumber(acvo::tools::percentile(r.ms, 0.9))
            << ", \"median_vs_rgbd\": "
            << jsonNumber(it != rgbd_median.end() && it->second > 0 ? median / it->second : NAN)
            << "}";
      }
      out << "\n]}\n";
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "acvo_compare: " << e.what() << "\n";
    return 2;
  }
}
