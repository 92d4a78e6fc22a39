// tyre_relaxation (dynamics/effects/tyre_relaxation.hpp) against an oracle written here: the
// lateral dynamics of the single-track car (lateral velocity and yaw rate at the speed the model
// drove, free-rolling tyres at their static loads, the Magic Formula written out in double) with
// and without a first-order lag of each axle's lateral contact-patch velocity over the distance
// sigma. The model's response to a steering step, relaxed minus unrelaxed, must match the
// oracle's; an oracle with twice the relaxation length must not.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

#include "dynamics/corrected_model.hpp"
#include "dynamics/with_effects.hpp"

namespace {

using mppi::CorrectedSingleTrack;
using mppi::EffectParams;
using mppi::SingleTrack;
using mppi::SingleTrackParams;

constexpr double kDt = 0.002, kSteerAt = 0.3, kEnd = 1.5, kSteer = 0.06, kSpeed = 5.0;

struct Drive {
  std::vector<double> vx, yaw_rate;
};

// The model on a straight at kSpeed, free rolling (the motor's torque-free command), then a
// steering step of kSteer at kSteerAt.
Drive drive_model(double sigma_m) {
  const SingleTrackParams car;
  EffectParams e;
  e.tyre_relaxation_length_m = sigma_m;
  const CorrectedSingleTrack m(SingleTrack(car), e);
  float x[CorrectedSingleTrack::kNx];
  mppi::VehicleState s;
  s.vx_mps = static_cast<float>(kSpeed);
  m.init_state(s, x);
  const float throttle = static_cast<float>(kSpeed / car.no_load_speed_mps);
  Drive d;
  for (int k = 0; k * kDt < kEnd; ++k) {
    const float u[2] = {k * kDt < kSteerAt ? 0.f : static_cast<float>(kSteer), throttle};
    CorrectedSingleTrack::set_actuators(x, u[0], u[1]);
    d.vx.push_back(x[mppi::state::kVx]);
    d.yaw_rate.push_back(x[mppi::state::kYawRate]);
    m.step<1>(mppi::Batch<CorrectedSingleTrack::kNx, 1>{x}, u, static_cast<float>(kDt), nullptr);
  }
  return d;
}

// f_y / f_z of a freely rolling tyre at lateral slip s (the regularised Magic Formula).
double lateral_mu(double s, const mppi::PacejkaParams& t, double blend) {
  const double a = std::abs(s), se = a - t.Sh, bse = t.B * se;
  const double mu = t.D * std::sin(t.C * std::atan(bse - t.E * (bse - std::atan(se)))) + t.Sv;
  return -std::copysign(1.0, s) * mu * std::tanh(a / blend);
}

// The oracle: lateral velocity and yaw rate at the model's speeds, relaxation length sigma
// (0: none), explicit Euler at kDt.
std::vector<double> oracle_yaw_rate(const std::vector<double>& vx, double sigma_m) {
  const SingleTrackParams car;
  const double m = car.mass_kg, iz = car.yaw_inertia_kgm2, lf = car.cg_to_front_axle_m, lr = car.cg_to_rear_axle_m;
  const double fz_front = m * car.gravity_mps2 * lr / (lf + lr), fz_rear = m * car.gravity_mps2 * lf / (lf + lr);
  const double floor = car.slip_speed_floor_mps;
  double vy = 0, r = 0, front_lagged = 0, rear_lagged = 0;
  std::vector<double> out;
  for (std::size_t k = 0; k < vx.size(); ++k) {
    out.push_back(r);
    const double v = vx[k], delta = (k * kDt < kSteerAt ? 0.0 : kSteer) * car.max_steer_rad;
    const double front_vx = v * std::cos(delta) + (vy + lf * r) * std::sin(delta);
    const double front_vy = -v * std::sin(delta) + (vy + lf * r) * std::cos(delta);
    const double rear_vx = v, rear_vy = vy - lr * r;
    const double front_seen = sigma_m > 0 ? front_lagged : front_vy, rear_seen = sigma_m > 0 ? rear_lagged : rear_vy;
    const double fy_front = fz_front * lateral_mu(front_seen / std::max(std::abs(front_vx), floor), car.tyre, car.slip_blend);
    const double fy_rear = fz_rear * lateral_mu(rear_seen / std::max(std::abs(rear_vx), floor), car.rear_tyre(), car.slip_blend);
    const double dvy = (fy_front * std::cos(delta) + fy_rear) / m - v * r;
    const double dr = (lf * fy_front * std::cos(delta) - lr * fy_rear) / iz;
    if (sigma_m > 0) {
      front_lagged += (1 - std::exp(-std::max(std::abs(front_vx), floor) * kDt / sigma_m)) * (front_vy - front_lagged);
      rear_lagged += (1 - std::exp(-std::max(std::abs(rear_vx), floor) * kDt / sigma_m)) * (rear_vy - rear_lagged);
    }
    vy += dvy * kDt;
    r += dr * kDt;
  }
  return out;
}

double largest_gap(const std::vector<double>& a, const std::vector<double>& b) {
  double g = 0;
  for (std::size_t k = 0; k < a.size(); ++k) g = std::max(g, std::abs(a[k] - b[k]));
  return g;
}

}  // namespace

