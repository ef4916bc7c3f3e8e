#include "peers.hpp"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <Eigen/Core>
#include <opencv2/core/eigen.hpp>  // after Eigen's headers
#include <opencv2/imgproc.hpp>
#include <opencv2/rgbd.hpp>

namespace acvo::peers {

std::string toString(PeerKind kind) {
  switch (kind) {
    case PeerKind::kRgbd:
      return "rgbd";
    case PeerKind::kIcp:
      return "icp";
    case PeerKind::kRgbdIcp:
      return "rgbd_icp";
  }
  return "unknown";
}

PeerKind parsePeerKind(const std::string& name) {
  for (PeerKind k : {PeerKind::kRgbd, PeerKind::kIcp, PeerKind::kRgbdIcp}) {
    if (toString(k) == name) return k;
  }
  throw std::invalid_argument("unknown peer '" + name + "' (rgbd, icp, rgbd_icp)");
}

std::string rowName(const PeerSetup& setup) {
  std::ostringstream name;
  name << toString(setup.kind) << "@" << setup.max_depth << "m";
  return name.str();
}

struct PeerOdometry::State {
  PeerSetup setup;
  cv::Ptr<cv::rgbd::Odometry> odometry;
  cv::Ptr<cv::rgbd::OdometryFrame> previous;
  cv::Mat last_rt;  // the last frame-to-frame Rt (previous_motion_guess)
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
};

namespace {

cv::Ptr<cv::rgbd::Odometry> makeOdometry(const PeerSetup& s, const Camera& c) {
  const cv::Mat K = (cv::Mat_<float>(3, 3) << float(c.fx), 0.0f, float(c.cx), 0.0f, float(c.fy),
                     float(c.cy), 0.0f, 0.0f, 1.0f);
  switch (s.kind) {
    case PeerKind::kRgbd: {
      auto o = cv::rgbd::RgbdOdometry::create(K);
      o->setMaxDepth(s.max_depth);
      return o;
    }
    case PeerKind::kIcp: {
      auto o = cv::rgbd::ICPOdometry::create(K);
      o->setMaxDepth(s.max_depth);
      return o;
    }
    case PeerKind::kRgbdIcp: {
      auto o = cv::rgbd::RgbdICPOdometry::create(K);
      o->setMaxDepth(s.max_depth);
      return o;
    }
  }
  throw std::logic_error("makeOdometry: unknown peer");
}

// The frame as OpenCV's sample gives it: grey image, depth in metres with missing depth as NaN
// (unless a fault is switched on).
cv::Ptr<cv::rgbd::OdometryFrame> odometryFrame(const Frame& f, const PeerSetup& s) {
  cv::Mat grey;
  if (f.order == ColorOrder::kGray) {
    grey = f.color;
  } else {
    cv::cvtColor(f.color, grey, f.order == ColorOrder::kRgb ? cv::COLOR_RGB2GRAY : cv::COLOR_BGR2GRAY);
  }
  cv::Mat depth;
  f.depth.convertTo(depth, CV_32FC1, s.faults.depth_factor);
  const float hole = s.faults.holes_as_zeros ? 0.0f : std::numeric_limits<float>::quiet_NaN();
  // Not (d > 0): NaN stays a hole as well.
  depth.setTo(hole, ~(f.depth > 0.0f));
  return cv::rgbd::OdometryFrame::create(grey, depth);
}

}  // namespace

PeerOdometry::PeerOdometry(const PeerSetup& setup, const Camera& camera,
                           const Eigen::Isometry3d& start)
    : state_(std::make_unique<State>()) {
  state_->setup = setup;
  state_->odometry = makeOdometry(setup, camera);
  state_->pose = start;
}
PeerOdometry::~PeerOdometry() = default;
PeerOdometry::PeerOdometry(PeerOdometry&&) noexcept = default;
PeerOdometry& PeerOdometry::operator=(PeerOdometry&&) noexcept = default;

const Eigen::Isometry3d& PeerOdometry::pose() const { return state_->pose; }

bool PeerOdometry::process(const Frame& frame) {
  State& s = *state_;
  cv::Ptr<cv::rgbd::OdometryFrame> current = odometryFrame(frame, s.setup);
  bool ok = true;
  if (s.previous) {
    // Rt: dst_p = Rt src_p. From the current frame to the previous one, Rt maps current points
    // into the previous camera: pose_current = pose_previous Rt.
    const bool forward = s.setup.current_as_source;
    cv::Mat guess;
    if (s.setup.previous_motion_guess && !s.last_rt.empty()) guess = s.last_rt;
    cv::Mat rt;
    ok = forward ? s.odometry->compute(current, s.previous, rt, guess)
                 : s.odometry->compute(s.previous, current, rt, guess);
    if (ok && !rt.empty()) {
      Eigen::Matrix4d m;
      cv::cv2eigen(rt, m);
      const Eigen::Isometry3d motion(m);
      s.pose = s.pose * (forward != s.setup.faults.inverted_motion ? motion : motion.inverse());
      s.last_rt = rt;
    } else {
      ok = false;
      s.last_rt.release();
    }
  }
  s.previous = current;
  return ok;
}

}  // namespace acvo::peers
