#pragma once
// The AutoRally paper's double-track (four-wheel) model: the single-track's planar motion with
// a tyre at each corner, so that the lateral load transfer shifts normal load from the inner
// to the outer wheels. Body frame at the CG, x forward, y left, yaw CCW (ISO 8855). Wheels
// i = LF, RF, LR, RR at (l_f, +w_f/2), (l_f, -w_f/2), (-l_r, +w_r/2), (-l_r, -w_r/2); both
// front wheels steer by delta. State (kNx = 11): the common 7 (roll stays 0) + four wheel
// speeds. Controls: steer, throttle in [-1, 1] as for the single-track.
//
//   m dVx  = sum_i F^b_ix + F_res + m Vy r,     m dVy = sum_i F^b_iy - m Vx r
//   I_z dr = sum_i (x_i F^b_iy - y_i F^b_ix)
//   I_w,i domega_i = T_i - f_ix R          (I_w,i = I_f / 2 or I_r / 2; open rear differential:
//                                           each rear wheel gets half the motor torque)
// F^b_i: tyre friction force f_i = mu_i f_iz (dynamics/pacejka.hpp) rotated into the body frame.
// The paper's yaw equation (DoubleTrack3) leaves out the moments of the longitudinal forces
// about the track offsets (-y_i F^b_ix); we keep them (they vanish for w -> 0 and for equal
// left/right forces), see docs/PHYSICS.md.
//
// Normal loads, quasi-static (Velenis 2010's pitch transfer, plus the lateral transfer):
//   f_iz = f_iz^0 + a_i Fx + b_i Fy + e_i,     Fx, Fy = sum of the tyre forces (body frame)
//   pitch: front wheels a_i = -h / (2 L), rear +h / (2 L)   (moment balance about the CG)
//   roll:  left wheels b_i = -lambda chi_k h / w_k, right +lambda chi_k h / w_k  (axle k with
//          roll-moment share chi_f = front_roll_share, chi_r = 1 - chi_f; lambda = scale)
// and e_i an extra load (0 here; the full vehicle's suspension forces). Since the friction per
// unit load mu_i does not depend on f_iz, Fx and Fy solve a 2x2 linear system (explicit, like
// the single-track's closed form); loads are then clamped to [0, m g] (wheel lift).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>

#include "base/batch.hpp"
#include "base/error.hpp"
#include "base/fast_math.hpp"
#include "dynamics/fast_trig.hpp"
#include "dynamics/pacejka.hpp"
#include "dynamics/vehicle_params.hpp"
#include "mppi/vehicle_state.hpp"

namespace mppi {

namespace wheel {
inline constexpr int kLF = 0, kRF = 1, kLR = 2, kRR = 3;  // left/right, front/rear
}

// Planar four-wheel coefficients, in the scalar type of the evaluation.
template <class T>
struct FourWheelCoeffs {
  T inv_mass, inv_yaw_inertia, radius, weight;
  T pos_x[4], pos_y[4];                 // wheel positions relative to the CG [m]
  T inv_wheel_inertia[4];               // 1 / (I_f / 2) front, 1 / (I_r / 2) rear
  T static_load[4];                     // f_iz^0 [N]
  T load_per_fx[4], load_per_fy[4];     // a_i, b_i [N/N]
  T max_steer, stall_torque, brake_ratio, inv_no_load_speed, rolling_force, inv_rolling_speed, drag;
  T slip_floor, inv_slip_blend;
  PacejkaCoeffs<T> tyre, rear_tyre;  // front, rear axle

