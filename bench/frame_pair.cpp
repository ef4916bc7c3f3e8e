#include "frame_pair.hpp"

#include <cstdlib>
#include <filesystem>
#include <stdexcept>

#include "acvo/cloud/labelled_cloud.hpp"
#include "acvo/dataset/tum.hpp"
#include "synth/sequence.hpp"

namespace acvo::bench {
namespace {

namespace fs = std::filesystem;

std::string defaultDataFolder() {
  fs::path shared = ACVO_SHARED_DATA_DIR;
  if (const char* env = std::getenv("ACVO_SHARED_DATA")) shared = env;
  const fs::path folder = shared / "kitchen7s_dev";
  return fs::is_directory(folder) ? folder.string() : std::string("synthetic");
}

}  // namespace

FramePair loadFramePair(const std::string& data) {
  FramePair pair;
  const std::string source = data.empty() ? defaultDataFolder() : data;
  if (source == "synthetic") {
    // The generator's defaults: furnished, textured room, Kinect-like noise, 30 Hz.
    synth::SequenceOptions o;
    o.frames = 2;
    const synth::SynthSequence seq(o);
    pair.source = "synthetic";
    pair.fixed_frame = seq.frame(0).toFrame();
    pair.moving_frame = seq.frame(1).toFrame();
  } else {
    const TumDataset dataset(source);
    if (dataset.size() < 2) throw std::runtime_error(source + " has fewer than two frames");
    pair.source = fs::path(source).filename().string();
    pair.fixed_frame = dataset.loadFrame(0);
    pair.moving_frame = dataset.loadFrame(1);
  }
  const LabelledCloud fixed = buildLabelledCloud(pair.fixed_frame, pair.params.selection);
  const LabelledCloud moving = buildLabelledCloud(pair.moving_frame, pair.params.selection);
  pair.fixed = prepareCoarseToFine(fixed, pair.params.coarse_to_fine, true);
  pair.moving = prepareCoarseToFine(moving, pair.params.coarse_to_fine, false);
  pair.paper_fixed = preparePaper(fixed, pair.paper, true);
  pair.paper_moving = preparePaper(moving, pair.paper, false);
  pair.aligned = alignCoarseToFine(*pair.fixed, *pair.moving, Eigen::Isometry3d::Identity(),
                                   pair.params.coarse_to_fine)
                     .transform;
  return pair;
}

}  // namespace acvo::bench
