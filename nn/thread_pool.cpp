#include "nn/thread_pool.h"

#ifdef ROADNN_THREADS

#include <chrono>

namespace nn {

namespace {

// How long an idle thread polls before it blocks. Between two layers of a forward pass
// the caller's serial gap is a few microseconds, so workers that poll a little catch the
// next job without a futex wake-up (which costs tens of microseconds); between frames,
// and on a host where others need the core, they sleep.
constexpr std::chrono::microseconds kSpin{50};

inline void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#elif defined(__aarch64__)
  asm volatile("yield" ::: "memory");
#endif
}

// Polls until done() holds or kSpin has passed; true if it holds.
template <class Done>
bool spin_until(Done&& done) {
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0;; ++i) {
    if (done()) return true;
    cpu_relax();
    if ((i & 63) == 63 && std::chrono::steady_clock::now() - t0 > kSpin) return done();
  }
}

inline std::uint32_t generation(std::uint64_t state) { return static_cast<std::uint32_t>(state >> 32); }

}  // namespace

ThreadPool::~ThreadPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  for (std::thread& t : workers_) t.join();
}

ThreadPool& ThreadPool::of_this_thread() {
  thread_local ThreadPool pool;
  return pool;
}

void ThreadPool::grow(int workers) {
  // A new worker starts from the generation before the job about to be published, so it
  // takes part in that job however late the OS starts it.
  const std::uint32_t seen = generation(state_.load());
  while (static_cast<int>(workers_.size()) < workers) {
    const int slot = static_cast<int>(workers_.size()) + 1;
    workers_.emplace_back([this, slot, seen] { worker_main(slot, seen); });
  }
}

void ThreadPool::run(long long tasks, int threads, TaskFn fn, void* ctx) {
  if (tasks <= 0) return;
  grow(threads - 1);
  const std::uint32_t gen = generation(state_.load()) + 1;
  fn_.store(fn, std::memory_order_relaxed);
  ctx_.store(ctx, std::memory_order_relaxed);
  tasks_.store(tasks, std::memory_order_relaxed);
  participants_.store(threads, std::memory_order_relaxed);
  done_.store(0, std::memory_order_relaxed);
  // Publishes the fields above: generation `gen`, all `tasks` unclaimed.
  state_.store(static_cast<std::uint64_t>(gen) << 32 | static_cast<std::uint64_t>(tasks));
  if (sleepers_.load() > 0) {
    { std::lock_guard<std::mutex> lock(mutex_); }
    wake_.notify_all();
  }
  work(gen, 0);
  // Every task is claimed now (work() returns only when none is left); wait for those
  // still running on workers.
  if (spin_until([&] { return done_.load() == tasks; })) return;
  std::unique_lock<std::mutex> lock(mutex_);
  caller_waiting_.store(true);
  idle_.wait(lock, [&] { return done_.load() == tasks; });
  caller_waiting_.store(false);
}

void ThreadPool::work(std::uint32_t gen, int slot) {
  for (;;) {
    std::uint64_t s = state_.load();
    if (generation(s) != gen) return;
    const std::uint32_t unclaimed = static_cast<std::uint32_t>(s);
    if (unclaimed == 0) return;
    if (!state_.compare_exchange_weak(s, s - 1)) continue;
    // The claim succeeded on this job's word, so the fields below are this job's.
    const long long tasks = tasks_.load(std::memory_order_relaxed);
    const long long task = tasks - unclaimed;  // tasks are claimed in increasing order
    fn_.load(std::memory_order_relaxed)(ctx_.load(std::memory_order_relaxed), task, slot);
    if (done_.fetch_add(1) + 1 == tasks && slot != 0 && caller_waiting_.load()) {
      { std::lock_guard<std::mutex> lock(mutex_); }
      idle_.notify_one();
    }
  }
}

void ThreadPool::worker_main(int slot, std::uint32_t seen) {
  for (;;) {
    const auto fresh = [&] { return generation(state_.load()) != seen; };
    if (!spin_until(fresh)) {
      std::unique_lock<std::mutex> lock(mutex_);
      sleepers_.fetch_add(1);
      wake_.wait(lock, [&] { return stop_ || fresh(); });
      sleepers_.fetch_sub(1);
      if (stop_) return;
    }
    seen = generation(state_.load());
    if (slot < participants_.load(std::memory_order_relaxed)) work(seen, slot);
  }
}

}  // namespace nn

#endif  // ROADNN_THREADS
