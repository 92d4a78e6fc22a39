// mppi-fit diagnose: pure command delays are replayed exactly (oracle: the command columns
// shifted by hand), and a candidate that the later validation block cannot judge is judged on the
// earlier fold (oracle: a recording written here, whose truth is a FIFO delay of the throttle).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <deque>
#include <random>

#include "diagnose/diagnose.hpp"
#include "diagnose/replay.hpp"
#include "diagnose/synth.hpp"
#include "dynamics/single_track.hpp"
#include "sysid/real_data.hpp"

using namespace mppi;
using namespace mppi::diagnose;

namespace {

// Predictions of `model` on `d` along segments of 25 rows.
std::vector<double> predictions(const ReplayModel& model, const PreparedRecording& d, std::size_t first_start) {
  std::vector<double> all;
  std::vector<double> out(25 * kPredStride);
  for (std::size_t start = first_start; start + 30 < d.rows(); start += 37) {
    predict_segment(model, d, {start, 25}, ReplayOptions{}, out.data());
    all.insert(all.end(), out.begin(), out.end());
  }
  return all;
}

}  // namespace

TEST_CASE("a pure command delay is replayed as the recorded commands shifted in time", "[diagnose]") {
  const PreparedRecording d = prepare(synthesize_open_loop({}, 12, 20.0), "drive");
  const auto family = make_model_family("single-track");
  const auto plain = family->make({});
  // Shifted by hand: 3 rows (0.06 s) of steering; 2.5 rows (0.05 s) of throttle, which is the
  // average of the commands held 2 and 3 rows before.
  PreparedRecording shifted = d;
  for (std::size_t k = 0; k < d.rows(); ++k) {
    shifted.steer[k] = d.steer[k >= 3 ? k - 3 : 0];
    shifted.throttle[k] = 0.5 * (d.throttle[k >= 2 ? k - 2 : 0] + d.throttle[k >= 3 ? k - 3 : 0]);
  }
  EffectParams delays;
  delays.steer_delay_s = 3 * d.dt_s;
  delays.throttle_delay_s = 2.5 * d.dt_s;
  const auto delayed = family->make(delays);
  CHECK(delayed->command_delay.steer_s == Approx(0.06));
  const std::vector<double> a = predictions(*delayed, d, 60), b = predictions(*plain, shifted, 60);
  REQUIRE(a.size() == b.size());
  double worst = 0, spread = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    worst = std::max(worst, std::abs(a[i] - b[i]));
    spread = std::max(spread, std::abs(a[i]));
  }
  INFO("largest difference " << worst << " of values up to " << spread);
  CHECK(worst < 1e-4 * spread);
  // And the delay matters: the undelayed replay of the same recording differs.
  const std::vector<double> c = predictions(*plain, d, 60);
  double moved = 0;
  for (std::size_t i = 0; i < a.size(); ++i) moved = std::max(moved, std::abs(a[i] - c[i]));
  CHECK(moved > 100 * worst);
}

TEST_CASE("a delayed command is read inside its piece: before the piece it is not known", "[diagnose]") {
  // The same drive twice: once with its first 40 rows' steering missing (a command not yet
  // recorded: those rows are in no piece), once cut to start where the piece does. A 0.2-s delay
  // near the piece's start reaches back before it; in both the piece's first command stands for
  // the unknown ones, so the predictions agree (and stay finite).
  const sim::Recording rec = synthesize_open_loop({}, 12, 20.0);
  sim::Recording missing = rec;
  const auto steer_col = static_cast<std::size_t>(std::find(rec.columns.begin(), rec.columns.end(), "steer") -
                                                  rec.columns.begin());
  for (std::size_t k = 0; k < 40; ++k) missing.data[steer_col][k] = std::nan("");
  const PreparedRecording with_gap = prepare(missing, "missing");
  // The piece starts after the missing rows and the screening's guard row.
  const auto first = static_cast<std::size_t>(
      std::find_if(with_gap.piece.begin(), with_gap.piece.end(), [](int p) { return p >= 0; }) - with_gap.piece.begin());
  REQUIRE(first >= 40);
  REQUIRE(first < 45);
  const PreparedRecording cut = prepare(sysid::slice_recording(rec, first, rec.rows()), "cut");
  EffectParams e;
  e.steer_delay_s = 0.2;
  const auto delayed = make_model_family("single-track")->make(e);
  std::vector<double> a(25 * kPredStride), b(25 * kPredStride);
  predict_segment(*delayed, with_gap, {first + 5, 25}, ReplayOptions{}, a.data());
  predict_segment(*delayed, cut, {5, 25}, ReplayOptions{}, b.data());
  for (std::size_t i = 0; i < a.size(); ++i) {
    REQUIRE(std::isfinite(a[i]));
    CHECK(a[i] == Approx(b[i]).margin(1e-9));
  }
}

