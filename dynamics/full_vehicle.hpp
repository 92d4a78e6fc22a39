#pragma once
// The AutoRally paper's full vehicle model: the double-track's planar motion (total mass m,
// dynamics/double_track.hpp) with aerodynamic drag, and a sprung mass m^s = m - 4 wheels in
// heave z, roll phi and pitch theta on four spring-damper corners; the per-wheel normal loads
// follow the suspension, and the tyre forces come from them by the Pacejka total-slip formula.
// Small-angle roll and pitch. ISO 8855 signs: roll phi > 0 = right side down, pitch theta > 0 =
// nose down, heave z > 0 = up, all relative to the static equilibrium.
//
// State (kNx = 16): the common 7 (index 6 = roll phi), wheel speeds LF, RF, LR, RR (7..10),
// pitch theta (11), heave z (12), roll rate (13), pitch rate (14), heave rate V_z (15).
//
// Corner i at (x_i, y_i): deflection dz_i = z - x_i theta + y_i phi (up positive), suspension
// force on the body F_i = -K_i dz_i - C_i d(dz_i)/dt (K_i, C_i = K_f, C_f front, K_r, C_r rear).
//   m^s dV_z      = sum F_i
//   I^P_y ddtheta = sum -x_i F_i + m^s g h^s theta - m^s a_x h^s
//   I^R_x ddphi   = sum y_i F_i + m^s g (h^s - h^c) phi + m^s a_y (h^s - h^c)
// with a_x, a_y the body-frame tyre force sums / m (rolling resistance and drag are left out
// of a_x here, as in the double-track's load transfer, so that the stiff limit holds). This
// is the paper's (FullVehicle4)-(FullVehicle6) with consistent signs (the paper's heave line
// has theta for z) and sin, cos linearised. Drag: m dVx gets -C_D rho A Vx |Vx| / 2 (the
// paper writes it outside the 1/m).
// Normal loads: f_iz = static_i + F_i + the quasi-static transfer of the part of the inertial
// moments that does not go through the springs (unsprung masses, roll-centre links):
//   pitch (m h - m^s h^s) a_x, split over the axles like the double-track's m h a_x;
//   roll (m h - m^s (h^s - h^c)) a_y, split by the roll-stiffness share chi_f.
// So as the springs stiffen (deflections -> 0) the loads tend to the double-track's
// (FullVehicleParams::rigid_limit), which the tests check.
// Time stepping: semi-implicit Euler for the suspension (rates first, then angles from the new
// rates: stable for the undamped corner modes at the controller's 0.02 s), explicit Euler for
// the rest as in the single-track.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>

#include "base/batch.hpp"
#include "base/error.hpp"
#include "dynamics/double_track.hpp"
#include "dynamics/vehicle_params.hpp"
#include "mppi/vehicle_state.hpp"

