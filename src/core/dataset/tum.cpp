// TUM RGB-D folders: image lists, rgb/depth association, ground truth, trajectories.
#include "acvo/dataset/tum.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <stdexcept>
#include <utility>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "acvo/cloud/depth.hpp"
#include "stamp_association.hpp"

namespace acvo {
namespace {

namespace fs = std::filesystem;

// The text lines of a file, each with its 1-based number; blank and '#' lines left out.
struct Line {
  int number;
  std::string text;
};

std::vector<Line> readDataLines(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  std::vector<Line> lines;
  std::string text;
  for (int number = 1; std::getline(in, text); ++number) {
    if (!text.empty() && text.back() == '\r') text.pop_back();  // CRLF files
    const auto first = text.find_first_not_of(" \t\r");
    if (first == std::string::npos || text[first] == '#') continue;
    lines.push_back({number, text});
  }
  return lines;
}

// TUM's tools treat commas and tabs as spaces.
std::vector<std::string> splitFields(const std::string& line) {
  std::vector<std::string> fields;
  std::string field;
  for (const char c : line) {
    if (c == ' ' || c == '\t' || c == ',' || c == '\r') {
      if (!field.empty()) fields.push_back(std::move(field));
      field.clear();
    } else {
      field += c;
    }
  }
  if (!field.empty()) fields.push_back(std::move(field));
  return fields;
}

[[noreturn]] void malformed(const std::string& path, const Line& line, const std::string& why) {
  throw std::runtime_error(path + ":" + std::to_string(line.number) + ": " + why + ": '" +
                           line.text + "'");
}

// The whole field must be a number (strtod accepts "nan" and "inf" as Python's float() does).
// The end is checked against the field's size: strtod stops at a NUL byte inside the field.
bool parseNumber(const std::string& field, double& value) {
  char* end = nullptr;
  value = std::strtod(field.c_str(), &end);
  return end != field.c_str() && end == field.c_str() + field.size();
}

double parseStamp(const std::string& path, const Line& line, const std::string& field) {
  double stamp = 0.0;
  if (!parseNumber(field, stamp) || !std::isfinite(stamp)) {
    malformed(path, line, "timestamp '" + field + "' is not a number");
  }
  return stamp;
}

// Shortest text that reads back as exactly the same double.
std::string exactText(double value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

}  // namespace

std::vector<TumListEntry> readTumList(const std::string& path) {
  std::vector<TumListEntry> entries;
  for (const Line& line : readDataLines(path)) {
    const auto fields = splitFields(line.text);
    if (fields.size() != 2) malformed(path, line, "expected 'timestamp path'");
    entries.push_back({fields[0], parseStamp(path, line, fields[0]), fields[1]});
  }
  return entries;
}

std::vector<TumAssociation> readAssociations(const std::string& path) {
  // A file in a folder whose name starts with "depth" (TUM's depth/) is a depth image.
  auto underDepth = [](const std::string& file) {
    return fs::path(file).parent_path().filename().string().rfind("depth", 0) == 0;
  };
  std::vector<TumAssociation> associations;
  for (const Line& line : readDataLines(path)) {
    const auto f = splitFields(line.text);
    if (f.size() != 4) {
      malformed(path, line, "expected 'rgb_stamp rgb_path depth_stamp depth_path'");
    }
    TumAssociation a{{f[0], parseStamp(path, line, f[0]), f[1]},
                     {f[2], parseStamp(path, line, f[2]), f[3]}};
    // Depth first, as ICL-NUIM's TUM-format archives list it ("0 depth/0.png 0 rgb/0.png") and
    // as TUM's associate.py writes it when given depth.txt first.
    if (underDepth(f[1]) && !underDepth(f[3])) std::swap(a.rgb, a.depth);
    associations.push_back(std::move(a));
  }
  return associations;
}

std::vector<TumAssociation> associate(const std::vector<TumListEntry>& rgb,
                                      const std::vector<TumListEntry>& depth,
                                      double max_difference) {
  auto stamps = [](const std::vector<TumListEntry>& list) {
    std::vector<double> s;
    for (const TumListEntry& e : list) s.push_back(e.stamp);
    return s;
  };
  std::vector<TumAssociation> matches;
  for (const auto& [r, d] : detail::associateStamps(stamps(rgb), stamps(depth), max_difference)) {
    matches.push_back({rgb[r], depth[d]});
  }
  return matches;
}

Trajectory readTrajectory(const std::string& path) {
  Trajectory trajectory;
  for (const Line& line : readDataLines(path)) {
    const auto fields = splitFields(line.text);
    if (fields.size() != 8) malformed(path, line, "expected 'timestamp tx ty tz qx qy qz qw'");
    double v[8];
    for (int k = 0; k < 8; ++k) {
      if (!parseNumber(fields[k], v[k])) {
        malformed(path, line, "'" + fields[k] + "' is not a number");
      }
    }
    // As the TUM tools do: a pose with a NaN or an all-zero quaternion is no pose.
    if (std::any_of(v, v + 8, [](double x) { return std::isnan(x); })) continue;
    if (v[4] == 0.0 && v[5] == 0.0 && v[6] == 0.0 && v[7] == 0.0) continue;
    if (!std::all_of(v, v + 8, [](double x) { return std::isfinite(x); })) {
      malformed(path, line, "infinite value");
    }
    StampedPose p;
    p.stamp_text = fields[0];
    p.stamp = v[0];
    p.pose.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    p.pose.linear() = Eigen::Quaterniond(v[7], v[4], v[5], v[6]).normalized().toRotationMatrix();
    trajectory.push_back(std::move(p));
  }
  return trajectory;
}

void writeTrajectory(const std::string& path, const Trajectory& trajectory,
                     const std::string& header_comment) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  if (!header_comment.empty()) out << "# " << header_comment << "\n";
  out << "# timestamp tx ty tz qx qy qz qw\n";
  for (const StampedPose& p : trajectory) {
    Eigen::Quaterniond q(p.pose.rotation());
    if (q.w() < 0) q.coeffs() = -q.coeffs();  // same rotation; qw >= 0 reads more easily
    const Eigen::Vector3d t = p.pose.translation();
    out << (p.stamp_text.empty() ? exactText(p.stamp) : p.stamp_text);
    for (const double value : {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()}) {
      out << ' ' << exactText(value);
    }
    out << '\n';
  }
  if (!out) throw std::runtime_error("error while writing " + path);
}

std::string tumCameraOfName(const std::string& folder_name) {
  static const std::regex tum("(^|[^a-z0-9])(freiburg|fr)([123])([^0-9]|$)", std::regex::icase);
  std::smatch match;
  return std::regex_search(folder_name, match, tum) ? "fr" + match[3].str() : std::string();
}

namespace {

// A dataset's camera: its intrinsics, lens distortion and the TUM camera its folder is named
// for (empty: none).
struct DatasetCamera {
  Camera camera;
  LensDistortion distortion;
  std::string named;
};

// The camera of the dataset in `dir`, as TumDataset's `camera` argument picks it.
DatasetCamera datasetCamera(const fs::path& dir, const std::string& camera) {
  DatasetCamera out;
  if (camera.empty()) {
    const fs::path yaml = dir / "camera.yaml";
    if (fs::exists(yaml)) {
      const CameraFile file = readCameraFile(yaml.string());
      out.camera = file.camera;
      out.distortion = file.distortion;
    } else {
      fs::path name = fs::absolute(dir).lexically_normal();
      if (name.filename().empty()) name = name.parent_path();  // a path ending in '/'
      out.named = tumCameraOfName(name.filename().string());
      out.camera = cameraByName(out.named.empty() ? "default" : out.named);
      out.distortion = distortionByName(out.named);
    }
  } else if (camera == "fr1" || camera == "fr2" || camera == "fr3" || camera == "default") {
    out.camera = cameraByName(camera);
    out.distortion = distortionByName(camera);
  } else if (fs::exists(camera)) {
    const CameraFile file = readCameraFile(camera);
    out.camera = file.camera;
    out.distortion = file.distortion;
  } else {
    throw std::runtime_error("camera '" + camera +
                             "' is neither fr1, fr2, fr3, default nor a camera yaml file");
  }
  return out;
}

// The frames of the dataset `folder` (in `dir`): its associations.txt, else its rgb.txt and
// depth.txt associated.
std::vector<TumAssociation> datasetFrames(const fs::path& dir, const std::string& folder) {
  const fs::path associations = dir / "associations.txt";
  if (fs::exists(associations)) return readAssociations(associations.string());
  const fs::path rgb = dir / "rgb.txt", depth = dir / "depth.txt";
  for (const fs::path& list : {rgb, depth}) {
    if (!fs::exists(list)) {
      throw std::runtime_error("dataset " + folder + " has neither associations.txt nor " +
                               list.filename().string() + " (" + list.string() + ")");
    }
  }
  return associate(readTumList(rgb.string()), readTumList(depth.string()));
}

}  // namespace

TumDataset::TumDataset(const std::string& folder, const std::string& camera) : folder_(folder) {
  const fs::path dir(folder);
  if (!fs::is_directory(dir)) throw std::runtime_error("dataset folder " + folder + " not found");
  DatasetCamera found = datasetCamera(dir, camera);
  camera_ = found.camera;
  distortion_ = found.distortion;
  named_camera_ = std::move(found.named);
  frames_ = datasetFrames(dir, folder);

  const fs::path groundtruth = dir / "groundtruth.txt";
  if (fs::exists(groundtruth)) groundtruth_ = readTrajectory(groundtruth.string());

  if (camera_.width == 0 && camera_.height == 0 && !frames_.empty()) {
    // A camera file without the image size: the first colour image's.
    const std::string first = (dir / frames_.front().rgb.path).string();
    const cv::Mat image = cv::imread(first, cv::IMREAD_UNCHANGED);
    if (image.empty()) throw std::runtime_error("cannot load colour image " + first);
    camera_.width = image.cols;
    camera_.height = image.rows;
  }
  if (distortion_.any() && camera_.width > 0) {
    // OpenCV's undistortion maps, once: the same camera matrix, so that camera() stays the
    // camera of the images loadFrame returns.
    const cv::Matx33d K(camera_.fx, 0.0, camera_.cx, 0.0, camera_.fy, camera_.cy, 0.0, 0.0, 1.0);
    cv::initUndistortRectifyMap(K, cv::Mat(distortion_.coefficients), cv::noArray(), K,
                                cv::Size(camera_.width, camera_.height), CV_32FC1, undistort_x_,
                                undistort_y_);
  }
}

Frame TumDataset::loadFrame(std::size_t i) const {
  if (i >= frames_.size()) {
    throw std::out_of_range("frame " + std::to_string(i) + " of a dataset of " +
                            std::to_string(frames_.size()));
  }
  const TumAssociation& a = frames_[i];
  const std::string color_path = (fs::path(folder_) / a.rgb.path).string();
  const std::string depth_path = (fs::path(folder_) / a.depth.path).string();

  auto checkSize = [&](const cv::Mat& image, const std::string& path) {
    if (image.cols != camera_.width || image.rows != camera_.height) {
      throw std::runtime_error(path + " is " + std::to_string(image.cols) + "x" +
                               std::to_string(image.rows) + " but the camera is " +
                               std::to_string(camera_.width) + "x" +
                               std::to_string(camera_.height));
    }
  };

  Frame frame;
  frame.camera = camera_;
  frame.stamp = a.rgb.stamp;
  frame.depth_stamp = a.depth.stamp;
  frame.order = ColorOrder::kBgr;
  frame.color = cv::imread(color_path, cv::IMREAD_COLOR);  // 8-bit BGR whatever the file holds
  if (frame.color.empty()) throw std::runtime_error("cannot load colour image " + color_path);
  checkSize(frame.color, color_path);
  if (!undistort_x_.empty()) {
    cv::Mat undistorted;
    // Where no raw pixel saw, the colour of the nearest one that did: a black border would be
    // an edge standing still in every frame, pulling both acvo's points and a dense peer's
    // residuals towards no motion. The depth there stays unknown.
    cv::remap(frame.color, undistorted, undistort_x_, undistort_y_, cv::INTER_LINEAR,
              cv::BORDER_REPLICATE);
    frame.color = undistorted;
  }

  const cv::Mat raw = cv::imread(depth_path, cv::IMREAD_UNCHANGED);
  if (raw.empty()) throw std::runtime_error("cannot load depth image " + depth_path);
  if (raw.type() != CV_16UC1 && raw.type() != CV_32FC1) {
    throw std::runtime_error(depth_path + " has type " + cv::typeToString(raw.type()) +
                             ", expected a single-channel 16-bit (or 32-bit float) depth image");
  }
  checkSize(raw, depth_path);
  if (!undistort_x_.empty()) {
    cv::Mat undistorted;
    cv::remap(raw, undistorted, undistort_x_, undistort_y_, cv::INTER_NEAREST, cv::BORDER_CONSTANT,
              cv::Scalar::all(0));
    frame.depth = depthToMeters(undistorted, camera_.depth_scale);
    return frame;
  }
  frame.depth = depthToMeters(raw, camera_.depth_scale);
  return frame;
}

}  // namespace acvo
