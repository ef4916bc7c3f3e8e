#include "synth/sequence.hpp"

#include <atomic>
#include <cmath>
#include <filesystem>
#include <mutex>
#include <sstream>
#include <stdexcept>

#include <tbb/parallel_for.h>
#include <opencv2/imgcodecs.hpp>

#include "synth/random.hpp"
#include "synth/tum_writer.hpp"

namespace acvo::synth {
namespace {

const SequenceOptions& validated(const SequenceOptions& o) {
  if (o.frames < 0) throw std::invalid_argument("frames must not be negative");
  if (!(o.rate > 0) || !std::isfinite(o.rate)) throw std::invalid_argument("rate must be positive");
  if (!(o.speed >= 0) || !std::isfinite(o.speed))
    throw std::invalid_argument("speed must be a non-negative number");
  if (!o.camera.valid()) throw std::invalid_argument("invalid camera");
  if (o.blur_samples < 1) throw std::invalid_argument("blur_samples must be at least 1");
  if (!(o.exposure >= 0 && o.exposure <= 1))
    throw std::invalid_argument("exposure must be within [0, 1]");
  if (!(o.colour_focal_ratio >= 0.5 && o.colour_focal_ratio <= 2))
    throw std::invalid_argument("colour_focal_ratio must be within [0.5, 2]");
  if (!(std::abs(o.colour_baseline) <= 1))
    throw std::invalid_argument("colour_baseline must be within [-1, 1] m");
  // Less than half a frame either way keeps the stamps in order.
  if (!(std::abs(o.colour_delay) * o.rate < 0.5))
    throw std::invalid_argument("colour_delay must be under half a frame interval");
  if (!(o.brightness_swing >= 0 && o.brightness_swing <= 0.9))
    throw std::invalid_argument("brightness_swing must be within [0, 0.9]");
  if (!(o.vignetting >= -3 && o.vignetting <= 0))
    throw std::invalid_argument("vignetting must be within [-3, 0]");
  if (!(o.depth_noise_correlation >= 0 && o.depth_noise_correlation <= 50))
    throw std::invalid_argument("depth_noise_correlation must be within [0, 50] pixels");
  if (!(o.walker_speed >= 0 && o.walker_speed <= 5))
    throw std::invalid_argument("walker_speed must be within [0, 5] m/s");
  if (!(o.depth_distortion >= 0 && o.depth_distortion <= 0.05))
    throw std::invalid_argument("depth_distortion must be within [0, 0.05]");
  if (o.walker_speed > 0 && !o.structure)
    throw std::invalid_argument("a walker needs the furnished room (structure on)");
  return o;
}

std::string describe(const SequenceOptions& o) {
  std::ostringstream s;
  s << "synthetic sequence (acvo_synth): motion " << toString(o.motion) << ", speed " << o.speed
    << " m/s, rate " << o.rate << " Hz, seed " << o.seed << ", structure "
    << (o.structure ? "on" : "off") << ", texture " << (o.texture ? "on" : "off") << ", noise "
    << (o.noise ? "on" : "off") << ", blur " << (o.blur ? "on" : "off") << ", " << o.camera.width
    << "x" << o.camera.height;
  if (!o.renderOptions().colourRegistered()) {
    s << ", colour unregistered: focal x" << o.colour_focal_ratio << ", baseline "
      << o.colour_baseline << " m";
  }
  if (o.colour_delay != 0.0) s << ", colour taken " << o.colour_delay << " s after the depth";
  if (o.brightness_swing != 0.0) s << ", brightness swinging by " << o.brightness_swing;
  if (o.vignetting != 0.0) s << ", vignetting " << o.vignetting;
  if (o.noise && o.depth_noise_correlation > 0.0) {
    s << ", depth noise correlated over " << o.depth_noise_correlation << " px";
  }
  if (o.noise && o.depth_distortion > 0.0) s << ", depth distorted by " << o.depth_distortion;
  if (o.walker_speed > 0.0) s << ", a person walking across at " << o.walker_speed << " m/s";
  return s.str();
}

void writeImage(const std::string& path, const cv::Mat& image) {
  bool ok = false;
  try {
    ok = cv::imwrite(path, image);
  } catch (const cv::Exception& e) {
    throw std::runtime_error("cannot write " + path + ": " + e.what());
  }
  if (!ok) throw std::runtime_error("cannot write " + path);
}

}  // namespace

MotionOptions SequenceOptions::motionOptions() const {
  MotionOptions m;
  m.kind = motion;
  m.frames = frames;
  m.rate = rate;
  m.speed = speed;
  m.seed = seed;
  return m;
}

RenderOptions SequenceOptions::renderOptions() const {
  RenderOptions r;
  r.camera = camera;
  r.noise = noise;
  r.colour_focal_ratio = colour_focal_ratio;
  r.colour_baseline = colour_baseline;
  r.vignetting = vignetting;
  r.kinect.correlation_px = depth_noise_correlation;
  r.kinect.distortion_relative = depth_distortion;
  r.kinect.distortion_seed = hashCombine(seed, 17);
  return r;
}

Camera scaledDefaultCamera(int width, int height) {
  Camera c;  // 640x480 defaults
  const double sx = width / 640.0, sy = height / 480.0;
  c.fx *= sx;
  c.fy *= sy;
  // Scale the distance from the image corner (-0.5, -0.5), not from pixel (0, 0).
  c.cx = (c.cx + 0.5) * sx - 0.5;
  c.cy = (c.cy + 0.5) * sy - 0.5;
  c.width = width;
  c.height = height;
  return c;
}

SynthSequence::SynthSequence(const SequenceOptions& options)
    : options_(validated(options)),
      scene_(makeScene(options.sceneOptions())),
      motion_(options.motionOptions()) {
  poses_.reserve(options_.frames);
  for (int i = 0; i < options_.frames; ++i) poses_.push_back(motion_.poseAt(i / options_.rate));
}

Eigen::Isometry3d SynthSequence::colourPose(int i) const {
  if (options_.colour_delay == 0.0) return poses_.at(std::size_t(i));
  return motion_.poseAt(i / options_.rate + options_.colour_delay);
}

Scene SynthSequence::sceneAt(double t) const {
  if (options_.walker_speed == 0.0) return scene_;
  Scene scene = scene_;
  scene.boxes.push_back(walkerAt(options_.walker_speed, t,
                                 static_cast<int>(scene.materials.size()) - 1));
  return scene;
}

double SynthSequence::brightness(double t) const {
  if (options_.brightness_swing == 0.0) return 1.0;
  Rng rng(hashCombine(options_.seed, 11));
  const double phase_a = 2.0 * M_PI * rng.uniform();
  const double phase_b = 2.0 * M_PI * rng.uniform();
  const double s = 0.6 * std::sin(2.0 * M_PI * t / 3.7 + phase_a) +
                   0.4 * std::sin(2.0 * M_PI * t / 1.3 + phase_b);
  return 1.0 + options_.brightness_swing * s;
}

SynthFrame SynthSequence::frame(int i) const {
  if (i < 0 || i >= size()) throw std::out_of_range("synthetic frame index out of range");
  const std::uint64_t noise_seed = hashCombine(hashCombine(options_.seed, 3), i);
  RenderOptions render_options = options_.renderOptions();
  // The frame of `pose` at time t, blurred over the shutter time centred on t.
  auto renderAt = [&](const Eigen::Isometry3d& pose, double t, std::uint64_t seed) {
    render_options.brightness = brightness(t);
    const Scene scene = sceneAt(t);
    if (!(options_.blur && options_.blur_samples > 1 && options_.exposure > 0))
      return render(scene, pose, render_options, seed);
    std::vector<Eigen::Isometry3d> exposure;
    const double shutter = options_.exposure / options_.rate;
    for (int k = 0; k < options_.blur_samples; ++k)
      exposure.push_back(motion_.poseAt(t + shutter * (k / (options_.blur_samples - 1.0) - 0.5)));
    return renderBlurred(scene, pose, exposure, render_options, seed);
  };
  const double t = i / options_.rate;
  SynthFrame f = renderAt(poses_[i], t, noise_seed);
  f.stamp = stamp(i);
  if (options_.colour_delay != 0.0) {
    // The colour of the pose colour_delay later, with noise of its own.
    f.bgr = renderAt(colourPose(i), t + options_.colour_delay, hashCombine(noise_seed, 5)).bgr;
    f.depth_stamp = f.stamp;
    f.stamp += options_.colour_delay;
  }
  return f;
}

cv::Mat depthToPng16(const cv::Mat& depth_m, double depth_scale) {
  CV_Assert(depth_m.type() == CV_32FC1);
  cv::Mat out(depth_m.size(), CV_16UC1);
  for (int v = 0; v < depth_m.rows; ++v) {
    const float* in = depth_m.ptr<float>(v);
    auto* o = out.ptr<std::uint16_t>(v);
    for (int u = 0; u < depth_m.cols; ++u) {
      const double raw = std::round(static_cast<double>(in[u]) * depth_scale);
      o[u] = raw > 0 && raw < 65535 ? static_cast<std::uint16_t>(raw) : 0;  // 65535: no reading
    }
  }
  return out;
}

namespace {

// The ground truth at the depth's stamps and, with the colour taken at other instants, at the
// colour's too, in time order (as a motion-capture trajectory at a higher rate than the
// camera's holds both).
void writeSequenceTruth(const std::string& path, const std::string& about,
                        const SynthSequence& sequence, const std::vector<std::string>& stamps,
                        const std::vector<StampedFile>& rgb) {
  std::vector<std::string> truth_stamps = stamps;
  std::vector<Eigen::Isometry3d> truth_poses = sequence.poses();
  const double delay = sequence.options().colour_delay;
  if (delay != 0.0) {
    truth_stamps.clear();
    truth_poses.clear();
    for (int i = 0; i < sequence.size(); ++i) {
      for (int k = 0; k < 2; ++k) {
        const bool colour = (k == 0) == (delay < 0.0);
        truth_stamps.push_back(colour ? rgb[i].stamp : stamps[i]);
        truth_poses.push_back(colour ? sequence.colourPose(i) : sequence.poses()[i]);
      }
    }
  }
  writeGroundtruth(path,
                   "ground truth trajectory: camera-to-world, optical frame (x right, y down, "
                   "z forward)\n" +
                       about,
                   truth_stamps, truth_poses);
}

}  // namespace

void writeSequence(const std::string& folder, const SequenceOptions& options,
                   const std::function<void(int done, int total)>& progress) {
  const SynthSequence sequence(options);
  namespace fs = std::filesystem;
  std::error_code error;
  for (const char* sub : {"rgb", "depth"}) {
    fs::create_directories(fs::path(folder) / sub, error);
    if (error)
      throw std::runtime_error("cannot create " + folder + "/" + sub + ": " + error.message());
  }

  const int n = sequence.size();
  std::vector<StampedFile> rgb(n), depth(n);
  std::vector<std::string> stamps(n);
  for (int i = 0; i < n; ++i) {
    stamps[i] = formatStamp(sequence.stamp(i));
    const std::string rgb_stamp = formatStamp(sequence.stamp(i) + options.colour_delay);
    rgb[i] = {rgb_stamp, "rgb/" + rgb_stamp + ".png"};
    depth[i] = {stamps[i], "depth/" + stamps[i] + ".png"};
  }

  std::atomic<int> done{0};
  std::mutex progress_mutex;
  // One frame per task: frames are independent, and each renders its rows in parallel too.
  tbb::parallel_for(0, n, [&](int i) {
    const SynthFrame f = sequence.frame(i);
    writeImage((fs::path(folder) / rgb[i].path).string(), f.bgr);
    writeImage((fs::path(folder) / depth[i].path).string(),
               depthToPng16(f.depth_m, options.camera.depth_scale));
    const int finished = ++done;
    if (progress) {
      const std::lock_guard<std::mutex> lock(progress_mutex);
      progress(finished, n);
    }
  });

  const std::string about = describe(options);
  const fs::path root(folder);
  writeFileList((root / "rgb.txt").string(), "color images\n" + about, rgb);
  writeFileList((root / "depth.txt").string(), "depth maps\n" + about, depth);
  writeAssociations((root / "associations.txt").string(), about, rgb, depth);
  writeSequenceTruth((root / "groundtruth.txt").string(), about, sequence, stamps, rgb);
  saveCameraYaml((root / "camera.yaml").string(), options.camera);
}

}  // namespace acvo::synth
