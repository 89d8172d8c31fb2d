#include "nn/threads.h"

#include "nn/exec.h"

#ifdef ROADNN_THREADS
#include <thread>

#include "nn/thread_pool.h"
#ifdef __linux__
#include <sched.h>
#endif
#endif

namespace nn {

ExecOptions& mutable_exec();  // nn/exec.cpp

void set_num_threads(int n) { mutable_exec().threads = n; }

#ifdef ROADNN_THREADS
namespace {

// The cores this process may run on (its affinity mask, as `taskset` or a container
// sets it), else all the machine has.
int available_cores() {
#ifdef __linux__
  cpu_set_t set;
  if (sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) > 0) return CPU_COUNT(&set);
#endif
  const unsigned n = std::thread::hardware_concurrency();
  return n > 0 ? static_cast<int>(n) : 1;
}

// The calling thread's slot in the region it is running a task of, -1 outside one.
thread_local int tl_slot = -1;

}  // namespace

namespace detail {

void run_tasks(long long tasks, int threads, TaskFn fn, void* ctx) {
  struct Region {
    TaskFn fn;
    void* ctx;
  } region{fn, ctx};
  // Every thread, the caller included, marks itself inside the region for the task's
  // duration: team_size() is 1 there and thread_index() its slot.
  ThreadPool::of_this_thread().run(tasks, threads, [](void* c, long long t, int slot) noexcept {
    const Region& r = *static_cast<const Region*>(c);
    const int outer = tl_slot;
    tl_slot = slot;
    r.fn(r.ctx, t, slot);
    tl_slot = outer;
  }, &region);
}

}  // namespace detail

int num_threads() {
  const int n = current_exec().threads;
  static const int cores = available_cores();
  return n > 0 ? n : cores;
}

int thread_index() { return tl_slot < 0 ? 0 : tl_slot; }

int team_size() { return tl_slot < 0 ? num_threads() : 1; }

#else

int num_threads() { return 1; }
int thread_index() { return 0; }
int team_size() { return 1; }

#endif

}  // namespace nn