TEST_CASE("tyre relaxation: the yaw response to a steering step lags as the oracle's does", "[dynamics][effects]") {
  const double sigma_m = 0.5;
  const Drive nominal = drive_model(0.0), relaxed = drive_model(sigma_m);
  std::vector<double> model_change(nominal.vx.size()), oracle_change(nominal.vx.size()),
      wrong_change(nominal.vx.size());
  const std::vector<double> oracle_nominal = oracle_yaw_rate(nominal.vx, 0.0);
  const std::vector<double> oracle_relaxed = oracle_yaw_rate(relaxed.vx, sigma_m);
  const std::vector<double> oracle_wrong = oracle_yaw_rate(relaxed.vx, 2 * sigma_m);
  for (std::size_t k = 0; k < nominal.vx.size(); ++k) {
    model_change[k] = relaxed.yaw_rate[k] - nominal.yaw_rate[k];
    oracle_change[k] = oracle_relaxed[k] - oracle_nominal[k];
    wrong_change[k] = oracle_wrong[k] - oracle_nominal[k];
  }
  const double peak_rate = *std::max_element(nominal.yaw_rate.begin(), nominal.yaw_rate.end());
  const double change = largest_gap(oracle_change, std::vector<double>(oracle_change.size(), 0.0));
  INFO("peak yaw rate " << peak_rate << " rad/s, relaxation changes it by up to " << change);
  // The oracle's own nominal response is the model's (the same car; it leaves out wheel spin and
  // load transfer): within 5 % of the peak.
  CHECK(largest_gap(oracle_nominal, nominal.yaw_rate) < 0.05 * peak_rate);
  // The lag matters here (a fifth of the response or more) ...
  REQUIRE(change > 0.2 * peak_rate);
  // ... the model's change is the oracle's within 10 % of it, and twice the length is told apart.
  CHECK(largest_gap(model_change, oracle_change) < 0.1 * change);
  CHECK(largest_gap(model_change, wrong_change) > 0.3 * change);
  // In the steady turn the lag has settled: the same yaw rate as without it.
  CHECK(relaxed.yaw_rate.back() == Approx(nominal.yaw_rate.back()).epsilon(0.01));
}

TEST_CASE("tyre relaxation is an effect of the table: file key, range, off by default, by name only", "[dynamics][effects]") {
  const mppi::EffectSpec& spec = mppi::effect_spec("tyre_relaxation");
  REQUIRE(spec.params.size() == 1);
  CHECK(std::string(spec.params[0].name) == "tyre_relaxation_length_m");
  CHECK(std::string(spec.params[0].unit) == "m");
  CHECK(spec.hook == mppi::EffectHook::kChassis);
  CHECK_FALSE(spec.default_candidate);
  CHECK(EffectParams{}.*(spec.params[0].member) == 0.0);
  EffectParams e;
  e.tyre_relaxation_length_m = 0.8;
  mppi::CorrectedModelFile f;
  f.effects = e;
  const mppi::CorrectedModelFile back = mppi::corrected_model_from_yaml(mppi::corrected_model_to_yaml(f), "mem");
  CHECK(back.effects.tyre_relaxation_length_m == 0.8);
  CHECK_THROWS_WITH(mppi::corrected_model_from_yaml("effects:\n  tyre_relaxation_length_m: -1\n", "neg.yaml"),
                    Catch::Contains("tyre_relaxation_length_m"));
  // A model without tyres refuses it.
  CHECK_THROWS_WITH(mppi::KinematicWithEffects(mppi::KinematicBicycle(), e), Catch::Contains("tyre_relaxation"));
}
