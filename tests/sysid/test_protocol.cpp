// The simulated estimation protocol: the recorded commands replayed through the double-
// precision model reproduce the recorded true states (the contract estimators rely on), the
// measurement noise has the configured statistics, each manoeuvre does what the paper
// describes, and the files round-trip through the recording reader and the YAML loader.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <set>
#include <filesystem>
#include <string>

#include "dynamics/full_vehicle.hpp"
#include "sim/recording.hpp"
#include "sysid/protocol.hpp"

using namespace mppi;

namespace {

struct Stats {
  double mean = 0, sd = 0;
};
Stats residual_stats(const sim::Recording& measured, const sim::Recording& truth, const std::string& col,
                     std::size_t offset) {
  const auto& m = measured.column(col);
  const auto& t = truth.column(col);
  double s = 0, s2 = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    const double d = m[i] - t[i + offset];
    s += d;
    s2 += d * d;
  }
  const double n = static_cast<double>(m.size());
  return {s / n, std::sqrt(s2 / n - (s / n) * (s / n))};
}

}  // namespace

TEST_CASE("Protocol: replaying the commands through the model reproduces the truth",
          "[sysid][protocol]") {
  const FullVehicleParams params;
  const sysid::ProtocolOptions options;
  const sysid::ProtocolRun run = sysid::run_protocol(params, options);
  REQUIRE(run.training.rows() == 5000);
  REQUIRE(run.validation.rows() == 650);
  REQUIRE(run.truth.rows() == 5650);
  CHECK(run.validation.column("t").front() == Approx(100.0));
  const auto k = full_vehicle_coeffs(params);
  const char* names[FullVehicle::kNx] = {"x", "y", "yaw", "vx", "vy", "yaw_rate", "roll", "omega_lf",
                                         "omega_rf", "omega_lr", "omega_rr", "pitch", "heave",
                                         "roll_rate", "pitch_rate", "heave_rate"};
  // From rows in every segment, 0.5 s (25 samples x 10 plant steps) of open-loop replay.
  const int substeps = static_cast<int>(std::lround(1 / (options.sample_rate_hz * options.plant_dt_s)));
  double worst_v = 0;
  for (std::size_t start : {10u, 1210u, 2410u, 3610u, 4810u, 5300u}) {
    double x[FullVehicle::kNx];
    for (int i = 0; i < FullVehicle::kNx; ++i) x[i] = run.truth.column(names[i])[start];
    for (std::size_t row = start; row < start + 25; ++row) {
      const double u[2] = {run.truth.column("steer")[row], run.truth.column("throttle")[row]};
      for (int s = 0; s < substeps; ++s) FullVehicle::step_double(k, x, u, options.plant_dt_s);
      for (int i : {state::kVx, state::kVy, state::kYawRate})
        worst_v = std::max(worst_v, std::abs(x[i] - run.truth.column(names[i])[row + 1]));
    }
  }
  CHECK(worst_v < 0.02);  // float plant vs double replay
}

TEST_CASE("Protocol: sensor noise has the configured statistics, commands are exact",
          "[sysid][protocol]") {
  const sysid::ProtocolOptions o;
  const sysid::ProtocolRun run = sysid::run_protocol(FullVehicleParams{}, o);
  const std::pair<const char*, double> channels[] = {
      {"x", o.position_noise_m},  {"yaw", o.yaw_noise_rad},  {"vx", o.velocity_noise_mps},
      {"vy", o.velocity_noise_mps}, {"yaw_rate", o.rate_noise_radps}, {"roll", o.angle_noise_rad},
      {"pitch", o.angle_noise_rad}, {"ax", o.accel_noise_mps2}, {"omega_rr", o.wheel_noise_radps}};
  for (const auto& [col, sigma] : channels) {
    const Stats s = residual_stats(run.training, run.truth, col, 0);
    INFO(col);
    CHECK(s.sd == Approx(sigma).epsilon(0.05));
    CHECK(std::abs(s.mean) < 4 * sigma / std::sqrt(5000.0));
  }
  const Stats steer = residual_stats(run.validation, run.truth, "steer", 5000);
  CHECK(steer.sd == 0.0);
  CHECK(steer.mean == 0.0);
}

