// A minimal writer for the TUM RGB-D benchmark's text files, enough for synthetic sequences:
// image lists, associations and a groundtruth trajectory.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace acvo::synth {

// "1000.033333": seconds with six decimals, as TUM stamps are written.
std::string formatStamp(double seconds);

// The shortest text that reads back as exactly `value` (round trip, full precision).
std::string formatExact(double value);

struct StampedFile {
  std::string stamp;  // formatted stamp text
  std::string path;   // relative to the dataset folder, e.g. "rgb/1000.000000.png"
};

// Each writer prefixes every line of `comment` (may hold several lines) with "# " and throws
// std::runtime_error naming the file when it cannot be written.

// "timestamp filename" lines (rgb.txt, depth.txt).
void writeFileList(const std::string& path, const std::string& comment,
                   const std::vector<StampedFile>& files);

// "rgb_stamp rgb_path depth_stamp depth_path" lines; rgb and depth of equal length.
void writeAssociations(const std::string& path, const std::string& comment,
                       const std::vector<StampedFile>& rgb, const std::vector<StampedFile>& depth);

// "timestamp tx ty tz qx qy qz qw" lines of camera-to-world poses, exact numbers, unit
// quaternions with qw >= 0.
void writeGroundtruth(const std::string& path, const std::string& comment,
                      const std::vector<std::string>& stamps,
                      const std::vector<Eigen::Isometry3d>& poses);

}  // namespace acvo::synth
