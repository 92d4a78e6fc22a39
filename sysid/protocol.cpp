#include "sysid/protocol.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <cstdio>
#include <fstream>
#include <map>
#include <numbers>
#include <random>
#include <utility>

#include "base/error.hpp"
#include "dynamics/full_vehicle.hpp"
#include "dynamics/model_registry.hpp"
#include "sim/plant.hpp"

namespace mppi::sysid {

namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

double clamp1(double v) { return std::clamp(v, -1.0, 1.0); }

// The scripted driver: speed by a feedforward + proportional throttle, steering by pattern
// (manoeuvres 1-5) or by a yaw-rate / heading controller (the validation lap).
class Driver {
 public:
  explicit Driver(const FullVehicleParams& p)
      : wheelbase_(p.base.wheelbase_m()), max_steer_(p.base.max_steer_rad) {}

  // Command for segment `seg` (1..6), `tin` seconds into it, at true state x.
  Control command(int seg, double tin, const float* x) {
    const double vx = x[state::kVx], r = x[state::kYawRate], yaw = x[state::kYaw];
    double steer = 0, throttle = 0;
    switch (seg) {
      case 1:  // low speed, normal driving, 4-6 m/s
        throttle = speed(5.0 + std::sin(kTwoPi * tin / 10), vx);
        steer = 0.35 * std::sin(kTwoPi * tin / 8) + 0.15 * std::sin(kTwoPi * tin / 3.1);
        break;
      case 2:  // zig-zag at 4-6 m/s
        throttle = speed(5.0 + 0.5 * std::sin(kTwoPi * tin / 7), vx);
        steer = 0.7 * std::tanh(3 * std::sin(kTwoPi * tin / 2));
        break;
      case 3: {  // full throttle in a straight line, full brake, then a slow turn; 10 s cycles
        const double c = std::fmod(tin, 10.0);
        if (c < 4.0) {
          throttle = 1.0;
          steer = -0.3 * r;
        } else if (c < 6.5) {
          throttle = vx > 1.0 ? -1.0 : 0.0;
          steer = -0.3 * r;
        } else {
          throttle = speed(3.0, vx);
          steer = 0.5;
        }
        break;
      }
      case 4: {  // sliding: approach, power slide at full lock, countersteer; 5 s, alternating
        const double c = std::fmod(tin, 5.0);
        const double side = static_cast<int>(tin / 5.0) % 2 ? -1.0 : 1.0;
        if (c < 1.5) {
          throttle = speed(7.0, vx);
          steer = 0.1 * side;
        } else if (c < 3.0) {
          throttle = 0.9;
          steer = side;
        } else if (c < 4.0) {
          throttle = 0.4;
          steer = -0.5 * side;
        } else {
          throttle = speed(6.0, vx);
          steer = -0.3 * r;
        }
        break;
      }
      case 5:  // high speed, up to 10 m/s, wide curves
        throttle = speed(9.5, vx);
        steer = 0.12 * std::sin(kTwoPi * tin / 6);
        break;
      default:  // validation lap: 11.5 m straights and 180-degree turns of radius 6 m
        lap(vx, r, yaw, &steer, &throttle);
        break;
    }
    return {static_cast<float>(clamp1(steer)), static_cast<float>(clamp1(throttle))};
  }

  void advance_distance(double metres) { distance_ += metres; }

 private:
  static double speed(double target_mps, double vx) {
    // Steady speed is about 20 m/s x (throttle - 0.04) for the AutoRally drivetrain defaults.
    return clamp1(target_mps / 20.0 + 0.04 + 0.4 * (target_mps - vx));
  }

  void lap(double vx, double r, double yaw, double* steer, double* throttle) {
    constexpr double kStraight = 11.5, kRadius = 6.0;
    if (!started_) {
      started_ = true;
      turning_ = false;
      heading_ = yaw;
      distance_ = 0;
    }
    if (!turning_ && distance_ >= kStraight) {
      turning_ = true;
      turn_start_yaw_ = heading_;
    } else if (turning_ && yaw - turn_start_yaw_ >= std::numbers::pi) {
      turning_ = false;
      heading_ = turn_start_yaw_ + std::numbers::pi;
      distance_ = 0;
    }
    if (turning_) {
      *throttle = speed(5.0, vx);
      const double ff = std::atan(wheelbase_ / kRadius) / max_steer_;
      *steer = ff + 0.5 * (vx / kRadius - r);
    } else {
      *throttle = speed(6.0, vx);
      *steer = 0.8 * (heading_ - yaw) - 0.2 * r;
    }
  }

