#include "bench/peak.h"

#include <map>
#include <mutex>
#include <string>
#include <utility>

#include "nn/isa.h"
#include "nn/peak.h"

namespace nnbench {

double peak_gflops(int threads) {
  static std::mutex mutex;
  static std::map<std::pair<int, int>, double> cache;
  std::lock_guard<std::mutex> lock(mutex);
  const auto key = std::make_pair(static_cast<int>(nn::active_isa()), threads);
  auto it = cache.find(key);
  if (it == cache.end()) it = cache.emplace(key, nn::peak_gflops(threads)).first;
  return it->second;
}

void set_flop_counters(benchmark::State& state, double flops_per_iteration, int threads) {
  const double gflop = flops_per_iteration * static_cast<double>(state.iterations()) * 1e-9;
  state.counters["GFLOP/s"] = benchmark::Counter(gflop, benchmark::Counter::kIsRate);
  // A rate too: GFLOP / seconds / peak * 100 is the percentage of peak.
  state.counters["pct_peak"] =
      benchmark::Counter(gflop / peak_gflops(threads) * 100.0, benchmark::Counter::kIsRate);
}

namespace {

// The peak itself as a benchmark (one loop of ~1 ms per iteration), so reports show what
// pct_peak divides by.
void bm_peak(benchmark::State& state, nn::Isa isa, int threads) {
  constexpr long kIterations = 1 << 17;
  double flops = 0.0;
  float sink = 0.0f;
  for (auto _ : state) {
    flops += nn::peak_parallel(static_cast<int>(isa), kIterations, threads, &sink);
  }
  benchmark::DoNotOptimize(sink);
  state.counters["GFLOP/s"] = benchmark::Counter(flops * 1e-9, benchmark::Counter::kIsRate);
}

int register_peak() {
  for (nn::Isa isa : {nn::Isa::Scalar, nn::Isa::Avx2, nn::Isa::Avx512}) {
    if (!nn::isa_supported(isa)) continue;
    for (int threads : {1, 2}) {
      const std::string name = std::string("peak_fma/") + nn::isa_name(isa) +
                               "/threads:" + std::to_string(threads);
      benchmark::RegisterBenchmark(name.c_str(), bm_peak, isa, threads)->UseRealTime();
    }
  }
  return 0;
}

const int kPeakRegistered = register_peak();

}  // namespace

}  // namespace nnbench
