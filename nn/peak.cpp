#include "nn/peak.h"

#include <algorithm>
#include <chrono>

#include "nn/isa.h"
#include "nn/kernel_table.h"

#ifdef ROADNN_OPENMP
#include <omp.h>
#endif

namespace nn {

namespace {

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
  return kernel_table(static_cast<Isa>(isa)).peak_fma(iterations, sink);
}

double peak_gflops(int threads) { return measure(active_isa(), threads); }

}  // namespace nn
