#include "nn/peak.h"

#include <algorithm>
#include <chrono>

#include "nn/isa.h"
#include "nn/kernel_table.h"
#include "nn/exec.h"
#include "nn/threads.h"

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
    const auto t0 = std::chrono::steady_clock::now();
    const double flops = peak_parallel(static_cast<int>(isa), iterations, threads, &sink);
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

double peak_parallel(int isa, long iterations, int threads, float* sink) {
  // One slot per thread: the loops run at once, so each needs a thread of its own (a
  // team of `threads` whose ids are claimed within microseconds of a 0.3 s loop).
  constexpr int kMaxThreads = 256;
  threads = std::max(1, std::min(threads, kMaxThreads));
  double flops[kMaxThreads] = {};
  float sinks[kMaxThreads] = {};
  const ExecScope threads_scope(with_threads(threads));
  parallel_team(threads, [&](int id, int) { flops[id] = peak_loop(isa, iterations, &sinks[id]); });
  double total = 0.0;
  for (int i = 0; i < threads; ++i) {
    total += flops[i];
    *sink += sinks[i];
  }
  return total;
}

double peak_gflops(int threads) { return measure(active_isa(), threads); }

}  // namespace nn
