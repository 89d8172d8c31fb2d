// The machine's FP32 FMA peak, measured with a register-only FMA loop of the widest
// kernel set active (nn/isa.h), so "% of peak" figures hold on any CPU. Shared by
// nn_bench's counters and `nnrun --profile --format json|csv`.
#pragma once

namespace nn {

// GFLOP/s of `threads` threads running the active kernel set's loop at once (each
// ~0.3 s, best of three runs: about a second per call; callers cache it).
double peak_gflops(int threads);

// One run of the loop of kernel set `isa` (static_cast<int>(nn::Isa); its kernel table's peak_fma)
// for `iterations` rounds on the calling thread; returns the flops performed and adds
// to *sink so the loop is kept.
double peak_loop(int isa, long iterations, float* sink);

// peak_loop on `threads` threads at once (the calling thread's pool); returns the flops
// of all of them and adds their results to *sink.
double peak_parallel(int isa, long iterations, int threads, float* sink);

}  // namespace nn
