#include "evidence/generator.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <random>

#include "base/error.hpp"
#include "evidence/actuators.hpp"
#include "evidence/car_physics.hpp"
#include "evidence/drivers.hpp"
#include "evidence/ground.hpp"
#include "evidence/truth_file.hpp"
#include "sim/crash_detector.hpp"
#include "sim/data_dir.hpp"
#include "sim/geometry.hpp"
#include "sim/recording.hpp"
#include "sim/track.hpp"

namespace mppi::evidence {
namespace {

std::string stem_of(const std::string& csv) {
  return csv.size() > 4 && csv.substr(csv.size() - 4) == ".csv" ? csv.substr(0, csv.size() - 4) : csv;
}

struct Sample {
  CarState s;
  int segment;  // increments at each respawn
};

// The passes of the car over a disc: runs of log rows inside it, runs less than kPassGap_s apart
// merged into one pass.
std::vector<std::pair<double, double>> passes_over(const std::vector<Sample>& history, int substeps, int rows,
                                                   double log_dt_s, sim::Vec2 centre, double radius_m) {
  std::vector<std::pair<double, double>> passes;
  for (int k = 0; k < rows; ++k) {
    const CarState& s = history[static_cast<std::size_t>(k) * substeps].s;
    if (!(std::hypot(s[kX] - centre.x, s[kY] - centre.y) < radius_m)) continue;
    const double t = k * log_dt_s;
    if (!passes.empty() && t - passes.back().second <= kPassGap_s) passes.back().second = t;
    else passes.push_back({t, t});
  }
  return passes;
}

// The track, the direction and the driver: as the options name them, else chosen by the seed.
void choose_track_direction_driver(const EvidenceOptions& o, EvidenceResult* res) {
  static const char* kTracks[] = {"gazebo", "marietta", "ccrf"};
  res->track = o.track.empty() ? kTracks[o.seed % 3] : o.track;
  res->direction = o.direction.empty() ? ((o.seed / 3) % 2 ? "cw" : "ccw") : o.direction;
  res->driver = o.driver.empty() ? (o.seed % 2 ? "pursuit" : "human") : o.driver;
  if (res->direction != "ccw" && res->direction != "cw") throw Error("evidence: direction must be ccw or cw");
}

// The car at rest on the centreline point nearest (x, y), heading along the track.
CarState at_rest_on_centreline(const sim::Track& track, double x, double y) {
  const sim::ClosestPoint c = sim::closest_point(track.centreline(), true, {x, y});
  const sim::Vec2 a = track.centreline()[c.segment];
  const sim::Vec2 b = track.centreline()[(c.segment + 1) % track.centreline().size()];
  CarState s{};
  s[kX] = c.point.x;
  s[kY] = c.point.y;
  s[kYaw] = std::atan2(b.y - a.y, b.x - a.x);
  return s;
}

// The car at rest at the track's start pose.
CarState at_start(const sim::Track& track) {
  const sim::Pose2 start = track.start_pose();
  CarState s{};
  s[kX] = start.x_m;
  s[kY] = start.y_m;
  s[kYaw] = start.yaw_rad;
  return s;
}

// The inputs of one physics step: the actuators' wheel angle and torque, the ground under the car
// and the hidden effects on the car itself.
CarInputs car_inputs_at(const CarState& s, double wheel_angle_rad, double motor_torque_Nm, double front_share,
                        const Ground& ground, const TruthEffects& truth, const CarConstants& car) {
  CarInputs in;
  in.wheel_angle_rad = wheel_angle_rad;
  in.motor_torque_Nm = motor_torque_Nm;
  in.front_torque_share = front_share;
  in.grip_scale = ground.map.grip(s[kX], s[kY]);
  const sim::Vec2 slope = ground.map.slope(s[kX], s[kY]);
  ground_gravity_body(slope.x, slope.y, s[kYaw], car.gravity_mps2, &in.gravity_x_mps2, &in.gravity_y_mps2);
  in.extra_drag_kgpm = truth.extra_drag_kgpm;
  in.downforce_kgpm = truth.downforce_kgpm;
  in.front_rolling_coefficient = truth.front_rolling_coefficient;
  in.rear_rolling_coefficient = truth.rear_rolling_coefficient;
  in.mass_scale = truth.payload_mass_scale;
  in.yaw_inertia_scale = truth.payload_yaw_inertia_scale;
  in.cg_rearward_m = truth.weight_shift * (car.lf_m + car.lr_m);
  return in;
}

// The drive: the car's state at every physics step and the command of every log row.
struct Drive {
  int substeps = 0, rows = 0;
  double dt = 0;                                    // the physics step [s]
  std::vector<Sample> history;                      // every physics step, history[i] at time i dt
  std::vector<std::pair<double, double>> commands;  // per log row: steer, throttle
};

// What the drive needs besides the options: the track, its ground, the car, its driver and actuators.
struct DriveSetup {
  const sim::Track& track;
  const Ground& ground;
  const sim::CrashDetector& crashes;
  const CarConstants& car;
  Driver& driver;
  ActuatorChain& chain;
};

// Drives the car for the options' duration: the driver commands at each log row, the physics
// steps between rows; a crash puts the car back at rest on the centreline (counted in *crashes).
Drive drive_car(const EvidenceOptions& o, const DriveSetup& setup, int* crashes) {
  const CarConstants& car = setup.car;
  CarState s = at_start(setup.track);
  Drive drive;
  drive.substeps = static_cast<int>(std::lround(o.log_dt_s / o.physics_dt_s));
  drive.rows = static_cast<int>(std::lround(o.duration_s / o.log_dt_s));
  drive.dt = o.log_dt_s / drive.substeps;
  const double dt = drive.dt;
  std::vector<Sample>& history = drive.history;
  history.reserve(static_cast<std::size_t>(drive.rows) * drive.substeps + 1);
  drive.commands.resize(static_cast<std::size_t>(drive.rows));
  int segment = 0;
  history.push_back({s, segment});
  for (int k = 0; k < drive.rows; ++k) {
    const double t = k * o.log_dt_s;
    const auto cmd = setup.driver.command({t, s[kX], s[kY], s[kYaw], std::hypot(s[kVx], s[kVy]), s[kR]});
    drive.commands[static_cast<std::size_t>(k)] = cmd;
    setup.chain.issue(t, cmd.first, cmd.second);
    for (int i = 0; i < drive.substeps; ++i) {
      const double ti = t + i * dt;
      const double front_share = std::clamp(car.front_torque_share + o.truth.front_torque_share, 0.0, 1.0);
      const double motor_rim_mps = motor_wheel_speed(s, front_share) * car.wheel_radius_m;
      const auto [wheel_angle, torque] = setup.chain.step(ti, dt, motor_rim_mps);
      const CarInputs in = car_inputs_at(s, wheel_angle, torque, front_share, setup.ground, o.truth, car);
      s = rk4_step(car, s, in, dt);
      bool finite = true;
      for (double v : s) finite = finite && std::isfinite(v);
      if (!finite) throw Error("evidence: the car's state became non-finite at t = " + std::to_string(ti) + " s");
      if (setup.crashes.check(s[kX], s[kY], s[kYaw]).crashed) {  // a marshal puts it back, at rest
        ++*crashes;
        s = at_rest_on_centreline(setup.track, s[kX], s[kY]);
        setup.chain.reset();
        setup.driver.respawned();
        ++segment;
      }
      history.push_back({s, segment});
    }
  }
  return drive;
}

// Where the grip differs (each patch with its blended edge) and where the ground is not level.
std::vector<PlacePasses> place_passes_of(const Ground& ground, const Drive& drive, double log_dt_s) {
  std::vector<PlacePasses> place_passes;
  if (!ground.patches.empty()) {
    PlacePasses pp{"grip_patches", {}};
    for (const auto& p : ground.patches)
      pp.disc_passes_s.push_back(
          passes_over(drive.history, drive.substeps, drive.rows, log_dt_s, p.centre_m, p.radius_m + p.edge_m));
    place_passes.push_back(pp);
  }
  if (ground.bump.radius_m > 0)
    place_passes.push_back({"bump",
                            {passes_over(drive.history, drive.substeps, drive.rows, log_dt_s, ground.bump.centre_m,
                                         ground.bump.radius_m)}});
  return place_passes;
}

// The sensors' reading of the state at time ts, interpolated between physics steps; not valid
// before the start, after the end, or across a respawn from the state at time t of the row.
struct SensorReading {
  bool valid = false;
  double st[8] = {};
};

SensorReading sensor_reading(const Drive& drive, double t, double ts) {
  const std::vector<Sample>& history = drive.history;
  const double pos = ts / drive.dt;
  const std::size_t here = static_cast<std::size_t>(std::lround(t / drive.dt));
  SensorReading r;
  r.valid = pos >= 0 && pos <= static_cast<double>(history.size() - 1);
  if (r.valid) {
    const std::size_t i0 = std::min(static_cast<std::size_t>(pos), history.size() - 2);
    const double f = pos - static_cast<double>(i0);
    r.valid = history[i0].segment == history[here].segment && history[i0 + 1].segment == history[here].segment;
    for (int j = 0; j < 8; ++j) r.st[j] = (1 - f) * history[i0].s[j] + f * history[i0 + 1].s[j];
  }
  return r;
}

// The random draws of one row, drawn for every row (dropped or not) in this order, so that each
// row's noise does not depend on the rows before it being kept.
struct RowNoise {
  bool dropped = false;
  double glitch_draw = 0, glitch_sign = 0;
  double noise[5] = {};
  double noise_r = 0;
};

RowNoise draw_row_noise(std::mt19937_64& rng, std::normal_distribution<double>& n01,
                        std::uniform_real_distribution<double>& uni, const EvidenceNoise& noise) {
  RowNoise d;
  d.dropped = uni(rng) < noise.drop_rate;
  d.glitch_draw = uni(rng);
  d.glitch_sign = uni(rng) < 0.5 ? -1 : 1;
  for (double& v : d.noise) v = n01(rng);
  d.noise_r = n01(rng);
  return d;
}

// The sensors' noise and, at the glitch rate, a one-row spike in one channel, added to a row.
void add_sensor_noise(const RowNoise& d, const EvidenceNoise& noise, double row[9]) {
  row[1] += noise.position_m * d.noise[0];
  row[2] += noise.position_m * d.noise[1];
  row[3] += noise.yaw_rad * d.noise[2];
  row[4] += noise.vx_mps * d.noise[3];
  row[5] += noise.vy_mps * d.noise[4];
  row[6] += noise.yaw_rate_radps * d.noise_r;
  if (d.glitch_draw < noise.glitch_rate) {  // a one-row spike in one channel
    const int which = static_cast<int>(d.glitch_draw / noise.glitch_rate * 3);
    if (which == 0) row[4] += d.glitch_sign * 1.5;
    else if (which == 1) row[6] += d.glitch_sign * 0.6;
    else row[1] += d.glitch_sign * 0.5;
  }
}

std::vector<std::pair<std::string, std::string>> recording_metadata(const EvidenceOptions& o,
                                                                    const EvidenceResult& res) {
  std::vector<std::pair<std::string, std::string>> meta = {
      {"source", "mppi-fit evidence (independent generator)"}, {"track", res.track},
      {"direction", res.direction}, {"driver", res.driver}, {"seed", std::to_string(o.seed)},
      {"command_timing", "row k: the command sent at t_k, held until the next row"}};
  if (o.truth.speed_loop_top_speed_mps > 0) meta.emplace_back("throttle_command", "speed");
  return meta;
}

// Rows: the command sent at t_k and the sensors' reading of the state at t_k - offset; the noisy
// recording to res->csv, the same rows without noise to res->clean_csv. Counts res->rows.
void write_recordings(const EvidenceOptions& o, const Drive& drive, EvidenceResult* res) {
  std::mt19937_64 rng(o.seed * 9176 + 5);
  std::normal_distribution<double> n01(0, o.noise.scale);
  std::uniform_real_distribution<double> uni(0, 1);
  const auto& fx = o.truth;
  const auto meta = recording_metadata(o, *res);
  sim::RecordingWriter noisy(res->csv, {}, meta);
  sim::RecordingWriter clean(res->clean_csv, {}, meta);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int k = 0; k < drive.rows; ++k) {
    const double t = k * o.log_dt_s;
    const SensorReading reading = sensor_reading(drive, t, t - fx.sensor_time_offset_s);
    const RowNoise draws = draw_row_noise(rng, n01, uni, o.noise);
    if (draws.dropped && k > 0) continue;
    const auto [steer, throttle] = drive.commands[static_cast<std::size_t>(k)];
    double row[9] = {t, nan, nan, nan, nan, nan, nan, steer, throttle};
    if (reading.valid) {
      const double* st = reading.st;
      row[1] = st[kX];
      row[2] = st[kY];
      row[3] = st[kYaw];
      row[4] = fx.speed_sensor_scale * st[kVx];
      row[5] = fx.speed_sensor_scale * st[kVy];
      row[6] = st[kR] + fx.gyro_bias_radps;
    }
    clean.write_row(row);
    if (reading.valid) add_sensor_noise(draws, o.noise, row);
    noisy.write_row(row);
    ++res->rows;
  }
  noisy.close();
  clean.close();
}

}  // namespace

