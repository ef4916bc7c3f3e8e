// Fuzz target: arbitrary bytes as the text of a TUM list, association file, trajectory, camera
// yaml and parameter yaml. A parser may reject the text with an exception; it may not crash, and
// what it accepts must be consistent (finite stamps, rotations, valid intrinsics and parameters,
// a trajectory that reads back as written).
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "acvo/cloud/camera.hpp"
#include "acvo/params.hpp"
#include "acvo/dataset/tum.hpp"

#define FUZZ_CHECK(cond)                                                                  \
  do {                                                                                    \
    if (!(cond)) {                                                                        \
      std::fprintf(stderr, "fuzz check failed: %s (%s:%d)\n", #cond, __FILE__, __LINE__); \
      std::abort();                                                                       \
    }                                                                                     \
  } while (false)

namespace {

namespace fs = std::filesystem;

// One pair of scratch files per process (libFuzzer's -jobs runs several processes), removed when
// the process exits normally.
struct ScratchFiles {
  std::string paths[2];
  ScratchFiles() {
    const std::string stem = "acvo_fuzz_tum_" + std::to_string(getpid());
    paths[0] = (fs::temp_directory_path() / (stem + "_a.txt")).string();
    paths[1] = (fs::temp_directory_path() / (stem + "_b.txt")).string();
  }
  ~ScratchFiles() {
    for (const std::string& p : paths) std::remove(p.c_str());
  }
};

const std::string& scratch(int k) {
  static const ScratchFiles files;
  return files.paths[k];
}

template <typename F>
void tolerateExceptions(F&& f) {
  try {
    f();
  } catch (const std::exception&) {
    // Rejecting malformed text is the parsers' job.
  }
}

bool isRotation(const Eigen::Matrix3d& R) {
  return R.allFinite() && (R.transpose() * R - Eigen::Matrix3d::Identity()).norm() < 1e-9 &&
         std::abs(R.determinant() - 1.0) < 1e-9;
}

// An accepted stamp is a number: all of its text, which gives the stamp.
bool isStamp(const std::string& text, double stamp) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() && value == stamp && std::isfinite(stamp);
}

void checkList(const std::vector<acvo::TumListEntry>& list) {
  for (const auto& e : list) FUZZ_CHECK(isStamp(e.stamp_text, e.stamp) && !e.path.empty());
  const auto matches = acvo::associate(list, list, 0.02);
  FUZZ_CHECK(matches.size() <= list.size());
  for (std::size_t k = 0; k < matches.size(); ++k) {
    FUZZ_CHECK(std::abs(matches[k].rgb.stamp - matches[k].depth.stamp) < 0.02);
    if (k > 0) FUZZ_CHECK(matches[k - 1].rgb.stamp <= matches[k].rgb.stamp);
  }
}

void checkTrajectory(const acvo::Trajectory& t) {
  for (const auto& p : t) {
    FUZZ_CHECK(isStamp(p.stamp_text, p.stamp) && p.pose.translation().allFinite());
    FUZZ_CHECK(isRotation(p.pose.linear()));
  }
  acvo::writeTrajectory(scratch(1), t);
  const acvo::Trajectory back = acvo::readTrajectory(scratch(1));
  FUZZ_CHECK(back.size() == t.size());
  for (std::size_t k = 0; k < t.size(); ++k) {
    FUZZ_CHECK(back[k].stamp_text == t[k].stamp_text);
    FUZZ_CHECK(back[k].pose.translation() == t[k].pose.translation());
    FUZZ_CHECK((back[k].pose.linear() - t[k].pose.linear()).norm() < 1e-9);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::ofstream(scratch(0), std::ios::binary | std::ios::trunc) << text;

  tolerateExceptions([] { checkList(acvo::readTumList(scratch(0))); });
  tolerateExceptions([] {
    for (const auto& a : acvo::readAssociations(scratch(0))) {
      FUZZ_CHECK(isStamp(a.rgb.stamp_text, a.rgb.stamp) &&
                 isStamp(a.depth.stamp_text, a.depth.stamp));
    }
  });
  tolerateExceptions([] { checkTrajectory(acvo::readTrajectory(scratch(0))); });
  tolerateExceptions([] {
    // A camera without the image size is 0 x 0 (the dataset takes it from its images); all
    // else must be valid, and every distortion coefficient finite.
    const acvo::CameraFile file = acvo::readCameraFile(scratch(0));
    acvo::Camera c = file.camera;
    FUZZ_CHECK((c.width == 0) == (c.height == 0));
    if (c.width == 0) c.width = c.height = 1;
    FUZZ_CHECK(c.valid());
    for (const double k : file.distortion.coefficients) FUZZ_CHECK(std::isfinite(k));
  });
  tolerateExceptions([&] { FUZZ_CHECK(acvo::validate(acvo::parseParams(text)).empty()); });
  return 0;
}