namespace mppi {

template <class T>
struct FullVehicleCoeffs {
  FourWheelCoeffs<T> planar;
  T inv_sprung_mass, inv_pitch_inertia, inv_roll_inertia;
  T spring[4], damper[4];        // K_i [N/m], C_i [N s/m] per corner
  T pitch_gravity, roll_gravity;  // m^s g h^s, m^s g (h^s - h^c) [N m]
  T pitch_arm, roll_arm;          // m^s h^s, m^s (h^s - h^c) [kg m]
};

inline FullVehicleCoeffs<double> full_vehicle_coeffs(const FullVehicleParams& p) noexcept {
  FullVehicleCoeffs<double> k{};
  const double m = p.base.mass_kg, ms = p.sprung_mass_kg(), g = p.base.gravity_mps2;
  const double h = p.base.cg_height_m, hs = p.sprung_cg_height_m, hc = p.roll_centre_height_m;
  const double chi = p.front_roll_share();
  const double h_long = h - ms / m * hs;          // non-spring pitch transfer, per unit Fx
  const double h_roll = h - ms / m * (hs - hc);   // non-spring roll transfer, per unit Fy
  k.planar = FourWheelCoeffs<double>::from(p.base, p.front_track_m, p.rear_track_m, h_long,
                                           chi * h_roll, (1 - chi) * h_roll,
                                           0.5 * p.drag_coefficient * p.air_density_kgpm3 * p.frontal_area_m2);
  k.inv_sprung_mass = 1 / ms;
  k.inv_pitch_inertia = 1 / p.pitch_inertia_kgm2;
  k.inv_roll_inertia = 1 / p.roll_inertia_kgm2;
  for (int i = 0; i < 4; ++i) {
    k.spring[i] = i < 2 ? p.front_spring_Npm : p.rear_spring_Npm;
    k.damper[i] = i < 2 ? p.front_damper_Nspm : p.rear_damper_Nspm;
  }
  k.pitch_gravity = ms * g * hs;
  k.roll_gravity = ms * g * (hs - hc);
  k.pitch_arm = ms * hs;
  k.roll_arm = ms * (hs - hc);
  return k;
}

template <class T>
struct FullVehicleTerms {
  FourWheelTerms<T> planar;     // tyres, loads, planar accelerations, wheel spin
  T suspension_force_N[4];      // F_i on the body, relative to the static preload
  T ax_mps2, ay_mps2;           // acceleration of the car (all forces / m), body frame, as an
                                // accelerometer at the CG reads it (without gravity)
  T dheave_rate_mps2, dpitch_rate_radps2, droll_rate_radps2;
};
using FullVehicleForces = FullVehicleTerms<double>;

// Right-hand side of the whole model, given roll, pitch, heave and their rates. Branch-free.
template <class T>
[[gnu::always_inline]] inline void full_vehicle_terms(const FullVehicleCoeffs<T>& k, T vx, T vy, T r, const T* omega,
                               T roll, T pitch, T heave, T roll_rate, T pitch_rate, T heave_rate,
                               T steer, T throttle, FullVehicleTerms<T>* e) noexcept {
  T sum_f = T(0), pitch_moment = T(0), roll_moment = T(0);
  #pragma GCC unroll 4
  for (int i = 0; i < 4; ++i) {
    const T x = k.planar.pos_x[i], y = k.planar.pos_y[i];
    const T dz = heave - x * pitch + y * roll;
    const T ddz = heave_rate - x * pitch_rate + y * roll_rate;
    const T f = -k.spring[i] * dz - k.damper[i] * ddz;
    e->suspension_force_N[i] = f;
    sum_f += f;
    pitch_moment -= x * f;
    roll_moment += y * f;
  }
  four_wheel_terms<T>(k.planar, vx, vy, r, omega, steer, throttle, e->suspension_force_N, &e->planar);
  e->ax_mps2 = (e->planar.body_fx_N + e->planar.resist_force_N) * k.planar.inv_mass;
  e->ay_mps2 = e->planar.body_fy_N * k.planar.inv_mass;
  e->dheave_rate_mps2 = sum_f * k.inv_sprung_mass;
  // The pitch excitation is the tyre forces' part of a_x (the same ground forces whose moment
  // the double-track transfers): rolling resistance and drag do not pitch the body here.
  e->dpitch_rate_radps2 =
      (pitch_moment + k.pitch_gravity * pitch - k.pitch_arm * e->planar.body_fx_N * k.planar.inv_mass) *
      k.inv_pitch_inertia;
  e->droll_rate_radps2 =
      (roll_moment + k.roll_gravity * roll + k.roll_arm * e->ay_mps2) * k.inv_roll_inertia;
}

// The rates the batched step needs, from scalars (keeps arrays out of the omp-simd loop body).
template <class T>
struct FullVehicleRates {
  FourWheelRates<T> planar;
  T droll_rate, dpitch_rate, dheave_rate;
};
template <class T>
[[gnu::always_inline]] inline FullVehicleRates<T> full_vehicle_rates(
    const FullVehicleCoeffs<T>& k, T vx, T vy, T r, T w0, T w1, T w2, T w3, T roll, T pitch, T heave,
    T roll_rate, T pitch_rate, T heave_rate, T steer, T throttle) noexcept {
  const T omega[4] = {w0, w1, w2, w3};
  FullVehicleTerms<T> e;
  full_vehicle_terms<T>(k, vx, vy, r, omega, roll, pitch, heave, roll_rate, pitch_rate, heave_rate,
                        steer, throttle, &e);
  return {rates_of(e.planar), e.droll_rate_radps2, e.dpitch_rate_radps2, e.dheave_rate_mps2};
}

class FullVehicle {
 public:
  static constexpr int kNx = 16;
  static constexpr int kNu = 2;
  static constexpr int kOmega = 7;       // wheel speeds [rad/s] at kOmega + wheel::kLF ... kRR
  static constexpr int kPitch = 11;      // theta [rad], nose down positive
  static constexpr int kHeave = 12;      // z [m], up positive, from the static equilibrium
  static constexpr int kRollRate = 13;   // [rad/s]
  static constexpr int kPitchRate = 14;  // [rad/s]
  static constexpr int kHeaveRate = 15;  // V_z [m/s]

  // Throws mppi::Error if the parameters are not valid.
  explicit FullVehicle(const FullVehicleParams& params = {}) : params_(params) {
    std::string why;
    if (!params_.is_valid(&why)) throw Error("FullVehicle: invalid parameters: " + why);
    kd_ = full_vehicle_coeffs(params_);
    kf_ = convert(kd_);
  }

  const FullVehicleParams& params() const { return params_; }
  std::size_t scratch_floats(int) const { return 0; }

