// Pinhole intrinsics and lens: validity, the TUM cameras by name (fr1, fr2, fr3), camera.yaml
// read/write.
#include "acvo/cloud/camera.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

namespace acvo {

bool Camera::valid() const {
  const bool finite = std::isfinite(fx) && std::isfinite(fy) && std::isfinite(cx) &&
                      std::isfinite(cy) && std::isfinite(depth_scale);
  return finite && fx != 0 && fy != 0 && width > 0 && height > 0 && depth_scale > 0;
}

Camera cameraByName(const std::string& name) {
  Camera c;  // 640x480, depth scale 5000
  if (name == "fr1") {
    c.fx = 517.3, c.fy = 516.5, c.cx = 318.6, c.cy = 255.3;
  } else if (name == "fr2") {
    c.fx = 520.9, c.fy = 521.0, c.cx = 325.1, c.cy = 249.7;
  } else if (name == "fr3") {
    c.fx = 535.4, c.fy = 539.2, c.cx = 320.1, c.cy = 247.6;
  } else if (name == "default") {
    c.fx = 525.0, c.fy = 525.0, c.cx = 319.5, c.cy = 239.5;
  } else {
    throw std::invalid_argument("unknown camera name '" + name +
                                "' (expected fr1, fr2, fr3 or default)");
  }
  return c;
}

bool LensDistortion::any() const {
  return std::any_of(coefficients.begin(), coefficients.end(), [](double k) { return k != 0.0; });
}

LensDistortion distortionByName(const std::string& name) {
  // vision.in.tum.de/data/datasets/rgbd-dataset/file_formats, "Intrinsic Camera Calibration".
  LensDistortion d;
  if (name == "fr1") d.coefficients = {0.2624, -0.9531, -0.0054, 0.0026, 1.1633};
  if (name == "fr2") d.coefficients = {0.2312, -0.7849, -0.0033, -0.0001, 0.9172};
  return d;
}

bool nominalIntrinsics(const Camera& camera, const LensDistortion& distortion) {
  auto centred = [](double c, int size) {
    constexpr std::array<double, 3> kShifts{0.0, -1.0, 1.0};
    return std::any_of(kShifts.begin(), kShifts.end(),
                       [&](double shift) { return std::abs(c - 0.5 * (size + shift)) < 1e-6; });
  };
  return !distortion.any() && std::abs(std::abs(camera.fx) - std::abs(camera.fy)) < 1e-6 &&
         centred(camera.cx, camera.width) && centred(camera.cy, camera.height);
}

namespace {

std::string notANumber(const std::string& key) {
  return "key '" + key + "' is not a number";
}

// One camera file's YAML, and the way its errors name the file and the key.
class CameraYaml {
 public:
  explicit CameraYaml(const std::string& path) : path_(path) {
    try {
      root_ = YAML::LoadFile(path);
    } catch (const std::exception& e) {
      throw std::runtime_error("cannot read camera file " + path + ": " + e.what());
    }
  }
  YAML::Node operator[](const char* key) const { return root_[key]; }

  [[noreturn]] void fail(const std::string& why) const {
    throw std::runtime_error(path_ + ": " + why);
  }
  // `value` read as a T, or the error `why`.
  template <typename T>
  T as(const YAML::Node& value, const std::string& why) const {
    try {
      return value.as<T>();
    } catch (const std::exception&) {
      fail(why);
    }
  }
  // The key's value into `value`; an absent key is an error when required, else leaves it.
  template <typename T>
  void get(const char* key, T& value, bool required) const {
    if (root_[key]) {
      value = as<T>(root_[key], notANumber(key));
    } else if (required) {
      fail(std::string("missing key '") + key + "'");
    }
  }

 private:
  std::string path_;
  YAML::Node root_;
};

Camera intrinsicsOf(const CameraYaml& yaml) {
  Camera c;
  if (YAML::Node matrix = yaml["camera_matrix"]; matrix && !yaml["fx"]) {
    const std::string why = "key 'camera_matrix' is not a 3x3 matrix's 9 numbers";
    if (matrix.IsMap()) matrix = matrix["data"];
    if (!matrix || !matrix.IsSequence() || matrix.size() != 9) yaml.fail(why);
    std::array<double, 9> k{};
    for (std::size_t i = 0; i < k.size(); ++i) k[i] = yaml.as<double>(matrix[i], why);
    c.fx = k[0], c.cx = k[2], c.fy = k[4], c.cy = k[5];
  } else {
    yaml.get("fx", c.fx, true);
    yaml.get("fy", c.fy, true);
    yaml.get("cx", c.cx, true);
    yaml.get("cy", c.cy, true);
  }
  const bool named = yaml["image_width"] && !yaml["width"];
  if (yaml["width"] || yaml["height"] || named) {
    yaml.get(named ? "image_width" : "width", c.width, true);
    yaml.get(named ? "image_height" : "height", c.height, true);
  } else {
    c.width = c.height = 0;  // the caller's to take from the images
  }
  yaml.get("depth_scale", c.depth_scale, false);
  Camera sized = c;
  if (sized.width == 0 && sized.height == 0) sized.width = sized.height = 1;
  if (!sized.valid()) {
    yaml.fail("invalid intrinsics (a zero focal length, or a size or depth scale not positive)");
  }
  return c;
}

LensDistortion distortionOf(const CameraYaml& yaml) {
  LensDistortion d;
  auto coefficient = [&](const YAML::Node& value, const std::string& key) {
    const double k = yaml.as<double>(value, notANumber(key));
    if (!std::isfinite(k)) yaml.fail(notANumber(key));
    return k;
  };
  static const std::array<const char*, 5> opencv{"k1", "k2", "p1", "p2", "k3"};
  static const std::array<const char*, 5> tum{"d0", "d1", "d2", "d3", "d4"};
  for (std::size_t i = 0; i < d.coefficients.size(); ++i) {
    for (const char* key : {opencv[i], tum[i]}) {
      if (yaml[key]) d.coefficients[i] = coefficient(yaml[key], key);
    }
  }
  if (YAML::Node list = yaml["distortion_coefficients"]) {
    if (list.IsMap()) list = list["data"];
    if (!list || !list.IsSequence() || list.size() > d.coefficients.size()) {
      yaml.fail("key 'distortion_coefficients' is not a list of up to 5 numbers (k1 k2 p1 p2 k3)");
    }
    for (std::size_t i = 0; i < list.size(); ++i) {
      d.coefficients[i] = coefficient(list[i], "distortion_coefficients");
    }
  }
  return d;
}

}  // namespace

CameraFile readCameraFile(const std::string& path) {
  const CameraYaml yaml(path);
  return {intrinsicsOf(yaml), distortionOf(yaml)};
}

Camera loadCameraYaml(const std::string& path) {
  return readCameraFile(path).camera;
}

void saveCameraYaml(const std::string& path, const Camera& c) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  out.precision(17);
  out << "# pinhole intrinsics of the colour image; depth PNG units per metre\n"
      << "width: " << c.width << "\nheight: " << c.height << "\nfx: " << c.fx << "\nfy: " << c.fy
      << "\ncx: " << c.cx << "\ncy: " << c.cy << "\ndepth_scale: " << c.depth_scale << "\n";
}

}  // namespace acvo
