// Is the depth image registered to the colour image? acvo takes the two pixel for pixel: the
// colour at (u, v) is the colour of the point whose depth is at (u, v). A raw depth image from a
// Kinect-type driver (depth_registration off, 7-Scenes' recordings) comes from a second camera
// with another focal length (the Kinect's colour camera 525 px, its depth camera 585): the
// colour then lies up to 30 px off its point at the image border, and every colour method
// suffers (docs/accuracy.md: a rendered room, acvo 0.0004 -> 0.034 m/s).
//
// The evidence: where the depth jumps (an object's silhouette) the colour nearly always changes
// too. Per frame, the colour image's gradient magnitude (Sobel, smoothed by a 1-px Gaussian,
// normalised to mean 1) is read at the pixels in front of a depth jump (up to 3 px), mapped
// into a colour camera whose focal length is `ratio` times the depth's, about the same
// principal point (u' = cx + ratio (u - cx)), for ratios 0.80 ... 1.20 in steps of 0.01. Over
// enough frames with enough depth edges, a registered pair scores best at ratio 1 (TUM
// fr3/teddy: 1.01, 1.04x the score at 1; every rendered sequence of docs/accuracy.md within
// 0.01 of 1), an unregistered one away from it (7-Scenes' kitchen: 0.91, 1.6x; rendered at
// 0.897: 0.88-0.90, 1.3-1.6x; at 1.1: 1.10, 1.27x), but not at the grid's ends (kGridEnd). The
// verdict rests on that one-parameter search alone. Once unregistered, the frames' evidence is
// searched again for the colour camera itself: its focal ratio within 0.03 of the one found and
// its centre up to max_baseline along x (a Kinect's two cameras are 2.5 cm apart), each edge
// pixel's point (its depth known) projected into it:
// u' = cx + ratio (u - cx) - ratio fx baseline / z. With the depth, the baseline's shift differs from silhouette to silhouette by their depths,
// which a texture does not mimic (rendered rooms at 0.897 and 2.5 cm: found within 1 cm and 0.01;
// the ratio alone had come out 0.85-0.96, the baseline biasing it; docs/accuracy.md, fifteenth
// round). Colour and depth of two instants (free-running streams) misalign by the motion between
// them: Odometry, which runs the check, gives it the depth as it registered it (depthAsRegistered,
// odometry.hpp), and resamples an unregistered camera's colour by the ratio found, or by the camera
// found where asked (withColourResampled, below; OdometryParams::resample_colour_baseline).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "acvo/frame.hpp"

namespace acvo {

class ColourDepthCheck {
 public:
  static constexpr int kRatios = 41;  // 0.80, 0.81, ... 1.20
  static constexpr double kRatioStep = 0.01;
  static double ratioAt(int i) { return 0.8 + kRatioStep * i; }
  // A best ratio within this many steps of either end of the grid (0.80-0.83, 1.17-1.20) is not
  // taken for a camera: texture beside the silhouettes can make the score climb steadily across
  // the grid, with no peak (a rendered room at 0.897: its score rose from 0.58 at 0.89 to 1.18
  // at 1.20, and its next ten frames peaked at 1.18; resampled by 1.20, acvo lost 3x). Cameras
  // found lay at 0.85-0.93 and 1.11.
  static constexpr int kGridEnd = 4;
  static bool atGridEnd(int i);
  // Odometry gives it every kFrameStep-th frame until it decides. Every frame: the verdict
  // comes at the tenth frame with enough depth edges, so that colour from a second camera is
  // resampled (withColourResampled) from the first third of a second on. A frame looked at
  // costs about 3 ms at 640x480, on those first frames only. Over 12 rendered registered
  // sequences (texture, blur, delays, noise in blobs, fast turns) and teddy200 the verdict of
  // ten neighbouring frames was "registered" with the best ratio within 0.03 of 1.
  static constexpr int kFrameStep = 1;

  struct Options {
    double depth_jump = 0.05;      // a depth edge: a pixel within 3 px is farther by this x z
    int min_edge_pixels = 500;     // a frame with fewer depth-edge pixels does not count
    int frames_needed = 10;        // counted frames before a verdict
    double min_gain = 1.15;        // unregistered: the best ratio's score over ratio 1's ...
    double min_offset = 0.04;      // ... the best ratio this far from 1 ...
    double min_agreement = 0.6;    // ... and this fraction of the frames' own best within
    double agreement_within = 0.03;  // this of the best ratio
    double max_baseline = 0.06;    // m: the colour camera's centre searched within this along x
    int max_edges_per_frame = 1000;  // the camera search reads at most this many per frame
  };

  enum class State { kUndecided, kRegistered, kUnregistered };

  struct Verdict {
    State state = State::kUndecided;
    double best_ratio = 1.0;  // the colour focal length over the depth's that fits best
    // The colour camera found once unregistered (findColourCamera): its focal ratio and its
    // centre along x from the depth camera's, in m (best_ratio and 0 otherwise).
    double camera_ratio = 1.0;
    double baseline = 0.0;
    double gain = 1.0;        // the score at best_ratio over the score at ratio 1
    double agreement = 0.0;   // fraction of counted frames whose own best is within
                              // agreement_within of best_ratio
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
  void decide();
  // Searches the kept evidence for the colour camera (Verdict::camera_ratio, baseline).
  void findColourCamera();

  // A counted frame's evidence, kept until the verdict for the camera search.
  struct Evidence {
    cv::Mat strength;
    std::vector<EdgePoint> edges;
  };

  Options options_;
  std::vector<Evidence> evidence_;
  Camera camera_;
  std::array<double, kRatios> sum_{};
  std::vector<int> frame_best_;  // per counted frame, the index of its best ratio
  Verdict verdict_;
};

std::string toString(ColourDepthCheck::State state);

// The frame as a colour camera in the depth camera's place would have seen it, `ratio` being the
// colour camera's focal length over the depth's and `baseline` its centre along x in metres
// (Verdict::best_ratio, or Verdict::camera_ratio and baseline): the colour at each pixel (u, v)
// with depth z taken from (cx + ratio (u - cx) - ratio fx baseline / z, cy + ratio (v - cy))
// (bilinear; a pixel without depth as if at the frame's median depth), the depth cleared where
// that falls outside the colour image (no colour was seen there). A point hidden from the colour camera by a nearer
// one takes the nearer one's colour, as on any registered camera.
Frame withColourResampled(const Frame& frame, double ratio, double baseline = 0.0);

}  // namespace acvo
