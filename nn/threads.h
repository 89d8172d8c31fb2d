// Thread-count control. Work is always split so that every output element is
// computed by exactly one thread in a fixed order: results are bitwise identical
// for any thread count. The count is the calling thread's ExecOptions::threads
// (nn/exec.h). The threads are the calling thread and the workers of its pool
// (nn/thread_pool.h), which hand out work in tasks claimed dynamically.
#pragma once

#include <algorithm>

namespace nn {

// Sets the calling thread's thread count for its subsequent runs (<= 0: all cores).
void set_num_threads(int n);
// The team size for a parallel region started by the calling thread (>= 1).
int num_threads();
// Slot of the calling thread inside a parallel region (0 outside one): unique among the
// threads running one region and < its team size, so it indexes per-thread scratch.
int thread_index();
// num_threads() outside a parallel region, 1 inside one (no nested teams).
int team_size();

namespace detail {
using TaskFn = void (*)(void* ctx, long long task, int slot);
// Runs fn(ctx, t, slot) for t in [0, tasks) on up to `threads` threads of the calling
// thread's pool (the caller included), inside a parallel region.
void run_tasks(long long tasks, int threads, TaskFn fn, void* ctx);
}  // namespace detail

// Tasks per thread that parallel_for cuts its range into: with more tasks than threads
// a thread the OS deschedules on a loaded host holds up only the task it is running,
// while the others take the rest; with few, each task stays long enough that claiming
// it costs nothing measurable.
constexpr int kTasksPerThread = 4;

// Runs f(i) for i in [0, n), on a team of min(team_size(), n) threads when `parallel`
// (the caller's size test) holds, else on the calling thread. The range is cut into up
// to kTasksPerThread tasks per thread of consecutive indices, taken dynamically. Each
// f(i) must depend only on i: which thread runs it never changes a result (per-thread
// scratch is indexed by thread_index()). A team of one never touches the pool: forward
// passes allocate nothing on one thread either.
template <class F>
void parallel_for(long long n, bool parallel, F&& f) {
#ifdef ROADNN_THREADS
  const int threads = parallel && n > 1 ? static_cast<int>(std::min<long long>(team_size(), n)) : 1;
  if (threads > 1) {
    struct Ctx {
      F* f;
      long long n, tasks;
    } ctx{&f, n, std::min<long long>(n, static_cast<long long>(kTasksPerThread) * threads)};
    detail::run_tasks(ctx.tasks, threads, [](void* c, long long t, int) {
      const Ctx& x = *static_cast<const Ctx*>(c);
      const long long i1 = (t + 1) * x.n / x.tasks;
      for (long long i = t * x.n / x.tasks; i < i1; ++i) (*x.f)(i);
    }, &ctx);
    return;
  }
#else
  (void)parallel;
#endif
  for (long long i = 0; i < n; ++i) f(i);
}

// Runs f(id, team) once for every id in [0, team), team = min(threads, team_size()),
// the ids taken dynamically by the team's threads (one thread may run several); on the
// calling thread alone, f(0, 1), without touching the pool.
template <class F>
void parallel_team(int threads, F&& f) {
#ifdef ROADNN_THREADS
  threads = std::min(threads, team_size());
  if (threads > 1) {
    struct Ctx {
      F* f;
      int team;
    } ctx{&f, threads};
    detail::run_tasks(threads, threads, [](void* c, long long t, int) {
      const Ctx& x = *static_cast<const Ctx*>(c);
      (*x.f)(static_cast<int>(t), x.team);
    }, &ctx);
    return;
  }
#else
  (void)threads;
#endif
  f(0, 1);
}

}  // namespace nn
