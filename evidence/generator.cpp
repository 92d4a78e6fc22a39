#include "evidence/generator.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>

#include <nlohmann/json.hpp>

#include "base/error.hpp"
#include "evidence/actuators.hpp"
#include "evidence/car_physics.hpp"
#include "evidence/drivers.hpp"
#include "sim/crash_detector.hpp"
#include "sim/data_dir.hpp"
#include "sim/geometry.hpp"
#include "sim/recording.hpp"
#include "sim/surface_map.hpp"
#include "sim/track.hpp"

namespace mppi::evidence {
namespace {

std::string stem_of(const std::string& csv) {
  return csv.size() > 4 && csv.substr(csv.size() - 4) == ".csv" ? csv.substr(0, csv.size() - 4) : csv;
}

// The ground: grip discs on the track, a bump and a tilted plane, from the effects and the seed.
struct Ground {
  sim::SurfaceMap map;
  double grade_x = 0, grade_y = 0;
  std::vector<sim::SurfacePatch> patches;
  sim::SurfacePatch bump;  // radius 0: none
};

Ground make_ground(const TruthEffects& e, const sim::Track& ccw, std::uint64_t seed) {
  Ground g;
  std::mt19937_64 rng(seed * 7477 + 11);
  std::uniform_real_distribution<double> uni(0, 1);
  sim::SurfaceLayer grip, elevation;
  grip.default_value = 1;
  auto centreline_at = [&](double arc_m) {  // the centreline point at this arc length
    const auto& arc = ccw.centreline_arc_m();
    const auto it = std::upper_bound(arc.begin(), arc.end(), arc_m);
    const std::size_t k = static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, it - arc.begin() - 1)) % ccw.centreline().size();
    return ccw.centreline()[k];
  };
  for (int i = 0; i < e.grip_patches; ++i) {  // spread along the lap, jittered
    sim::SurfacePatch p;
    p.centre_m = centreline_at(ccw.length_m() * (i + 0.2 + 0.6 * uni(rng)) / e.grip_patches);
    p.radius_m = 2.5 + 1.5 * uni(rng);
    p.edge_m = 1.0;
    p.value = e.grip_patch_scale;
    grip.patches.push_back(p);
  }
  if (e.bump_height_m != 0) {  // on the centreline, somewhere along the lap
    sim::SurfacePatch hill;
    hill.centre_m = centreline_at(ccw.length_m() * uni(rng));
    hill.radius_m = e.bump_radius_m;
    hill.value = e.bump_height_m;
    elevation.patches.push_back(hill);
    g.bump = hill;
  }
  if (e.grade != 0) {
    const double heading = 2 * std::numbers::pi * uni(rng);
    g.grade_x = elevation.grade_x = e.grade * std::cos(heading);
    g.grade_y = elevation.grade_y = e.grade * std::sin(heading);
  }
  g.patches = grip.patches;
  g.map = sim::SurfaceMap(std::move(grip), std::move(elevation));
  return g;
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
  static const char* kTracks[] = {"gazebo", "marietta", "ccrf"};
  EvidenceResult res;
  res.track = o.track.empty() ? kTracks[o.seed % 3] : o.track;
  res.direction = o.direction.empty() ? ((o.seed / 3) % 2 ? "cw" : "ccw") : o.direction;
  res.driver = o.driver.empty() ? (o.seed % 2 ? "pursuit" : "human") : o.driver;
  if (res.direction != "ccw" && res.direction != "cw") throw Error("evidence: direction must be ccw or cw");
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

  auto at_rest_on_centreline = [&](double x, double y) {
    const sim::ClosestPoint c = sim::closest_point(track.centreline(), true, {x, y});
    const sim::Vec2 a = track.centreline()[c.segment];
    const sim::Vec2 b = track.centreline()[(c.segment + 1) % track.centreline().size()];
    CarState s{};
    s[kX] = c.point.x;
    s[kY] = c.point.y;
    s[kYaw] = std::atan2(b.y - a.y, b.x - a.x);
    return s;
  };
  const sim::Pose2 start = track.start_pose();
  CarState s{};
  s[kX] = start.x_m;
  s[kY] = start.y_m;
  s[kYaw] = start.yaw_rad;

