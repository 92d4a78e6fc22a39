#pragma once
// Runs the chunks of one parallel phase of an iteration (sampling, rollouts, weighted sum) on
// the controller's CPU threads, as its ThreadSchedule says:
//   kWorkStealing  oneTBB: a task arena of `threads` slots; idle threads steal chunks and,
//                  after a short spin, sleep instead of spinning against other processes
//   kDynamic       OpenMP, each thread takes the next chunk when done (OMP_WAIT_POLICY applies)
//   kStatic        OpenMP, equal shares fixed in advance
// body(i, slot) is called once for every i in [0, n); `slot` in [0, threads) is unique among
// the calls running at the same time (for per-thread scratch memory). Results do not depend on
// the schedule: each i is computed the same way by whichever thread runs it.
#include <omp.h>

#include <memory>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>
#include <tbb/task_arena.h>

#include "mppi/controller_options.hpp"

// ThreadSanitizer builds: Debian's oneTBB is not instrumented, so TSan cannot see that handing a
// task to a worker orders it after what the calling thread wrote before, nor that the end of
// parallel_for orders the caller after the tasks. run() states both edges itself.
#if defined(__SANITIZE_THREAD__)
#define MPPI_TSAN_ANNOTATE 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define MPPI_TSAN_ANNOTATE 1
#endif
#endif
#ifdef MPPI_TSAN_ANNOTATE
extern "C" void __tsan_acquire(void* addr);
extern "C" void __tsan_release(void* addr);
#endif

namespace mppi {

class ParallelRunner {
 public:
  ParallelRunner(int threads, ThreadSchedule schedule)
      : threads_(threads > 0 ? threads : omp_get_max_threads()), schedule_(schedule) {
    if (schedule_ == ThreadSchedule::kWorkStealing && threads_ > 1) {
      arena_ = std::make_unique<tbb::task_arena>(threads_, /*reserved for this thread:*/ 1);
      arena_->initialize();
    }
  }

  int threads() const noexcept { return threads_; }
  ThreadSchedule schedule() const noexcept { return schedule_; }

  // body(i, slot) for i in [0, n), `grain` consecutive i per task.
  template <class Body>
  void run(int n, int grain, const Body& body) const {
    if (threads_ == 1) {
      for (int i = 0; i < n; ++i) body(i, 0);
      return;
    }
    if (arena_) {
#ifdef MPPI_TSAN_ANNOTATE
      int handover = 0;  // only its address matters: TSan's name for the edges below
      __tsan_release(&handover);
#endif
      arena_->execute([&] {
        tbb::parallel_for(
            tbb::blocked_range<int>(0, n, grain),
            [&](const tbb::blocked_range<int>& r) {
#ifdef MPPI_TSAN_ANNOTATE
              __tsan_acquire(&handover);
#endif
              const int slot = tbb::this_task_arena::current_thread_index();
              for (int i = r.begin(); i < r.end(); ++i) body(i, slot);
#ifdef MPPI_TSAN_ANNOTATE
              __tsan_release(&handover);
#endif
            },
            tbb::simple_partitioner());
      });
#ifdef MPPI_TSAN_ANNOTATE
      __tsan_acquire(&handover);
#endif
      return;
    }
    if (schedule_ == ThreadSchedule::kDynamic) omp_set_schedule(omp_sched_dynamic, grain);
    else omp_set_schedule(omp_sched_static, 0);
#pragma omp parallel for schedule(runtime) num_threads(threads_)
    for (int i = 0; i < n; ++i) body(i, omp_get_thread_num());
  }

 private:
  int threads_;
  ThreadSchedule schedule_;
  std::unique_ptr<tbb::task_arena> arena_;
};

}  // namespace mppi
