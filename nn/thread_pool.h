// The engine's worker threads: one pool per calling thread (a session's run, a model's
// loader), grown on demand, whose workers live until that thread ends.
//
// Why not OpenMP's fork-join: at the end of every parallel region all of the team's
// threads must arrive, so on a host shared with other processes (an ECU's perception
// process always is) each layer waits for whichever thread the OS descheduled, even one
// that has not started yet. Here a job is a count of tasks that any participating thread
// claims from one counter; the caller works too, and returns once every *claimed* task
// has finished. A worker that wakes late finds nothing left and goes back to waiting,
// so a descheduled thread delays a layer by at most the task it holds.
//
// Results do not depend on which thread runs a task: tasks write disjoint outputs, and
// per-thread scratch is indexed by the running thread's slot (thread_index()), which is
// unique among the threads running one job. Dispatching a job allocates nothing; only
// creating workers does (the first job with more threads than the pool has).
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

namespace nn {

class ThreadPool {
 public:
  // f(ctx, task, slot): runs task `task` on the thread with slot `slot` (0 = the caller).
  using TaskFn = void (*)(void* ctx, long long task, int slot);

  ThreadPool() = default;
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  // Runs fn(ctx, t, slot) for every t in [0, tasks) on up to `threads` threads (the
  // caller and threads - 1 workers) and returns when all have finished. tasks < 2^31.
  void run(long long tasks, int threads, TaskFn fn, void* ctx);

  // The pool of the calling thread (created on first use).
  static ThreadPool& of_this_thread();

 private:
  void grow(int workers);
  // Waits for jobs after generation `seen` and works on them until the pool stops.
  void worker_main(int slot, std::uint32_t seen);
  // Claims and runs tasks of job `gen` until none is left.
  void work(std::uint32_t gen, int slot);

  // state_: the job's generation (high 32 bits) and how many of its tasks are still
  // unclaimed (low 32). A thread claims a task with a compare-exchange that also checks
  // the generation, so a worker that saw an older job can never claim a task of the
  // current one by mistake. The word alone decides whether a task is left: a claim that
  // first compared against tasks_ could read the *next* job's count (written once the
  // caller saw this job finish) while the word still held this job's generation, and
  // claim a task that does not exist.
  std::atomic<std::uint64_t> state_{0};
  // The job's description, valid while its generation is current. Written by the
  // caller before it publishes the generation; read by a worker only after its claim
  // succeeded (the job cannot finish, so the next cannot be written, before the claimed
  // task has).
  std::atomic<TaskFn> fn_{nullptr};
  std::atomic<void*> ctx_{nullptr};
  std::atomic<long long> tasks_{0};
  std::atomic<int> participants_{0};
  std::atomic<long long> done_{0};  // tasks finished in the current job

  std::mutex mutex_;
  std::condition_variable wake_;  // workers: a new job or stop
  std::condition_variable idle_;  // caller: the last claimed task finished
  std::atomic<int> sleepers_{0};  // workers blocked on wake_
  std::atomic<bool> caller_waiting_{false};
  bool stop_ = false;             // under mutex_
  std::vector<std::thread> workers_;
};

}  // namespace nn
