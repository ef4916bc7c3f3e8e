// TUM RGB-D benchmark formats: image lists, rgb/depth association, trajectories, datasets.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "acvo/cloud/camera.hpp"
#include "acvo/cloud/frame.hpp"

namespace acvo {

// One line of rgb.txt / depth.txt: "timestamp path". The stamp text is kept verbatim so that
// outputs repeat it exactly.
struct TumListEntry {
  std::string stamp_text;
  double stamp = 0.0;
  std::string path;  // relative to the dataset folder, as written in the list
};

struct TumAssociation {
  TumListEntry rgb;
  TumListEntry depth;
};

// A pose with its stamp: camera-to-world (TUM convention), stamp text kept verbatim.
struct StampedPose {
  std::string stamp_text;
  double stamp = 0.0;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
};
using Trajectory = std::vector<StampedPose>;

// Reads "timestamp path" lists; '#' lines and blank lines skipped. Throws std::runtime_error
// naming the file (and line number for a malformed line).
std::vector<TumListEntry> readTumList(const std::string& path);

// Reads associations.txt ("rgb_ts rgb_path depth_ts depth_path"; a line whose first file lies in
// a folder named depth* and whose second does not is read the other way round, depth first, as
// ICL-NUIM's TUM-format archives have it).
std::vector<TumAssociation> readAssociations(const std::string& path);

// Nearest-timestamp association as TUM's associate.py does: candidate pairs with
// |t_rgb - t_depth| < max_difference, taken greedily by increasing difference, each entry used
// at most once; the result is sorted by rgb stamp.
std::vector<TumAssociation> associate(const std::vector<TumListEntry>& rgb,
                                      const std::vector<TumListEntry>& depth,
                                      double max_difference = 0.02);

// TUM trajectory files: "timestamp tx ty tz qx qy qz qw". Commas and tabs also separate;
// '#' lines are skipped. Throws with file and line number for a malformed line.
Trajectory readTrajectory(const std::string& path);
// Writes with the stamp text as given and full double precision.
void writeTrajectory(const std::string& path, const Trajectory& trajectory,
                     const std::string& header_comment = "");

// The TUM camera a folder's name gives: "fr1", "fr2" or "fr3" where the name holds freiburgN or
// frN, N not followed by a digit and the word not preceded by a letter or digit (TUM's archives
// unpack to rgbd_dataset_freiburg1_desk and the like); "" otherwise.
std::string tumCameraOfName(const std::string& folder_name);

// A TUM-format dataset folder: rgb.txt, depth.txt, optional associations.txt,
// optional groundtruth.txt, optional camera.yaml.
class TumDataset {
 public:
  // `camera`: empty = camera.yaml in the folder if present, else the TUM camera the folder's name
  // gives (tumCameraOfName: its calibrated intrinsics and, for fr1 and fr2, its lens), else
  // "default"; a name (fr1, fr2, fr3, default) or a path to a camera yaml overrides it. A camera
  // yaml without the image size takes the first colour image's.
  explicit TumDataset(const std::string& folder, const std::string& camera = "");

  const std::string& folder() const { return folder_; }
  const Camera& camera() const { return camera_; }
  // The TUM camera the folder's name gave ("fr1", "fr2", "fr3"), "" where it did not decide.
  const std::string& namedCamera() const { return named_camera_; }
  const std::vector<TumAssociation>& frames() const { return frames_; }
  std::size_t size() const { return frames_.size(); }
  const std::optional<Trajectory>& groundtruth() const { return groundtruth_; }

  // The camera's lens distortion: where the camera file or name gives one, every frame is
  // undistorted on loading (below), and camera() describes the undistorted images.
  const LensDistortion& distortion() const { return distortion_; }

  // Loads frame i: colour as BGR (OpenCV's order, marked in Frame::order), depth converted to
  // metres with the camera's depth scale. With a lens distortion, both images are undistorted
  // to the same pinhole camera (the depth is registered to the colour pixel for pixel): the
  // colour bilinearly, the depth from its nearest pixel (no depth mixed across an edge), pixels
  // seen by no raw pixel without depth (their colour the nearest raw pixel's). Throws
  // std::runtime_error naming the file when an image does not load, has the wrong type, or its size
  // differs from the camera's.
  Frame loadFrame(std::size_t i) const;

 private:
  std::string folder_;
  Camera camera_;
  std::string named_camera_;
  LensDistortion distortion_;
  cv::Mat undistort_x_, undistort_y_;  // raw pixel of each undistorted pixel; empty: none
  std::vector<TumAssociation> frames_;
  std::optional<Trajectory> groundtruth_;
};

}  // namespace acvo
