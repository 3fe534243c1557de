// A test helper for claims of the form "the same result on any number of threads": it counts
// the TBB worker threads that joined an arena while it was observed, so that such a test can
// assert that the code offered work in parallel (on one CPU, an arena of four runs serially
// and the claim holds by construction). A worker that joins may still arrive after the work it
// was called for is done: this shows that the code is parallel, not that two threads ran at
// once.
#pragma once

#include <tbb/info.h>
#include <tbb/task_arena.h>
#include <tbb/task_scheduler_observer.h>

#include <chrono>
#include <mutex>
#include <set>
#include <string>
#include <thread>

#include "test_common.h"

namespace vobb::test {

// Observes `arena` from construction to destruction. A worker joins an arena only when the
// arena holds work that is waiting for a thread, so workers() > 0 means that the code run in
// it offered work in parallel and another thread came for it.
class ArenaThreads : public tbb::task_scheduler_observer {
 public:
  explicit ArenaThreads(tbb::task_arena& arena) : tbb::task_scheduler_observer(arena) {
    observe(true);
  }
  ~ArenaThreads() override { observe(false); }
  void on_scheduler_entry(bool is_worker) override {
    if (!is_worker) return;
    const std::lock_guard<std::mutex> lock(mutex_);
    workers_.insert(std::this_thread::get_id());
    ++inside_;
  }
  void on_scheduler_exit(bool is_worker) override {
    if (!is_worker) return;
    const std::lock_guard<std::mutex> lock(mutex_);
    --inside_;
  }
  // The distinct worker threads that joined so far.
  size_t workers() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return workers_.size();
  }
  // Waits, at most `patience`, until every worker that joined has left the arena (an idle worker
  // leaves within milliseconds). TBB keeps its record of this observer while a worker that it
  // notified is inside; one still inside when the process ends keeps it for good, and
  // LeakSanitizer reports the record as a leak.
  void wait_until_workers_left(std::chrono::seconds patience) const {
    const auto until = std::chrono::steady_clock::now() + patience;
    for (;;) {
      {
        const std::lock_guard<std::mutex> lock(mutex_);
        if (inside_ <= 0) return;
      }
      if (std::chrono::steady_clock::now() >= until) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }

 private:
  mutable std::mutex mutex_;
  std::set<std::thread::id> workers_;
  int inside_ = 0;  // workers in the arena now
};

// Runs f in an arena of `threads` (more than 1), again and again until a worker has joined or
// `patience` has passed (f runs at least once); whether one joined. A woken worker needs a CPU
// before it can join, and on a loaded machine (ctest -j2 beside a two-thread test) it may get
// none for the length of many short runs, so a fixed count of runs would be a flaky check. The
// runs follow each other in the same arena, so a worker late for one joins a later one. Each
// run's results are f's to check.
template <class F>
bool runs_until_a_worker_joins(int threads, std::chrono::seconds patience, const F& f) {
  tbb::task_arena arena(threads);
  ArenaThreads joined(arena);
  const auto until = std::chrono::steady_clock::now() + patience;
  arena.execute([&] {
    do f();
    while (joined.workers() == 0 && std::chrono::steady_clock::now() < until);
  });
  joined.wait_until_workers_left(std::chrono::seconds(10));
  return joined.workers() > 0;
}

// Runs check on `threads` threads: once in an arena of one, or, for more, until a worker joins
// (runs_until_a_worker_joins). Where a second CPU is there (test_common.h, check_runs), a run on
// more than one thread that no worker joined within 30 s fails the test, naming `what` ran: the
// scheduler gives a runnable thread a CPU within milliseconds even beside two busy ones, so
// 30 s is missed only where the code offered no parallel work. Without a second CPU, no worker
// can join and check runs once.
template <class F>
void expect_on_threads(int threads, const F& check, const std::string& what) {
  if (threads == 1) {
    tbb::task_arena(1).execute(check);
    return;
  }
  if (!check_runs(tbb::info::default_concurrency() >= 2, "a second CPU")) {
    tbb::task_arena(threads).execute(check);
    return;
  }
  const bool joined = runs_until_a_worker_joins(threads, std::chrono::seconds(30), check);
  EXPECT_TRUE(joined) << threads << " threads: " << what << " ran on one";
}

}  // namespace vobb::test
