// The machine's FP32 FMA peak (nn/peak.h, shared with nnrun --profile) as benchmark
// counters, so "% of peak" counters hold on any CPU.
#pragma once

#include <benchmark/benchmark.h>

namespace nnbench {

// GFLOP/s with `threads` threads (nn::peak_gflops).
double peak_gflops(int threads);

// Sets the counters GFLOP/s and pct_peak on a benchmark that performs
// `flops_per_iteration` floating-point operations per iteration with `threads` threads.
void set_flop_counters(benchmark::State& state, double flops_per_iteration, int threads);

}  // namespace nnbench
