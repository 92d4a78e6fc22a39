#pragma once
// The AutoRally paper's single-track (bicycle) model with Pacejka tyres and wheel spin,
// after Velenis 2010: body frame at the CG, x forward, y left, yaw CCW, steering positive
// left. State (kNx = 9): the library's common 7 (roll stays 0) + front and rear wheel
// speeds. Controls: steer in [-1, 1] (delta = steer * max_steer_rad), throttle in [-1, 1].
//
//   dVx = (fFx cos d - fFy sin d + fRx + F_res) / m + Vy r
//   dVy = (fFx sin d + fFy cos d + fRy) / m - Vx r
//   dr  = ((fFy cos d + fFx sin d) l_f - fRy l_r) / I_z
//   I_f domega_f = s T - fFx R,   I_r domega_r = (1 - s) T - fRx R
// T = T_stall (max(u, 0) + k_brake min(u, 0) - omega_m R / v_no_load) (vehicle_params.hpp), with s
// the front axle's share of the drive (front_drive_share; 0 = rear-wheel drive, the paper's car)
// and omega_m = s omega_f + (1 - s) omega_r the motor's wheel-equivalent speed.
// Tyre-frame velocities: front (Vx cos d + (Vy + r l_f) sin d, -Vx sin d + (Vy + r l_f) cos d),
// rear (Vx, Vy - r l_r); friction from dynamics/pacejka.hpp (the rear tyre's B, C, D scaled by
// rear_tyre_*_scale); normal loads from Velenis'
// quasi-static pitch transfer
//   f_Fz = m g (l_r - h mu_Rx) / (l_f + l_r + h (mu_Fx cos d - mu_Fy sin d - mu_Rx)),
//   f_Rz = m g - f_Fz   (explicit: mu_k = f_k / f_z does not depend on f_z), clamped to [0, m g].
// F_res = -c_rr m g tanh(Vx / v_rr) - c_d Vx |Vx| (rolling resistance, air drag) is not in the
// paper's single-track equations (the paper's full model has the drag); set both to 0 for the
// paper's model. Time stepping is explicit Euler, positions from the old velocities.
#include <algorithm>
#include <cmath>
#include <cstddef>

#include "base/batch.hpp"
#include "base/error.hpp"
#include "base/fast_math.hpp"
#include "dynamics/fast_trig.hpp"
#include "dynamics/pacejka.hpp"
#include "dynamics/vehicle_params.hpp"
#include "mppi/vehicle_state.hpp"

namespace mppi {

// Parameters in the form the equations use, in the scalar type of the evaluation.
template <class T>
struct SingleTrackCoeffs {
  T inv_mass, inv_yaw_inertia, lf, lr, h, radius, inv_front_inertia, inv_rear_inertia;
  T weight;  // m g [N]
  T max_steer, stall_torque, brake_ratio, inv_no_load_speed, rolling_force, inv_rolling_speed, drag;
  T slip_floor, inv_slip_blend;
  T front_drive, rear_drive;   // shares of the motor torque (sum 1)
  PacejkaCoeffs<T> tyre;       // front axle
  PacejkaCoeffs<T> rear_tyre;  // rear axle (SingleTrackParams::rear_tyre())