  // Geometry, tyres, drivetrain and static loads from the single-track parameters and tracks;
  // the load-transfer rows a_i = -+h_long / (2 L), b_i = -+roll_k / w_k (roll_k: N/N per axle).
  static FourWheelCoeffs from(const SingleTrackParams& p, double front_track_m, double rear_track_m,
                              double h_long_m, double roll_front_m, double roll_rear_m,
                              double drag_kgpm) noexcept {
    auto t = [](double v) { return static_cast<T>(v); };
    FourWheelCoeffs k{};
    const double lf = p.cg_to_front_axle_m, lr = p.cg_to_rear_axle_m, L = lf + lr;
    const double mg = p.mass_kg * p.gravity_mps2;
    k.inv_mass = t(1 / p.mass_kg);
    k.inv_yaw_inertia = t(1 / p.yaw_inertia_kgm2);
    k.radius = t(p.wheel_radius_m);
    k.weight = t(mg);
    const double xs[4] = {lf, lf, -lr, -lr};
    const double ys[4] = {front_track_m / 2, -front_track_m / 2, rear_track_m / 2, -rear_track_m / 2};
    for (int i = 0; i < 4; ++i) {
      const bool front = i < 2;
      const double side = (i % 2 == 0) ? -1.0 : 1.0;  // left wheels lose load for Fy > 0
      k.pos_x[i] = t(xs[i]);
      k.pos_y[i] = t(ys[i]);
      k.inv_wheel_inertia[i] = t(2 / (front ? p.front_wheel_inertia_kgm2 : p.rear_wheel_inertia_kgm2));
      k.static_load[i] = t(mg * (front ? lr : lf) / (2 * L));
      k.load_per_fx[i] = t((front ? -1.0 : 1.0) * h_long_m / (2 * L));
      k.load_per_fy[i] = t(side * (front ? roll_front_m / front_track_m : roll_rear_m / rear_track_m));
    }
    k.max_steer = t(p.max_steer_rad);
    k.stall_torque = t(p.stall_torque_Nm);
    k.brake_ratio = t(p.brake_torque_ratio);
    k.inv_no_load_speed = t(1 / p.no_load_speed_mps);
    k.rolling_force = t(p.rolling_resistance * mg);
    k.inv_rolling_speed = t(1 / p.rolling_resistance_speed_mps);
    k.drag = t(drag_kgpm);
    k.slip_floor = t(p.slip_speed_floor_mps);
    k.inv_slip_blend = t(1 / p.slip_blend);
    k.tyre = PacejkaCoeffs<T>::from(p.tyre);
    k.rear_tyre = PacejkaCoeffs<T>::from(p.rear_tyre());
    return k;
  }
};

// Every intermediate of one evaluation (accelerations, and for diagnostics the tyre-frame
// velocities, slips, loads and forces of each wheel).
template <class T>
struct FourWheelTerms {
  T delta_rad;                       // front wheel angle
  T wheel_vx_mps[4], wheel_vy_mps[4];  // tyre-frame contact velocity
  TyreFriction<T> tyre[4];           // slips and friction coefficients
  T fz_N[4];                         // normal loads
  T fx_N[4], fy_N[4];                // friction force, tyre frame
  T body_fx_N, body_fy_N;            // sum of the tyre forces, body frame
  T drive_torque_Nm;                 // motor torque at the rear axle (both wheels)
  T resist_force_N;                  // rolling resistance + drag along body x
  T dvx_mps2, dvy_mps2, dyaw_rate_radps2, domega_radps2[4];
};
using FourWheelForces = FourWheelTerms<double>;

// The planar right-hand side. `extra_load` (may be null) adds e_i to the loads. Branch-free.
template <class T>
[[gnu::always_inline]] inline void four_wheel_terms(const FourWheelCoeffs<T>& k, T vx, T vy, T r, const T* omega, T steer,
                             T throttle, const T* extra_load, FourWheelTerms<T>* e) noexcept {
  e->delta_rad = std::min(std::max(steer, T(-1)), T(1)) * k.max_steer;
  T sd, cd;
  phys::sincos(e->delta_rad, &sd, &cd);
  T mbx[4], mby[4];  // friction per unit load, body frame
  #pragma GCC unroll 4
  for (int i = 0; i < 4; ++i) {
    const T cvx = vx - r * k.pos_y[i];  // contact-point velocity, body frame
    const T cvy = vy + r * k.pos_x[i];
    const T c = i < 2 ? cd : T(1), s = i < 2 ? sd : T(0);  // compile-time after unrolling
    e->wheel_vx_mps[i] = cvx * c + cvy * s;
    e->wheel_vy_mps[i] = -cvx * s + cvy * c;
    e->tyre[i] = tyre_friction(e->wheel_vx_mps[i], e->wheel_vy_mps[i], omega[i] * k.radius,
                               k.slip_floor, k.inv_slip_blend, i < 2 ? k.tyre : k.rear_tyre);
    mbx[i] = e->tyre[i].mu_x * c - e->tyre[i].mu_y * s;
    mby[i] = e->tyre[i].mu_x * s + e->tyre[i].mu_y * c;
  }
  // Fx = sum mbx_i (c_i + a_i Fx + b_i Fy), Fy = sum mby_i (...): 2x2 solve (Cramer).
  T a11 = T(1), a12 = T(0), a21 = T(0), a22 = T(1), b1 = T(0), b2 = T(0);
  T base[4];
  #pragma GCC unroll 4
  for (int i = 0; i < 4; ++i) {
    base[i] = k.static_load[i] + (extra_load ? extra_load[i] : T(0));
    a11 -= mbx[i] * k.load_per_fx[i];
    a12 -= mbx[i] * k.load_per_fy[i];
    a21 -= mby[i] * k.load_per_fx[i];
    a22 -= mby[i] * k.load_per_fy[i];
    b1 += mbx[i] * base[i];
    b2 += mby[i] * base[i];
  }
  // det = 1 for no transfer; it stays near 1 for real cars. The floor only keeps NaN out.
  const T inv_det = T(1) / std::max(a11 * a22 - a12 * a21, T(0.05));
  const T fx_sum = (b1 * a22 - a12 * b2) * inv_det;
  const T fy_sum = (a11 * b2 - a21 * b1) * inv_det;
  T body_fx = T(0), body_fy = T(0), yaw_moment = T(0);
  #pragma GCC unroll 4
  for (int i = 0; i < 4; ++i) {
    const T fz = base[i] + k.load_per_fx[i] * fx_sum + k.load_per_fy[i] * fy_sum;
    e->fz_N[i] = std::min(std::max(fz, T(0)), k.weight);
    e->fx_N[i] = e->tyre[i].mu_x * e->fz_N[i];
    e->fy_N[i] = e->tyre[i].mu_y * e->fz_N[i];
    const T bfx = mbx[i] * e->fz_N[i], bfy = mby[i] * e->fz_N[i];
    body_fx += bfx;
    body_fy += bfy;
    yaw_moment += k.pos_x[i] * bfy - k.pos_y[i] * bfx;
  }
  e->body_fx_N = body_fx;
  e->body_fy_N = body_fy;
  const T omega_rear = T(0.5) * (omega[wheel::kLR] + omega[wheel::kRR]);  // differential carrier
  e->drive_torque_Nm = k.stall_torque * (std::max(throttle, T(0)) + k.brake_ratio * std::min(throttle, T(0)) -
                                         omega_rear * k.radius * k.inv_no_load_speed);
  e->resist_force_N =
      -k.rolling_force * phys::tanh(vx * k.inv_rolling_speed) - k.drag * vx * std::abs(vx);
  e->dvx_mps2 = (body_fx + e->resist_force_N) * k.inv_mass + vy * r;
  e->dvy_mps2 = body_fy * k.inv_mass - vx * r;
  e->dyaw_rate_radps2 = yaw_moment * k.inv_yaw_inertia;
  #pragma GCC unroll 4
  for (int i = 0; i < 4; ++i) {
    const T torque = i < 2 ? T(0) : T(0.5) * e->drive_torque_Nm;
    e->domega_radps2[i] = (torque - e->fx_N[i] * k.radius) * k.inv_wheel_inertia[i];
  }
}

// The accelerations only, from scalar wheel speeds: what the batched step needs. Keeping the
// terms struct (arrays) out of the omp-simd loop body lets GCC vectorise the lane loop.
template <class T>
struct FourWheelRates {
  T dvx, dvy, dr, dw0, dw1, dw2, dw3;
};
// The rates out of one evaluation's terms.
template <class T>
[[gnu::always_inline]] inline FourWheelRates<T> rates_of(const FourWheelTerms<T>& e) noexcept {
  return {e.dvx_mps2, e.dvy_mps2, e.dyaw_rate_radps2, e.domega_radps2[0], e.domega_radps2[1],
          e.domega_radps2[2], e.domega_radps2[3]};
}
template <class T>
[[gnu::always_inline]] inline FourWheelRates<T> four_wheel_rates(const FourWheelCoeffs<T>& k, T vx, T vy, T r,
                                                                  T w0, T w1, T w2, T w3, T steer,
                                                                  T throttle) noexcept {
  const T omega[4] = {w0, w1, w2, w3};
  FourWheelTerms<T> e;
  four_wheel_terms<T>(k, vx, vy, r, omega, steer, throttle, nullptr, &e);
  return rates_of(e);
}

// The planar rows of a four-wheel batch (pose, body velocities, wheel speeds from row `omega`):
// what the double-track and the full vehicle step alike.
template <int W>
struct FourWheelLanes {
  float *x, *y, *yaw, *vx, *vy, *yaw_rate, *w0, *w1, *w2, *w3;

