#include "ocs/loop_page.hpp"

#include <cstdio>

#include "mppi/controller.hpp"
#include "ocs/live_observer.hpp"
#include "ocs/server.hpp"
#include "ocs/track_json.hpp"

namespace mppi::ocs {

LoopPage::LoopPage(ServerSettings server_settings, const std::string& track, sim::PathPredictor predictor,
                   double target_speed_mps)
    : target_speed_mps_(target_speed_mps) {
  LiveSettings settings;
  settings.realtime = false;      // the control loop keeps its own clock
  settings.allow_pause = false;   // a vehicle cannot be paused: the runstop stops it
  live_ = std::make_unique<LiveObserver>(settings);
  live_->on_start(std::move(predictor));
  server_ = std::make_unique<OcsServer>(std::move(server_settings), live_.get(),
                                        track.empty() ? std::string() : track_json(track, false), "");
  server_->start();
  std::fprintf(stderr, "ocs: operator page on %s\n", server_->page_url().c_str());
}

LoopPage::~LoopPage() { server_->stop(); }

void LoopPage::apply_requests(Controller& controller) {
  const sim::OperatorRequests r = live_->poll_requests(0.0);
  std::string why;
  if (r.target_speed_mps && controller.set_cost_param("target_speed_mps", *r.target_speed_mps, &why))
    target_speed_mps_ = *r.target_speed_mps;
  else if (r.target_speed_mps)
    std::fprintf(stderr, "ocs: target speed refused: %s\n", why.c_str());
}

void LoopPage::after_step(double t_s, const VehicleState& state, std::span<const float> model_state, Control output,
                          Control applied, const StepSummary& summary, const Controller& controller,
                          bool motion_enabled, bool watchdog_tripped) {
  sim::StepView v;
  v.t_s = t_s;
  v.state = state;
  v.model_state = model_state;
  v.output = output;
  v.applied = applied;
  v.summary = &summary;
  v.controller = &controller;
  v.target_speed_mps = target_speed_mps_;
  v.remote_chassis = true;
  v.remote_motion_enabled = motion_enabled;
  v.remote_watchdog_tripped = watchdog_tripped;
  live_->after_step(v);
}

bool LoopPage::motion_allowed() const { return live_->motion_enabled_request(); }

}  // namespace mppi::ocs
