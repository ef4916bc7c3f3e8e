// A labelled semi-dense point cloud: points in the camera optical frame + 5-D labels
// [H, S, V, gx, gy] (docs/method.md §1).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "acvo/cloud/frame.hpp"
#include "acvo/params.hpp"
#include "acvo/cloud/point_selector.hpp"

namespace acvo {

using Label = Eigen::Matrix<float, 5, 1>;

struct LabelledCloud {
  std::vector<Eigen::Vector3f> points;            // optical frame, metres
  std::vector<Label> labels;                      // H/180, S/255, V/255, gx/255*2, gy/255*2
  std::vector<cv::Point> pixels;                  // where each point came from
  std::vector<std::array<std::uint8_t, 3>> rgb;   // colour of each point, R G B
  double stamp = 0.0;
  int width = 0, height = 0;  // image size it was built from
  // The grey and depth images and intrinsics it was built from (the default engine's direct
  // terms read them; empty for a cloud made of points alone).
  cv::Mat gray;   // CV_8UC1
  cv::Mat depth;  // CV_32FC1 metres, 0 or NaN = none
  Camera camera;
  // The camera's motion while its shutter was open, as predicted (identity: none known). A
  // moving camera blurs the colour along each point's image motion over it.
  Eigen::Isometry3d blur_motion = Eigen::Isometry3d::Identity();
  // Whether the depth was taken at another instant than the colour (Frame::depth_stamp set and
  // not the colour's stamp), moved to the colour's time (Odometry, sync_depth) or not: it then
  // carries the motion over the delay, or the error of the motion it was moved by.
  bool depth_of_another_instant = false;

  std::size_t size() const { return points.size(); }
  bool empty() const { return points.empty(); }
};

struct CloudStats {
  Selection selection;  // what the selector did (pixels are moved into the cloud)
  double ms_selection = 0.0;
  double ms_labels = 0.0;
};

// Builds the cloud of a frame. The frame must be usable (Frame::problem() empty); HSV is
// computed from the image's real channel order. gx, gy are central differences of the grey
// image (0.5 * (I[u+1] - I[u-1])).
LabelledCloud buildLabelledCloud(const Frame& frame, const SelectionParams& params,
                                 CloudStats* stats = nullptr);

// The cloud of the same pixels with their points from `depth_m` (CV_32FC1 metres, the same
// camera's depth at the cloud's instant, measured again: Odometry moves the depth to the
// colour's time by a better motion). Pixels whose depth there is missing or outside
// [min_depth, max_depth] are dropped; labels, colours and the grey image stay the pixels' own.
LabelledCloud withDepth(const LabelledCloud& cloud, const cv::Mat& depth_m,
                        const SelectionParams& params);

// A cloud with `cloud`'s images, camera, stamp and motions and room for `count` points, none yet.
LabelledCloud withoutPoints(const LabelledCloud& cloud, std::size_t count);

}  // namespace acvo