  template <int Nx>
  FourWheelLanes(Batch<Nx, W> b, int omega) noexcept
      : x(b[state::kX]), y(b[state::kY]), yaw(b[state::kYaw]), vx(b[state::kVx]), vy(b[state::kVy]),
        yaw_rate(b[state::kYawRate]), w0(b[omega]), w1(b[omega + 1]), w2(b[omega + 2]), w3(b[omega + 3]) {}

  // Explicit Euler of lane j's planar state by the rates d; the pose moves with the old velocities.
  [[gnu::always_inline]] void advance(int j, const FourWheelRates<float>& d, float dt_s) const noexcept {
    const float u = vx[j], v = vy[j], r = yaw_rate[j];
    float sy, cy;
    fast_sincos(yaw[j], &sy, &cy);
    x[j] += (cy * u - sy * v) * dt_s;
    y[j] += (sy * u + cy * v) * dt_s;
    yaw[j] += r * dt_s;
    vx[j] = u + d.dvx * dt_s;
    vy[j] = v + d.dvy * dt_s;
    yaw_rate[j] = r + d.dr * dt_s;
    w0[j] += d.dw0 * dt_s;
    w1[j] += d.dw1 * dt_s;
    w2[j] += d.dw2 * dt_s;
    w3[j] += d.dw3 * dt_s;
  }
};

// dx = f(x, u) of the planar rows (all but roll and what follows the wheel speeds at `omega`),
// in double, from one evaluation's terms.
inline void four_wheel_planar_derivatives(const double* x, const FourWheelTerms<double>& e, int omega,
                                          double* dx) noexcept {
  const double sy = std::sin(x[state::kYaw]), cy = std::cos(x[state::kYaw]);
  dx[state::kX] = cy * x[state::kVx] - sy * x[state::kVy];
  dx[state::kY] = sy * x[state::kVx] + cy * x[state::kVy];
  dx[state::kYaw] = x[state::kYawRate];
  dx[state::kVx] = e.dvx_mps2;
  dx[state::kVy] = e.dvy_mps2;
  dx[state::kYawRate] = e.dyaw_rate_radps2;
  for (int i = 0; i < 4; ++i) dx[omega + i] = e.domega_radps2[i];
}

inline FourWheelCoeffs<double> double_track_coeffs(const DoubleTrackParams& p) noexcept {
  const double h = p.base.cg_height_m, lambda = p.lateral_load_transfer;
  return FourWheelCoeffs<double>::from(p.base, p.front_track_m, p.rear_track_m, h,
                                       lambda * p.front_roll_share * h,
                                       lambda * (1 - p.front_roll_share) * h, p.base.aero_drag_kgpm);
}

class DoubleTrack {
 public:
  static constexpr int kNx = 11;
  static constexpr int kNu = 2;
  static constexpr int kOmega = 7;  // wheel speeds [rad/s] at kOmega + wheel::kLF ... kRR