TEST_CASE("Protocol layouts: 20 s of each manoeuvre, interleaved has all five in every 20 s",
          "[sysid][protocol]") {
  // Oracle: count 50 Hz samples per manoeuvre over the 100 s, and which manoeuvres occur in
  // each 20 s window; the pattern clock must advance with the manoeuvre's own samples.
  for (const auto layout : {sysid::ProtocolLayout::interleaved, sysid::ProtocolLayout::sequential}) {
    sysid::ProtocolOptions o;
    o.layout = layout;
    INFO(sysid::protocol_layout_name(layout));
    int count[6] = {0, 0, 0, 0, 0, 0};
    std::array<std::set<int>, 5> window_segments;
    double clock[6] = {0, 0, 0, 0, 0, 0};
    double worst_clock = 0;
    for (int k = 0; k < 5000; ++k) {
      const double t = k / 50.0;
      const auto st = sysid::protocol_segment_at(o, t);
      REQUIRE(st.segment >= 1);
      REQUIRE(st.segment <= 5);
      worst_clock = std::max(worst_clock, std::abs(st.manoeuvre_time_s - clock[st.segment]));
      clock[st.segment] += 1 / 50.0;
      ++count[st.segment];
      window_segments[static_cast<std::size_t>(k / 1000)].insert(st.segment);
    }
    for (int s = 1; s <= 5; ++s) CHECK(count[s] == 1000);
    CHECK(worst_clock < 1e-9);
    for (const auto& w : window_segments)
      CHECK(w.size() == (layout == sysid::ProtocolLayout::interleaved ? 5u : 1u));
  }
  CHECK(sysid::parse_protocol_layout("sequential") == sysid::ProtocolLayout::sequential);
  CHECK_THROWS_WITH(sysid::parse_protocol_layout("mixed"), Catch::Contains("mixed"));
}

TEST_CASE("Protocol: the five manoeuvres and the validation lap", "[sysid][protocol]") {
  for (const auto layout : {sysid::ProtocolLayout::interleaved, sysid::ProtocolLayout::sequential}) {
    INFO(sysid::protocol_layout_name(layout));
    sysid::ProtocolOptions o;
    o.layout = layout;
    const sysid::ProtocolRun run = sysid::run_protocol(FullVehicleParams{}, o);
    const auto& seg = run.truth.column("segment");
    const auto& vx = run.truth.column("vx");
    const auto& vy = run.truth.column("vy");
    const auto& yaw = run.truth.column("yaw");
    // Statistics of a segment, leaving out the first 1.5 s after each change of manoeuvre (the
    // car brakes or speeds up from the previous piece's speed).
    auto range = [&](int s, const std::vector<double>& v, bool abs_value) {
      double lo = 1e9, hi = -1e9, sum = 0;
      int n = 0;
      std::size_t since_change = 0;
      for (std::size_t i = 0; i < seg.size(); ++i) {
        since_change = (i > 0 && seg[i] != seg[i - 1]) ? 0 : since_change + 1;
        if (seg[i] == s && since_change >= 75) {
          const double a = abs_value ? std::abs(v[i]) : v[i];
          lo = std::min(lo, a), hi = std::max(hi, a), sum += a, ++n;
        }
      }
      return std::array<double, 3>{lo, hi, sum / n};
    };
    CHECK(range(1, vx, false)[2] > 4.0);  // low speed: 4-6 m/s
    CHECK(range(1, vx, false)[1] < 6.5);
    CHECK(range(2, vx, false)[2] > 4.0);  // zig-zag at low speed, with yaw swings
    CHECK(range(2, vx, false)[1] < 6.5);
    CHECK(range(3, vx, false)[1] > 9.0);  // full acceleration ...
    CHECK(range(3, vx, false)[0] < 1.5);  // ... and braking
    CHECK(range(4, vy, true)[1] > 2.0);   // sliding: large side slip
    CHECK(range(5, vx, false)[1] > 9.0);  // high speed up to ~10 m/s
    CHECK(range(5, vx, false)[1] < 11.0);
    // Validation: one lap (yaw turns by 2 pi) at lap speeds.
    double y0 = 0, y1 = 0;
    bool first = true;
    for (std::size_t i = 0; i < seg.size(); ++i)
      if (seg[i] == 6) {
        if (first) y0 = yaw[i], first = false;
        y1 = yaw[i];
      }
    CHECK(std::abs(y1 - y0) == Approx(2 * M_PI).margin(0.6));
  }
}

TEST_CASE("Protocol files: recordings and truth.yaml round-trip", "[sysid][protocol]") {
  sysid::ProtocolOptions o;
  o.manoeuvre_duration_s = 1.0;
  o.validation_duration_s = 0.5;
  FullVehicleParams p;
  p.front_damper_Nspm = 90.0;
  const sysid::ProtocolRun run = sysid::run_protocol(p, o);
  const std::string dir = (std::filesystem::temp_directory_path() / "mppi_test_protocol").string();
  sysid::write_protocol(run, p, dir);
  const sim::Recording train = sim::RecordingReader::read(dir + "/train.csv");
  CHECK(train.rows() == 250);
  CHECK(train.column("vx")[17] == Approx(run.training.column("vx")[17]).epsilon(1e-12));
  CHECK(train.metadata.at("model") == "full-vehicle");
  CHECK(sim::RecordingReader::read(dir + "/validation.csv").rows() == 25);
  CHECK(load_full_vehicle_params(dir + "/truth.yaml").front_damper_Nspm == 90.0);
  std::filesystem::remove_all(dir);
  sysid::ProtocolOptions bad;
  bad.plant_dt_s = 0.003;
  CHECK_THROWS_WITH(sysid::run_protocol(p, bad), Catch::Contains("plant_dt_s"));
}
