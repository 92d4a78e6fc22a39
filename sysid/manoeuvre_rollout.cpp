#include "sysid/manoeuvre_rollout.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "base/error.hpp"
#include "mppi/vehicle_state.hpp"

namespace mppi::sysid {

namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

// One piece's randomised pattern constants.
struct Piece {
  int manoeuvre = 1;
  double target_mps = 5, amplitude = 0.3, period_s = 4, side = 1, brake = -0.8;
};

Piece draw_piece(int manoeuvre, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  auto in = [&](double a, double b) { return a + (b - a) * u01(rng); };
  Piece p;
  p.manoeuvre = manoeuvre;
  p.side = u01(rng) < 0.5 ? -1.0 : 1.0;
  switch (manoeuvre) {
    case 1: p.target_mps = in(4, 6); p.amplitude = in(0.2, 0.45); p.period_s = in(2.5, 6); break;
    case 2: p.target_mps = in(4, 6); p.amplitude = in(0.3, 0.6); p.period_s = in(1.5, 3); break;
    case 3: p.target_mps = in(7, 10); p.brake = in(-0.99, -0.3); break;
    case 4: p.target_mps = in(6, 8); p.amplitude = in(0.45, 0.8); break;
    default: p.target_mps = in(8, 10); p.amplitude = in(0.08, 0.2); p.period_s = in(3, 7); break;
  }
  return p;
}

// The pattern's steer and throttle at `tin` into the piece, before the noise, with the recovery
// from a spin or slide taking over where the car left the regime of the data.
struct Command {
  double steer = 0, throttle = 0;
};

Command manoeuvre_command(const Piece& piece, double tin, const std::vector<double>& x, const ManoeuvreOptions& o) {
  const double vx = x[state::kVx], r = x[state::kYawRate];
  auto hold = [&](double target) {
    return o.ff_offset + o.ff_per_mps * target + o.speed_gain_per_mps * (target - vx);
  };
  double steer = 0, throttle = 0;
  switch (piece.manoeuvre) {
    case 1:  // low speed, normal driving
      throttle = hold(piece.target_mps + std::sin(kTwoPi * tin / 3.7));
      steer = piece.side * piece.amplitude * std::sin(kTwoPi * tin / piece.period_s);
      break;
    case 2:  // zig-zag
      throttle = hold(piece.target_mps);
      steer = piece.side * piece.amplitude * std::tanh(3 * std::sin(kTwoPi * tin / piece.period_s));
      break;
    case 3:  // accelerate hard, then brake to about 4 m/s, heading held by yaw-rate feedback
      if (tin < 0.4 * o.piece_duration_s && vx < piece.target_mps) throttle = o.max_throttle;
      else if (vx > 4.0) throttle = piece.brake;
      else throttle = hold(5.0);
      steer = -0.3 * r;
      break;
    case 4:  // sliding: approach, power slide at (near) full lock, countersteer, recover
      if (tin < 0.3 * o.piece_duration_s) {
        throttle = hold(piece.target_mps);
        steer = 0.1 * piece.side;
      } else if (tin < 0.55 * o.piece_duration_s) {
        throttle = o.max_throttle;
        steer = piece.side * piece.amplitude;
      } else if (tin < 0.7 * o.piece_duration_s) {
        throttle = 0.3;
        steer = -0.4 * piece.side;
      } else {
        throttle = hold(5.0);
        steer = -0.3 * r;
      }
      break;
    default:  // high speed, wide curves
      throttle = hold(piece.target_mps);
      steer = piece.side * piece.amplitude * std::sin(kTwoPi * tin / piece.period_s);
      break;
  }
  // Recovery, as a driver catches a spin: countersteer on the yaw rate and hold a moderate
  // speed while the car is outside the regime of the data (spinning, sliding far, too slow).
  if (std::abs(r) > o.recover_yaw_rate_radps || std::abs(x[state::kVy]) > o.recover_lateral_mps ||
      vx < o.recover_below_mps) {
    steer = std::clamp(-0.3 * r, -0.6, 0.6);
    throttle = hold(5.0);
  }
  return {steer, throttle};
}

// An empty recording of the rollout's columns: the required ones, roll, segment, then the extras.
sim::Recording rollout_recording(std::size_t state_size, const ManoeuvreOptions& o) {
  sim::Recording rec;
  rec.columns.assign(sim::kRecordingRequiredColumns.begin(), sim::kRecordingRequiredColumns.end());
  rec.columns.insert(rec.columns.end(), {"roll", "segment"});
  if (state_size < static_cast<std::size_t>(state::kCommonStates) + o.extra_state_columns.size())
    throw Error("manoeuvre rollout: more extra_state_columns than model states after the common 7");
  rec.columns.insert(rec.columns.end(), o.extra_state_columns.begin(), o.extra_state_columns.end());
  rec.data.resize(rec.columns.size());
  rec.metadata["source"] = "scripted manoeuvres (sysid/manoeuvre_rollout.cpp), seed " + std::to_string(o.seed);
  return rec;
}

}  // namespace

