// The controller's parallel phases on oneTBB's work stealing (mppi/thread_schedule.hpp). These
// cases are also the ThreadSanitizer's view of that schedule (scripts/sanitize.sh, tag
// [threads]): the writes below are plain, so two threads touching the same element or the same
// scratch slot at once would be a reported race as well as a wrong sum.
#include <catch2/catch.hpp>
#include <vector>

#include "mppi/controller.hpp"
#include "mppi/thread_schedule.hpp"
#include "tests/mppi/linear_system.hpp"

TEST_CASE("work stealing calls the body once per index, slots never shared at the same time",
          "[core][mppi][threads]") {
  const int n = 20000, threads = 2;
  mppi::ParallelRunner runner(threads, mppi::ThreadSchedule::kWorkStealing);
  REQUIRE(runner.threads() == threads);
  for (int repeat = 0; repeat < 20; ++repeat) {
    std::vector<int> visits(n, 0);
    std::vector<long long> slot_sum(threads, 0);  // per-slot scratch, as the controller uses it
    int bad_slots = 0;
    runner.run(n, 64, [&](int i, int slot) {
      ++visits[i];
      if (slot < 0 || slot >= threads) {
        ++visits[i];  // counted as a second visit: fails below without a shared counter
        return;
      }
      slot_sum[slot] += i;
    });
    for (int i = 0; i < n; ++i) bad_slots += visits[i] != 1;
    REQUIRE(bad_slots == 0);
    long long total = 0;
    for (long long s : slot_sum) total += s;
    REQUIRE(total == static_cast<long long>(n) * (n - 1) / 2);  // closed form of 0 + 1 + ... + n-1
  }
}

TEST_CASE("two work-stealing threads give the controls of one thread", "[core][mppi][threads]") {
  mppi::ControllerOptions o;
  o.num_samples = 1000;
  o.horizon = 30;
  o.iterations = 2;
  o.smoothing_window = 5;
  o.noise_std = {0.5f};
  o.control_min = {-5.f};
  o.control_max = {5.f};
  o.safe_control = {0.f};
  o.schedule = mppi::ThreadSchedule::kWorkStealing;
  std::vector<std::vector<float>> runs;
  for (int threads : {1, 2}) {
    o.num_threads = threads;
    auto controller = mppi::make_cpu_controller(mppi::test::DoubleIntegrator{}, mppi::test::QuadraticCost{}, o);
    std::vector<float> controls;
    float x[2] = {1.f, 0.3f};
    for (int step = 0; step < 10; ++step) {
      const float u = controller.step(x)[0];
      controls.push_back(u);
      x[0] += 0.1f * x[1];
      x[1] += 0.1f * u;
    }
    runs.push_back(controls);
  }
  for (std::size_t i = 0; i < runs[0].size(); ++i) REQUIRE(runs[0][i] == runs[1][i]);
}
