#pragma once
// tyre_relaxation: the tyres' lateral force lags the slip. A tyre builds up its lateral force
// over a rolling distance, its relaxation length sigma, so that the force follows the slip
// through a first-order lag of time constant sigma / |v| (Pacejka, "Tyre and Vehicle Dynamics",
// ch. 7). The term keeps, per axle, the lateral velocity of the contact patch as the tyre
// carcass has taken it up, v_y':
//   d v_y' / dt = |v_x| / sigma (v_y - v_y')          (v_x, v_y: the axle's tyre-frame velocity,
//                                                     |v_x| floored at the model's slip speed floor)
// and corrects the base model's force by what the tyre would give at v_y' instead of v_y:
//   dF = (mu_y(v_y') - mu_y(v_y)) F_z,   F_z the axle's static load,
// with mu_y the model's own Magic Formula at free rolling (no longitudinal slip). In the
// tyres' linear range this is the relaxation model exactly; under wheel spin and load transfer
// it is its first-order part. Hook: a chassis term (it needs the tyres, mass, yaw inertia and axle
// positions of a single-track core), added to the body-axis accelerations of the step. State:
// v_y' of the front and the rear axle [m/s], 0 at the start (a fraction sigma / |v| of a second
// settles them). sigma = 0: off.
#include <algorithm>
#include <cmath>

#include "base/batch.hpp"
#include "base/param_table.hpp"
#include "dynamics/effect_spec.hpp"
#include "dynamics/fast_trig.hpp"
#include "dynamics/pacejka.hpp"
#include "dynamics/vehicle_params.hpp"
#include "mppi/concepts.hpp"

namespace mppi::effects {

struct TyreRelaxation {
  struct Params {
    double tyre_relaxation_length_m = 0.0;  // [m] sigma (0 = off)
  };

  static EffectDecl<Params> decl() {
    return {"tyre_relaxation",
            "the tyres' lateral force lags the slip over a rolling distance sigma (relaxation length)",
            EffectHook::kChassis,
            {{"tyre_relaxation_length_m", &Params::tyre_relaxation_length_m, "m", non_negative(), 0.0, 3.0, 0.1}},
            {0.2, 0.5, 1.0},
            DataGrid::kNone,
            Excitation::kCornering,
            /*dynamics_of=*/{},
            /*partner=*/{},
            // Its lag time sigma / |v| is, at one speed, a steering lag: a candidate where asked for.
            /*default_candidate=*/false};
  }

  static constexpr int kStates = 2;  // v_y' of the front and the rear contact patch [m/s]

  class Term {
   public:
    Term() = default;
    Term(const Params& p, const SingleTrackParams& chassis) {
      if (!(p.tyre_relaxation_length_m > 0.0)) return;
      active_ = true;
      const double wheelbase_m = chassis.cg_to_front_axle_m + chassis.cg_to_rear_axle_m;
      const double weight_N = chassis.mass_kg * chassis.gravity_mps2;
      inv_sigma_ = static_cast<float>(1.0 / p.tyre_relaxation_length_m);
      lf_ = static_cast<float>(chassis.cg_to_front_axle_m);
      lr_ = static_cast<float>(chassis.cg_to_rear_axle_m);
      front_load_per_kg_ = static_cast<float>(weight_N * chassis.cg_to_rear_axle_m / wheelbase_m / chassis.mass_kg);
      rear_load_per_kg_ = static_cast<float>(weight_N * chassis.cg_to_front_axle_m / wheelbase_m / chassis.mass_kg);
      mass_per_yaw_inertia_ = static_cast<float>(chassis.mass_kg / chassis.yaw_inertia_kgm2);
      max_steer_rad_ = static_cast<float>(chassis.max_steer_rad);
      slip_floor_mps_ = static_cast<float>(chassis.slip_speed_floor_mps);
      inv_slip_blend_ = static_cast<float>(1.0 / chassis.slip_blend);
      front_tyre_ = PacejkaCoeffs<float>::from(chassis.tyre);
      rear_tyre_ = PacejkaCoeffs<float>::from(chassis.rear_tyre());
    }
    bool active() const noexcept { return active_; }

    // Adds the lag's force to the lanes' accelerations (from the start-of-step state) and
    // advances the lagged velocities, state[0] (front) and state[1] (rear), by dt_s.
    template <int W>
    void add_body_accelerations(const BodyAccelLanes<W>& b, float* const* state, float dt_s) const noexcept {
      float* const front_lagged = state[0];
      float* const rear_lagged = state[1];
      MPPI_SIMD_LOOP
      for (int j = 0; j < W; ++j) {
        const float vx = b.vx_mps[j], vy = b.vy_mps[j], r = b.yaw_rate_radps[j];
        float sd, cd;
        fast_sincos(std::clamp(b.applied_steer[j], -1.f, 1.f) * max_steer_rad_, &sd, &cd);
        const float front_vx = vx * cd + (vy + lf_ * r) * sd, front_vy = -vx * sd + (vy + lf_ * r) * cd;
        const float rear_vx = vx, rear_vy = vy - lr_ * r;
        const float front_dF = front_load_per_kg_ * (lateral_mu(front_vx, front_lagged[j], front_tyre_) -
                                                     lateral_mu(front_vx, front_vy, front_tyre_));
        const float rear_dF = rear_load_per_kg_ * (lateral_mu(rear_vx, rear_lagged[j], rear_tyre_) -
                                                   lateral_mu(rear_vx, rear_vy, rear_tyre_));
        b.ax_mps2[j] -= front_dF * sd;
        b.ay_mps2[j] += front_dF * cd + rear_dF;
        b.yaw_accel_radps2[j] += mass_per_yaw_inertia_ * (lf_ * front_dF * cd - lr_ * rear_dF);
        front_lagged[j] += lag_weight(front_vx, dt_s) * (front_vy - front_lagged[j]);
        rear_lagged[j] += lag_weight(rear_vx, dt_s) * (rear_vy - rear_lagged[j]);
      }
    }

   private:
    // The share of the gap the lag closes in dt: 1 - exp(-|v_x| dt / sigma).
    float lag_weight(float vx, float dt_s) const noexcept {
      return 1.f - std::exp(-std::max(std::abs(vx), slip_floor_mps_) * dt_s * inv_sigma_);
    }
    // f_y / f_z of a freely rolling tyre (rim speed = v_x) at lateral velocity vy.
    float lateral_mu(float vx, float vy, const PacejkaCoeffs<float>& tyre) const noexcept {
      return tyre_friction(vx, vy, vx, slip_floor_mps_, inv_slip_blend_, tyre).mu_y;
    }

    bool active_ = false;
    float inv_sigma_ = 0, lf_ = 0, lr_ = 0, front_load_per_kg_ = 0, rear_load_per_kg_ = 0;
    float mass_per_yaw_inertia_ = 0, max_steer_rad_ = 0, slip_floor_mps_ = 1, inv_slip_blend_ = 1;
    PacejkaCoeffs<float> front_tyre_{}, rear_tyre_{};
  };
};

}  // namespace mppi::effects
