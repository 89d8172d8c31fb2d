#include "nn/peak.h"

#include <emmintrin.h>

#include <algorithm>
#include <chrono>

#include "nn/isa.h"

#ifdef ROADNN_OPENMP
#include <omp.h>
#endif

namespace nn {

// nn/peak_avx2.cpp, nn/peak_avx512.cpp.
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

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Every thread runs the loop ~0.3 s inside one parallel region; best of three runs, since
// the machine may be shared and the peak is the best it does.
double measure(Isa isa, int threads) {
  float sink = 0.0f;
  long iterations = 1 << 16;
  for (;;) {  // calibrate on one thread until a run takes at least 20 ms
    const auto t0 = std::chrono::steady_clock::now();
    peak_loop(static_cast<int>(isa), iterations, &sink);
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
      flops += peak_loop(static_cast<int>(isa), iterations, &local);
#pragma omp critical
      sink += local;
    }
#else
    (void)threads;
    flops = peak_loop(static_cast<int>(isa), iterations, &sink);
#endif
    best = std::max(best, flops / seconds_since(t0) * 1e-9);
  }
  volatile float keep = sink;  // the loops' result is used
  (void)keep;
  return best;
}

}  // namespace

double peak_loop(int isa, long iterations, float* sink) {
  switch (static_cast<Isa>(isa)) {
    case Isa::Avx512: return peak_fma_avx512(iterations, sink);
    case Isa::Avx2: return peak_fma_avx2(iterations, sink);
    case Isa::Scalar: break;
  }
  return peak_sse2(iterations, sink);
}

double peak_gflops(int threads) { return measure(active_isa(), threads); }

}  // namespace nn
