#include "ocs/live_observer.hpp"

#include <algorithm>
#include <cmath>
#include <thread>

#include "chassis/sim_adapter.hpp"
#include "mppi/controller.hpp"

namespace mppi::ocs {

using Clock = std::chrono::steady_clock;

LiveObserver::LiveObserver(LiveSettings settings) : settings_(settings) {
  // 2^18 steps each (87 min at 50 Hz); later steps are not recorded, so nothing allocates here
  timing_.without_page_ms.reserve(1 << 18);
  timing_.with_page_ms.reserve(1 << 18);
}

void LiveObserver::on_start(sim::PathPredictor predictor) { predictor_ = std::move(predictor); }

void LiveObserver::after_step(const sim::StepView& view) {
  const bool connected = clients_.load(std::memory_order_relaxed) > 0;
  std::vector<double>& times = connected ? timing_.with_page_ms : timing_.without_page_ms;
  if (times.size() < times.capacity()) times.push_back(view.summary->optimizer_ms);
  if (view.chassis && !have_priorities_) {  // once: the chassis' priority list for the page
    const std::lock_guard<std::mutex> lock(info_mutex_);
    priorities_ = view.chassis->arbiter().priorities().entries();
    have_priorities_ = true;
  }
  if (!connected) return;
  const auto now = Clock::now();
  if (now < next_capture_) return;
  next_capture_ = now + std::chrono::duration_cast<Clock::duration>(
                            std::chrono::duration<double>(1.0 / settings_.frame_rate_hz));
  const ControllerOptions& o = view.controller->options();
  const int nu = static_cast<int>(o.noise_std.size());
  if (!reserved_) {  // first capture: size both buffers once
    back_.reserve(static_cast<int>(view.model_state.size()), nu, o.horizon);
    shared_.reserve(static_cast<int>(view.model_state.size()), nu, o.horizon);
    reserved_ = true;
  }
  LiveFrame& f = back_;
  f.t_s = view.t_s;
  f.state = view.state;
  f.output = view.output;
  f.applied = view.applied;
  f.optimizer_ms = static_cast<float>(view.summary->optimizer_ms);
  f.effective_sample_size = view.summary->effective_sample_size;
  f.valid_samples = view.summary->valid_samples;
  f.num_samples = o.num_samples;
  f.laps_completed = view.laps_completed;
  f.crashes = view.crashes;
  f.progress_m = view.progress_m;
  f.target_speed_mps = view.target_speed_mps;
  f.chassis.present = view.chassis != nullptr || view.remote_chassis;
  if (view.remote_chassis) {  // only the flags of its state message; who commands is not sent
    f.chassis.motion_enabled = view.remote_motion_enabled;
    f.chassis.watchdog_tripped = view.remote_watchdog_tripped;
    f.chassis.steering_commander = f.chassis.throttle_commander = f.chassis.front_brake_commander = kCommanderNotReported;
  } else if (view.chassis) {
    const chassis::Decision& d = view.chassis->last_output().decision;
    f.chassis.motion_enabled = d.motion_enabled;
    f.chassis.watchdog_tripped = d.watchdog_tripped;
    f.chassis.steering_commander = d.steering_commander;
    f.chassis.throttle_commander = d.throttle_commander;
    f.chassis.front_brake_commander = d.front_brake_commander;
    f.chassis.commands_accepted = view.chassis->arbiter().counters().commands_accepted;
    f.chassis.runstops_accepted = view.chassis->arbiter().counters().runstops_accepted;
  }
  f.model_state.assign(view.model_state.begin(), view.model_state.end());
  const float first[2] = {view.output.steer, view.output.throttle};
  float first_control[8] = {};
  for (int c = 0; c < nu && c < 8; ++c) first_control[c] = c < 2 ? first[c] : view.controller->nominal()[c];
  capture_paths(*view.controller, std::span<const float>(first_control, static_cast<std::size_t>(std::min(nu, 8))), f);
  std::unique_lock<std::mutex> lock(frame_mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return;  // a server thread is copying: skip this frame
  std::swap(back_, shared_);
  shared_.step = ++sequence_;
}

bool LiveObserver::take_frame(LiveFrame* out, std::uint64_t* seen) {
  std::unique_lock<std::mutex> lock(frame_mutex_, std::try_to_lock);
  if (!lock.owns_lock() || sequence_ == *seen) return false;
  *out = shared_;
  *seen = sequence_;
  return true;
}

std::vector<chassis::PriorityEntry> LiveObserver::priorities() const {
  const std::lock_guard<std::mutex> lock(info_mutex_);
  return priorities_;
}

std::optional<double> LiveObserver::target_speed_request() const {
  const double v = last_target_speed_.load();
  return v < 0.0 ? std::nullopt : std::optional<double>(v);
}

void LiveObserver::request_target_speed(double mps) {
  last_target_speed_ = mps;
  const std::lock_guard<std::mutex> lock(request_mutex_);
  target_speed_request_ = mps;
}

void LiveObserver::request_motion_enabled(bool enabled) {
  motion_enabled_ = enabled;
  const std::lock_guard<std::mutex> lock(request_mutex_);
  motion_request_ = enabled;
}

sim::OperatorRequests LiveObserver::poll_requests(double t_s) {
  sim::OperatorRequests r;
  auto wall_of = [&](double sim_s) {
    return wall_zero_ + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(sim_s));
  };
  if (!started_) {
    wall_zero_ = Clock::now() - std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(t_s));
    started_ = true;
  }
  if (paused_) {  // the operator holds the simulation; the time paused does not count
    const auto paused_at = Clock::now();
    while (paused_ && !stop_) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    wall_zero_ += Clock::now() - paused_at;
  }
  if (settings_.realtime) {
    const auto due = wall_of(t_s);
    if (Clock::now() < due) std::this_thread::sleep_until(due);
  }
  r.stop = stop_;
  if (std::unique_lock<std::mutex> lock(request_mutex_, std::try_to_lock); lock) {
    r.target_speed_mps = target_speed_request_;
    r.motion_enabled = motion_request_;
    target_speed_request_.reset();
    motion_request_.reset();
  }
  return r;
}

void LiveObserver::on_finish() { finished_ = true; }

TimingSplit LiveObserver::timing() const { return timing_; }

}  // namespace mppi::ocs
