// Thread-count control. Work is always split so that every output element is
// computed by exactly one thread in a fixed order: results are bitwise identical
// for any thread count. The count is the calling thread's ExecOptions::threads
// (nn/exec.h), never the caller's OpenMP setting.
#pragma once

#ifdef ROADNN_OPENMP
#include <omp.h>
#endif

namespace nn {

// Sets the calling thread's thread count for its subsequent runs (<= 0: all cores).
void set_num_threads(int n);
// The team size for a parallel region started by the calling thread (>= 1).
int num_threads();
// Index of the calling thread inside a parallel region (0 outside one).
int thread_index();
// num_threads() outside a parallel region, 1 inside one (no nested teams).
int team_size();

// Runs f(i) for i in [0, n) split statically over a team of team_size() threads when
// `parallel` (the caller's size test) holds, else on the calling thread. A team of one
// never enters the OpenMP runtime, which allocates and frees a one-thread team at
// every region (libgomp): forward passes allocate nothing on one thread too.
template <class F>
void parallel_for(long long n, bool parallel, F&& f) {
#ifdef ROADNN_OPENMP
  const int threads = parallel && n > 1 ? team_size() : 1;
  if (threads > 1) {
#pragma omp parallel for schedule(static) num_threads(threads)
    for (long long i = 0; i < n; ++i) f(i);
    return;
  }
#else
  (void)parallel;
#endif
  for (long long i = 0; i < n; ++i) f(i);
}

// Runs f(id, team) on each thread of a team of `threads` (clamped to team_size());
// on the calling thread alone, f(0, 1), without entering the OpenMP runtime.
template <class F>
void parallel_team(int threads, F&& f) {
#ifdef ROADNN_OPENMP
  if (threads > team_size()) threads = team_size();
  if (threads > 1) {
#pragma omp parallel num_threads(threads)
    f(omp_get_thread_num(), omp_get_num_threads());
    return;
  }
#else
  (void)threads;
#endif
  f(0, 1);
}

}  // namespace nn
