// The engine's threads (nn/threads.h over nn/thread_pool.h): every index runs exactly
// once, slots are unique among the threads of one region, nested regions run serially,
// and jobs keep working across sleeps, growth, shrinking and many threads.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <future>
#include <thread>
#include <vector>

#include "nn/exec.h"
#include "nn/threads.h"

namespace {

// Sets the calling thread's thread count for the test's duration.
struct Threads {
  explicit Threads(int n) : scope(nn::with_threads(n)) {}
  nn::ExecScope scope;
};

TEST(Threads, EveryIndexRunsOnceForAnyCountAndTeam) {
  for (int threads : {1, 2, 3, 8}) {
    Threads t(threads);
    for (long long n : {0LL, 1LL, 2LL, 3LL, 7LL, 64LL, 1001LL}) {
      std::vector<std::atomic<int>> hits(static_cast<std::size_t>(n));
      nn::parallel_for(n, true, [&](long long i) { hits[static_cast<std::size_t>(i)].fetch_add(1); });
      for (long long i = 0; i < n; ++i)
        ASSERT_EQ(hits[static_cast<std::size_t>(i)].load(), 1) << "threads " << threads << " n " << n << " i " << i;
    }
  }
}

TEST(Threads, SlotsAreUniqueAmongTheRunningThreadsAndBelowTheTeam) {
  constexpr int kThreads = 4;
  Threads t(kThreads);
  std::atomic<int> busy[kThreads] = {};
  std::atomic<int> clashes{0}, out_of_range{0};
  for (int job = 0; job < 200; ++job)
    nn::parallel_for(64, true, [&](long long) {
      const int slot = nn::thread_index();
      if (slot < 0 || slot >= kThreads) {
        out_of_range.fetch_add(1);
        return;
      }
      if (busy[slot].fetch_add(1) != 0) clashes.fetch_add(1);
      std::this_thread::yield();
      busy[slot].fetch_sub(1);
    });
  EXPECT_EQ(out_of_range.load(), 0);
  EXPECT_EQ(clashes.load(), 0) << "two threads of one region had the same slot (their scratch would overlap)";
}

TEST(Threads, InsideARegionTheTeamIsOneAndNestedLoopsRunOnTheirThread) {
  Threads t(3);
  const int team = nn::num_threads();  // 3, or 1 in a build without threads
  EXPECT_EQ(nn::team_size(), team);
  EXPECT_EQ(nn::thread_index(), 0);
  std::atomic<int> wrong{0}, inner{0};
  nn::parallel_for(12, true, [&](long long) {
    if (nn::team_size() != 1) wrong.fetch_add(1);
    const int slot = nn::thread_index();
    nn::parallel_for(5, true, [&](long long) {
      inner.fetch_add(1);
      if (nn::thread_index() != slot) wrong.fetch_add(1);
    });
  });
  EXPECT_EQ(wrong.load(), 0);
  EXPECT_EQ(inner.load(), 60);
  EXPECT_EQ(nn::team_size(), team);  // restored outside
  EXPECT_EQ(nn::thread_index(), 0);
}

TEST(Threads, TeamRunsEachIdOnceWithTheClampedTeamSize) {
  Threads t(3);
  for (int asked : {1, 2, 3, 5}) {
    std::vector<std::atomic<int>> hits(8);
    std::atomic<int> bad_team{0};
    const int expected = std::min(asked, nn::num_threads());  // 3, or 1 without threads
    nn::parallel_team(asked, [&](int id, int team) {
      if (team != expected) bad_team.fetch_add(1);
      hits[static_cast<std::size_t>(id)].fetch_add(1);
    });
    EXPECT_EQ(bad_team.load(), 0) << "asked " << asked;
    for (int i = 0; i < 8; ++i) EXPECT_EQ(hits[static_cast<std::size_t>(i)].load(), i < expected ? 1 : 0) << "asked " << asked;
  }
}

// Workers that went to sleep between jobs (longer than their polling) wake for the next
// one; the thread count may rise and fall between jobs.
TEST(Threads, JobsAfterSleepsAndCountChangesStillRunEverything) {
  for (int round = 0; round < 6; ++round) {
    Threads t(round % 2 ? 2 : 5);
    std::atomic<long long> sum{0};
    nn::parallel_for(1000, true, [&](long long i) { sum.fetch_add(i); });
    EXPECT_EQ(sum.load(), 999LL * 1000 / 2) << "round " << round;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

// Two callers on two threads each have their own pool: their regions neither mix nor
// wait for each other.
TEST(Threads, TwoCallingThreadsRunTheirRegionsIndependently) {
  auto worker = [](long long* result) {
    Threads t(2);
    long long total = 0;
    for (int job = 0; job < 300; ++job) {
      std::atomic<long long> sum{0};
      nn::parallel_for(100, true, [&](long long i) { sum.fetch_add(i + job); });
      total += sum.load();
    }
    *result = total;
  };
  long long a = 0, b = 0;
  std::thread ta(worker, &a), tb(worker, &b);
  ta.join();
  tb.join();
  long long expected = 0;
  for (int job = 0; job < 300; ++job) expected += 99LL * 100 / 2 + 100LL * job;
  EXPECT_EQ(a, expected);
  EXPECT_EQ(b, expected);
}

// A region whose worker is held up (here: a task that sleeps) still completes, and every
// index is done by then: the caller waits for claimed work, never skips it.
TEST(Threads, ARegionWaitsForATaskStillRunningOnAnotherThread) {
  Threads t(2);
  std::atomic<int> finished{0};
  nn::parallel_for(8, true, [&](long long i) {
    if (i == 0 || i == 7) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    finished.fetch_add(1);
  });
  EXPECT_EQ(finished.load(), 8);
}

// Many short jobs whose task counts alternate between few and many: a worker still
// looking at a finished job must never claim a task of it that does not exist when the
// next, larger job is being written (that once ran tasks twice or out of range, let the
// caller return before a task finished, or left it waiting forever). The jobs run on
// their own thread so that a hang becomes a failure naming the test, not a suite timeout.
TEST(Threads, AlternatingJobSizesRunEveryTaskOnceWithoutHanging) {
  struct Count {
    int threads;
    long long wrong, out_of_range;
  };
  auto jobs = std::async(std::launch::async, [] {
    std::vector<Count> counts;
    for (int threads : {2, 3, 8}) {
      Threads t(threads);
      std::vector<std::atomic<int>> hits(static_cast<std::size_t>(4 * threads));
      long long wrong = 0;
      std::atomic<long long> out_of_range{0};
      for (int job = 0; job < 20000 && wrong + out_of_range.load() == 0; ++job) {
        const long long n = job % 2 ? 2 : 4 * threads;
        nn::parallel_for(n, true, [&](long long i) {
          if (i < 0 || i >= n) {
            out_of_range.fetch_add(1);
            return;
          }
          hits[static_cast<std::size_t>(i)].fetch_add(1, std::memory_order_relaxed);
        });
        for (long long i = 0; i < n; ++i)
          if (hits[static_cast<std::size_t>(i)].exchange(0) != 1) ++wrong;
      }
      counts.push_back({threads, wrong, out_of_range.load()});
    }
    return counts;
  });
  if (jobs.wait_for(std::chrono::seconds(300)) != std::future_status::ready) {
    ADD_FAILURE() << "a job did not finish within 300 s (the pool lost a task or a wake-up)";
    std::_Exit(1);  // the blocked thread cannot be joined
  }
  for (const Count& c : jobs.get()) {
    EXPECT_EQ(c.wrong, 0) << c.threads
                          << " threads: a task ran twice, or had not finished when the job returned";
    EXPECT_EQ(c.out_of_range, 0) << c.threads << " threads: a task index beyond the job's range ran";
  }
}

}  // namespace