std::string clean_path_of(const std::string& csv_path) { return stem_of(csv_path) + ".clean.csv"; }
std::string truth_path_of(const std::string& csv_path) { return stem_of(csv_path) + ".truth.json"; }

double log_interval_s(double rate_hz, double physics_dt_s) {
  auto shortest = [](double v) {  // 33 and 0.002, not 33.000000 and 0.002000
    char b[32];
    std::snprintf(b, sizeof b, "%g", v);
    return std::string(b);
  };
  if (!(rate_hz >= 5 && rate_hz <= 500)) throw Error("evidence: the log rate must be in [5, 500] Hz, got " + shortest(rate_hz));
  const double steps = 1.0 / (rate_hz * physics_dt_s);
  if (std::abs(steps - std::round(steps)) > 1e-9 * steps)
    throw Error("evidence: the log rate " + shortest(rate_hz) + " Hz is not a whole number of " +
                shortest(physics_dt_s) + " s physics steps (e.g. 10, 20, 25, 50, 100, 200 Hz)");
  return std::round(steps) * physics_dt_s;
}

EvidenceResult generate_evidence(const EvidenceOptions& o, const std::string& csv_path) {
  if (!(o.duration_s > 1 && o.physics_dt_s > 0 && o.log_dt_s >= o.physics_dt_s))
    throw Error("evidence: need duration > 1 s and 0 < physics step <= log step");
  EvidenceResult res;
  choose_track_direction_driver(o, &res);
  sim::TrackOptions to;
  to.direction = res.direction == "cw" ? sim::Direction::kClockwise : sim::Direction::kCounterClockwise;
  const sim::Track track = sim::Track::load(res.track, to);
  const sim::Track ccw = sim::Track::load(res.track);
  const Ground ground = make_ground(o.truth, ccw, o.seed);
  const sim::CrashDetector crashes(track);
  res.vehicle_yaml = o.vehicle_yaml.empty() ? sim::data_file("config/autorally_single_track.yaml") : o.vehicle_yaml;
  const CarConstants car = read_car_constants(res.vehicle_yaml);
  Driver driver(res.driver, track, o.seed, o.speed_min_mps, o.speed_max_mps, car.lf_m + car.lr_m, car.max_steer_rad,
                o.log_dt_s);
  ActuatorChain chain(o.truth, car);

  const Drive drive = drive_car(o, {track, ground, crashes, car, driver, chain}, &res.crashes);
  res.place_passes = place_passes_of(ground, drive, o.log_dt_s);

  std::filesystem::path parent = std::filesystem::path(csv_path).parent_path();
  if (!parent.empty()) std::filesystem::create_directories(parent);
  res.csv = csv_path;
  res.clean_csv = clean_path_of(csv_path);
  res.truth_json = truth_path_of(csv_path);
  write_recordings(o, drive, &res);
  write_truth_json(o, ground, res);
  return res;
}

}  // namespace mppi::evidence
