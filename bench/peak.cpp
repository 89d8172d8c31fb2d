#include "bench/peak.h"

#include <emmintrin.h>

#include <algorithm>
#include <chrono>
#include <map>
#include <mutex>
#include <string>
#include <utility>

#include "nn/isa.h"

#ifdef ROADNN_OPENMP
#include <omp.h>
#endif

namespace nnbench {

// bench/peak_avx2.cpp, bench/peak_avx512.cpp.
double peak_fma_avx2(long iterations, float* sink);
double peak_fma_avx512(long iterations, float* sink);

namespace {

// What the scalar path can reach: baseline SSE2, a multiply and an add per lane (no FMA),
// 12 independent chains.
double peak_sse2(long iterations, float* sink) {
  __m128 acc[12];
#pragma GCC unroll 12
  for (int i = 0; i < 12; ++i) acc[i] = _mm_set1_ps(static_cast<float>(i) * 1e-3f);
  const __m128 mul = _mm_set1_ps(0.999999f), add = _mm_set1_ps(1e-6f);
  for (long it = 0; it < iterations; ++it) {
#pragma GCC unroll 12
    for (int i = 0; i < 12; ++i) acc[i] = _mm_add_ps(_mm_mul_ps(acc[i], mul), add);
  }
  __m128 s = acc[0];
  for (int i = 1; i < 12; ++i) s = _mm_add_ps(s, acc[i]);
  alignas(16) float lanes[4];
  _mm_store_ps(lanes, s);
  for (float v : lanes) *sink += v;
  return static_cast<double>(iterations) * 12 * 4 * 2;
}

double run_loop(nn::Isa isa, long iterations, float* sink) {
  switch (isa) {
    case nn::Isa::Avx512: return peak_fma_avx512(iterations, sink);
    case nn::Isa::Avx2: return peak_fma_avx2(iterations, sink);
    case nn::Isa::Scalar: break;
  }
  return peak_sse2(iterations, sink);
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Every thread runs the loop ~0.3 s inside one parallel region; best of three runs, since
// the machine may be shared and the peak is the best it does.
double measure(nn::Isa isa, int threads) {
  float sink = 0.0f;
  long iterations = 1 << 16;
  for (;;) {  // calibrate on one thread until a run takes at least 20 ms
    const auto t0 = std::chrono::steady_clock::now();
    run_loop(isa, iterations, &sink);
    const double s = seconds_since(t0);
    if (s >= 0.02) {
      iterations = static_cast<long>(iterations * (0.3 / s));
      break;
    }
    iterations *= 4;
  }
  double best = 0.0;
  for (int rep = 0; rep < 3; ++rep) {
    double flops = 0.0;
    const auto t0 = std::chrono::steady_clock::now();
#ifdef ROADNN_OPENMP
#pragma omp parallel num_threads(threads) reduction(+ : flops)
    {
      float local = 0.0f;
      flops += run_loop(isa, iterations, &local);
#pragma omp critical
      sink += local;
    }
#else
    (void)threads;
    flops = run_loop(isa, iterations, &sink);
#endif
    best = std::max(best, flops / seconds_since(t0) * 1e-9);
  }
  benchmark::DoNotOptimize(sink);
  return best;
}

}  // namespace

double peak_gflops(int threads) {
  static std::mutex mutex;
  static std::map<std::pair<int, int>, double> cache;
  const nn::Isa isa = nn::active_isa();
  std::lock_guard<std::mutex> lock(mutex);
  const auto key = std::make_pair(static_cast<int>(isa), threads);
  auto it = cache.find(key);
  if (it == cache.end()) it = cache.emplace(key, measure(isa, threads)).first;
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
#ifdef ROADNN_OPENMP
#pragma omp parallel num_threads(threads) reduction(+ : flops)
    {
      float local = 0.0f;
      flops += run_loop(isa, kIterations, &local);
#pragma omp critical
      sink += local;
    }
#else
    flops += run_loop(isa, kIterations, &sink);
#endif
  }
  benchmark::DoNotOptimize(sink);
  state.counters["GFLOP/s"] = benchmark::Counter(flops * 1e-9, benchmark::Counter::kIsRate);
}

int register_peak() {
  for (nn::Isa isa : {nn::Isa::Scalar, nn::Isa::Avx2, nn::Isa::Avx512}) {
    if (static_cast<int>(isa) > static_cast<int>(nn::detect_isa())) continue;
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