  static SingleTrackCoeffs from(const SingleTrackParams& p) noexcept {
    auto t = [](double v) { return static_cast<T>(v); };
    return {t(1 / p.mass_kg), t(1 / p.yaw_inertia_kgm2), t(p.cg_to_front_axle_m),
            t(p.cg_to_rear_axle_m), t(p.cg_height_m), t(p.wheel_radius_m),
            t(1 / p.front_wheel_inertia_kgm2), t(1 / p.rear_wheel_inertia_kgm2),
            t(p.mass_kg * p.gravity_mps2), t(p.max_steer_rad), t(p.stall_torque_Nm), t(p.brake_torque_ratio),
            t(1 / p.no_load_speed_mps), t(p.rolling_resistance * p.mass_kg * p.gravity_mps2),
            t(1 / p.rolling_resistance_speed_mps), t(p.aero_drag_kgpm), t(p.slip_speed_floor_mps),
            t(1 / p.slip_blend), t(p.front_drive_share), t(1 - p.front_drive_share),
            PacejkaCoeffs<T>::from(p.tyre),
            PacejkaCoeffs<T>::from(p.rear_tyre())};
  }
};

// Every intermediate of one evaluation of the model: the body accelerations and, for
// diagnostics, the tyre velocities, slips, loads and forces (SingleTrackForces).
template <class T>
struct SingleTrackTerms {
  T delta_rad;                        // front wheel angle
  T front_vx_mps, front_vy_mps;       // front tyre-frame velocity (V_Fx, V_Fy)
  T rear_vx_mps, rear_vy_mps;         // rear tyre-frame velocity (V_Rx, V_Ry)
  TyreFriction<T> front, rear;        // slips and friction coefficients
  T front_fz_N, rear_fz_N;            // normal loads
  T front_fx_N, front_fy_N;           // front friction force, tyre frame
  T rear_fx_N, rear_fy_N;             // rear friction force, tyre frame (= body frame)
  T drive_torque_Nm;                  // motor torque (both axles together)
  T resist_force_N;                   // rolling resistance + drag along body x (negative = retarding)
  T dvx_mps2, dvy_mps2, dyaw_rate_radps2, domega_front_radps2, domega_rear_radps2;
};
using SingleTrackForces = SingleTrackTerms<double>;

// The right-hand side for the body and wheel states. Branch-free, noexcept, no allocation.
template <class T>
inline void single_track_terms(const SingleTrackCoeffs<T>& k, T vx, T vy, T r, T omega_f, T omega_r,
                               T steer, T throttle, SingleTrackTerms<T>* e) noexcept {
  e->delta_rad = std::min(std::max(steer, T(-1)), T(1)) * k.max_steer;
  T sd, cd;
  phys::sincos(e->delta_rad, &sd, &cd);
  const T vy_front = vy + r * k.lf;  // lateral velocity at the front axle, body frame
  e->front_vx_mps = vx * cd + vy_front * sd;
  e->front_vy_mps = -vx * sd + vy_front * cd;
  e->rear_vx_mps = vx;
  e->rear_vy_mps = vy - r * k.lr;
  e->front = tyre_friction(e->front_vx_mps, e->front_vy_mps, omega_f * k.radius, k.slip_floor,
                           k.inv_slip_blend, k.tyre);
  e->rear = tyre_friction(e->rear_vx_mps, e->rear_vy_mps, omega_r * k.radius, k.slip_floor,
                          k.inv_slip_blend, k.rear_tyre);
  const T den = k.lf + k.lr + k.h * (e->front.mu_x * cd - e->front.mu_y * sd - e->rear.mu_x);
  // den > 0 is guaranteed by SingleTrackParams::is_valid; the floor only keeps NaN out.
  const T fz_front = k.weight * (k.lr - k.h * e->rear.mu_x) / std::max(den, T(1e-3));
  e->front_fz_N = std::min(std::max(fz_front, T(0)), k.weight);
  e->rear_fz_N = k.weight - e->front_fz_N;
  e->front_fx_N = e->front.mu_x * e->front_fz_N;
  e->front_fy_N = e->front.mu_y * e->front_fz_N;
  e->rear_fx_N = e->rear.mu_x * e->rear_fz_N;
  e->rear_fy_N = e->rear.mu_y * e->rear_fz_N;
  const T motor_omega = k.front_drive * omega_f + k.rear_drive * omega_r;
  e->drive_torque_Nm = k.stall_torque * (std::max(throttle, T(0)) + k.brake_ratio * std::min(throttle, T(0)) -
                                         motor_omega * k.radius * k.inv_no_load_speed);
  e->resist_force_N = -k.rolling_force * phys::tanh(vx * k.inv_rolling_speed) - k.drag * vx * std::abs(vx);
  const T body_fx = e->front_fx_N * cd - e->front_fy_N * sd + e->rear_fx_N;  // body x
  const T body_fy = e->front_fx_N * sd + e->front_fy_N * cd + e->rear_fy_N;  // body y
  e->dvx_mps2 = (body_fx + e->resist_force_N) * k.inv_mass + vy * r;
  e->dvy_mps2 = body_fy * k.inv_mass - vx * r;
  e->dyaw_rate_radps2 =
      ((e->front_fy_N * cd + e->front_fx_N * sd) * k.lf - e->rear_fy_N * k.lr) * k.inv_yaw_inertia;
  e->domega_front_radps2 = (k.front_drive * e->drive_torque_Nm - e->front_fx_N * k.radius) * k.inv_front_inertia;
  e->domega_rear_radps2 = (k.rear_drive * e->drive_torque_Nm - e->rear_fx_N * k.radius) * k.inv_rear_inertia;
}

class SingleTrack {
 public:
  static constexpr int kNx = 9;
  static constexpr int kNu = 2;
  static constexpr int kOmegaFront = 7;  // front wheel speed [rad/s] (both front wheels)
  static constexpr int kOmegaRear = 8;   // rear wheel speed [rad/s]

  // Throws mppi::Error if the parameters are not valid.
  explicit SingleTrack(const SingleTrackParams& params = {}) : params_(params) {
    std::string why;
    if (!params_.is_valid(&why)) throw Error("SingleTrack: invalid parameters: " + why);
    kf_ = SingleTrackCoeffs<float>::from(params_);
    kd_ = SingleTrackCoeffs<double>::from(params_);
  }

  const SingleTrackParams& params() const { return params_; }
  std::size_t scratch_floats(int) const { return 0; }

  // x <- x + dt f(x, u) (explicit Euler), every lane. Float, fast branch-free math.
  template <int W>
  void step(Batch<kNx, W> x, ConstBatch<kNu, W> u, float dt_s, float* /*scratch*/) const noexcept {
    step_impl<W, false>(x, u, dt_s, nullptr, nullptr, nullptr);
  }

