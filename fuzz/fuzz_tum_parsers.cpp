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

#include "acvo/camera.hpp"
#include "acvo/params.hpp"
#include "acvo/tum.hpp"

#define FUZZ_CHECK(cond)                                                                  \
  do {                                                                                    \
    if (!(cond)) {                                                                        \
      std::fprintf(stderr, "fuzz check failed: %s (%s:%d)\n", #cond, __FILE__, __LINE__); \
      std::abort();                                                                       \
    }                                                                                     \
  } while (false)

namespace {

namespace fs = std::filesystem;

// One pair of scratch files per process (libFuzzer's -jobs runs several processes).
const std::string& scratch(int k) {
  static const std::string paths[2] = {
      (fs::temp_directory_path() / ("acvo_fuzz_tum_" + std::to_string(getpid()) + "_a.txt"))
          .string(),
      (fs::temp_directory_path() / ("acvo_fuzz_tum_" + std::to_string(getpid()) + "_b.txt"))
          .string()};
  return paths[k];
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

void checkList(const std::vector<acvo::TumListEntry>& list) {
  for (const auto& e : list) FUZZ_CHECK(std::isfinite(e.stamp) && !e.path.empty());
  const auto matches = acvo::associate(list, list, 0.02);
  FUZZ_CHECK(matches.size() <= list.size());
  for (std::size_t k = 0; k < matches.size(); ++k) {
    FUZZ_CHECK(std::abs(matches[k].rgb.stamp - matches[k].depth.stamp) < 0.02);
    if (k > 0) FUZZ_CHECK(matches[k - 1].rgb.stamp <= matches[k].rgb.stamp);
  }
}

void checkTrajectory(const acvo::Trajectory& t) {
  for (const auto& p : t) {
    FUZZ_CHECK(std::isfinite(p.stamp) && p.pose.translation().allFinite());
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
      FUZZ_CHECK(std::isfinite(a.rgb.stamp) && std::isfinite(a.depth.stamp));
    }
  });
  tolerateExceptions([] { checkTrajectory(acvo::readTrajectory(scratch(0))); });
  tolerateExceptions([] { FUZZ_CHECK(acvo::loadCameraYaml(scratch(0)).valid()); });
  tolerateExceptions([&] { FUZZ_CHECK(acvo::validate(acvo::parseParams(text)).empty()); });
  return 0;
}
