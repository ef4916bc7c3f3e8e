// Is the depth image registered to the colour image? acvo takes the two pixel for pixel: the
// colour at (u, v) is the colour of the point whose depth is at (u, v). A raw depth image from a
// Kinect-type driver (depth_registration off, 7-Scenes' recordings) comes from a second camera
// with another focal length (the Kinect's colour camera 525 px, its depth camera 585): the
// colour then lies up to 30 px off its point at the image border, and every colour method
// suffers (docs/accuracy.md: the rendered room whose colour is unregistered).
//
// The evidence: where the depth jumps (an object's silhouette) the colour nearly always changes
// too. Per frame, the colour image's gradient magnitude (Sobel, smoothed by a 1-px Gaussian,
// normalised to mean 1) is read at the pixels in front of a depth jump (up to 3 px), each edge
// pixel's point (its depth z known) projected into a colour camera whose focal length is
// `ratio` times the depth's, about the same principal point, its centre `baseline` along x:
// u' = cx + ratio (u - cx) - ratio fx baseline / z, v' = cy + ratio (v - cy). A grid of such
// cameras (ratios 0.80 ... 1.20 by 0.01, centres within max_baseline by 1 cm; a Kinect's two
// cameras are 2.5 cm apart) is scored on every counted frame. Over enough frames with enough
// depth edges, a registered pair scores best at ratio 1 (TUM fr3/teddy: 1.01, 1.03x the score
// at 1), an unregistered one away from it (7-Scenes' kitchen: 0.90 and 3 cm, 1.8x; rendered
// cameras of 0.9 and 2.5 cm: 0.86-0.94, 1.2-2.7x). The baseline's shift differs from silhouette to
// silhouette by their depths, which a texture does not mimic; judged by the ratio alone, the
// cameras' baseline blurs the ratio's peak, and a colour camera on a fast, blurred camera goes
// unseen (ColourDepthCheck.AColourCameraIsFoundThroughMotionBlur).
// The verdict "unregistered" asks of the best camera of the grid: its ratio not at the grid's
// ends (kGridEnd) and min_offset from 1; min_gain over a camera in the depth camera's place; the
// same in all quarters of the image but one (min_quarter_gain: a person's colour late on its
// silhouette fits a camera in one part of the image only); most frames' own best camera near
// it (min_agreement); and the focal ratio alone that fits best near it (the default
// resampling's, best_ratio) also min_offset from 1 and not at the grid's ends. Before
// frames_needed, only a clear "unregistered" is given (early_frames): every frame's own best
// camera near the one found and the gains well above the last rule's. Colour and depth
// of two instants (free-running streams) misalign by the motion between them: Odometry, which
// runs the check, gives it the depth as it registered it (depthAsRegistered, odometry.hpp), and
// resamples an unregistered camera's colour by the ratio found (withColourResampled, below).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "acvo/cloud/frame.hpp"

namespace acvo {

class ColourDepthCheck {
 public:
  static constexpr int kRatios = 41;  // 0.80, 0.81, ... 1.20
  static constexpr double kRatioStep = 0.01;
  static double ratioAt(int i) { return 0.8 + kRatioStep * i; }
  static constexpr double kBaselineStep = 0.01;  // m: the camera grid's centres along x
  // A quarter of the image with this share of the edge pixels or more has its say
  // (min_quarter_gain).
  static constexpr double kMinQuarterShare = 0.05;
  // A best ratio within this many steps of either end of the grid (0.80-0.83, 1.17-1.20) is not
  // taken for a camera: texture beside the silhouettes can make the score climb steadily across
  // the grid, with no peak (a rendered room at 0.897: its score rose from 0.58 at 0.89 to 1.18
  // at 1.20, and its next ten frames peaked at 1.18; resampled by 1.20, acvo lost 3x). Cameras
  // found lay at 0.85-0.93 and 1.11.
  static constexpr int kGridEnd = 4;
  static bool atGridEnd(int i);
  // Odometry gives it every kFrameStep-th frame until it decides. Every frame: the verdict
  // comes at the tenth frame with enough depth edges, or at the third where the evidence is
  // clear (early_frames: 7-Scenes' kitchen, 2.1x), so that colour from a second camera is
  // resampled (withColourResampled) after a third of a second at 30 Hz, or a tenth where clear.
  // A frame looked at costs about as much as registering one (the grid of 41 x 13 cameras on
  // its thinned edge pixels, up to 2000 of them), on those first frames only.
  static constexpr int kFrameStep = 1;

