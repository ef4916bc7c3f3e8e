// acvo_bench_cloud: what publishing a frame's cloud costs. The nodelet publishes `cloud` only
// when someone subscribes; then each frame's LabelledCloud becomes a PCL point cloud with its
// labels and a PointCloud2 through pcl::toROSMsg (toPointCloud2). Measured against the least a
// PointCloud2 can cost: the same points and colours (xyz + rgb, 16 bytes a point) written
// straight into the message, as the package did before its clouds went through PCL.
//
//   acvo_bench_cloud [--benchmark_* flags]
#include <array>
#include <cstdint>
#include <cstring>
#include <random>

#include <benchmark/benchmark.h>

#include "conversions.hpp"

namespace {

acvo::LabelledCloud randomCloud(int n) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  acvo::LabelledCloud c;
  for (int i = 0; i < n; ++i) {
    c.points.emplace_back(u(rng) - 0.5f, u(rng) - 0.5f, 1.0f + 3.0f * u(rng));
    acvo::Label l;
    l << u(rng), u(rng), u(rng), u(rng) - 0.5f, u(rng) - 0.5f;
    c.labels.push_back(l);
    c.rgb.push_back({std::uint8_t(255 * u(rng)), std::uint8_t(255 * u(rng)),
                     std::uint8_t(255 * u(rng))});
  }
  return c;
}

void BM_ToPointCloud2ThroughPcl(benchmark::State& state) {
  const acvo::LabelledCloud cloud = randomCloud(int(state.range(0)));
  std_msgs::Header h;
  h.frame_id = "camera";
  for (auto _ : state) {
    sensor_msgs::PointCloud2 msg = acvo_ros::toPointCloud2(cloud, h);
    benchmark::DoNotOptimize(msg.data.data());
  }
}
BENCHMARK(BM_ToPointCloud2ThroughPcl)->Arg(4000)->Unit(benchmark::kMicrosecond);

// The baseline: xyz + packed rgb copied into the message by hand, no labels.
void BM_XyzRgbByHand(benchmark::State& state) {
  const acvo::LabelledCloud cloud = randomCloud(int(state.range(0)));
  for (auto _ : state) {
    sensor_msgs::PointCloud2 msg;
    msg.header.frame_id = "camera";
    msg.height = 1;
    msg.width = std::uint32_t(cloud.size());
    const char* names[] = {"x", "y", "z", "rgb"};
    for (std::uint32_t i = 0; i < 4; ++i) {
      sensor_msgs::PointField f;
      f.name = names[i];
      f.offset = 4 * i;
      f.datatype = sensor_msgs::PointField::FLOAT32;
      f.count = 1;
      msg.fields.push_back(f);
    }
    msg.point_step = 16;
    msg.row_step = msg.point_step * msg.width;
    msg.is_dense = true;
    msg.data.resize(std::size_t{msg.row_step});
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      float xyzc[4] = {cloud.points[i].x(), cloud.points[i].y(), cloud.points[i].z(), 0.0f};
      const std::uint32_t packed = (std::uint32_t{cloud.rgb[i][0]} << 16) |
                                   (std::uint32_t{cloud.rgb[i][1]} << 8) | cloud.rgb[i][2];
      std::memcpy(&xyzc[3], &packed, 4);
      std::memcpy(&msg.data[i * msg.point_step], xyzc, sizeof xyzc);
    }
    benchmark::DoNotOptimize(msg.data.data());
  }
}
BENCHMARK(BM_XyzRgbByHand)->Arg(4000)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
