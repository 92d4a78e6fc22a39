#pragma once
// The operator page for a controller that runs in its own control loop against a chassis over
// UDP (apps/mppi_udp_drive.cpp), e.g. on a real vehicle. The loop calls
// apply_requests() before and after_step() after each controller step; neither waits on the
// network. There is no pause on a vehicle: the page's runstop is the operator's stop, sent by
// the loop as its runstop messages (motion_allowed()).
#include <memory>
#include <span>
#include <string>

#include "mppi/vehicle_state.hpp"
#include "ocs/server.hpp"
#include "sim/step_observer.hpp"

namespace mppi {
class Controller;
struct StepSummary;
}  // namespace mppi

namespace mppi::ocs {

class LoopPage {
 public:
  // Serves as `settings` say (127.0.0.1 by default) and prints the page's URL with its token;
  // track: the built-in track to draw ("" = none). Throws mppi::Error if the port cannot be
  // bound, the address needs TLS (OcsServer::start), or the track is unknown.
  LoopPage(ServerSettings settings, const std::string& track, sim::PathPredictor predictor, double target_speed_mps);
  ~LoopPage();

  // Applies the operator's new target speed, if any, to the controller (between steps).
  void apply_requests(Controller& controller);
  // After a step: the car as the chassis reported it, the controller's state and output, and the
  // chassis' runstop and watchdog flags from its state datagram.
  void after_step(double t_s, const VehicleState& state, std::span<const float> model_state, Control output,
                  Control applied, const StepSummary& summary, const Controller& controller,
                  bool motion_enabled, bool watchdog_tripped);
  // What the operator's runstop says: false once the page's RUNSTOP was pressed (until released).
  bool motion_allowed() const;

 private:
  std::unique_ptr<LiveObserver> live_;
  std::unique_ptr<OcsServer> server_;
  double target_speed_mps_;
};

}  // namespace mppi::ocs