  struct Options {
    double depth_jump = 0.05;      // a depth edge: a pixel within 3 px is farther by this x z
    int min_edge_pixels = 500;     // a frame with fewer depth-edge pixels does not count
    int frames_needed = 10;        // counted frames before a verdict, but ...
    int early_frames = 3;          // ... "unregistered" from this many on where every frame's
    double early_gain = 1.5;       // own best camera agrees with the one found and its gains
    double early_quarter_gain = 1.3;  // reach these (min_gain, min_quarter_gain: the last rule)
    double min_gain = 1.15;        // unregistered: the best camera's score over ratio 1's ...
    double min_offset = 0.04;      // ... its ratio, and the ratio alone, this far from 1 ...
    double min_quarter_gain = 1.1;  // ... and this gain in all quarters of the image but one ...
    double min_agreement = 0.6;    // ... and this fraction of the frames' own best camera's
    double agreement_within = 0.03;  // ratio within this of its ratio
    double max_baseline = 0.06;    // m: the colour camera's centre searched within this along x
    int max_edges_per_frame = 1000;  // the grid reads every k-th edge pixel of a frame,
                                     // k = edges / this (rounded down)
  };

  enum class State { kUndecided, kRegistered, kUnregistered };

  // Undecided from early_frames on, the figures say what the evidence so far gives.
  struct Verdict {
    State state = State::kUndecided;
    // The colour focal length over the depth's that fits best alone (no baseline, every edge
    // pixel) within agreement_within of grid_ratio: the default resampling's.
    double best_ratio = 1.0;
    // The camera of the grid (focal ratio by 0.01, centre by kBaselineStep) that fits
    // best, and its score over the score of a camera in the depth camera's place.
    double grid_ratio = 1.0;
    double grid_baseline = 0.0;
    double gain = 1.0;
    // The same gain in the image's quarters that hold kMinQuarterShare of the edges: the second
    // least of three or four, else the least.
    double quarter_gain = 1.0;
    double agreement = 0.0;   // fraction of counted frames whose own best camera's ratio is
                              // within agreement_within of grid_ratio
    int frames = 0;           // frames counted (enough depth edges)
    int frames_seen = 0;      // frames given
  };

  ColourDepthCheck() : ColourDepthCheck(Options{}) {}
  explicit ColourDepthCheck(const Options& options);

  // Adds one frame's evidence (a frame with problem() is ignored) and returns the verdict so
  // far; once decided, frames are no longer looked at.
  const Verdict& add(const Frame& frame);
  const Verdict& verdict() const { return verdict_; }
  bool decided() const { return verdict_.state != State::kUndecided; }

  // One line for a log: what was found and, when unregistered, what to do.
  std::string describe() const;

  // The depth-edge pixels of `depth` (CV_32FC1 metres) as (u, v), and the per-ratio mean of
  // the normalised gradient magnitude of `grey` (CV_8UC1) there: for tests.
  static std::vector<std::array<int, 2>> depthEdges(const cv::Mat& depth, double depth_jump);
  static std::array<double, kRatios> scores(const cv::Mat& grey, const Camera& camera,
                                            const std::vector<std::array<int, 2>>& edges);
  // The colour image's gradient magnitude, smoothed and normalised to mean 1 (empty for a blank
  // image), and its mean at depth-edge points (u, v, z) as seen by a colour camera of focal
  // ratio `ratio` whose centre is `baseline` m along x.
  struct EdgePoint {
    float u, v, z;
  };
  static cv::Mat edgeStrength(const cv::Mat& grey);
  static double score(const cv::Mat& strength, const Camera& camera,
                      const std::vector<EdgePoint>& edges, double ratio, double baseline);

 private:
  // score() at every ratio of the grid, without a baseline.
  static std::array<double, kRatios> ratioScores(const cv::Mat& strength, const Camera& camera,
                                                 const std::vector<EdgePoint>& edges);
  // The verdict on the evidence so far; before frames_needed (final false) "unregistered" alone,
  // on the early rule, and otherwise undecided still.
  void decide(bool final);
  // The image's quarter of an edge pixel about the principal point (0-3), and the sums and counts
  // of score() by quarter.
  struct Quarters {
    std::array<double, 4> sum{};
    std::array<int, 4> n{};
  };
  static int quarterOf(const Camera& camera, const EdgePoint& e);
  static Quarters quarterScores(const cv::Mat& strength, const Camera& camera,
                                const std::vector<EdgePoint>& edges, double ratio,
                                double baseline);
  int baselines() const;           // the camera grid's centres: -max_baseline ... max_baseline
  double baselineAt(int j) const;
  std::size_t cameraIndex(int i, int j) const;  // ratio i, centre j in camera_sum_

  Options options_;
  std::array<double, kRatios> sum_{};
  std::vector<double> camera_sum_;  // per camera of the grid (cameraIndex)
  std::array<std::vector<double>, 4> quarter_sum_;  // the same, by the image's quarters
  std::array<int, 4> quarter_edges_{};              // the evidence's edges in each quarter
  std::vector<int> frame_camera_best_;  // per counted frame, its best camera's ratio index
  Verdict verdict_;
};

std::string toString(ColourDepthCheck::State state);

// The frame as a colour camera in the depth camera's place would have seen it, `ratio` being the
// colour camera's focal length over the depth's (Verdict::best_ratio): the colour at each pixel
// (u, v) taken from (cx + ratio (u - cx), cy + ratio (v - cy)) (bilinear), the depth cleared where
// that falls outside the colour image (no colour was seen there).
Frame withColourResampled(const Frame& frame, double ratio);

}  // namespace acvo