bool ManoeuvreOptions::is_valid(std::string* why) const {
  auto fail = [&](const char* m) {
    if (why) *why = m;
    return false;
  };
  if (!(duration_s > 0 && std::isfinite(duration_s))) return fail("duration_s must be > 0");
  if (!(piece_duration_s > 0 && std::isfinite(piece_duration_s))) return fail("piece_duration_s must be > 0");
  if (!(sample_dt_s > 0 && sample_dt_s < piece_duration_s)) return fail("sample_dt_s must be in (0, piece_duration_s)");
  if (!(min_throttle < max_throttle)) return fail("min_throttle must be < max_throttle");
  if (!(speed_gain_per_mps >= 0)) return fail("speed_gain_per_mps must be >= 0");
  if (!(initial_speed_mps >= 0)) return fail("initial_speed_mps must be >= 0");
  if (!(steer_dither_std >= 0 && steer_dither_std <= 1 && throttle_dither_std >= 0 && throttle_dither_std <= 1))
    return fail("steer_dither_std and throttle_dither_std must be in [0, 1]");
  return true;
}

sim::Recording roll_out_manoeuvres(const RolloutStep& step, std::vector<double> x, const ManoeuvreOptions& o) {
  std::string why;
  if (!o.is_valid(&why)) throw Error("manoeuvre rollout: " + why);
  if (x.size() < static_cast<std::size_t>(state::kCommonStates))
    throw Error("manoeuvre rollout: the state must hold at least the 7 common states");
  x[state::kVx] = o.initial_speed_mps;
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  // The dither has its own stream, so a recording with dither is the same drive plus the dither.
  // (A distribution of its own too: std::normal_distribution may cache a draw of its engine.)
  std::mt19937_64 dither_rng(o.seed ^ 0x9e3779b97f4a7c15ULL);
  std::normal_distribution<double> dither_gauss(0.0, 1.0);

  sim::Recording rec = rollout_recording(x.size(), o);

  const long samples = std::lround(o.duration_s / o.sample_dt_s);
  const long per_piece = std::max(1L, std::lround(o.piece_duration_s / o.sample_dt_s));
  Piece piece;
  double steer_noise = 0, throttle_noise = 0;  // first-order coloured noise (0.2 s)
  const double a = std::exp(-o.sample_dt_s / 0.2);
  const double b = std::sqrt(1 - a * a);
  for (long i = 0; i < samples; ++i) {
    if (i % per_piece == 0) piece = draw_piece(static_cast<int>((i / per_piece) % 5) + 1, rng);
    const double tin = static_cast<double>(i % per_piece) * o.sample_dt_s;  // time in the piece
    const auto [steer, throttle] = manoeuvre_command(piece, tin, x, o);
    steer_noise = a * steer_noise + b * 0.08 * gauss(rng);
    throttle_noise = a * throttle_noise + b * 0.05 * gauss(rng);
    const double steer_dither = o.steer_dither_std * dither_gauss(dither_rng);
    const double throttle_dither = o.throttle_dither_std * dither_gauss(dither_rng);
    const double u[2] = {std::clamp(steer + steer_noise + steer_dither, -0.99, 0.99),
                         std::clamp(throttle + throttle_noise + throttle_dither, o.min_throttle, o.max_throttle)};
    const double row[11] = {static_cast<double>(i) * o.sample_dt_s, x[state::kX], x[state::kY],
                            x[state::kYaw], x[state::kVx], x[state::kVy], x[state::kYawRate],
                            u[0], u[1], x[state::kRoll], static_cast<double>(piece.manoeuvre)};
    for (int c = 0; c < 11; ++c) rec.data[c].push_back(row[c]);
    for (std::size_t e = 0; e < o.extra_state_columns.size(); ++e)
      rec.data[11 + e].push_back(x[static_cast<std::size_t>(state::kCommonStates) + e]);
    step(x, u, o.sample_dt_s);
    for (double v : x)
      if (!std::isfinite(v))
        throw Error("manoeuvre rollout: the state became non-finite at t = " +
                    std::to_string(static_cast<double>(i + 1) * o.sample_dt_s) + " s");
  }
  return rec;
}

}  // namespace mppi::sysid
