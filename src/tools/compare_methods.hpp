// The methods acvo_compare runs, behind one interface: acvo's odometry and an OpenCV peer
// (peers.hpp).
#pragma once

#include <Eigen/Geometry>

#include "acvo/odometry/odometry.hpp"
#include "peers.hpp"

namespace acvo::tools {

// A method that registers frames one after the other: process() returns false when the frame
// is lost; pose() is the camera pose after it.
class Method {
 public:
  virtual ~Method() = default;
  virtual bool process(const Frame& frame) = 0;
  virtual const Eigen::Isometry3d& pose() const = 0;
  // Its poses are the depth camera's, at the depth images' stamps (a method of depth alone);
  // otherwise at the colour images' (the stamps acvo's poses carry).
  virtual bool depthOnly() const { return false; }
};

class AcvoMethod : public Method {
 public:
  AcvoMethod(const Params& params, const Eigen::Isometry3d& start) : odometry_(params) {
    odometry_.reset(start);
  }
  bool process(const Frame& frame) override {
    const OdometryResult r = odometry_.process(frame);
    return r.tracking != Tracking::kLost && r.tracking != Tracking::kBadFrame;
  }
  const Eigen::Isometry3d& pose() const override { return odometry_.pose(); }

 private:
  Odometry odometry_;
};

class PeerMethod : public Method {
 public:
  PeerMethod(const peers::PeerSetup& setup, const Camera& camera, const Eigen::Isometry3d& start)
      : peer_(setup, camera, start), depth_only_(setup.kind == peers::PeerKind::kIcp) {}
  bool process(const Frame& frame) override { return peer_.process(frame); }
  const Eigen::Isometry3d& pose() const override { return peer_.pose(); }
  bool depthOnly() const override { return depth_only_; }

 private:
  peers::PeerOdometry peer_;
  bool depth_only_;
};

}  // namespace acvo::tools