  const int substeps = static_cast<int>(std::lround(o.log_dt_s / o.physics_dt_s));
  const int rows = static_cast<int>(std::lround(o.duration_s / o.log_dt_s));
  const double dt = o.log_dt_s / substeps;
  std::vector<Sample> history;  // every physics step, history[i] at time i dt
  history.reserve(static_cast<std::size_t>(rows) * substeps + 1);
  std::vector<std::pair<double, double>> commands(static_cast<std::size_t>(rows));
  int segment = 0;
  history.push_back({s, segment});
  for (int k = 0; k < rows; ++k) {
    const double t = k * o.log_dt_s;
    const auto cmd = driver.command({t, s[kX], s[kY], s[kYaw], std::hypot(s[kVx], s[kVy]), s[kR]});
    commands[static_cast<std::size_t>(k)] = cmd;
    chain.issue(t, cmd.first, cmd.second);
    for (int i = 0; i < substeps; ++i) {
      const double ti = t + i * dt;
      const double front_share = std::clamp(car.front_torque_share + o.truth.front_torque_share, 0.0, 1.0);
      const double motor_rim_mps = motor_wheel_speed(s, front_share) * car.wheel_radius_m;
      const auto [wheel_angle, torque] = chain.step(ti, dt, motor_rim_mps);
      CarInputs in;
      in.wheel_angle_rad = wheel_angle;
      in.motor_torque_Nm = torque;
      in.front_torque_share = front_share;
      in.grip_scale = ground.map.grip(s[kX], s[kY]);
      const sim::Vec2 slope = ground.map.slope(s[kX], s[kY]);
      ground_gravity_body(slope.x, slope.y, s[kYaw], car.gravity_mps2, &in.gravity_x_mps2, &in.gravity_y_mps2);
      in.extra_drag_kgpm = o.truth.extra_drag_kgpm;
      in.front_rolling_coefficient = o.truth.front_rolling_coefficient;
      in.rear_rolling_coefficient = o.truth.rear_rolling_coefficient;
      in.mass_scale = o.truth.payload_mass_scale;
      in.yaw_inertia_scale = o.truth.payload_yaw_inertia_scale;
      in.cg_rearward_m = o.truth.weight_shift * (car.lf_m + car.lr_m);
      s = rk4_step(car, s, in, dt);
      bool finite = true;
      for (double v : s) finite = finite && std::isfinite(v);
      if (!finite) throw Error("evidence: the car's state became non-finite at t = " + std::to_string(ti) + " s");
      if (crashes.check(s[kX], s[kY], s[kYaw]).crashed) {  // a marshal puts it back, at rest
        ++res.crashes;
        s = at_rest_on_centreline(s[kX], s[kY]);
        chain.reset();
        driver.respawned();
        ++segment;
      }
      history.push_back({s, segment});
    }
  }

  // Where the grip differs (each patch with its blended edge) and where the ground is not level.
  if (!ground.patches.empty()) {
    PlacePasses pp{"grip_patches", {}};
    for (const auto& p : ground.patches)
      pp.disc_passes_s.push_back(passes_over(history, substeps, rows, o.log_dt_s, p.centre_m, p.radius_m + p.edge_m));
    res.place_passes.push_back(pp);
  }
  if (ground.bump.radius_m > 0)
    res.place_passes.push_back(
        {"bump", {passes_over(history, substeps, rows, o.log_dt_s, ground.bump.centre_m, ground.bump.radius_m)}});

  // Rows: the command sent at t_k and the sensors' reading of the state at t_k - offset.
  std::mt19937_64 rng(o.seed * 9176 + 5);
  std::normal_distribution<double> n01(0, o.noise.scale);
  std::uniform_real_distribution<double> uni(0, 1);
  const auto& fx = o.truth;
  std::vector<std::pair<std::string, std::string>> meta = {
      {"source", "mppi-fit evidence (independent generator)"}, {"track", res.track},
      {"direction", res.direction}, {"driver", res.driver}, {"seed", std::to_string(o.seed)},
      {"command_timing", "row k: the command sent at t_k, held until the next row"}};
  if (fx.speed_loop_top_speed_mps > 0) meta.emplace_back("throttle_command", "speed");
  std::filesystem::path parent = std::filesystem::path(csv_path).parent_path();
  if (!parent.empty()) std::filesystem::create_directories(parent);
  res.csv = csv_path;
  res.clean_csv = clean_path_of(csv_path);
  res.truth_json = truth_path_of(csv_path);
  {
    sim::RecordingWriter noisy(res.csv, {}, meta);
    sim::RecordingWriter clean(res.clean_csv, {}, meta);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (int k = 0; k < rows; ++k) {
      const double t = k * o.log_dt_s;
      const double ts = t - fx.sensor_time_offset_s;
      const double pos = ts / dt;
      const std::size_t here = static_cast<std::size_t>(std::lround(t / dt));
      double st[8] = {};
      bool valid = pos >= 0 && pos <= static_cast<double>(history.size() - 1);
      if (valid) {
        const std::size_t i0 = std::min(static_cast<std::size_t>(pos), history.size() - 2);
        const double f = pos - static_cast<double>(i0);
        valid = history[i0].segment == history[here].segment && history[i0 + 1].segment == history[here].segment;
        for (int j = 0; j < 8; ++j) st[j] = (1 - f) * history[i0].s[j] + f * history[i0 + 1].s[j];
      }
      const bool dropped = uni(rng) < o.noise.drop_rate;
      const double glitch_draw = uni(rng), glitch_sign = uni(rng) < 0.5 ? -1 : 1;
      const double noise[5] = {n01(rng), n01(rng), n01(rng), n01(rng), n01(rng)};
      const double noise_r = n01(rng);
      if (dropped && k > 0) continue;
      const auto [steer, throttle] = commands[static_cast<std::size_t>(k)];
      double row[9] = {t, nan, nan, nan, nan, nan, nan, steer, throttle};
      if (valid) {
        row[1] = st[kX];
        row[2] = st[kY];
        row[3] = st[kYaw];
        row[4] = fx.speed_sensor_scale * st[kVx];
        row[5] = fx.speed_sensor_scale * st[kVy];
        row[6] = st[kR] + fx.gyro_bias_radps;
      }
      clean.write_row(row);
      if (valid) {
        row[1] += o.noise.position_m * noise[0];
        row[2] += o.noise.position_m * noise[1];
        row[3] += o.noise.yaw_rad * noise[2];
        row[4] += o.noise.vx_mps * noise[3];
        row[5] += o.noise.vy_mps * noise[4];
        row[6] += o.noise.yaw_rate_radps * noise_r;
        if (glitch_draw < o.noise.glitch_rate) {  // a one-row spike in one channel
          const int which = static_cast<int>(glitch_draw / o.noise.glitch_rate * 3);
          if (which == 0) row[4] += glitch_sign * 1.5;
          else if (which == 1) row[6] += glitch_sign * 0.6;
          else row[1] += glitch_sign * 0.5;
        }
      }
      noisy.write_row(row);
      ++res.rows;
    }
    noisy.close();
    clean.close();
  }

