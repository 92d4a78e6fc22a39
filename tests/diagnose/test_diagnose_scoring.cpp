// How the sweep judges a correction: multi-step predictions scored against the noise-free states
// of a synthetic recording, and the start-state observer. Oracles: sensor noise on the scored
// sample is independent of the prediction, so RMSE^2 against the recording = RMSE^2 against the
// clean states + sigma^2 (closed form); a raw (unfiltered) start state carries the full sensor
// noise into the prediction, the observer a fraction of it.
#include <catch2/catch.hpp>

#include <cmath>

#include "base/error.hpp"
#include "diagnose/replay.hpp"
#include "diagnose/sweep.hpp"
#include "diagnose/synth.hpp"

using namespace mppi;
using namespace mppi::diagnose;

namespace {

struct NoisyAndClean {
  PreparedRecording noisy, clean;
  SensorNoise noise;
};

// The same open-loop drive twice: the noise draws are taken either way, so the commands and
// states are identical and only the logged noise differs.
NoisyAndClean drive(const EffectParams& truth, std::uint64_t seed) {
  NoisyAndClean out;
  SensorNoise none = out.noise;
  none.scale = 0.0;
  out.noisy = prepare(synthesize_open_loop(truth, seed, 30.0, out.noise), "noisy");
  out.clean = prepare(synthesize_open_loop(truth, seed, 30.0, none), "clean");
  return out;
}

}  // namespace

TEST_CASE("scoring against noise-free states removes exactly the sensor noise of the scored sample",
          "[diagnose][scoring]") {
  EffectParams truth;
  truth.steer_delay_s = 0.08;
  const NoisyAndClean d = drive(truth, 31);
  REQUIRE(d.noisy.rows() == d.clean.rows());
  REQUIRE(d.noisy.vx[100] != d.clean.vx[100]);
  REQUIRE(d.noisy.steer[100] == d.clean.steer[100]);
  const std::vector<char> all;
  const auto truth_ptr = make_model_family("single-track")->make(truth);
  const ReplayModel& truth_model = *truth_ptr;
  const ReplayOptions o;
  const auto measured = horizon_metrics(truth_model, d.noisy, all, {0.5, 1.0}, 3, o);
  const auto clean = horizon_metrics(truth_model, d.noisy, all, {0.5, 1.0}, 3, o, &d.clean);
  const double sigma[kChannels] = {d.noise.vx_mps, d.noise.vy_mps, d.noise.yaw_rate_radps};
  for (std::size_t h = 0; h < measured.size(); ++h)
    for (int c = 0; c < kChannels; ++c) {
      INFO("horizon " << measured[h].horizon_s << " s, channel " << kChannelNames[c] << ": measured "
                      << measured[h].rmse[c] << ", clean " << clean[h].rmse[c]);
      const double predicted = std::sqrt(clean[h].rmse[c] * clean[h].rmse[c] + sigma[c] * sigma[c]);
      CHECK(measured[h].rmse[c] == Approx(predicted).epsilon(0.12));
      CHECK(clean[h].rmse[c] < 0.7 * measured[h].rmse[c]);  // the truth model is near the floor
    }
  // The nominal model misses the delay: scored either way, its error is above the truth model's.
  const auto nominal_clean = horizon_metrics(*make_model_family("single-track")->make({}), d.noisy, all, {1.0}, 3, o, &d.clean);
  CHECK(nominal_clean[0].normalized_rmse > 2 * clean[1].normalized_rmse);
}

TEST_CASE("a reference with other rows is refused", "[diagnose][scoring]") {
  const NoisyAndClean d = drive(EffectParams{}, 32);
  const PreparedRecording shorter = prepare(synthesize_open_loop(EffectParams{}, 32, 20.0), "shorter");
  CHECK_THROWS_AS(horizon_metrics(*make_model_family("single-track")->make({}), d.noisy, {}, {1.0}, 3, {}, &shorter),
                  Error);
}

TEST_CASE("the start-state observer takes most of the sensor noise off the start state", "[diagnose][scoring]") {
  const NoisyAndClean d = drive(EffectParams{}, 33);
  const auto truth_ptr = make_model_family("single-track")->make({});
  const ReplayModel& truth_model = *truth_ptr;
  ReplayOptions raw;
  raw.observer_gain = 1.0;  // start from the measured state as it is
  const ReplayOptions observed;
  const auto e_raw = horizon_metrics(truth_model, d.noisy, {}, {0.2}, 3, raw, &d.clean)[0];
  const auto e_obs = horizon_metrics(truth_model, d.noisy, {}, {0.2}, 3, observed, &d.clean)[0];
  INFO("0.2-s vx error from a raw start " << e_raw.rmse[0] << ", observed start " << e_obs.rmse[0]);
  // From a raw start, the velocity error 0.2 s later is about the sensor noise (v_x barely
  // changes in 0.2 s without a command change); the observer must at least halve it.
  CHECK(e_raw.rmse[0] > 0.6 * d.noise.vx_mps);
  CHECK(e_obs.rmse[0] < 0.5 * e_raw.rmse[0]);
  CHECK(e_obs.rmse[1] < 0.7 * e_raw.rmse[1]);
}

TEST_CASE("sweep summary counts right, wrong and halved errors per run", "[diagnose][scoring]") {
  auto run = [](const std::string& truth, const std::vector<std::string>& named, double before, double after,
                double truth_clean) {
    SweepRun r;
    r.truth = truth;
    r.size = truth == "none" ? "clean" : "small";
    if (truth != "none") r.truth_ids = {truth};
    r.named = named;
    for (const auto& n : named) (n == truth ? r.right : r.wrong) = true;
    r.before = {before + 0.1, before};
    r.after = {after + 0.1, after};
    r.truth_model = {truth_clean + 0.1, truth_clean};
    return r;
  };
  const SweepRun a = run("steer_delay", {"steer_delay"}, 1.0, 0.2, 0.1);     // 80 % reduction
  const SweepRun b = run("aero_drag", {"rolling_resistance"}, 1.0, 0.6, 0.1);  // wrong, 40 %
  const SweepRun c = run("none", {}, 0.1, 0.1, 0.1);
  CHECK(a.reduction_clean() == Approx(0.8));
  CHECK(a.removable_removed() == Approx(0.8 / 0.9));
  CHECK(b.reduction_measured() == Approx(1 - 0.7 / 1.1));
  const std::string md = sweep_summary_markdown({a, b, c});
  INFO(md);
  CHECK(md.find("right effect named: 1/2 (50 %)") != std::string::npos);
  CHECK(md.find("a wrong effect named: 1/2 (50 %)") != std::string::npos);
  CHECK(md.find("noise-free states: 1/2 (50 %)") != std::string::npos);
  CHECK(md.find("something named in 0/1") != std::string::npos);
}
