#pragma once
// Online adaptation to the grip the car has: at every control step the controller compares how
// the measured lateral velocity changed with how its model said it would, fits a scale of the
// model's lateral tyre force, and
//   - holds a target speed of the requested one x scale^speed_exponent (the cost parameter
//     `speed_param`): 0.5 is the law of steady cornering (the speed a car holds in a turn of given
//     radius goes with sqrt(mu)); the default 1 leaves a margin for a model that is wrong in a
//     slide as well;
//   - caps the throttle at its upper limit x scale^throttle_exponent (the control channel
//     control::kThrottle): the drive torque the rear tyres pass on without spinning goes with mu,
//     and a model that believes in more grip plans a throttle that spins the car out of a turn;
//   - with `scale_model`, also plans with the model's lateral force (and yaw moment) scaled by it
//     (the model parameter kLateralForceScaleParam, e.g. dynamics/autorally_nn.hpp).
// It is for a surface that grips less (or more) than the one the model learnt: wet, dusty, worn
// tyres. The speed is what keeps the car on the track (docs/CONTROLLER.md, "Grip adaptation"):
// with the AutoRally network on a plant of 30 % less grip, the governed speed alone laps without
// a crash, while the network with its force scaled still spins out now and then, since the scale
// does not mend the network's yaw in a slide (below). So `scale_model` is off by default. The
// fitted scale is the network's against that plant, not the plant's grip alone: about 0.85 on the
// nominal plant, 0.63 on the one of 30 % less grip.
//
// The model is asked for one step from the last measured state under the input that acted (after
// the actuators), at its current scale s_now (1 without `scale_model`). The force part of the lateral velocity's change
// (the change less the kinematic term -vx r), measured with a trapezoid (the car moved on within
// the step) and predicted with the model's own Euler term:
//   m = (vy1 - vy0) + (vx0 r0 + vx1 r1) dt / 2,    p = ((vy_pred - vy0) + vx0 r0 dt) / s_now
// (the model's force terms are linear in s, so p is its unscaled force part; s_now is 1 unless
// the model is scaled). The scale is the
// least-squares fit of m = s p with exponential forgetting over `memory_s`, pulled towards 1 by
// `prior_weight` (a straight says little about the tyres and leaves the scale where it was),
// and clamped to [min_scale, max_scale]. Steps below `min_speed_mps` and steps whose measured
// change no car can make (a put-back, a collision) are skipped.
//
// Only the lateral channel is fitted: the yaw rate's change is the small difference of the front
// and rear axles' moments, which a model learnt on another car or surface gets wrong in a slide
// in ways one scale does not describe (in the AutoRally network's slides its fitted scale drifts
// to a third of the lateral one), while the lateral force sum follows the surface's friction.
#include <algorithm>
#include <cmath>
#include <string>
#include <string_view>

#include "mppi/vehicle_state.hpp"

namespace mppi {

// The name of the model parameter the adaptation sets (Backend::set_model_param).
inline constexpr std::string_view kLateralForceScaleParam = "lateral_force_scale";

struct LateralForceAdaptation {
  bool enabled = false;
  float memory_s = 2.0f;        // time constant of the forgetting [s]
  // Information of the prior s = 1 [(m/s)^2]: steady cornering at 5 m/s^2 gathers about
  // (5 * 0.02)^2 * memory_s / dt = 1; 0.02 keeps a long straight from drifting the scale.
  float prior_weight = 0.02f;
  float min_scale = 0.4f, max_scale = 1.5f;
  float min_speed_mps = 2.0f;   // below this the tyres' forces are too small to tell anything
  float max_accel_mps2 = 40.f;  // a measured change beyond this (per second) is not driving
  // The cost parameter of the target speed that is held at the requested value x
  // scale^speed_exponent (Controller::set_cost_param gives the requested value); empty: the
  // speed is left alone.
  std::string speed_param = "target_speed_mps";
  float speed_exponent = 1.0f;
  // The throttle's upper limit is held at the configured one x scale^throttle_exponent (0: kept).
  float throttle_exponent = 1.0f;
  // Plan with the model's lateral force x scale as well (the model needs kLateralForceScaleParam).
  bool scale_model = false;

  bool is_valid(std::string* why) const {
    auto fail = [&](const std::string& msg) {
      if (why) *why = "lateral force adaptation: " + msg;
      return false;
    };
    if (!enabled) return scale_model ? fail("scale_model needs the adaptation enabled") : true;
    if (!(memory_s > 0.f) || !std::isfinite(memory_s)) return fail("memory_s must be > 0 and finite");
    if (!(prior_weight > 0.f) || !std::isfinite(prior_weight)) return fail("prior_weight must be > 0 and finite");
    if (!(min_scale > 0.f && min_scale <= 1.f && max_scale >= 1.f) || !std::isfinite(max_scale))
      return fail("the bounds need 0 < min_scale <= 1 <= max_scale < inf");
    if (!(min_speed_mps >= 0.f) || !std::isfinite(min_speed_mps)) return fail("min_speed_mps must be >= 0");
    if (!(max_accel_mps2 > 0.f) || !std::isfinite(max_accel_mps2)) return fail("max_accel_mps2 must be > 0");
    if (!(speed_exponent >= 0.f && speed_exponent <= 2.f)) return fail("speed_exponent must be in [0, 2]");
    if (!(throttle_exponent >= 0.f && throttle_exponent <= 2.f)) return fail("throttle_exponent must be in [0, 2]");
    return true;
  }
};

class LateralForceScaleEstimator {
 public:
  explicit LateralForceScaleEstimator(const LateralForceAdaptation& o = {}) : o_(o) {}

  // One control step of dt_s: x0 measured at its start, predicted the model's step from x0 with
  // the model's scale at model_scale, x1 measured at its end (the common state indices of
  // mppi/vehicle_state.hpp). Returns the fitted scale (unchanged where the step tells nothing).
  float update(const float* x0, const float* predicted, const float* x1, float dt_s, float model_scale) noexcept {
    using namespace state;
    const double dt = dt_s, vx0 = x0[kVx], r0 = x0[kYawRate], vy0 = x0[kVy];
    const double measured = (x1[kVy] - vy0) + 0.5 * (vx0 * r0 + static_cast<double>(x1[kVx]) * x1[kYawRate]) * dt;
    const double model = ((predicted[kVy] - vy0) + vx0 * r0 * dt) / model_scale;
    const double limit = static_cast<double>(o_.max_accel_mps2) * dt;
    const bool usable = std::isfinite(measured) && std::isfinite(model) && std::abs(vx0) >= o_.min_speed_mps &&
                        std::abs(measured) <= limit && std::abs(model) <= limit;
    if (!usable) return scale_;
    const double forget = std::exp(-dt / o_.memory_s);
    info_ = forget * info_ + model * model;
    cross_ = forget * cross_ + model * measured;
    const double s = (cross_ + o_.prior_weight) / (info_ + o_.prior_weight);
    scale_ = static_cast<float>(std::clamp(s, static_cast<double>(o_.min_scale), static_cast<double>(o_.max_scale)));
    return scale_;
  }
  float scale() const noexcept { return scale_; }

  // Forget the evidence and start again from 1.
  void clear() noexcept {
    info_ = cross_ = 0.0;
    scale_ = 1.f;
  }

 private:
  LateralForceAdaptation o_;
  double info_ = 0.0, cross_ = 0.0;  // sum p p and sum p m, forgotten over memory_s
  float scale_ = 1.f;
};

}  // namespace mppi