  using json = nlohmann::ordered_json;
  json j;
  j["generator"] = "mppi evidence generator (evidence/), independent of the diagnosis' candidates";
  j["recording"] = std::filesystem::path(res.csv).filename().string();
  j["clean_states"] = std::filesystem::path(res.clean_csv).filename().string();
  j["seed"] = o.seed;
  j["track"] = res.track;
  j["direction"] = res.direction;
  j["driver"] = res.driver;
  j["duration_s"] = o.duration_s;
  j["vehicle_params"] = res.vehicle_yaml;  // an effect-free recording has these constants: the nominal
  j["crashes"] = res.crashes;
  j["noise"] = {{"position_m", o.noise.position_m * o.noise.scale}, {"yaw_rad", o.noise.yaw_rad * o.noise.scale},
                {"vx_mps", o.noise.vx_mps * o.noise.scale}, {"vy_mps", o.noise.vy_mps * o.noise.scale},
                {"yaw_rate_radps", o.noise.yaw_rate_radps * o.noise.scale}, {"glitch_rate", o.noise.glitch_rate},
                {"drop_rate", o.noise.drop_rate}};
  json effects = json::array();
  for (const auto& name : o.truth_names) {
    const TruthEffectInfo& info = truth_effect_info(name);
    json e;
    e["name"] = info.name;
    e["form"] = info.form;
    json sizes;
    for (const auto& key : info.keys) sizes[key] = truth_effect_value(o.truth, key);
    if (info.name == "hill") {
      sizes["grade_x"] = ground.grade_x;
      sizes["grade_y"] = ground.grade_y;
    }
    if (info.name == "bump") sizes["centre_m"] = {ground.bump.centre_m.x, ground.bump.centre_m.y};
    if (info.name == "grip_patches") {
      json discs = json::array();
      for (const auto& p : ground.patches)
        discs.push_back({{"centre_m", {p.centre_m.x, p.centre_m.y}}, {"radius_m", p.radius_m}, {"edge_m", p.edge_m}});
      sizes["patches"] = discs;
    }
    for (const auto& pp : res.place_passes)  // when the car was on it: [enter, leave] of each pass [s]
      if (pp.effect == info.name) {
        auto passes_json = [](const std::vector<std::pair<double, double>>& passes) {
          json out = json::array();
          for (const auto& [enter, leave] : passes) out.push_back({enter, leave});
          return out;
        };
        if (info.name == "bump") sizes["passes_s"] = passes_json(pp.disc_passes_s[0]);
        else
          for (std::size_t i = 0; i < pp.disc_passes_s.size(); ++i)
            sizes["patches"][i]["passes_s"] = passes_json(pp.disc_passes_s[i]);
        e["crossed_once"] = pp.crossed_once();
      }
    e["sizes"] = sizes;
    e["table_ids"] = info.table_ids;
    e["in_library"] = !info.table_ids.empty();
    if (info.table_ids.empty())
      e["expected_answer"] = "out of library: a correct diagnosis names nothing reliable or says suspected";
    effects.push_back(e);
  }
  j["effects"] = effects;
  std::ofstream(res.truth_json) << j.dump(2) << "\n";
  return res;
}

}  // namespace mppi::evidence
