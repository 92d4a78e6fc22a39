#pragma once
// A differential-drive robot (the model of the MPPI-Generic / Nav2 cross-implementation
// benchmark): state (x [m], y [m], yaw [rad]), control (v [m/s], omega [rad/s]) = forward speed
// and yaw rate of the body, as Nav2's DiffDrive motion model samples them. Forward Euler:
//   x += v cos(yaw) dt,  y += v sin(yaw) dt,  yaw += omega dt.
// The wheel radius r and wheel base L map body speeds to wheel speeds (omega_l, omega_r):
//   v = r (omega_r + omega_l) / 2,  omega = r (omega_r - omega_l) / L
// (MPPI-Generic's DiffDrive samples the wheel speeds instead; with r = L = 1 m the two
// parametrisations do the same work per rollout step). Not a vehicle model of the car library:
// it has no common vehicle state, so it works with generic costs (costs/goal_obstacle_cost.hpp),
// not with AutoRallyCost or the track simulator.
#include <cmath>
#include <cstddef>
#include <string>

#include "base/batch.hpp"
#include "base/error.hpp"
#include "dynamics/fast_trig.hpp"

namespace mppi {

struct DiffDriveParams {
  double wheel_radius_m = 1.0;  // r: wheel radius [m] (benchmark value)
  double wheel_base_m = 1.0;    // L: distance between the wheels [m] (benchmark value)

  // True if both are finite and > 0; otherwise false with the reason in *why.
  bool is_valid(std::string* why = nullptr) const {
    if (!(std::isfinite(wheel_radius_m) && wheel_radius_m > 0)) {
      if (why) *why = "wheel_radius_m must be finite and > 0";
      return false;
    }
    if (!(std::isfinite(wheel_base_m) && wheel_base_m > 0)) {
      if (why) *why = "wheel_base_m must be finite and > 0";
      return false;
    }
    return true;
  }
};

class DiffDrive {
 public:
  static constexpr int kNx = 3;
  static constexpr int kNu = 2;
  // state and control indices
  static constexpr int kX = 0, kY = 1, kYaw = 2;
  static constexpr int kV = 0, kOmega = 1;

  // Throws mppi::Error if the parameters are not valid.
  explicit DiffDrive(const DiffDriveParams& params = {}) : params_(params) {
    std::string why;
    if (!params_.is_valid(&why)) throw Error("DiffDrive: invalid parameters: " + why);
  }

  const DiffDriveParams& params() const { return params_; }
  std::size_t scratch_floats(int) const { return 0; }

  template <int W>
  void step(Batch<kNx, W> x, ConstBatch<kNu, W> u, float dt_s, float* /*scratch*/) const noexcept {
    float* px = x[kX];
    float* py = x[kY];
    float* pyaw = x[kYaw];
    const float* pv = u[kV];
    const float* pw = u[kOmega];
    MPPI_SIMD_LOOP
    for (int j = 0; j < W; ++j) {
      float s, c;
      fast_sincos(pyaw[j], &s, &c);
      const float ds = pv[j] * dt_s;
      px[j] += ds * c;
      py[j] += ds * s;
      pyaw[j] += pw[j] * dt_s;
    }
  }

  // dx = f(x, u) in double (the reference for tests).
  static void derivatives(const double* x, const double* u, double* dx) noexcept {
    dx[kX] = u[kV] * std::cos(x[kYaw]);
    dx[kY] = u[kV] * std::sin(x[kYaw]);
    dx[kYaw] = u[kOmega];
  }

  // Body speeds from wheel speeds [rad/s] and back.
  void body_from_wheels(double omega_left, double omega_right, double* v_mps, double* omega_radps) const {
    *v_mps = params_.wheel_radius_m * (omega_right + omega_left) / 2;
    *omega_radps = params_.wheel_radius_m * (omega_right - omega_left) / params_.wheel_base_m;
  }
  void wheels_from_body(double v_mps, double omega_radps, double* omega_left, double* omega_right) const {
    const double half_diff = omega_radps * params_.wheel_base_m / 2;
    *omega_left = (v_mps - half_diff) / params_.wheel_radius_m;
    *omega_right = (v_mps + half_diff) / params_.wheel_radius_m;
  }

 private:
  DiffDriveParams params_;
};

}  // namespace mppi
