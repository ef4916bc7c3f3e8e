// acvo_bench_kernels: Google Benchmark timings of each stage of one registration, on one pair
// of real frames (see frame_pair.hpp): pixel selection, cloud building, the depth moved to the
// colour's time; for the default engine
// a reference's search grids, the kernel pass of a level (fresh and with warm candidate lists),
// the last level's direct terms and their medians, a frame's depth grid for the dense term and a whole
// registration; for the paper's engine the cloud preparation (search grid and
// self-kernel pairs), its kernel pass, the step-size sums, the self-kernel sums and a whole
// registration.
//
//   acvo_bench_kernels [--threads=N] [--data=TUM_DIR|synthetic] [--benchmark_* flags]
//
// --threads: size of the TBB arena the stages run in, as acvo_tum --threads (default 2).
// --data: the frames (default kitchen7s_dev from the shared data, else synthetic).
// The kernel passes run at the transform the default engine converges to, at ell in millimetres
// (the default engine's ell_min and ell_init, the paper's ell_min and ell_max). Times are wall-clock ("Time"): the
// work is spread over the arena's threads, which the "CPU" column (main thread) does not see.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>
#include <opencv2/imgproc.hpp>

#include "acvo/cloud/depth.hpp"
#include "acvo/cloud/labelled_cloud.hpp"
#include "acvo/math/order_statistics.hpp"
#include "acvo/cloud/point_selector.hpp"
#include "frame_pair.hpp"