  double wheelbase_, max_steer_;
  bool started_ = false, turning_ = false;
  double heading_ = 0, turn_start_yaw_ = 0, distance_ = 0;
};

const std::vector<std::string> kMeasuredExtras = {
    "roll", "pitch", "roll_rate", "pitch_rate", "vz", "ax", "ay", "wheel_speed",
    "omega_lf", "omega_rf", "omega_lr", "omega_rr", "segment"};
const std::vector<std::string> kTruthExtras = {
    "roll", "omega_lf", "omega_rf", "omega_lr", "omega_rr", "pitch", "heave", "roll_rate",
    "pitch_rate", "heave_rate", "ax", "ay", "segment"};

sim::Recording empty_recording(const std::vector<std::string>& extras,
                               const std::map<std::string, std::string>& metadata) {
  sim::Recording rec;
  rec.metadata = metadata;
  rec.columns.assign(sim::kRecordingRequiredColumns.begin(), sim::kRecordingRequiredColumns.end());
  rec.columns.insert(rec.columns.end(), extras.begin(), extras.end());
  rec.data.resize(rec.columns.size());
  return rec;
}

void append(sim::Recording& rec, const std::vector<double>& row) {
  for (std::size_t c = 0; c < row.size(); ++c) rec.data[c].push_back(row[c]);
}

void write_recording_file(const sim::Recording& rec, const std::string& path) {
  std::vector<std::pair<std::string, std::string>> meta(rec.metadata.begin(), rec.metadata.end());
  const std::vector<std::string> extras(rec.columns.begin() + sim::kRecordingRequiredColumns.size(),
                                        rec.columns.end());
  sim::RecordingWriter writer(path, extras, meta);
  std::vector<double> row(rec.columns.size());
  for (std::size_t i = 0; i < rec.rows(); ++i) {
    for (std::size_t c = 0; c < row.size(); ++c) row[c] = rec.data[c][i];
    writer.write_row(row);
  }
  writer.close();
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// The metadata every recording of the run carries: source, timing, segments, layout, noise.
std::map<std::string, std::string> protocol_metadata(const ProtocolOptions& o) {
  return {
      {"source", "mppi sysid protocol (simulated AutoRally full vehicle, sysid/protocol.cpp)"},
      {"model", mppi::models::FullVehicleModel::kName},
      {"truth_parameters", "truth.yaml"},
      {"seed", std::to_string(o.seed)},
      {"sample_rate_hz", num(o.sample_rate_hz)},
      {"plant_dt_s", num(o.plant_dt_s)},
      {"command_timing", "steer, throttle are held from this row's t to the next row's t"},
      {"segments", "1 low_speed, 2 zig_zag, 3 accelerate_brake, 4 sliding, 5 high_speed (" +
                       num(o.manoeuvre_duration_s) + " s each), 6 validation (" +
                       num(o.validation_duration_s) + " s)"},
      {"layout", o.layout == ProtocolLayout::sequential
                     ? std::string("sequential (each manoeuvre in turn)")
                     : "interleaved (cycles of five " + num(o.piece_duration_s) + " s pieces, one per manoeuvre)"},
      {"noise_std", "position " + num(o.position_noise_m) + " m, yaw " + num(o.yaw_noise_rad) +
                        " rad, velocity " + num(o.velocity_noise_mps) + " m/s, rates " +
                        num(o.rate_noise_radps) + " rad/s, roll/pitch " + num(o.angle_noise_rad) +
                        " rad, accel " + num(o.accel_noise_mps2) + " m/s^2, wheels " +
                        num(o.wheel_noise_radps) + " rad/s"}};
}

// A row of the measured recording: the true state `x` with noise drawn by `noisy` (in the order of
// the columns), the commands, the accelerations, the wheel speeds and the segment.
template <class Noisy>
std::vector<double> measured_row(double t, const double* x, const Control& u, double ax, double ay, int seg,
                                 double radius, const ProtocolOptions& o, Noisy& noisy) {
  const double w[4] = {noisy(x[7], o.wheel_noise_radps), noisy(x[8], o.wheel_noise_radps),
                       noisy(x[9], o.wheel_noise_radps), noisy(x[10], o.wheel_noise_radps)};
  return {
      t,
      noisy(x[state::kX], o.position_noise_m),
      noisy(x[state::kY], o.position_noise_m),
      noisy(x[state::kYaw], o.yaw_noise_rad),
      noisy(x[state::kVx], o.velocity_noise_mps),
      noisy(x[state::kVy], o.velocity_noise_mps),
      noisy(x[state::kYawRate], o.rate_noise_radps),
      u.steer,
      u.throttle,
      noisy(x[state::kRoll], o.angle_noise_rad),
      noisy(x[FullVehicle::kPitch], o.angle_noise_rad),
      noisy(x[FullVehicle::kRollRate], o.rate_noise_radps),
      noisy(x[FullVehicle::kPitchRate], o.rate_noise_radps),
      noisy(x[FullVehicle::kHeaveRate], o.velocity_noise_mps),
      noisy(ax, o.accel_noise_mps2),
      noisy(ay, o.accel_noise_mps2),
      radius * 0.25 * (w[0] + w[1] + w[2] + w[3]),
      w[0], w[1], w[2], w[3],
      static_cast<double>(seg)};
}

}  // namespace

bool ProtocolOptions::is_valid(std::string* why) const {
  auto fail = [&](const std::string& msg) {
    if (why) *why = msg;
    return false;
  };
  if (!(manoeuvre_duration_s > 0 && std::isfinite(manoeuvre_duration_s)))
    return fail("manoeuvre_duration_s must be > 0");
  if (!(piece_duration_s > 0 && std::isfinite(piece_duration_s)))
    return fail("piece_duration_s must be > 0");
  if (layout != ProtocolLayout::interleaved && layout != ProtocolLayout::sequential)
    return fail("layout must be interleaved or sequential");
  if (!(validation_duration_s >= 0 && std::isfinite(validation_duration_s)))
    return fail("validation_duration_s must be >= 0");
  if (!(sample_rate_hz > 0 && std::isfinite(sample_rate_hz))) return fail("sample_rate_hz must be > 0");
  if (!(plant_dt_s > 0 && plant_dt_s <= 1 / sample_rate_hz)) return fail("plant_dt_s must be in (0, 1 / sample_rate_hz]");
  const double ratio = 1 / (sample_rate_hz * plant_dt_s);
  if (std::abs(ratio - std::round(ratio)) > 1e-6) return fail("plant_dt_s must divide 1 / sample_rate_hz");
  for (double s : {position_noise_m, yaw_noise_rad, velocity_noise_mps, rate_noise_radps,
                   angle_noise_rad, accel_noise_mps2, wheel_noise_radps})
    if (!(s >= 0 && std::isfinite(s))) return fail("noise standard deviations must be >= 0");
  return true;
}

const std::vector<std::string>& protocol_segment_names() {
  static const std::vector<std::string> names = {"low_speed", "zig_zag", "accelerate_brake",
                                                 "sliding", "high_speed", "validation"};
  return names;
}

std::string protocol_layout_name(ProtocolLayout layout) {
  return layout == ProtocolLayout::sequential ? "sequential" : "interleaved";
}

ProtocolLayout parse_protocol_layout(const std::string& name) {
  if (name == "interleaved") return ProtocolLayout::interleaved;
  if (name == "sequential") return ProtocolLayout::sequential;
  throw Error("protocol layout '" + name + "': expected interleaved or sequential");
}

ProtocolSegmentTime protocol_segment_at(const ProtocolOptions& o, double t) {
  ProtocolSegmentTime st;
  if (o.layout == ProtocolLayout::sequential) {
    st.segment = std::clamp(static_cast<int>(std::floor(t / o.manoeuvre_duration_s)) + 1, 1, 5);
    st.manoeuvre_time_s = t - (st.segment - 1) * o.manoeuvre_duration_s;
    return st;
  }
  // Interleaved: cycle c, piece s in it; the manoeuvre has run c full pieces before.
  const double cycle_s = 5 * o.piece_duration_s;
  const double c = std::floor(t / cycle_s);
  const double in_cycle = t - c * cycle_s;
  st.segment = std::clamp(static_cast<int>(std::floor(in_cycle / o.piece_duration_s)) + 1, 1, 5);
  st.manoeuvre_time_s = c * o.piece_duration_s + in_cycle - (st.segment - 1) * o.piece_duration_s;
  return st;
}

ProtocolRun run_protocol(const FullVehicleParams& params, const ProtocolOptions& o) {
  std::string why;
  if (!o.is_valid(&why)) throw Error("protocol options: " + why);
  const FullVehicle model(params);  // validates the parameters
  const auto coeffs = full_vehicle_coeffs(params);
  sim::ActuatorLimits limits;
  limits.steer_rate_per_s = limits.throttle_rate_per_s = 1e9f;  // commands act at once
  sim::Plant<FullVehicle> plant(model, limits, static_cast<float>(o.plant_dt_s));
  VehicleState start;
  start.vx_mps = 4.0f;
  plant.reset(start);

  const double sample_dt = 1 / o.sample_rate_hz;
  const long n_train = std::lround(5 * o.manoeuvre_duration_s * o.sample_rate_hz);
  const long n_val = std::lround(o.validation_duration_s * o.sample_rate_hz);

  const std::map<std::string, std::string> meta = protocol_metadata(o);
  ProtocolRun run;
  run.training = empty_recording(kMeasuredExtras, meta);
  run.validation = empty_recording(kMeasuredExtras, meta);
  auto truth_meta = meta;
  truth_meta.erase("noise_std");
  truth_meta["noise_std"] = "none (true states)";
  run.truth = empty_recording(kTruthExtras, truth_meta);

  Driver driver(params);
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> N01(0.0, 1.0);
  auto noisy = [&](double v, double sigma) { return v + sigma * N01(rng); };
  const double radius = params.base.wheel_radius_m;

  for (long k = 0; k < n_train + n_val; ++k) {
    const double t = k * sample_dt;
    const ProtocolSegmentTime st = protocol_segment_at(o, t);
    const int seg = k < n_train ? st.segment : 6;
    const double tin = k < n_train ? st.manoeuvre_time_s : t - n_train * sample_dt;
    const float* xf = plant.state();
    double x[FullVehicle::kNx];
    std::copy(xf, xf + FullVehicle::kNx, x);
    for (double v : x)
      if (!std::isfinite(v)) throw Error("protocol: the plant state became non-finite at t = " + num(t));
    const Control u = driver.command(seg, tin, xf);
    const double ud[2] = {u.steer, u.throttle};
    const auto f = FullVehicle::forces(coeffs, x, ud);
    const double ax = f.ax_mps2, ay = f.ay_mps2;

    append(run.truth, {t, x[0], x[1], x[2], x[3], x[4], x[5], u.steer, u.throttle, x[6], x[7],
                       x[8], x[9], x[10], x[11], x[12], x[13], x[14], x[15], ax, ay,
                       static_cast<double>(seg)});
    const std::vector<double> row = measured_row(t, x, u, ax, ay, seg, radius, o, noisy);
    append(k < n_train ? run.training : run.validation, row);

    plant.advance(u, static_cast<float>(sample_dt));
    const float* xn = plant.state();
    driver.advance_distance(std::hypot(xn[state::kX] - x[state::kX], xn[state::kY] - x[state::kY]));
  }
  return run;
}

void write_protocol(const ProtocolRun& run, const FullVehicleParams& params, const std::string& dir) {
  std::filesystem::create_directories(dir);
  write_recording_file(run.training, dir + "/train.csv");
  write_recording_file(run.validation, dir + "/validation.csv");
  write_recording_file(run.truth, dir + "/truth.csv");
  std::ofstream yaml(dir + "/truth.yaml");
  if (!yaml) throw Error(dir + "/truth.yaml: cannot open for writing");
  yaml << "# The parameters of the simulated plant (mppi sysid protocol); load_full_vehicle_params.\n"
       << to_yaml(params);
  if (!yaml) throw Error(dir + "/truth.yaml: write failed");
}

}  // namespace mppi::sysid
