// Pinhole intrinsics: validity, the TUM cameras by name (fr1, fr2, fr3), camera.yaml read/write.
#include "acvo/camera.hpp"

#include <cmath>
#include <fstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

namespace acvo {

bool Camera::valid() const {
  const bool finite = std::isfinite(fx) && std::isfinite(fy) && std::isfinite(cx) &&
                      std::isfinite(cy) && std::isfinite(depth_scale);
  return finite && fx > 0 && fy > 0 && width > 0 && height > 0 && depth_scale > 0;
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

Camera loadCameraYaml(const std::string& path) {
  YAML::Node node;
  try {
    node = YAML::LoadFile(path);
  } catch (const std::exception& e) {
    throw std::runtime_error("cannot read camera file " + path + ": " + e.what());
  }
  Camera c;
  auto get = [&](const char* key, auto& value, bool required) {
    if (!node[key]) {
      if (required) throw std::runtime_error(path + ": missing key '" + key + "'");
      return;
    }
    try {
      value = node[key].as<std::decay_t<decltype(value)>>();
    } catch (const std::exception&) {
      throw std::runtime_error(path + ": key '" + key + "' is not a number");
    }
  };
  if (YAML::Node matrix = node["camera_matrix"]; matrix && !node["fx"]) {
    if (matrix.IsMap()) matrix = matrix["data"];
    if (!matrix || !matrix.IsSequence() || matrix.size() != 9) {
      throw std::runtime_error(path + ": key 'camera_matrix' is not a 3x3 matrix's 9 numbers");
    }
    double k[9];
    for (std::size_t i = 0; i < 9; ++i) {
      try {
        k[i] = matrix[i].as<double>();
      } catch (const std::exception&) {
        throw std::runtime_error(path + ": key 'camera_matrix' is not a 3x3 matrix's 9 numbers");
      }
    }
    c.fx = k[0], c.cx = k[2], c.fy = k[4], c.cy = k[5];
  } else {
    get("fx", c.fx, true);
    get("fy", c.fy, true);
    get("cx", c.cx, true);
    get("cy", c.cy, true);
  }
  const bool named = node["image_width"] && !node["width"];
  if (node["width"] || node["height"] || named) {
    get(named ? "image_width" : "width", c.width, true);
    get(named ? "image_height" : "height", c.height, true);
  } else {
    c.width = c.height = 0;  // the caller's to take from the images
  }
  get("depth_scale", c.depth_scale, false);
  Camera sized = c;
  if (sized.width == 0 && sized.height == 0) sized.width = sized.height = 1;
  if (!sized.valid()) {
    throw std::runtime_error(path + ": invalid intrinsics (non-positive values)");
  }
  return c;
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