namespace {

using acvo::bench::FramePair;

// Set by main() before any benchmark runs.
const FramePair* g_pair = nullptr;
std::unique_ptr<tbb::task_arena> g_arena;

template <typename F>
void inArena(F&& f) {
  g_arena->execute(std::forward<F>(f));
}

double ellOf(const benchmark::State& state) {
  return double(state.range(0)) / 1000.0;
}

// The length-scales the kernel benchmarks run at (mm, rounded; the level kernels run at the
// level nearest to it).
void levelArguments(benchmark::internal::Benchmark* b) {
  const acvo::CoarseToFineParams p;
  b->ArgName("ell_mm");
  for (double ell : {p.ell_min, p.ell_init}) b->Arg(std::lround(ell * 1000.0));
  b->Unit(benchmark::kMillisecond)->UseRealTime();
}
void paperArguments(benchmark::internal::Benchmark* b) {
  const acvo::PaperParams p;
  b->ArgName("ell_mm");
  for (double ell : {p.ell_min, p.ell_max}) b->Arg(std::lround(ell * 1000.0));
  b->Unit(benchmark::kMillisecond)->UseRealTime();
}

// The default engine's level whose length-scale is nearest the benchmark's argument.
std::size_t levelOf(const benchmark::State& state) {
  const std::vector<double> ells = acvo::levelElls(g_pair->params.coarse_to_fine);
  std::size_t best = 0;
  for (std::size_t k = 0; k < ells.size(); ++k) {
    if (std::abs(ells[k] - ellOf(state)) < std::abs(ells[best] - ellOf(state))) best = k;
  }
  return best;
}

void BM_Selection(benchmark::State& state) {
  const acvo::Frame& f = g_pair->moving_frame;
  cv::Mat gray;
  cv::cvtColor(f.color, gray,
               f.order == acvo::ColorOrder::kRgb ? cv::COLOR_RGB2GRAY : cv::COLOR_BGR2GRAY);
  std::size_t selected = 0;
  inArena([&] {
    for (auto _ : state) {
      const acvo::Selection s = acvo::selectPixels(gray, f.depth, g_pair->params.selection);
      selected = s.pixels.size();
      benchmark::DoNotOptimize(s.pixels.data());
    }
  });
  state.counters["points"] = double(selected);
}
BENCHMARK(BM_Selection)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_BuildCloud(benchmark::State& state) {
  std::size_t points = 0;
  inArena([&] {
    for (auto _ : state) {
      const acvo::LabelledCloud c =
          acvo::buildLabelledCloud(g_pair->moving_frame, g_pair->params.selection);
      points = c.size();
      benchmark::DoNotOptimize(c.points.data());
    }
  });
  state.counters["points"] = double(points);
}
BENCHMARK(BM_BuildCloud)->Unit(benchmark::kMillisecond)->UseRealTime();

// The depth moved to the colour's time (odometry.sync_depth): 10 ms of the frames' motion.
void BM_DepthSeenFrom(benchmark::State& state) {
  const acvo::Frame& f = g_pair->moving_frame;
  const Eigen::Isometry3d moved =
      acvo::expSE3(acvo::logSE3(g_pair->aligned) * (0.010 * 30.0));  // frames 1/30 s apart
  std::size_t landed = 0;
  for (auto _ : state) {
    const cv::Mat d = acvo::depthSeenFrom(f.depth, f.camera, moved);
    landed = std::size_t(cv::countNonZero(d));
    benchmark::DoNotOptimize(d.data);
  }
  state.counters["pixels"] = double(landed);
}
BENCHMARK(BM_DepthSeenFrom)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_PrepareReference(benchmark::State& state) {
  inArena([&] {
    for (auto _ : state) {
      state.PauseTiming();  // a fresh copy of the cloud, untimed
      auto c = acvo::prepareCoarseToFine(g_pair->moving->cloud, g_pair->params.coarse_to_fine,
                                         false);
      state.ResumeTiming();
      acvo::prepareCoarseToFineReference(*c, g_pair->params.coarse_to_fine);
      benchmark::DoNotOptimize(c->level_grids.data());
    }
  });
  state.counters["points"] = double(g_pair->moving->size());
}
BENCHMARK(BM_PrepareReference)->Unit(benchmark::kMillisecond)->UseRealTime();

// A new kernel per pass: the candidate lists are built every time (a level's first iteration).
void BM_LevelKernelFresh(benchmark::State& state) {
  std::int64_t nnz = 0;
  const std::size_t level = levelOf(state);
  const double ell = acvo::levelElls(g_pair->params.coarse_to_fine)[level];
  inArena([&] {
    for (auto _ : state) {
      acvo::LevelKernel k(g_pair->fixed->cloud, g_pair->moving->cloud,
                          g_pair->fixed->level_grids[level], g_pair->params.coarse_to_fine);
      nnz = k.evaluate(g_pair->aligned, ell).nnz;
    }
  });
  state.counters["nnz"] = double(nnz);
}
BENCHMARK(BM_LevelKernelFresh)->Apply(levelArguments);

// One kernel evaluated again at the same transform: its candidate lists stay valid, so this is
// the cost of a later iteration.
void BM_LevelKernelWarm(benchmark::State& state) {
  const std::size_t level = levelOf(state);
  const double ell = acvo::levelElls(g_pair->params.coarse_to_fine)[level];
  acvo::LevelKernel k(g_pair->fixed->cloud, g_pair->moving->cloud,
                      g_pair->fixed->level_grids[level], g_pair->params.coarse_to_fine);
  std::int64_t nnz = 0;
  inArena([&] {
    k.evaluate(g_pair->aligned, ell);
    const int builds = k.listBuilds();
    for (auto _ : state) nnz = k.evaluate(g_pair->aligned, ell).nnz;
    if (k.listBuilds() != builds) state.SkipWithError("candidate lists were rebuilt");
  });
  state.counters["nnz"] = double(nnz);
}
BENCHMARK(BM_LevelKernelWarm)->Apply(levelArguments);

// Writes over 64 MB, more than the last-level cache of most machines (a CPU with a larger one
// keeps more), so that the next read of the images starts from main
// memory, as it does in a frame after other work (another odometry, the driver, the next frame's
// decoding) has run.
void evictCaches() {
  static std::vector<unsigned char> junk(std::size_t(64) << 20);
  static unsigned char round = 0;
  ++round;
  for (std::size_t k = 0; k < junk.size(); k += 64) junk[k] = round;
  benchmark::ClobberMemory();
}

// The last level's direct terms at one iterate: where the moving points land, then the
// photometric and point-to-plane sums (each with its learned scale). cold:1 evicts the caches
// before each iteration (untimed): the terms read the reference's images at scattered pixels,
// and their reads are prefetched for that case.
void BM_DirectTerms(benchmark::State& state) {
  const bool cold = state.range(0) != 0;
  int used = 0;
  for (auto _ : state) {
    if (cold) {
      state.PauseTiming();
      evictCaches();
      state.ResumeTiming();
    }
    const std::vector<acvo::Landing> landed = acvo::landings(
        g_pair->fixed->images, g_pair->moving->images, g_pair->moving->cloud, g_pair->aligned);
    const acvo::DirectSums a = acvo::photometricSums(g_pair->fixed->images, g_pair->moving->images,
                                                     g_pair->moving->cloud, landed,
                                                     g_pair->params.coarse_to_fine.photometric_gain,
                                                     g_pair->params.coarse_to_fine.photometric_vignetting);
    const acvo::DirectSums b = acvo::pointToPlaneSums(
        g_pair->fixed->images, landed, g_pair->params.coarse_to_fine.depth_noise);
    used = a.used + b.used;
    benchmark::DoNotOptimize(a.H);
    benchmark::DoNotOptimize(b.H);
  }
  state.counters["residuals"] = used;
}
BENCHMARK(BM_DirectTerms)
    ->ArgName("cold")
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The weighted median that learns a direct term's scale, over as many (|r|, say) pairs as the
// pair's photometric term has landed points (heavy-tailed values, fixed seed). Each iteration
// copies the values first from one of 64 orders of them: the same values in the same order every
// time would let the branch predictor learn the comparisons, which an iteration's new residuals
// never repeat.
constexpr int kOrders = 64;
void BM_WeightedMedian(benchmark::State& state) {
  const std::size_t n = acvo::landings(g_pair->fixed->images, g_pair->moving->images,
                                       g_pair->moving->cloud, g_pair->aligned)
                            .size();
  std::mt19937 rng(1);
  std::cauchy_distribution<double> residual(0.0, 2.0);
  std::exponential_distribution<double> say(1.0 / 200.0);
  std::vector<std::pair<double, double>> pairs(n);
  for (auto& [r, w] : pairs) r = std::abs(residual(rng)), w = say(rng);
  std::vector<std::vector<std::pair<double, double>>> orders(kOrders, pairs);
  for (auto& o : orders) std::shuffle(o.begin(), o.end(), rng);
  std::vector<std::pair<double, double>> v;
  std::size_t k = 0;
  for (auto _ : state) {
    v = orders[k++ % kOrders];
    benchmark::DoNotOptimize(acvo::weightedMedian(v));
  }
  state.counters["values"] = double(pairs.size());
}
BENCHMARK(BM_WeightedMedian)->Unit(benchmark::kMicrosecond);

// A frame's depth grid for the dense term: the twists that decide it, and the window means where
// it is on (real Kinect frames: off, the twists alone; the synthetic pair, noise per pixel: on).
void BM_DenseGrid(benchmark::State& state) {
  const acvo::LabelledCloud& c = g_pair->moving->cloud;
  acvo::DepthGrid grid;
  for (auto _ : state) {
    grid = acvo::denseGrid(c.depth, c.camera, g_pair->params.coarse_to_fine.depth_noise);
    benchmark::DoNotOptimize(grid.points.data());
  }
  state.counters["independence"] = grid.independence;
  state.counters["points"] = double(grid.points.size());
}
BENCHMARK(BM_DenseGrid)->Unit(benchmark::kMillisecond)->UseRealTime();

// A whole registration of the default engine from the identity guess.
void BM_Align(benchmark::State& state) {
  int iterations = 0;
  inArena([&] {
    for (auto _ : state) {
      const acvo::SolverResult r =
          acvo::alignCoarseToFine(*g_pair->fixed, *g_pair->moving, Eigen::Isometry3d::Identity(),
                                  g_pair->params.coarse_to_fine);
      iterations = r.iterations;
      benchmark::DoNotOptimize(r.transform);
    }
  });
  state.counters["iterations"] = iterations;
}
BENCHMARK(BM_Align)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_PaperPrepareCloud(benchmark::State& state) {
  std::size_t self_pairs = 0;
  inArena([&] {
    for (auto _ : state) {
      state.PauseTiming();  // preparePaper takes the cloud by value: copy it untimed
      acvo::LabelledCloud cloud = g_pair->moving->cloud;
      state.ResumeTiming();
      const auto p = acvo::preparePaper(std::move(cloud), g_pair->paper, false);
      self_pairs = p->self_pairs.size();
      benchmark::DoNotOptimize(p->self_d2.data());
    }
  });
  state.counters["points"] = double(g_pair->moving->size());
  state.counters["self_pairs"] = double(self_pairs);
}
BENCHMARK(BM_PaperPrepareCloud)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_PaperKernel(benchmark::State& state) {
  acvo::PaperKernel k(g_pair->paper_fixed->cloud, g_pair->paper_moving->cloud,
                      g_pair->paper_fixed->grid, g_pair->paper);
  std::int64_t nnz = 0;
  inArena([&] {
    for (auto _ : state) nnz = k.evaluate(g_pair->aligned, ellOf(state)).nnz;
  });
  state.counters["nnz"] = double(nnz);
}
BENCHMARK(BM_PaperKernel)->Apply(paperArguments);

void BM_PaperStepSums(benchmark::State& state) {
  acvo::PaperKernel k(g_pair->paper_fixed->cloud, g_pair->paper_moving->cloud,
                      g_pair->paper_fixed->grid, g_pair->paper);
  inArena([&] {
    const acvo::CrossSums s = k.evaluate(g_pair->aligned, ellOf(state));
    for (auto _ : state) {
      const acvo::StepSums sums = k.stepSums(s.omega, s.v);
      benchmark::DoNotOptimize(sums);
    }
    state.counters["nnz"] = double(s.nnz);
  });
}
BENCHMARK(BM_PaperStepSums)->Apply(paperArguments);

void BM_PaperSelfKernelSums(benchmark::State& state) {
  std::int64_t nnz = 0;
  inArena([&] {
    for (auto _ : state) {
      const acvo::SelfSums s =
          acvo::selfKernelSums(*g_pair->paper_fixed, ellOf(state), g_pair->paper);
      nnz = s.nnz;
      benchmark::DoNotOptimize(s);
    }
  });
  state.counters["nnz"] = double(nnz);
}
BENCHMARK(BM_PaperSelfKernelSums)->Apply(paperArguments);

// A whole registration of the paper's A-CVO from the identity guess.
void BM_PaperAlign(benchmark::State& state) {
  int iterations = 0;
  inArena([&] {
    for (auto _ : state) {
      const acvo::SolverResult r = acvo::alignPaper(*g_pair->paper_fixed, *g_pair->paper_moving,
                                                    Eigen::Isometry3d::Identity(), g_pair->paper);
      iterations = r.iterations;
      benchmark::DoNotOptimize(r.transform);
    }
  });
  state.counters["iterations"] = iterations;
}
BENCHMARK(BM_PaperAlign)->Unit(benchmark::kMillisecond)->UseRealTime();

// Takes --name=value off argv (Google Benchmark has removed its own flags already).
std::optional<std::string> takeFlag(int* argc, char** argv, const std::string& name) {
  const std::string prefix = "--" + name + "=";
  std::optional<std::string> value;
  int out = 1;
  for (int k = 1; k < *argc; ++k) {
    const std::string a = argv[k];
    if (a.rfind(prefix, 0) == 0) {
      value = a.substr(prefix.size());
    } else {
      argv[out++] = argv[k];
    }
  }
  *argc = out;
  return value;
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  const std::string data = takeFlag(&argc, argv, "data").value_or("");
  const std::string threads_text = takeFlag(&argc, argv, "threads").value_or("2");
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 2;
  const int threads = std::atoi(threads_text.c_str());
  if (threads < 1) {
    std::cerr << "acvo_bench_kernels: --threads expects a positive integer, got '" << threads_text
              << "'\n";
    return 2;
  }
  g_arena = std::make_unique<tbb::task_arena>(threads);

  try {
    static const FramePair pair = acvo::bench::loadFramePair(data);
    g_pair = &pair;
  } catch (const std::exception& e) {
    std::cerr << "acvo_bench_kernels: " << e.what() << "\n";
    return 2;
  }
  benchmark::AddCustomContext("acvo_data", g_pair->source);
  benchmark::AddCustomContext("acvo_threads", std::to_string(threads));
  benchmark::AddCustomContext("acvo_points", std::to_string(g_pair->fixed->size()) + " fixed, " +
                                                 std::to_string(g_pair->moving->size()) + " moving");
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
