// The two frames the micro-benchmarks time: the first two frames of the shared Kinect
// sequence (kitchen7s_dev) when it is present, else a synthetic pair with known motion.
#pragma once

#include <string>

#include <Eigen/Geometry>

#include <memory>

#include "acvo/cloud/frame.hpp"
#include "acvo/params.hpp"
#include "acvo/registration/coarse_to_fine.hpp"
#include "acvo/registration/paper.hpp"

namespace acvo::bench {

struct FramePair {
  std::string source;  // what the frames are, for the benchmark labels
  Frame fixed_frame, moving_frame;
  Params params;  // the defaults; paper: paperParams()
  // Both frames' clouds as each engine prepares them (the fixed one as a reference).
  std::shared_ptr<CoarseToFineCloud> fixed, moving;
  std::shared_ptr<PaperCloud> paper_fixed, paper_moving;
  PaperParams paper = paperParams().paper;
  // Where the default engine converges from the identity guess: the kernel benchmarks evaluate
  // there, so that they see the pairs of a registration near its end.
  Eigen::Isometry3d aligned = Eigen::Isometry3d::Identity();
};

// `data`: a TUM folder, "synthetic", or empty for the default (kitchen7s_dev beside the
// repository, or ACVO_SHARED_DATA/kitchen7s_dev, falling back to synthetic frames).
// Throws std::runtime_error when a folder given explicitly cannot be loaded.
FramePair loadFramePair(const std::string& data);

}  // namespace acvo::bench
