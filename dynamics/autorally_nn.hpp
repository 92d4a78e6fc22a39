#pragma once
// AutoRally's neural-network dynamics model (autorally_nnet_09_12_2018.npz: a 6-32-32-4 MLP,
// tanh, tanh, linear) in the library's conventions. The network gives the time derivatives of
// the body states from the body states and the controls; the pose follows by kinematics;
// explicit Euler at dt, every derivative from the state at the start of the step (as AutoRally):
//   x   += (cos(yaw) vx - sin(yaw) vy) dt,   y += (sin(yaw) vx + cos(yaw) vy) dt
//   yaw += yaw_rate dt
//   [roll, vx, vy, yaw_rate] += net([roll, vx, vy, yaw_rate, steer, throttle]) dt
//
// Conventions. AutoRally's state is [x, y, yaw, roll, u_x, u_y, yaw_mder] with yaw_mder = minus
// the yaw rate, and its steering is positive to the RIGHT; the network was trained on
// [roll, u_x, u_y, yaw_mder, steering, throttle] -> d/dt [roll, u_x, u_y, yaw_mder]. load()
// folds both sign flips into the weights once (W1 columns of yaw_mder and steering negated, W3
// row and b3 entry of d yaw_mder negated), so step() runs the network directly on the
// library's state (mppi/vehicle_state.hpp: yaw rate CCW positive, steer positive left).
// Roll needs no flip: the network rolls the car left side down (negative, ISO: right side
// down positive) in a right turn and right side down in a left turn, i.e. it leans outward
// as a car does, so its roll already is the ISO/REP-103 roll (tests/dynamics/test_autorally_nn.cpp).
//
// Controls reach step() as given: AutoRally clamped steering to [-0.99, 0.99] and throttle to
// [-0.99, max_throttle (0.65)] before the network; the controller's limits must do the same.
#include <algorithm>
#include <cstddef>
#include <string>
#include <string_view>

#include "base/batch.hpp"
#include "dynamics/fast_trig.hpp"
#include "dynamics/mlp.hpp"
#include "mppi/lateral_force_adaptation.hpp"
#include "mppi/vehicle_state.hpp"

namespace mppi {

class AutoRallyNetwork {
 public:
  static constexpr int kNx = state::kCommonStates;  // 7: x, y, yaw, vx, vy, yaw_rate, roll
  static constexpr int kNu = control::kCommonControls;  // 2: steer (left +), throttle
  static constexpr int kNetIn = 6;   // roll, vx, vy, yaw_rate, steer_left, throttle
  static constexpr int kNetOut = 4;  // d/dt of roll, vx, vy, yaw_rate
  static constexpr double kAutoRallyDt_s = 0.02;  // the step AutoRally ran the model at (50 Hz)

  // Reads keys dynamics_W1 (32,6), dynamics_b1 (32,), dynamics_W2 (32,32), dynamics_b2 (32,),
  // dynamics_W3 (4,32), dynamics_b3 (4,) (AutoRally's conventions) and converts them. Throws
  // mppi::Error naming the file and the array if one is missing, misshaped or not finite.
  static AutoRallyNetwork load(const std::string& npz_path);

  // A network already in the library's conventions (inputs/outputs as kNetIn/kNetOut above).
  // Throws mppi::Error if it does not take 6 inputs and give 4 outputs.
  explicit AutoRallyNetwork(Mlp net_library_frame);

  const Mlp& network() const { return net_; }

  // FP32 (the default) or bf16 hidden layers (Mlp::set_precision): bf16 roughly halves the
  // network's arithmetic on CPUs with AVX512-BF16 and changes the derivatives by ~1e-2 of
  // their spread (docs/BENCHMARKS.md, "Reduced precision"). Returns false and keeps FP32 where
  // the CPU lacks AVX512-BF16. The choice is made once; step() then calls one kernel per chunk.
  bool set_precision(NetPrecision precision) { return net_.set_precision(precision); }
  NetPrecision precision() const { return net_.precision(); }

