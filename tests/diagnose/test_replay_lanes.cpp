// mppi-fit diagnose: the replay of many segments at once in SIMD lanes (predict_segments) against a
// naive replay written here, one segment and one model step at a time through ReplayModel's scalar
// calls (the oracle), on a regular recording with a piece boundary (segments of several command
// histories), for every nominal model the diagnosis takes, with effects of every hook on; on a
// recording with missing rows (a lane whose interval differs takes its own step); and on a
// recording with timing jitter, where the lanes share each row's step.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "diagnose/model_family.hpp"
#include "diagnose/replay.hpp"
#include "diagnose/synth.hpp"

using namespace mppi;
using namespace mppi::diagnose;

namespace {

// The replay as specified, for a model without sensor faults or pure delays: the command history
// (up to prime_s, inside the start's piece) through the actuator chains, its last wheel_prime_s
// through the full model with the measured states forced back every row (velocities blended by
// the observer gain after the first full row), then len rows open loop from the measured state.
std::vector<double> naive_predict(const ReplayModel& m, const PreparedRecording& d, const Segment& s, const ReplayOptions& o) {
  float x[ReplayModel::kMaxStates] = {};
  const std::size_t k0 = s.start;
  VehicleState vs;
  vs.x_m = static_cast<float>(d.x[k0]);
  vs.y_m = static_cast<float>(d.y[k0]);
  vs.yaw_rad = static_cast<float>(d.yaw[k0]);
  vs.vx_mps = static_cast<float>(d.vx[k0]);
  vs.vy_mps = static_cast<float>(d.vy[k0]);
  vs.yaw_rate_radps = static_cast<float>(d.r[k0]);
  const bool roll = !d.roll.empty();  // the network's models carry roll
  if (roll) vs.roll_rad = static_cast<float>(d.roll[k0]);
  m.init_state(vs, x);
  std::size_t h = k0;
  for (int i = 0; i < static_cast<int>(std::lround(o.prime_s / d.dt_s)) && h > 0 && d.piece[h - 1] == d.piece[k0]; ++i) --h;
  m.set_actuators(x, static_cast<float>(d.steer_over(h)), static_cast<float>(d.throttle_over(h)));
  float gain = 1.f;
  auto measured = [&](std::size_t k) {
    x[state::kX] = static_cast<float>(d.x[k]);
    x[state::kY] = static_cast<float>(d.y[k]);
    x[state::kYaw] = static_cast<float>(d.yaw[k]);
    x[state::kVx] += gain * (static_cast<float>(d.vx[k]) - x[state::kVx]);
    x[state::kVy] += gain * (static_cast<float>(d.vy[k]) - x[state::kVy]);
    x[state::kYawRate] += gain * (static_cast<float>(d.r[k]) - x[state::kYawRate]);
    if (roll) x[state::kRoll] += gain * (static_cast<float>(d.roll[k]) - x[state::kRoll]);
    x[m.time_index()] = static_cast<float>(d.t[k]);
  };
  auto advance = [&](std::size_t k) {
    const double dt = d.t[k + 1] - d.t[k];
    const int n = std::max(1, static_cast<int>(std::lround(dt / o.substep_s)));
    for (int j = 0; j < n; ++j)
      m.step(x, static_cast<float>(d.steer_over(k)), static_cast<float>(d.throttle_over(k)), static_cast<float>(dt / n));
  };
  for (std::size_t k = h; k < k0; ++k) {
    measured(k);
    if (static_cast<double>(k0 - k) * d.dt_s > o.wheel_prime_s) {
      m.advance_actuators(x, static_cast<float>(d.steer_over(k)), static_cast<float>(d.throttle_over(k)),
                          static_cast<float>(d.t[k + 1] - d.t[k]));
      continue;
    }
    advance(k);
    gain = static_cast<float>(o.observer_gain);
  }
  measured(k0);
  std::vector<double> out;
  for (int i = 0; i < s.len; ++i) {
    advance(k0 + static_cast<std::size_t>(i));
    for (int c : {state::kVx, state::kVy, state::kYawRate, state::kX, state::kY}) out.push_back(x[c]);
  }
  return out;
}

// Segments of 25 rows: every 7th row (overlapping), so that runs of lanes, their remainders and
// the starts just after the piece boundary (short histories: lanes that join their group late) all occur.
std::vector<Segment> segments_of(const PreparedRecording& d) {
  std::vector<Segment> segs;
  for (std::size_t k = 0; k + 26 < d.rows(); k += 7)
    if (d.continuous(k, 25)) segs.push_back({k, 25});
  return segs;
}

// Largest |lanes - oracle| over all predictions, against the largest |oracle|.
struct Gap {
  double worst = 0, spread = 0;
};
Gap lanes_vs_naive(const ReplayModel& m, const PreparedRecording& d, const std::vector<Segment>& segs) {
  const ReplayOptions o;
  std::vector<double> lanes(segs.size() * 25 * kPredStride);
  predict_segments(m, d, segs, o, lanes.data());
  Gap g;
  for (std::size_t n = 0; n < segs.size(); ++n) {
    const std::vector<double> ref = naive_predict(m, d, segs[n], o);
    for (std::size_t i = 0; i < ref.size(); ++i) {
      const double v = lanes[n * 25 * kPredStride + i];
      g.worst = std::max(g.worst, std::isfinite(v) ? std::abs(v - ref[i]) : 1e9);
      g.spread = std::max(g.spread, std::abs(ref[i]));
    }
  }
  return g;
}

// A recording of `model` with a piece boundary at row 300 (a gap, as a respawn leaves).
PreparedRecording regular_recording(const std::string& model) {
  PreparedRecording d = prepare(synthesize_open_loop({}, 5, 14.0, {}, model), "drive");
  for (std::size_t k = 300; k < d.rows(); ++k)
    if (d.piece[k] >= 0) d.piece[k] += 1;
  return d;
}

}  // namespace