  // Throws mppi::Error if the parameters are not valid.
  explicit DoubleTrack(const DoubleTrackParams& params = {}) : params_(params) {
    std::string why;
    if (!params_.is_valid(&why)) throw Error("DoubleTrack: invalid parameters: " + why);
    kd_ = double_track_coeffs(params_);
    kf_ = convert(kd_);
  }

  const DoubleTrackParams& params() const { return params_; }
  std::size_t scratch_floats(int) const { return 0; }

  // x <- x + dt f(x, u) (explicit Euler, positions from the old velocities), every lane.
  template <int W>
  void step(Batch<kNx, W> x, ConstBatch<kNu, W> u, float dt_s, float* /*scratch*/) const noexcept {
    const FourWheelCoeffs<float> k = kf_;
    const FourWheelLanes<W> p(x, kOmega);
    const float* ps = u[control::kSteer];
    const float* pt = u[control::kThrottle];
    MPPI_SIMD_LOOP
    for (int j = 0; j < W; ++j) {
      const FourWheelRates<float> d = four_wheel_rates<float>(k, p.vx[j], p.vy[j], p.yaw_rate[j], p.w0[j],
                                                              p.w1[j], p.w2[j], p.w3[j], ps[j], pt[j]);
      p.advance(j, d, dt_s);
    }
  }

