#pragma once
// The simulation's side of the operator page. After each step, and only while a page is
// connected and the frame interval has passed, it captures a LiveFrame into its back buffer
// and swaps it into a one-slot mailbox if the lock is free at once (otherwise the frame is
// skipped): the simulation thread never waits on the server. The operator's requests (pause,
// target speed, runstop, stop) come back through poll_requests(). It can also pace the
// simulation to wall-clock time, and it keeps the optimizer times of the steps run with and
// without a page connected.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "chassis/priorities.hpp"
#include "ocs/live_frame.hpp"
#include "sim/step_observer.hpp"

namespace mppi::ocs {

struct LiveSettings {
  double frame_rate_hz = 20.0;  // frames captured per second of wall time, at most
  bool realtime = true;         // hold the simulation to wall-clock time
  bool allow_pause = true;      // false: the page's pause is refused (a vehicle cannot pause)
};

// Optimizer times split by whether a page was connected during the step.
struct TimingSplit {
  std::vector<double> without_page_ms, with_page_ms;
};

class LiveObserver final : public sim::StepObserver {
 public:
  explicit LiveObserver(LiveSettings settings = {});

  // --- simulation thread ---
  void on_start(sim::PathPredictor predictor) override;
  void after_step(const sim::StepView& view) override;
  sim::OperatorRequests poll_requests(double t_s) override;
  void on_finish() override;

  // --- server threads ---
  // Copies the newest frame into *out if there is one newer than *seen; never blocks.
  bool take_frame(LiveFrame* out, std::uint64_t* seen);
  const sim::PathPredictor& predictor() const { return predictor_; }  // set before the server starts
  // The chassis' controller priorities (empty until the first step through a chassis).
  std::vector<chassis::PriorityEntry> priorities() const;
  void add_client() { clients_.fetch_add(1); }
  void remove_client() { clients_.fetch_sub(1); }
  int clients() const { return clients_.load(); }
  bool pause_allowed() const { return settings_.allow_pause; }
  void request_pause(bool paused) { paused_ = paused && settings_.allow_pause; }
  void request_target_speed(double mps);
  void request_motion_enabled(bool enabled);
  void request_stop() { stop_ = true; }
  bool paused() const { return paused_.load(); }
  bool finished() const { return finished_.load(); }
  bool motion_enabled_request() const { return motion_enabled_.load(); }
  // The last target speed the page asked for (none before the first request).
  std::optional<double> target_speed_request() const;

  TimingSplit timing() const;  // call after the run

 private:
  LiveSettings settings_;
  sim::PathPredictor predictor_;
  std::atomic<int> clients_{0};
  std::atomic<bool> paused_{false}, stop_{false}, finished_{false}, motion_enabled_{true};
  std::atomic<double> last_target_speed_{-1.0};  // < 0: none requested

  // frames: back_ is the simulation thread's, shared_ is guarded by frame_mutex_
  LiveFrame back_, shared_;
  std::uint64_t sequence_ = 0;
  std::mutex frame_mutex_;
  std::chrono::steady_clock::time_point next_capture_{};
  bool reserved_ = false;

  mutable std::mutex info_mutex_;
  std::vector<chassis::PriorityEntry> priorities_;
  bool have_priorities_ = false;

  std::mutex request_mutex_;
  std::optional<double> target_speed_request_;
  std::optional<bool> motion_request_;

  // pacing: wall time of simulated time 0, moved on by the time spent paused
  std::chrono::steady_clock::time_point wall_zero_{};
  bool started_ = false;

  TimingSplit timing_;
};

}  // namespace mppi::ocs
