// Thread-count control. Work is always split so that every output element is
// computed by exactly one thread in a fixed order: results are bitwise identical
// for any thread count. The count is the calling thread's ExecOptions::threads
// (nn/exec.h), never the caller's OpenMP setting.
#pragma once

namespace nn {

// Sets the calling thread's thread count for its subsequent runs (<= 0: all cores).
void set_num_threads(int n);
// The team size for a parallel region started by the calling thread (>= 1).
int num_threads();
// Index of the calling thread inside a parallel region (0 outside one).
int thread_index();
// num_threads() outside a parallel region, 1 inside one (no nested teams).
int team_size();

}  // namespace nn