  // Common state copied; roll 0; wheels rolling without slip: omega = vx / R.
  void init_state(const VehicleState& s, float* x) const {
    const auto common = s.to_array();
    std::copy(common.begin(), common.end(), x);
    x[state::kRoll] = 0.f;
    for (int i = 0; i < 4; ++i) x[kOmega + i] = static_cast<float>(s.vx_mps / params_.base.wheel_radius_m);
  }

  // dx = f(x, u) in double with libm (reference, estimators, higher-order integrators).
  void derivatives(const double* x, const double* u, double* dx) const noexcept {
    derivatives(kd_, x, u, dx);
  }
  // The same from coefficients (double_track_coeffs(params)): no validation, no allocation,
  // for estimators that vary the parameters at every step.
  static void derivatives(const FourWheelCoeffs<double>& k, const double* x, const double* u,
                          double* dx) noexcept {
    FourWheelTerms<double> e;
    four_wheel_terms<double>(k, x[state::kVx], x[state::kVy], x[state::kYawRate], x + kOmega,
                             u[control::kSteer], u[control::kThrottle], nullptr, &e);
    four_wheel_planar_derivatives(x, e, kOmega, dx);
    dx[state::kRoll] = 0.0;
  }

  // Tyre velocities, slips, loads and forces at (x, u), in double.
  FourWheelForces forces(const double* x, const double* u) const noexcept {
    FourWheelForces e;
    four_wheel_terms<double>(kd_, x[state::kVx], x[state::kVy], x[state::kYawRate], x + kOmega,
                             u[control::kSteer], u[control::kThrottle], nullptr, &e);
    return e;
  }

  // Float copy of double coefficients (also used by the full vehicle).
  static FourWheelCoeffs<float> convert(const FourWheelCoeffs<double>& d) noexcept {
    FourWheelCoeffs<float> f{};
    auto t = [](double v) { return static_cast<float>(v); };
    f.inv_mass = t(d.inv_mass);
    f.inv_yaw_inertia = t(d.inv_yaw_inertia);
    f.radius = t(d.radius);
    f.weight = t(d.weight);
    for (int i = 0; i < 4; ++i) {
      f.pos_x[i] = t(d.pos_x[i]);
      f.pos_y[i] = t(d.pos_y[i]);
      f.inv_wheel_inertia[i] = t(d.inv_wheel_inertia[i]);
      f.static_load[i] = t(d.static_load[i]);
      f.load_per_fx[i] = t(d.load_per_fx[i]);
      f.load_per_fy[i] = t(d.load_per_fy[i]);
    }
    f.max_steer = t(d.max_steer);
    f.stall_torque = t(d.stall_torque);
    f.brake_ratio = t(d.brake_ratio);
    f.inv_no_load_speed = t(d.inv_no_load_speed);
    f.rolling_force = t(d.rolling_force);
    f.inv_rolling_speed = t(d.inv_rolling_speed);
    f.drag = t(d.drag);
    f.slip_floor = t(d.slip_floor);
    f.inv_slip_blend = t(d.inv_slip_blend);
    f.tyre = {t(d.tyre.B), t(d.tyre.C), t(d.tyre.D), t(d.tyre.E), t(d.tyre.Sh), t(d.tyre.Sv)};
    f.rear_tyre = {t(d.rear_tyre.B), t(d.rear_tyre.C), t(d.rear_tyre.D), t(d.rear_tyre.E), t(d.rear_tyre.Sh),
                   t(d.rear_tyre.Sv)};
    return f;
  }

 private:
  DoubleTrackParams params_;
  FourWheelCoeffs<double> kd_{};
  FourWheelCoeffs<float> kf_{};
};

}  // namespace mppi