  template <int W>
  void step(Batch<kNx, W> x, ConstBatch<kNu, W> u, float dt_s, float* /*scratch*/) const noexcept {
    const FullVehicleCoeffs<float> k = kf_;
    const FourWheelLanes<W> p(x, kOmega);
    float* proll = x[state::kRoll];
    float* ppitch = x[kPitch];
    float* pz = x[kHeave];
    float* proll_rate = x[kRollRate];
    float* ppitch_rate = x[kPitchRate];
    float* pz_rate = x[kHeaveRate];
    const float* ps = u[control::kSteer];
    const float* pt = u[control::kThrottle];
    MPPI_SIMD_LOOP
    for (int j = 0; j < W; ++j) {
      const FullVehicleRates<float> e = full_vehicle_rates<float>(
          k, p.vx[j], p.vy[j], p.yaw_rate[j], p.w0[j], p.w1[j], p.w2[j], p.w3[j], proll[j], ppitch[j], pz[j],
          proll_rate[j], ppitch_rate[j], pz_rate[j], ps[j], pt[j]);
      p.advance(j, e.planar, dt_s);
      const float roll_rate = proll_rate[j] + e.droll_rate * dt_s;
      const float pitch_rate = ppitch_rate[j] + e.dpitch_rate * dt_s;
      const float heave_rate = pz_rate[j] + e.dheave_rate * dt_s;
      proll_rate[j] = roll_rate;
      ppitch_rate[j] = pitch_rate;
      pz_rate[j] = heave_rate;
      proll[j] += roll_rate * dt_s;
      ppitch[j] += pitch_rate * dt_s;
      pz[j] += heave_rate * dt_s;
    }
  }

  // Common state copied (roll included); wheels rolling without slip; suspension at rest.
  void init_state(const VehicleState& s, float* x) const {
    const auto common = s.to_array();
    std::copy(common.begin(), common.end(), x);
    for (int i = 0; i < 4; ++i) x[kOmega + i] = static_cast<float>(s.vx_mps / params_.base.wheel_radius_m);
    for (int i = kPitch; i < kNx; ++i) x[i] = 0.f;
  }

  // dx = f(x, u) in double with libm (reference, estimators, higher-order integrators).
  void derivatives(const double* x, const double* u, double* dx) const noexcept {
    derivatives(kd_, x, u, dx);
  }
  // The same from coefficients (full_vehicle_coeffs(params)): no validation, no allocation.
  static void derivatives(const FullVehicleCoeffs<double>& k, const double* x, const double* u,
                          double* dx) noexcept {
    const FullVehicleTerms<double> e = terms(k, x, u);
    four_wheel_planar_derivatives(x, e.planar, kOmega, dx);
    dx[state::kRoll] = x[kRollRate];
    dx[kPitch] = x[kPitchRate];
    dx[kHeave] = x[kHeaveRate];
    dx[kRollRate] = e.droll_rate_radps2;
    dx[kPitchRate] = e.dpitch_rate_radps2;
    dx[kHeaveRate] = e.dheave_rate_mps2;
  }

  // Suspension forces, tyre velocities, slips, loads and forces at (x, u), in double.
  FullVehicleForces forces(const double* x, const double* u) const noexcept { return terms(kd_, x, u); }
  static FullVehicleForces forces(const FullVehicleCoeffs<double>& k, const double* x,
                                  const double* u) noexcept {
    return terms(k, x, u);
  }

  // One step of the same integrator as step(), in double (for estimators and references).
  static void step_double(const FullVehicleCoeffs<double>& k, double* x, const double* u,
                          double dt_s) noexcept {
    double dx[kNx];
    derivatives(k, x, u, dx);
    for (int i = 0; i < kNx; ++i)
      if (i != state::kRoll && i != kPitch && i != kHeave) x[i] += dx[i] * dt_s;
    // Semi-implicit: the angles move with the new rates.
    x[state::kRoll] += x[kRollRate] * dt_s;
    x[kPitch] += x[kPitchRate] * dt_s;
    x[kHeave] += x[kHeaveRate] * dt_s;
  }

  static FullVehicleCoeffs<float> convert(const FullVehicleCoeffs<double>& d) noexcept {
    FullVehicleCoeffs<float> f{};
    auto t = [](double v) { return static_cast<float>(v); };
    f.planar = DoubleTrack::convert(d.planar);
    f.inv_sprung_mass = t(d.inv_sprung_mass);
    f.inv_pitch_inertia = t(d.inv_pitch_inertia);
    f.inv_roll_inertia = t(d.inv_roll_inertia);
    for (int i = 0; i < 4; ++i) {
      f.spring[i] = t(d.spring[i]);
      f.damper[i] = t(d.damper[i]);
    }
    f.pitch_gravity = t(d.pitch_gravity);
    f.roll_gravity = t(d.roll_gravity);
    f.pitch_arm = t(d.pitch_arm);
    f.roll_arm = t(d.roll_arm);
    return f;
  }

 private:
  static FullVehicleTerms<double> terms(const FullVehicleCoeffs<double>& k, const double* x,
                                        const double* u) noexcept {
    FullVehicleTerms<double> e;
    full_vehicle_terms<double>(k, x[state::kVx], x[state::kVy], x[state::kYawRate], x + kOmega,
                               x[state::kRoll], x[kPitch], x[kHeave], x[kRollRate], x[kPitchRate],
                               x[kHeaveRate], u[control::kSteer], u[control::kThrottle], &e);
    return e;
  }

  FullVehicleParams params_;
  FullVehicleCoeffs<double> kd_{};
  FullVehicleCoeffs<float> kf_{};
};

}  // namespace mppi
