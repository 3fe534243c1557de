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
  }
  // The distinct worker threads that joined so far.
  size_t workers() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return workers_.size();
  }

 private:
  mutable std::mutex mutex_;
  std::set<std::thread::id> workers_;
};

// Runs f in an arena of `threads` (more than 1) until a worker has joined, at most `attempts`
// times; whether one did. A short run may end before a woken worker arrives, more so on a
// loaded machine, so a single run would be a flaky check; the runs follow each other in the
// same arena, so a worker late for one joins a later one. Each run's results are f's to check.
template <class F>
bool runs_until_a_worker_joins(int threads, int attempts, const F& f) {
  tbb::task_arena arena(threads);
  ArenaThreads joined(arena);
  arena.execute([&] {
    for (int i = 0; i < attempts && joined.workers() == 0; ++i) f();
  });
  return joined.workers() > 0;
}

// Runs check on `threads` threads: once in an arena of one, or, for more, until a worker joins
// (runs_until_a_worker_joins); where a second CPU is there (test_common.h, check_runs), a run
// on more than one thread that no worker joined fails the test, naming `what` ran.
template <class F>
void expect_on_threads(int threads, int attempts, const F& check, const std::string& what) {
  if (threads == 1) {
    tbb::task_arena(1).execute(check);
    return;
  }
  const bool joined = runs_until_a_worker_joins(threads, attempts, check);
  if (check_runs(tbb::info::default_concurrency() >= 2, "a second CPU")) {
    EXPECT_TRUE(joined) << threads << " threads: " << what << " ran on one";
  }
}

}  // namespace vobb::test
