// Whole ConvNeXt-Tiny features at the sizes users run: 224x224 (ImageNet) and
// 1280x1920 (StixelNExT++ on Waymo frames), 1 and 2 threads, with seeded random
// weights. Counters: GFLOP/s, percent of the measured FP32 peak, peak RSS.
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <map>
#include <memory>
#include <string>

#include "bench/peak.h"
#include "nn/gemm_bf16.h"
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

// ConvNeXt-Tiny planned for the benchmark's (h, w, threads) arguments, with a seeded
// random frame, after one warm-up pass (the first touch of the arena).
struct TinyRun {
  explicit TinyRun(const benchmark::State& state, nn::Precision precision = nn::Precision::F32)
      : threads(static_cast<int>(state.range(2))), model(tiny_weights(), "features.", precision) {
    const int h = static_cast<int>(state.range(0)), w = static_cast<int>(state.range(1));
    nn::set_num_threads(threads);
    model.plan(1, h, w);
    nn::SplitMix64 rng(7);
    x.resize(static_cast<std::size_t>(3) * h * w);
    for (auto& v : x) v = static_cast<float>(255.0 * rng.uniform());
    model.forward(x.data());
  }
  ~TinyRun() { nn::set_num_threads(0); }
  int threads;
  nn::ConvNeXt model;
  std::vector<float> x;
};

void run_whole(benchmark::State& state, nn::Precision precision) {
  TinyRun run(state, precision);
  nn::ConvNeXt& model = run.model;
  const std::vector<float>& x = run.x;
  const int threads = run.threads;
  for (auto _ : state) benchmark::DoNotOptimize(model.forward(x.data()).data);
  nnbench::set_flop_counters(state, model.flops(), threads);
  state.counters["arena_MB"] = model.arena_bytes() / 1e6;
  state.counters["weights_MB"] = model.weight_bytes() / 1e6;
  state.counters["peak_RSS_MB"] = peak_rss_mb();
}

void BM_ConvNeXtTiny(benchmark::State& state) { run_whole(state, nn::Precision::F32); }

// The optional bf16 MLP GEMMs (--precision bf16); needs AVX512_BF16.
void BM_ConvNeXtTinyBf16(benchmark::State& state) {
  if (!nn::bf16_gemm_available()) return state.SkipWithError("no AVX512_BF16 on this CPU");
  run_whole(state, nn::Precision::Bf16);
}

// Where the time goes: per group of layers (stem, each stage's depthwise convs, each
// stage's fused MLP blocks, each downsampling), GFLOP/s and percent of the measured
// peak, from the model's profiler. Read with --benchmark_counters_tabular=true.
std::string group_of(const nn::ProfileEntry& e) {
  const std::string stage = e.layer.substr(0, e.layer.find('.', e.layer.find('.') + 1));  // "features.N"
  const std::string n = stage.substr(stage.find('.') + 1);
  if (e.op.rfind("dwconv", 0) == 0) return "f" + n + ".dw";
  if (e.op.rfind("LN+pw1", 0) == 0) return "f" + n + ".mlp";
  return "f" + n + (n == "0" ? ".stem" : ".down");
}

void BM_ConvNeXtTinyLayers(benchmark::State& state) {
  TinyRun run(state);
  nn::ConvNeXt& model = run.model;
  const std::vector<float>& x = run.x;
  const int threads = run.threads;
  model.profiler().set_enabled(true);
  model.profiler().reset_times();
  for (auto _ : state) benchmark::DoNotOptimize(model.forward(x.data()).data);
  std::map<std::string, std::pair<double, double>> groups;  // name -> (flops, ms) per forward
  for (const auto& e : model.profiler().entries()) {
    if (e.calls == 0) continue;
    auto& g = groups[group_of(e)];
    g.first += e.flops;
    g.second += e.total_ms / e.calls;
  }
  const double peak = nnbench::peak_gflops(threads);
  for (const auto& [name, g] : groups) {
    const double gflops = g.first / (g.second * 1e6);
    state.counters[name + "_ms"] = g.second;
    state.counters[name + "_pct"] = 100.0 * gflops / peak;
  }
}

BENCHMARK(BM_ConvNeXtTinyLayers)
    ->ArgNames({"h", "w", "threads"})
    ->Args({1280, 1920, 2})
    ->Args({224, 224, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);

BENCHMARK(BM_ConvNeXtTiny)
    ->ArgNames({"h", "w", "threads"})
    ->Args({224, 224, 1})
    ->Args({224, 224, 2})
    ->Args({1280, 1920, 1})
    ->Args({1280, 1920, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);

BENCHMARK(BM_ConvNeXtTinyBf16)
    ->ArgNames({"h", "w", "threads"})
    ->Args({224, 224, 2})
    ->Args({1280, 1920, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);

// Issue 16: --dump off costs nothing. The dump hook is a null-pointer test at each
// block boundary; these cases put a forward of a model whose dump was never set beside
// one whose dump was set and switched off again (the state nnrun and an API session are
// in after a dumping run), and, for scale, one dumping every tensor to a sink that
// discards them (the NHWC -> NCHW conversions). Run on a quiet machine, e.g. with
//   --benchmark_filter=ConvNeXtDump --benchmark_repetitions=10
//   --benchmark_enable_random_interleaving=true --benchmark_report_aggregates_only=true
// and compare the medians of never and switched_off (equal within noise).
struct DiscardingSink : nn::DumpSink {
  bool wants(const std::string&) const override { return true; }
  void tensor(const std::string&, const std::vector<std::int64_t>&, const float* data, const std::string&) override {
    benchmark::DoNotOptimize(data);
  }
};

enum class DumpState { Never, SwitchedOff, On };

void BM_ConvNeXtDump(benchmark::State& state, DumpState mode) {
  TinyRun run(state);
  DiscardingSink sink;
  if (mode != DumpState::Never) {
    run.model.set_dump(&sink);
    run.model.forward(run.x.data());  // grows the sink's conversion buffer once
    if (mode == DumpState::SwitchedOff) run.model.set_dump(nullptr);
  }
  for (auto _ : state) benchmark::DoNotOptimize(run.model.forward(run.x.data()).data);
  nnbench::set_flop_counters(state, run.model.flops(), run.threads);
}

void dump_cases(benchmark::internal::Benchmark* b) {
  b->ArgNames({"h", "w", "threads"})
      ->Args({224, 224, 1})
      ->Args({224, 224, 2})
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime()
      ->MinTime(1.0);
}

BENCHMARK_CAPTURE(BM_ConvNeXtDump, never, DumpState::Never)->Apply(dump_cases);
BENCHMARK_CAPTURE(BM_ConvNeXtDump, switched_off, DumpState::SwitchedOff)->Apply(dump_cases);
BENCHMARK_CAPTURE(BM_ConvNeXtDump, on, DumpState::On)->Apply(dump_cases);

}  // namespace