namespace {

// The library's default single-track car, stepped here at 2 ms behind a FIFO that delays the
// throttle by 0.15 s. Random steering and throttle steps, except that from 17 s to 28.5 s the
// throttle is held: the later validation block (about 19-28 s of the 28 s of training) cannot
// show the delay, the earlier part and the held-out part (28-40 s) can.
sim::Recording throttle_delay_with_a_held_stretch(std::uint64_t seed) {
  const SingleTrack car;
  float x[SingleTrack::kNx];
  VehicleState s0;
  s0.vx_mps = 4.f;
  car.init_state(s0, x);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.01);
  sim::Recording rec;
  rec.columns = {sim::kRecordingRequiredColumns.begin(), sim::kRecordingRequiredColumns.end()};
  rec.data.assign(rec.columns.size(), {});
  std::deque<float> throttle_fifo(75, 0.f);  // 0.15 s of 2-ms steps
  float steer = 0.f, throttle = 0.3f;
  double steer_hold = 0, throttle_hold = 0;
  for (int k = 0; k < 2000; ++k) {
    const double t = 0.02 * k;
    if ((steer_hold -= 0.02) <= 0) {
      steer_hold = 0.2 + 0.4 * uni(rng);
      steer = static_cast<float>(0.5 * (2 * uni(rng) - 1));
    }
    const bool held = t >= 17.0 && t < 28.5;
    if ((throttle_hold -= 0.02) <= 0 && !held) {
      throttle_hold = 0.2 + 0.4 * uni(rng);
      const double v = x[state::kVx];
      throttle = static_cast<float>(std::clamp((v < 3 ? 0.6 : v > 7 ? -0.1 : 0.3) + 0.5 * (2 * uni(rng) - 1), -0.6, 0.9));
    }
    if (held) throttle = 0.3f;
    const double row[] = {t, x[state::kX], x[state::kY], x[state::kYaw], x[state::kVx] + noise(rng),
                          x[state::kVy] + noise(rng), x[state::kYawRate] + noise(rng), steer, throttle};
    for (std::size_t c = 0; c < rec.columns.size(); ++c) rec.data[c].push_back(row[c]);
    for (int j = 0; j < 10; ++j) {
      throttle_fifo.push_back(throttle);
      const float u[2] = {steer, throttle_fifo.front()};
      throttle_fifo.pop_front();
      car.step<1>(Batch<SingleTrack::kNx, 1>{x}, ConstBatch<2, 1>{u}, 0.002f, nullptr);
    }
  }
  return rec;
}

}  // namespace

// The candidates: the throttle's forms of dynamics and the other longitudinal terms, and the
// steering's delay and lag; two stability resamples (they judge on the earlier fold too).
TEST_CASE("an effect the later validation block cannot show is judged on the earlier fold", "[diagnose]") {
  const PreparedRecording d = prepare(throttle_delay_with_a_held_stretch(5), "held throttle");
  const auto family = make_model_family("single-track");
  DiagnoseOptions o;
  o.plots = false;
  o.selection.candidates = {"throttle_delay", "throttle_lag",      "throttle_rate_limit", "throttle_gain",
                            "throttle_offset", "motor_voltage_sag", "motor_speed",         "aero_drag",
                            "rolling_resistance", "steer_delay",    "steer_lag"};
  o.selection.stability_resamples = 2;
  const DiagnoseResult r = run_diagnosis(d, *family, o);
  std::string log;
  for (const auto& line : r.selection.log) log += line + "\n";
  INFO(log);
  REQUIRE(r.selection.selected.size() == 1);
  CHECK(r.selection.selected[0] == "throttle_delay");
  CHECK_THAT(log, Catch::Contains("later block inconclusive"));
  bool found = false;
  for (const auto& p : r.selection.final_params)
    if (p.name == "throttle_delay_s") {
      found = true;
      CHECK(p.value == Approx(0.15).margin(0.02));
    }
  CHECK(found);
  // Without the earlier fold, the later block alone leaves the delay unnamed.
  DiagnoseOptions later_only = o;
  later_only.selection.inconclusive_share = 0.0;
  const DiagnoseResult r2 = run_diagnosis(d, *family, later_only);
  CHECK(std::find(r2.selection.selected.begin(), r2.selection.selected.end(), "throttle_delay") ==
        r2.selection.selected.end());
}
