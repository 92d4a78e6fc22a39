#pragma once
// The kinematic bicycle: the simplest car model, no tyre slip. State is the library's
// common layout only (kNx = 7); its reference point is the rear-axle centre, the one point
// of a kinematic bicycle whose velocity has no lateral component, so vy = 0 and roll = 0.
//   x' = v cos yaw,  y' = v sin yaw,  yaw' = v tan(delta) / L,  delta = steer * max_steer_rad
//   v' = max_accel * throttle - speed_damping * v
// (steady speed max_accel / speed_damping x throttle; negative throttle brakes, then reverses).
// Explicit Euler with the old speed and heading; the yaw-rate state is set to v tan(delta)/L
// with the new speed (the rate the car has after the step under the applied steering).
#include <algorithm>
#include <cmath>
#include <cstddef>

#include "base/batch.hpp"
#include "base/error.hpp"
#include "dynamics/fast_trig.hpp"
#include "dynamics/vehicle_params.hpp"
#include "mppi/vehicle_state.hpp"

namespace mppi {

class KinematicBicycle {
 public:
  static constexpr int kNx = state::kCommonStates;  // 7
  static constexpr int kNu = 2;

  // Throws mppi::Error if the parameters are not valid.
  explicit KinematicBicycle(const KinematicBicycleParams& params = {}) : params_(params) {
    std::string why;
    if (!params_.is_valid(&why)) throw Error("KinematicBicycle: invalid parameters: " + why);
    inv_wheelbase_ = static_cast<float>(1 / params_.wheelbase_m);
    max_steer_ = static_cast<float>(params_.max_steer_rad);
    max_accel_ = static_cast<float>(params_.max_accel_mps2);
    damping_ = static_cast<float>(params_.speed_damping_per_s);
  }

  const KinematicBicycleParams& params() const { return params_; }
  std::size_t scratch_floats(int) const { return 0; }

  template <int W>
  void step(Batch<kNx, W> x, ConstBatch<kNu, W> u, float dt_s, float* /*scratch*/) const noexcept {
    const float inv_l = inv_wheelbase_, max_steer = max_steer_, a_max = max_accel_, c = damping_;
    float* px = x[state::kX];
    float* py = x[state::kY];
    float* pyaw = x[state::kYaw];
    float* pv = x[state::kVx];
    float* pvy = x[state::kVy];
    float* pr = x[state::kYawRate];
    float* proll = x[state::kRoll];
    const float* ps = u[control::kSteer];
    const float* pt = u[control::kThrottle];
    MPPI_SIMD_LOOP
    for (int j = 0; j < W; ++j) {
      const float steer = ps[j];  // a local: std::max on a memory reference blocks vectorising
      const float delta = std::min(std::max(steer, -1.f), 1.f) * max_steer;
      float sd, cd, sy, cy;
      fast_sincos(delta, &sd, &cd);
      fast_sincos(pyaw[j], &sy, &cy);
      const float curvature = sd / cd * inv_l;  // tan(delta) / L [1/m]; |delta| < 1.5 by is_valid
      const float v = pv[j];
      px[j] += v * cy * dt_s;
      py[j] += v * sy * dt_s;
      pyaw[j] += v * curvature * dt_s;
      const float v_new = v + (a_max * pt[j] - c * v) * dt_s;
      pv[j] = v_new;
      pvy[j] = 0.f;
      pr[j] = v_new * curvature;
      proll[j] = 0.f;
    }
  }

  // Common state copied, then vy = 0 and roll = 0; the yaw rate is kept as given (the first
  // step sets it from the steering).
  void init_state(const VehicleState& s, float* x) const {
    const auto common = s.to_array();
    std::copy(common.begin(), common.end(), x);
    x[state::kVy] = 0.f;
    x[state::kRoll] = 0.f;
  }

  // dx = f(x, u) in double (yaw-rate entry: d/dt of v tan(delta)/L at fixed steering).
  void derivatives(const double* x, const double* u, double* dx) const noexcept {
    const double delta = std::clamp(u[control::kSteer], -1.0, 1.0) * params_.max_steer_rad;
    const double curvature = std::tan(delta) / params_.wheelbase_m;
    const double v = x[state::kVx];
    const double dv = params_.max_accel_mps2 * u[control::kThrottle] - params_.speed_damping_per_s * v;
    dx[state::kX] = v * std::cos(x[state::kYaw]);
    dx[state::kY] = v * std::sin(x[state::kYaw]);
    dx[state::kYaw] = v * curvature;
    dx[state::kVx] = dv;
    dx[state::kVy] = 0.0;
    dx[state::kYawRate] = dv * curvature;
    dx[state::kRoll] = 0.0;
  }

 private:
  KinematicBicycleParams params_;
  float inv_wheelbase_ = 0.f, max_steer_ = 0.f, max_accel_ = 0.f, damping_ = 0.f;
};

}  // namespace mppi
