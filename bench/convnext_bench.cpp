// Whole ConvNeXt-Tiny features at the sizes users run: 224x224 (ImageNet) and
// 1280x1920 (StixelNExT++ on Waymo frames), 1 and 2 threads, with seeded random
// weights. Counters: GFLOP/s, percent of the measured FP32 peak, peak RSS.
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <memory>

#include "bench/peak.h"
#include "nn/models/convnext.h"
#include "nn/models/synthetic_weights.h"
#include "nn/threads.h"

namespace {

const weights::SafeTensors& tiny_weights() {
  static const weights::SafeTensors st = weights::SafeTensors::from_bytes(
      nn::synthetic_weights(nn::convnext_tensor_specs(nn::convnext_tiny_config(), "features."), 1).bytes(),
      "synthetic convnext_tiny");
  return st;
}

double peak_rss_mb() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_maxrss / 1024.0;
}

void BM_ConvNeXtTiny(benchmark::State& state) {
  const int h = static_cast<int>(state.range(0)), w = static_cast<int>(state.range(1));
  const int threads = static_cast<int>(state.range(2));
  nn::set_num_threads(threads);
  nn::ConvNeXt model(tiny_weights());
  model.plan(1, h, w);
  nn::SplitMix64 rng(7);
  std::vector<float> x(static_cast<std::size_t>(3) * h * w);
  for (auto& v : x) v = static_cast<float>(255.0 * rng.uniform());
  model.forward(x.data());  // warm-up: first touch of the arena
  for (auto _ : state) benchmark::DoNotOptimize(model.forward(x.data()).data);
  nnbench::set_flop_counters(state, model.flops(), threads);
  state.counters["arena_MB"] = model.arena_bytes() / 1e6;
  state.counters["weights_MB"] = model.weight_bytes() / 1e6;
  state.counters["peak_RSS_MB"] = peak_rss_mb();
  nn::set_num_threads(0);
}

BENCHMARK(BM_ConvNeXtTiny)
    ->ArgNames({"h", "w", "threads"})
    ->Args({224, 224, 1})
    ->Args({224, 224, 2})
    ->Args({1280, 1920, 1})
    ->Args({1280, 1920, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);

}  // namespace
