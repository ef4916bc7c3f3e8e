// OdometryNodelet: the camera-to-base transform and the motion guess from TF, and what is
// published for a frame (odometry, TF, clouds, odom_info).
#include "odometry_nodelet.hpp"

namespace acvo_ros {

std::string OdometryNodelet::baseFrame() const {
  return settings_.base_frame_id.empty() ? camera_frame_ : settings_.base_frame_id;
}

bool OdometryNodelet::baseIsCamera() const {
  return settings_.base_is_optical_frame || baseFrame() == camera_frame_;
}

std::optional<Eigen::Isometry3d> OdometryNodelet::lookup(const std::string& target,
                                                         const std::string& source,
                                                         const ros::Time& stamp, double wait,
                                                         std::string* error) {
  // Poll on wall time: under use_sim_time a paused clock must not stall the callback.
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(wait);
  while (true) {
    error->clear();  // canTransform appends
    if (tf_buffer_->canTransform(target, source, stamp, error)) {
      return tf2::transformToEigen(tf_buffer_->lookupTransform(target, source, stamp));
    }
    if (ros::WallTime::now() >= deadline) return std::nullopt;
    ros::WallDuration(0.005).sleep();
  }
}

std::optional<Eigen::Isometry3d> OdometryNodelet::baseFromCamera() {
  if (baseIsCamera()) return Eigen::Isometry3d::Identity();
  if (base_from_camera_) return base_from_camera_;
  const std::string base = baseFrame();
  std::string error;
  // Wait for it once (the static transform may come a moment after the first image), then only
  // look: waiting frame after frame would stall the callback queue.
  const double wait = base_waited_ ? 0.0 : settings_.wait_for_transform_duration;
  base_waited_ = true;
  base_from_camera_ = lookup(base, camera_frame_, ros::Time(0), wait, &error);
  if (base_from_camera_) {
    NODELET_INFO("camera '%s' in base '%s': looked up once", camera_frame_.c_str(), base.c_str());
  } else {
    NODELET_ERROR_THROTTLE(5.0,
                           "no transform from base frame '%s' to camera frame '%s' (%s): "
                           "odometry runs but is not published until it is available",
                           base.c_str(), camera_frame_.c_str(), error.c_str());
  }
  return base_from_camera_;
}

OdometryNodelet::FrameTf OdometryNodelet::frameTf(const ros::Time& stamp) {
  FrameTf tf;
  tf.base_from_camera = baseFromCamera();
  if (settings_.guess_frame_id.empty() || !tf.base_from_camera) return tf;
  const std::string& guess = settings_.guess_frame_id;
  const std::string base = baseFrame();
  std::string error;
  // Wait for the guess frame's transform at this stamp (wheel odometry may come a little after
  // the image), but not frame after frame while it is missing: that would stall every frame.
  const double wait = guess_found_ ? settings_.wait_for_transform_duration : 0.0;
  tf.guess_from_base = lookup(guess, base, stamp, wait, &error);
  guess_found_ = tf.guess_from_base.has_value();
  const std::optional<double> last = odometry_->lastTrackedStamp();
  if (tf.guess_from_base && last) {
    ros::Time then;
    then.fromSec(*last);
    const std::optional<Eigen::Isometry3d> before = lookup(guess, base, then, 0.0, &error);
    if (before) {
      // The base's motion from the last tracked frame to this one, seen from the camera.
      tf.motion_guess =
          conjugate(tf.base_from_camera->inverse(), before->inverse() * *tf.guess_from_base);
    }
  }
  if (!tf.guess_from_base || (last && !tf.motion_guess)) {
    NODELET_WARN_THROTTLE(kGuessWarning,
                          "no motion guess from '%s' to '%s' at %.6f (%s): the constant-velocity "
                          "prior is used%s",
                          guess.c_str(), base.c_str(), stamp.toSec(), error.c_str(),
                          tf.guess_from_base ? "" : ", and the correction is not published");
  }
  return tf;
}

void OdometryNodelet::publish(const acvo::OdometryResult& r, const ContinuousOdom::Pose& pose,
                              const std_msgs::Header& header, const FrameTf& tf) {
  if (!tf.base_from_camera) return;
  const Eigen::Isometry3d& base_from_camera = *tf.base_from_camera;
  const std::string base = baseFrame();
  std_msgs::Header odom_header;
  odom_header.stamp = header.stamp;
  odom_header.frame_id = settings_.odom_frame_id;
  // The published pose is continuous through losses (odom_continuity.hpp).
  acvo::OdometryResult published = r;
  published.pose = pose.pose;
  published.pose_covariance = pose.covariance;
  const bool lost = r.tracking == acvo::Tracking::kLost;
  if (lost && settings_.lost_odom == LostOdom::kNull) {
    odom_pub_.publish(nullOdometryMsg(odom_header, base));
  } else if (!(lost && settings_.lost_odom == LostOdom::kNone)) {
    odom_pub_.publish(toOdometryMsg(published, base_from_camera, odom_header, base));
  }
  // TF goes on whatever lost_odom says: a frame tree that stops would make every consumer's
  // lookups fail (extrapolation errors) for as long as tracking is lost.
  const Eigen::Isometry3d base_pose = conjugate(base_from_camera, pose.pose);
  if (settings_.publish_tf && settings_.guess_frame_id.empty()) {
    tf_broadcaster_->sendTransform(
        toTransformMsg(base_pose, settings_.odom_frame_id, base, header.stamp));
  } else if (settings_.publish_tf && tf.guess_from_base) {
    // odom -> guess -> base: the correction of the guess frame, so that the chain gives the
    // estimate and the base keeps its one parent (the wheel odometry's frame). While lost the
    // estimate follows the guess, so the correction stays as it was and the base goes on
    // with the wheels.
    tf_broadcaster_->sendTransform(toTransformMsg(base_pose * tf.guess_from_base->inverse(),
                                                  settings_.odom_frame_id, settings_.guess_frame_id,
                                                  header.stamp));
  }
  std_msgs::Header cloud_header = header;
  if (settings_.base_is_optical_frame) cloud_header.frame_id = base;  // the estimated camera
  if (r.cloud && cloud_pub_.getNumSubscribers() > 0) {
    cloud_pub_.publish(toPointCloud2(*r.cloud, cloud_header));
  }
  // The keyframe's cloud, in its own camera frame at its own stamp, once per keyframe.
  const std::uint64_t keyframe = r.new_keyframe ? r.frame_index : r.keyframe_index;
  const acvo::LabelledCloud* keyframe_cloud = odometry_->keyframeCloud();
  if (keyframe_cloud && published_keyframe_ != keyframe &&
      keyframe_cloud_pub_.getNumSubscribers() > 0) {
    cloud_header.stamp.fromSec(keyframe_cloud->stamp);
    keyframe_cloud_pub_.publish(toPointCloud2(*keyframe_cloud, cloud_header));
    published_keyframe_ = keyframe;
  }
}

void OdometryNodelet::publishInfo(const acvo::OdometryResult& r, const std_msgs::Header& header,
                                  const InfoExtras& extras) {
  last_.ms_total = extras.ms_total;
  last_.ms_latency = extras.ms_latency;
  info_pub_.publish(toInfoMsg(r, header, extras));
}

}  // namespace acvo_ros
