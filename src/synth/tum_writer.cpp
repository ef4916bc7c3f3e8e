#include "synth/tum_writer.hpp"

#include <charconv>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace acvo::synth {
namespace {

std::ofstream openForWriting(const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  return out;
}

void writeComment(std::ostream& out, const std::string& comment) {
  std::istringstream lines(comment);
  for (std::string line; std::getline(lines, line);) out << "# " << line << '\n';
}

void finishWriting(std::ofstream& out, const std::string& path) {
  out.flush();
  if (!out) throw std::runtime_error("error while writing " + path);
}

}  // namespace

std::string formatStamp(double seconds) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.6f", seconds);
  return buffer;
}

std::string formatExact(double value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

void writeFileList(const std::string& path, const std::string& comment,
                   const std::vector<StampedFile>& files) {
  std::ofstream out = openForWriting(path);
  writeComment(out, comment);
  out << "# timestamp filename\n";
  for (const StampedFile& f : files) out << f.stamp << ' ' << f.path << '\n';
  finishWriting(out, path);
}

void writeAssociations(const std::string& path, const std::string& comment,
                       const std::vector<StampedFile>& rgb, const std::vector<StampedFile>& depth) {
  if (rgb.size() != depth.size())
    throw std::invalid_argument("writeAssociations: rgb and depth lists differ in length");
  std::ofstream out = openForWriting(path);
  writeComment(out, comment);
  for (std::size_t i = 0; i < rgb.size(); ++i)
    out << rgb[i].stamp << ' ' << rgb[i].path << ' ' << depth[i].stamp << ' ' << depth[i].path
        << '\n';
  finishWriting(out, path);
}

void writeGroundtruth(const std::string& path, const std::string& comment,
                      const std::vector<std::string>& stamps,
                      const std::vector<Eigen::Isometry3d>& poses) {
  if (stamps.size() != poses.size())
    throw std::invalid_argument("writeGroundtruth: stamps and poses differ in length");
  std::ofstream out = openForWriting(path);
  writeComment(out, comment);
  out << "# timestamp tx ty tz qx qy qz qw\n";
  for (std::size_t i = 0; i < poses.size(); ++i) {
    Eigen::Quaterniond q(poses[i].linear());
    q.normalize();
    if (q.w() < 0) q.coeffs() = -q.coeffs();  // one of the two equivalent signs, always the same
    const Eigen::Vector3d t = poses[i].translation();
    out << stamps[i];
    for (double value : {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()})
      out << ' ' << formatExact(value);
    out << '\n';
  }
  finishWriting(out, path);
}

}  // namespace acvo::synth
