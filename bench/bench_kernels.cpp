// acvo_bench_kernels: Google Benchmark timings of each stage of one registration, on one pair
// of real frames (see frame_pair.hpp): pixel selection, cloud building, cloud preparation
// (search grid + self-kernel pairs), the cross-kernel pass (fresh and with warm candidate
// lists), the step-size sums, the self-kernel sums and a whole align().
//
//   acvo_bench_kernels [--threads=N] [--data=TUM_DIR|synthetic] [--benchmark_* flags]
//
// --threads: size of the TBB arena the stages run in, as acvo_tum --threads (default 2).
// --data: the frames (default kitchen7s_dev from the shared data, else synthetic).
// The kernel passes run at the transform align() converges to, at ell in millimetres
// (ell_min, ell_init, ell_max of the default parameters). Times are wall-clock ("Time"): the
// work is spread over the arena's threads, which the "CPU" column (main thread) does not see.
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>
#include <opencv2/imgproc.hpp>

#include "acvo/cross_kernel.hpp"
#include "acvo/labelled_cloud.hpp"
#include "acvo/point_selector.hpp"
#include "acvo/solver.hpp"
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

// The length-scales the kernel benchmarks run at: the solver's bounds and its start value.
void ellArguments(benchmark::internal::Benchmark* b) {
  const acvo::SolverParams p;
  b->ArgName("ell_mm");
  for (double ell : {p.ell_min, p.ell_init, p.ell_max}) b->Arg(std::lround(ell * 1000.0));
  b->Unit(benchmark::kMillisecond)->UseRealTime();
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

void BM_PrepareCloud(benchmark::State& state) {
  std::size_t self_pairs = 0;
  inArena([&] {
    for (auto _ : state) {
      state.PauseTiming();  // prepareCloud takes the cloud by value: copy it untimed
      acvo::LabelledCloud cloud = g_pair->moving.cloud;
      state.ResumeTiming();
      const acvo::PreparedCloud p = acvo::prepareCloud(std::move(cloud), g_pair->params.solver);
      self_pairs = p.self_pairs.size();
      benchmark::DoNotOptimize(p.self_d2.data());
    }
  });
  state.counters["points"] = double(g_pair->moving.size());
  state.counters["self_pairs"] = double(self_pairs);
}
BENCHMARK(BM_PrepareCloud)->Unit(benchmark::kMillisecond)->UseRealTime();

// A new CrossKernel per pass: the candidate lists are built every time (first iteration of a
// registration).
void BM_CrossKernelFresh(benchmark::State& state) {
  std::int64_t nnz = 0;
  inArena([&] {
    for (auto _ : state) {
      acvo::CrossKernel k(g_pair->fixed, g_pair->moving, g_pair->params.solver);
      nnz = k.evaluate(g_pair->aligned, ellOf(state)).nnz;
    }
  });
  state.counters["nnz"] = double(nnz);
}
BENCHMARK(BM_CrossKernelFresh)->Apply(ellArguments);

// One CrossKernel evaluated again at the same transform: its candidate lists stay valid, so
// this is the cost of a later iteration.
void BM_CrossKernelWarm(benchmark::State& state) {
  acvo::CrossKernel k(g_pair->fixed, g_pair->moving, g_pair->params.solver);
  std::int64_t nnz = 0;
  inArena([&] {
    k.evaluate(g_pair->aligned, ellOf(state));
    const int builds = k.candidateListBuilds();
    for (auto _ : state) nnz = k.evaluate(g_pair->aligned, ellOf(state)).nnz;
    if (k.candidateListBuilds() != builds) state.SkipWithError("candidate lists were rebuilt");
  });
  state.counters["nnz"] = double(nnz);
}
BENCHMARK(BM_CrossKernelWarm)->Apply(ellArguments);

void BM_StepSums(benchmark::State& state) {
  acvo::CrossKernel k(g_pair->fixed, g_pair->moving, g_pair->params.solver);
  inArena([&] {
    const acvo::CrossSums s = k.evaluate(g_pair->aligned, ellOf(state));
    for (auto _ : state) {
      const acvo::StepSums sums = k.stepSums(s.omega, s.v);
      benchmark::DoNotOptimize(sums);
    }
    state.counters["nnz"] = double(s.nnz);
  });
}
BENCHMARK(BM_StepSums)->Apply(ellArguments);

void BM_SelfKernelSums(benchmark::State& state) {
  std::int64_t nnz = 0;
  inArena([&] {
    for (auto _ : state) {
      const acvo::SelfSums s =
          acvo::selfKernelSums(g_pair->fixed, ellOf(state), g_pair->params.solver);
      nnz = s.nnz;
      benchmark::DoNotOptimize(s);
    }
  });
  state.counters["nnz"] = double(nnz);
}
BENCHMARK(BM_SelfKernelSums)->Apply(ellArguments);

// A whole registration from the identity guess, as the odometry's first pair.
void BM_Align(benchmark::State& state) {
  int iterations = 0;
  inArena([&] {
    for (auto _ : state) {
      const acvo::SolverResult r = acvo::align(
          g_pair->fixed, g_pair->moving, Eigen::Isometry3d::Identity(), g_pair->params.solver);
      iterations = r.iterations;
      benchmark::DoNotOptimize(r.transform);
    }
  });
  state.counters["iterations"] = iterations;
}
BENCHMARK(BM_Align)->Unit(benchmark::kMillisecond)->UseRealTime();

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
  benchmark::AddCustomContext("acvo_points", std::to_string(g_pair->fixed.size()) + " fixed, " +
                                                 std::to_string(g_pair->moving.size()) + " moving");
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