  // The share of the network's lateral tyre force the car has (online adaptation of the model,
  // mppi/lateral_force_adaptation.hpp). The network's d vy/dt is the tyres' lateral force per
  // mass minus the kinematic term vx r, and its d r/dt the tyres' yaw moment per inertia; the
  // scale s multiplies both force terms and keeps the kinematic one:
  //   d vy/dt = net_vy + (s - 1) (net_vy + vx r),   d r/dt = s net_r.
  // A friction change that scales the whole tyre curve (Pacejka D) scales both by the same s.
  // s = 1 (the default) leaves every number as the network gives it, bit for bit.
  static constexpr std::string_view kLateralForceScaleKey = kLateralForceScaleParam;
  static constexpr double kMinLateralForceScale = 0.2, kMaxLateralForceScale = 2.0;
  // Sets kLateralForceScaleKey (in [kMinLateralForceScale, kMaxLateralForceScale]). False with
  // the reason in *why for another key or a value out of range; nothing changes then.
  bool set_param(std::string_view key, double value, std::string* why);
  float lateral_force_scale() const { return lateral_force_scale_; }

  std::size_t scratch_floats(int width) const {
    return static_cast<std::size_t>(kNetIn + kNetOut) * static_cast<std::size_t>(width) +
           net_.scratch_floats(width);
  }

  template <int W>
  void step(Batch<kNx, W> x, ConstBatch<kNu, W> u, float dt_s, float* scratch) const noexcept {
    float* in = scratch;              // kNetIn x W
    float* der = in + kNetIn * W;     // kNetOut x W
    float* net_scratch = der + kNetOut * W;
    std::copy_n(x[state::kRoll], W, in + 0 * W);
    std::copy_n(x[state::kVx], W, in + 1 * W);
    std::copy_n(x[state::kVy], W, in + 2 * W);
    std::copy_n(x[state::kYawRate], W, in + 3 * W);
    std::copy_n(u[control::kSteer], W, in + 4 * W);
    std::copy_n(u[control::kThrottle], W, in + 5 * W);
    net_.forward<W>(in, der, net_scratch);

    float* px = x[state::kX];
    float* py = x[state::kY];
    float* pyaw = x[state::kYaw];
    float* pvx = x[state::kVx];
    float* pvy = x[state::kVy];
    float* pr = x[state::kYawRate];
    float* proll = x[state::kRoll];
    const float* d_roll = der + 0 * W;
    const float* d_vx = der + 1 * W;
    const float* d_vy = der + 2 * W;
    const float* d_r = der + 3 * W;
    const float extra_force = lateral_force_scale_ - 1.f;  // 0: the network's own numbers
    MPPI_SIMD_LOOP
    for (int j = 0; j < W; ++j) {
      float s, c;
      fast_sincos(pyaw[j], &s, &c);
      const float vx = pvx[j], vy = pvy[j], r = pr[j];
      px[j] += (c * vx - s * vy) * dt_s;
      py[j] += (s * vx + c * vy) * dt_s;
      pyaw[j] += r * dt_s;
      proll[j] += d_roll[j] * dt_s;
      pvx[j] = vx + d_vx[j] * dt_s;
      pvy[j] = vy + (d_vy[j] + extra_force * (d_vy[j] + vx * r)) * dt_s;
      pr[j] = r + lateral_force_scale_ * d_r[j] * dt_s;
    }
  }

  // The network state is exactly the common state.
  void init_state(const VehicleState& s, float* x) const {
    const auto common = s.to_array();
    std::copy(common.begin(), common.end(), x);
  }

  // dx = f(x, u) in the library's conventions (kNx entries), evaluated in double (tests,
  // linearisation; allocates).
  void derivatives(const double* x, const double* u, double* dx) const;

  // The network in AutoRally's own conventions, for comparison with AutoRally:
  // s = [x, y, yaw, roll, u_x, u_y, yaw_mder], u = [steering (right +), throttle] ->
  // out = d/dt [roll, u_x, u_y, yaw_mder]. Double precision.
  void derivatives_autorally_frame(const double s[7], const double u[2], double out[4]) const;

 private:
  Mlp net_;  // library conventions
  float lateral_force_scale_ = 1.f;
};

}  // namespace mppi