  // step() with extra accelerations along the body axes [m/s^2] and about the vertical axis
  // [rad/s^2] per lane, added inside the force balance (the force hook of WithEffects<SingleTrack>).
  template <int W>
  void step_with_body_accel(Batch<kNx, W> x, ConstBatch<kNu, W> u, float dt_s, float* /*scratch*/,
                            const float* ax_mps2, const float* ay_mps2,
                            const float* yaw_accel_radps2) const noexcept {
    step_impl<W, true>(x, u, dt_s, ax_mps2, ay_mps2, yaw_accel_radps2);
  }

 private:
  template <int W, bool kExtraAccel>
  void step_impl(Batch<kNx, W> x, ConstBatch<kNu, W> u, float dt_s, const float* ax_mps2,
                 const float* ay_mps2, const float* yaw_accel_radps2) const noexcept {
    const SingleTrackCoeffs<float> k = kf_;  // local copy: no aliasing with the state
    float* px = x[state::kX];
    float* py = x[state::kY];
    float* pyaw = x[state::kYaw];
    float* pvx = x[state::kVx];
    float* pvy = x[state::kVy];
    float* pr = x[state::kYawRate];
    float* pwf = x[kOmegaFront];
    float* pwr = x[kOmegaRear];
    const float* ps = u[control::kSteer];
    const float* pt = u[control::kThrottle];
    MPPI_SIMD_LOOP
    for (int j = 0; j < W; ++j) {
      const float vx = pvx[j], vy = pvy[j], r = pr[j];
      SingleTrackTerms<float> e;
      single_track_terms(k, vx, vy, r, pwf[j], pwr[j], ps[j], pt[j], &e);
      float sy, cy;
      fast_sincos(pyaw[j], &sy, &cy);
      px[j] += (cy * vx - sy * vy) * dt_s;
      py[j] += (sy * vx + cy * vy) * dt_s;
      pyaw[j] += r * dt_s;
      if constexpr (kExtraAccel) {
        pvx[j] = vx + (e.dvx_mps2 + ax_mps2[j]) * dt_s;
        pvy[j] = vy + (e.dvy_mps2 + ay_mps2[j]) * dt_s;
        pr[j] = r + (e.dyaw_rate_radps2 + yaw_accel_radps2[j]) * dt_s;
      } else {
        pvx[j] = vx + e.dvx_mps2 * dt_s;
        pvy[j] = vy + e.dvy_mps2 * dt_s;
        pr[j] = r + e.dyaw_rate_radps2 * dt_s;
      }
      pwf[j] += e.domega_front_radps2 * dt_s;
      pwr[j] += e.domega_rear_radps2 * dt_s;
    }
  }

 public:
  // Common state copied; roll 0; wheels rolling without slip: omega = vx / R.
  void init_state(const VehicleState& s, float* x) const {
    const auto common = s.to_array();
    std::copy(common.begin(), common.end(), x);
    x[state::kRoll] = 0.f;
    x[kOmegaFront] = x[kOmegaRear] = static_cast<float>(s.vx_mps / params_.wheel_radius_m);
  }

  // dx = f(x, u) in double with libm (reference, diagnostics, higher-order integrators).
  void derivatives(const double* x, const double* u, double* dx) const noexcept {
    SingleTrackTerms<double> e;
    single_track_terms(kd_, x[state::kVx], x[state::kVy], x[state::kYawRate], x[kOmegaFront],
                       x[kOmegaRear], u[control::kSteer], u[control::kThrottle], &e);
    const double sy = std::sin(x[state::kYaw]), cy = std::cos(x[state::kYaw]);
    dx[state::kX] = cy * x[state::kVx] - sy * x[state::kVy];
    dx[state::kY] = sy * x[state::kVx] + cy * x[state::kVy];
    dx[state::kYaw] = x[state::kYawRate];
    dx[state::kVx] = e.dvx_mps2;
    dx[state::kVy] = e.dvy_mps2;
    dx[state::kYawRate] = e.dyaw_rate_radps2;
    dx[state::kRoll] = 0.0;
    dx[kOmegaFront] = e.domega_front_radps2;
    dx[kOmegaRear] = e.domega_rear_radps2;
  }

  // Tyre velocities, slips, loads and forces at (x, u), in double.
  SingleTrackForces forces(const double* x, const double* u) const noexcept {
    SingleTrackForces e;
    single_track_terms(kd_, x[state::kVx], x[state::kVy], x[state::kYawRate], x[kOmegaFront],
                       x[kOmegaRear], u[control::kSteer], u[control::kThrottle], &e);
    return e;
  }

 private:
  SingleTrackParams params_;
  SingleTrackCoeffs<float> kf_{};
  SingleTrackCoeffs<double> kd_{};
};

}  // namespace mppi
