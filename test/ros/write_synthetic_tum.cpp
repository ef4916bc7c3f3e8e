// Writes the synthetic room sequence as a TUM RGB-D folder for the bag test:
// rgb/*.png, depth/*.png (16-bit, 5000 per metre), rgb.txt, depth.txt, associations.txt,
// groundtruth.txt (camera pose in the world, TUM convention) and camera.yaml.
//
// Usage: write_synthetic_tum FOLDER [FRAMES=30]
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <string>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "synthetic_room.hpp"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: write_synthetic_tum FOLDER [FRAMES]\n";
    return 2;
  }
  namespace fs = std::filesystem;
  const fs::path folder = argv[1];
  const int frames = argc > 2 ? std::stoi(argv[2]) : 30;
  fs::create_directories(folder / "rgb");
  fs::create_directories(folder / "depth");
  const acvo::Camera camera = acvo_test::testCamera();
  const double depth_scale = 5000.0;

  std::ofstream rgb_list(folder / "rgb.txt"), depth_list(folder / "depth.txt"),
      assoc(folder / "associations.txt"), gt(folder / "groundtruth.txt");
  rgb_list << "# color images\n# timestamp filename\n";
  depth_list << "# depth maps\n# timestamp filename\n";
  gt << "# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n";
  for (int k = 0; k < frames; ++k) {
    // 30 Hz from a TUM-like epoch; depth 5 ms after colour, as in the real recordings.
    char rgb_stamp[32], depth_stamp[32];
    std::snprintf(rgb_stamp, sizeof rgb_stamp, "%.6f", 1305031102.175304 + k / 30.0);
    std::snprintf(depth_stamp, sizeof depth_stamp, "%.6f", 1305031102.180304 + k / 30.0);
    const Eigen::Isometry3d world_from_camera =
        acvo_test::worldFromFirstCamera() * acvo_test::cameraPose(k);
    const acvo_test::RgbdImage img = acvo_test::renderRoom(world_from_camera, camera);
    cv::Mat bgr, depth16;
    cv::cvtColor(img.rgb, bgr, cv::COLOR_RGB2BGR);
    img.depth.convertTo(depth16, CV_16UC1, depth_scale);
    const std::string rgb_file = std::string("rgb/") + rgb_stamp + ".png";
    const std::string depth_file = std::string("depth/") + depth_stamp + ".png";
    if (!cv::imwrite((folder / rgb_file).string(), bgr) ||
        !cv::imwrite((folder / depth_file).string(), depth16)) {
      std::cerr << "write_synthetic_tum: cannot write images in " << folder << "\n";
      return 1;
    }
    rgb_list << rgb_stamp << ' ' << rgb_file << '\n';
    depth_list << depth_stamp << ' ' << depth_file << '\n';
    assoc << rgb_stamp << ' ' << rgb_file << ' ' << depth_stamp << ' ' << depth_file << '\n';
    const Eigen::Quaterniond q(world_from_camera.rotation());
    const Eigen::Vector3d t = world_from_camera.translation();
    gt << rgb_stamp << std::setprecision(17) << ' ' << t.x() << ' ' << t.y() << ' ' << t.z()
       << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' ' << q.w() << '\n';
  }
  std::ofstream yaml(folder / "camera.yaml");
  yaml << std::setprecision(17) << "fx: " << camera.fx << "\nfy: " << camera.fy
       << "\ncx: " << camera.cx << "\ncy: " << camera.cy << "\nwidth: " << camera.width
       << "\nheight: " << camera.height << "\ndepth_scale: " << depth_scale << "\n";
  std::cout << "write_synthetic_tum: " << frames << " frames in " << folder << "\n";
  return 0;
}