TEST_CASE("the replay in SIMD lanes predicts what one segment at a time does, for every nominal model", "[diagnose]") {
  EffectParams e;  // actuator, chassis and force hooks: a lag, a steering map, less grip, drag
  e.steer_lag_s = 0.08;
  e.steer_gain = 0.9;
  e.throttle_offset = 0.03;
  e.aero_drag_kgpm = 0.3;
  for (const std::string model : {"single-track", "double-track", "full-vehicle", "kinematic", "autorally-nn"}) {
    const auto family = make_model_family(model);
    EffectParams with = e;
    if (family->supports("tire_saturation")) with.tyre_peak_scale = 0.8;
    const PreparedRecording d = regular_recording(model);
    const std::vector<Segment> segs = segments_of(d);
    REQUIRE(segs.size() > 40);
    const auto member = family->make(with);
    const Gap g = lanes_vs_naive(*member, d, segs);
    INFO(model << ": largest difference " << g.worst << " of values up to " << g.spread);
    // float rounding of the vectorised step (fused multiply-adds) over 25 rows of 10 substeps
    CHECK(g.worst < 2e-5 * g.spread);
  }
}

TEST_CASE("the replay in SIMD lanes gives each segment its own start, commands and history", "[diagnose]") {
  const PreparedRecording d = regular_recording("single-track");
  const auto member = make_model_family("single-track")->make({});
  std::vector<Segment> segs = segments_of(d);
  std::vector<double> forward(segs.size() * 25 * kPredStride), backward(forward.size());
  predict_segments(*member, d, segs, ReplayOptions{}, forward.data());
  // The same segments in reverse order: each segment's predictions move with it.
  std::vector<Segment> reversed(segs.rbegin(), segs.rend());
  predict_segments(*member, d, reversed, ReplayOptions{}, backward.data());
  const std::size_t per = 25 * kPredStride, n = segs.size();
  double worst = 0;
  for (std::size_t s = 0; s < n; ++s)
    for (std::size_t i = 0; i < per; ++i)
      worst = std::max(worst, std::abs(forward[s * per + i] - backward[(n - 1 - s) * per + i]));
  CHECK(worst < 1e-3);
  // And neighbouring segments do differ (each lane reads its own rows).
  CHECK(std::abs(forward[per - kPredStride] - forward[2 * per - kPredStride]) > 1e-3);
}

TEST_CASE("the replay in SIMD lanes steps a lane across a missing row by its own interval", "[diagnose]") {
  PreparedRecording d = regular_recording("single-track");
  // Rows missing from the file: every later time moves on by one interval, inside the piece.
  for (std::size_t missing : {40u, 95u, 96u, 170u, 333u})
    for (std::size_t k = missing; k < d.rows(); ++k) d.t[k] += d.dt_s;
  const auto member = make_model_family("single-track")->make({});
  const Gap g = lanes_vs_naive(*member, d, segments_of(d));
  INFO("largest difference " << g.worst << " of values up to " << g.spread);
  CHECK(g.worst < 2e-5 * g.spread);
}

TEST_CASE("on a recording with timing jitter the lanes share each row's step, and stay close", "[diagnose]") {
  PreparedRecording d = regular_recording("single-track");
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> jitter(-0.05, 0.05);  // +-5 % of the sample interval: shared steps
  for (std::size_t k = 1; k < d.rows(); ++k) d.t[k] += jitter(rng) * d.dt_s;
  const auto member = make_model_family("single-track")->make({});
  const Gap g = lanes_vs_naive(*member, d, segments_of(d));
  INFO("largest difference " << g.worst << " of values up to " << g.spread);
  CHECK(g.worst > 1e-6 * g.spread);  // not the same: the lanes' steps are averaged
  CHECK(g.worst < 5e-3 * g.spread);
}
