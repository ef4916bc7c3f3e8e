// The odometry nodelet's own settings (frames, synchronisation, output when lost, the start
// pose): one struct with the default beside each field, loaded from the private namespace and
// checked in one function. The algorithm's parameters are acvo::Params (ros_params.hpp).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <xmlrpcpp/XmlRpcValue.h>
#include <Eigen/Geometry>

#include "conversions.hpp"

namespace acvo_ros {

// What the nodelet publishes on `odom` for a lost frame. TF goes on in every case, with the
// pose held or following the motion guess (odom_continuity.hpp): the frame tree never stops.
enum class LostOdom {
  kHeld,  // the held (or dead-reckoned) pose, its covariance grown; twist unknown (1e6)
  kNull,  // rtabmap's publish_null_when_lost: a zero pose (all-zero quaternion), 1e6 variances
  kNone,  // no odometry message
};
std::string toString(LostOdom v);
// Throws std::invalid_argument listing the accepted values ("held", "null", "none").
void fromString(const std::string& s, LostOdom& v);

struct NodeletSettings {
  std::string odom_frame_id = "odom";
  // REP 105: the robot's body frame, its transform to the camera's optical frame looked up in
  // TF. Empty = the colour image's frame (a camera alone, nothing above its optical frame).
  std::string base_frame_id = "base_link";
  // base_frame_id names the optical frame of the estimate itself (no lookup; for bags whose
  // ground truth owns the sensor's frames).
  bool base_is_optical_frame = false;
  // A frame whose transform to the base gives each frame's motion guess (wheel odometry's
  // odom, an IMU filter's); empty = the constant-velocity prior. When set, TF gets the
  // correction odom_frame_id -> guess_frame_id instead of odom_frame_id -> base.
  std::string guess_frame_id;
  bool publish_tf = true;
  double wait_for_transform_duration = 0.2;  // s, wall time, for each TF lookup
  double max_time_gap = 1.0;                 // s; a larger gap between frames is warned about
  double no_data_timeout = 3.0;              // s without a frame before diagnostics say so
  LostOdom lost_odom = LostOdom::kHeld;
  bool approx_sync = true;
  double approx_sync_max_interval = 0.0;  // s, 0 = unlimited
  // Per-topic subscriber queues: small, so that frames arriving while one is processed
  // replace each other instead of queueing up (latency stays one frame's processing).
  int topic_queue_size = 2;
  int sync_queue_size = 10;  // the synchroniser's queue (sets it can pair from)
  IntrinsicsOverride intrinsics;
  // The base's pose in the odometry frame at the first frame (`initial_pose`, "x y z roll
  // pitch yaw", metres and radians, the rotation R = Rz(yaw) Ry(pitch) Rx(roll)).
  std::optional<Eigen::Isometry3d> initial_pose;
};

// Reads the settings from `private_ns` (the node's private namespace as a struct) on top of
// `settings`. Returns one sentence per problem: a wrong type, an unknown value, a value out of
// range (that setting keeps its previous value) or a combination that cannot work; also the
// old names (`queue_size` is now `sync_queue_size`; `publish_null_when_lost`, with rtabmap's
// meaning: true = lost_odom null, false = none) with what they were taken as.
std::vector<std::string> loadNodeletSettings(const XmlRpc::XmlRpcValue& private_ns,
                                             NodeletSettings& settings);

// One sentence per parameter of the private namespace that nothing reads (a typo, another
// node's name for a setting), each with the nearest known name or what it is called here:
// `frame_id` is ~base_frame_id, `wait_for_transform` ~wait_for_transform_duration,
// `rgb/image_transport` ~image_transport, rtabmap's `Odom/...` are not read. Known: the
// settings above, the parameter sections (applyRosParams checks inside them), the transport
// hints and `also_known` (dynamic_reconfigure's names, which its server writes here).
std::vector<std::string> unknownParameters(const XmlRpc::XmlRpcValue& private_ns,
                                           const std::vector<std::string>& also_known);

// " (did you mean ~x?)" naming the entry of `known` closest to `name` in edit distance, when one
// is close (at most a third of the name's letters, and at least 2, apart); "" otherwise.
std::string closeMatchHint(const std::string& name, const std::vector<std::string>& known);

// "x y z roll pitch yaw" -> pose; nullopt (and a sentence in *problem) when it is not six
// finite numbers.
std::optional<Eigen::Isometry3d> parsePose6(const std::string& text, std::string* problem);

// One line for /rosout.
std::string describe(const NodeletSettings& settings);

}  // namespace acvo_ros
