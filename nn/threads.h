// Thread-count control. Work is always split so that every output element is
// computed by exactly one thread in a fixed order: results are bitwise identical
// for any thread count.
#pragma once

namespace nn {

// Sets the number of threads for subsequent forwards (<= 0: all cores).
void set_num_threads(int n);
int num_threads();
// Index of the calling thread inside a parallel region (0 outside one).
int thread_index();

}  // namespace nn
