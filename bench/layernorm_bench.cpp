// LayerNorm on ConvNeXt-Tiny's channels-last rows at 1280x1920 input, per ISA and
// thread count. Memory-bound: GB/s counts one read and one write of the rows.
// FLOPs count 8 per element (mean 1, squared deviations 3, normalise-scale-shift 4).
#include <benchmark/benchmark.h>

#include <vector>

#include "bench/peak.h"
#include "bench/random_data.h"
#include "nn/isa.h"
#include "nn/layernorm.h"
#include "nn/threads.h"

namespace {

void BM_LayerNorm(benchmark::State& state) {
  const auto rows = static_cast<std::size_t>(state.range(0));
  const int c = static_cast<int>(state.range(1));
  const auto isa = static_cast<nn::Isa>(state.range(2));
  const int threads = static_cast<int>(state.range(3));
  if (!nn::isa_supported(isa)) {
    state.SkipWithError("ISA not supported by this CPU");
    return;
  }
  nn::set_isa(isa);
  nn::set_num_threads(threads);
  nnbench::UniformStream u;
  const std::vector<float> x = u.vector(rows * c), g = u.vector(c, 0.1f, 1.0f), b = u.vector(c, 0.1f);
  std::vector<float> y(rows * c);
  nn::layernorm_parallel(rows, c, x.data(), c, y.data(), c, g.data(), b.data(), 1e-6f);
  for (auto _ : state) {
    nn::layernorm_parallel(rows, c, x.data(), c, y.data(), c, g.data(), b.data(), 1e-6f);
    benchmark::ClobberMemory();
  }
  const double elements = static_cast<double>(rows) * c;
  nnbench::set_flop_counters(state, 8.0 * elements, threads);
  state.counters["GB/s"] =
      benchmark::Counter(2.0 * elements * sizeof(float) * state.iterations() / 1e9,
                         benchmark::Counter::kIsRate);
  state.SetLabel(nn::isa_name(isa));
  nn::set_num_threads(0);
  nn::set_isa(nn::detect_isa());
}

void shapes(benchmark::internal::Benchmark* b) {
  const int layers[][2] = {{153600, 96}, {38400, 192}, {9600, 384}, {2400, 768}};
  for (const auto& l : layers)
    for (int isa = 0; isa <= 2; ++isa)
      for (int threads : {1, 2}) b->Args({l[0], l[1], isa, threads});
}

BENCHMARK(BM_LayerNorm)
    ->ArgNames({"rows", "c", "isa", "threads"})
    ->Apply(shapes)
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime()
    ->MinTime(0.5);

}  // namespace
