// The operator page's parts against naive references: the rollout pick, the copy of the plan and
// the sampled sequences out of a running controller, the path prediction (one sequence at a time
// through the model's width-1 step), the mailbox and frame rate of LiveObserver, the frame JSON,
// and the server's answers to good and bad requests.
#include <catch2/catch.hpp>
#include <cmath>
#include <nlohmann/json.hpp>
#include <set>
#include <thread>
#include <vector>

#include "dynamics/kinematic_bicycle.hpp"
#include "mppi/controller.hpp"
#include "mppi/controller_options.hpp"
#include "ocs/frame_json.hpp"
#include "ocs/live_frame.hpp"
#include "ocs/live_observer.hpp"
#include "ocs/server.hpp"
#include "sim/path_predictor.hpp"

// last: <httplib.h> pulls in <resolv.h>, whose `_res` macro breaks Eigen headers included after it
#include <httplib.h>

namespace {

// q = (v - 4)^2 + 0.1 y^2: drive along x at 4 m/s.
struct SpeedCost {
  template <int Nx, int Nu, int W>
  void accumulate(mppi::ConstBatch<Nx, W> x, mppi::ConstBatch<Nu, W>, int, float* cost) const noexcept {
    for (int j = 0; j < W; ++j) {
      const float dv = x[mppi::state::kVx][j] - 4.f, y = x[mppi::state::kY][j];
      cost[j] += dv * dv + 0.1f * y * y;
    }
  }
};

mppi::ControllerOptions options(int samples) {
  mppi::ControllerOptions o;
  o.num_samples = samples;
  o.horizon = 30;
  o.dt_s = 0.05f;
  o.lambda = 5.f;
  o.noise_std = {0.3f, 0.4f};
  o.control_min = {-1.f, -1.f};
  o.control_max = {1.f, 1.f};
  o.safe_control = {0.f, 0.f};
  o.num_threads = 1;
  return o;
}

}  // namespace

TEST_CASE("pick_rollouts takes the best sample and spreads the rest", "[ocs]") {
  std::vector<float> w(1000, 0.001f);
  w[777] = 0.5f;
  std::vector<int> idx(63);
  REQUIRE(mppi::ocs::pick_rollouts(w, idx) == 63);
  const std::set<int> distinct(idx.begin(), idx.end());
  CHECK(distinct.size() == 63);
  CHECK(distinct.count(777) == 1);
  for (int i : idx) CHECK((i >= 0 && i < 1000));
  // fewer samples than wanted: all of them
  std::vector<float> few(10, 0.1f);
  CHECK(mppi::ocs::pick_rollouts(few, idx) == 10);
  CHECK(mppi::ocs::pick_rollouts(std::span<const float>(), idx) == 0);
}

TEST_CASE("capture_paths copies the plan and the picked rollouts out of a running controller", "[ocs]") {
  auto controller = mppi::make_cpu_controller(mppi::KinematicBicycle{}, SpeedCost{}, options(300));
  float x[7] = {0, 0, 0, 2.f, 0, 0, 0};
  const auto u = controller.step(x);
  const std::vector<float> output(u.begin(), u.end());
  mppi::ocs::LiveFrame frame;
  frame.reserve(7, 2, 30);
  const float* capacity_before = frame.controls.data();
  mppi::ocs::capture_paths(controller, output, frame);
  CHECK(frame.controls.data() == capacity_before);  // no reallocation once reserved
  REQUIRE(frame.paths == 64);
  // naive reference: the same picks, read straight from the controller's buffers
  std::vector<int> idx(63);
  mppi::ocs::pick_rollouts(controller.weights(), idx);
  const auto sampled = controller.sampled_controls();
  const int padded = static_cast<int>(sampled.size() / (30 * 2));
  for (int t = 0; t < 30; ++t)
    for (int c = 0; c < 2; ++c) {
      const float plan = t == 0 ? output[c] : controller.nominal()[(t - 1) * 2 + c];
      REQUIRE(frame.controls[(t * 2 + c) * 64] == plan);
      for (int j = 0; j < 63; ++j) REQUIRE(frame.controls[(t * 2 + c) * 64 + 1 + j] == sampled[(t * 2 + c) * padded + idx[j]]);
    }
  for (int j = 0; j < 63; ++j) CHECK(frame.weights[1 + j] == controller.weights()[idx[j]]);
  CHECK(std::isnan(frame.weights[0]));
}

TEST_CASE("the path predictor matches the model stepped one sequence at a time", "[ocs]") {
  const mppi::KinematicBicycle model;
  const auto predict = mppi::sim::make_path_predictor(model, 0.05f);
  const int count = 5, horizon = 20;
  std::vector<float> controls(horizon * 2 * count);
  for (int t = 0; t < horizon; ++t)
    for (int j = 0; j < count; ++j) {
      controls[(t * 2 + 0) * count + j] = 0.2f * (j - 2) + 0.01f * t;
      controls[(t * 2 + 1) * count + j] = 0.5f - 0.1f * j;
    }
  const std::vector<float> x0 = {1.f, -2.f, 0.3f, 3.f, 0.f, 0.f, 0.f};
  std::vector<float> xy(count * (horizon + 1) * 2, -99.f);
  predict(x0, controls, count, xy);
  for (int j = 0; j < count; ++j) {
    float x[7];
    std::copy(x0.begin(), x0.end(), x);
    CHECK(xy[(j * (horizon + 1)) * 2] == x0[0]);
    for (int t = 0; t < horizon; ++t) {
      const float uu[2] = {controls[(t * 2) * count + j], controls[(t * 2 + 1) * count + j]};
      model.step<1>(mppi::Batch<7, 1>{x}, mppi::ConstBatch<2, 1>{uu}, 0.05f, nullptr);
      const float* p = xy.data() + (j * (horizon + 1) + t + 1) * 2;
      REQUIRE(p[0] == Approx(x[0]).margin(1e-4));
      REQUIRE(p[1] == Approx(x[1]).margin(1e-4));
    }
  }
  // the sequences turn differently, so the test can tell them apart
  CHECK(xy[(0 * (horizon + 1) + horizon) * 2 + 1] != Approx(xy[(4 * (horizon + 1) + horizon) * 2 + 1]).margin(0.1));
}

TEST_CASE("LiveObserver captures only with a page, at the frame rate, and hands requests over once", "[ocs]") {
  auto controller = mppi::make_cpu_controller(mppi::KinematicBicycle{}, SpeedCost{}, options(128));
  mppi::ocs::LiveSettings settings;
  settings.frame_rate_hz = 2.0;  // 0.5 s between frames
  settings.realtime = false;
  mppi::ocs::LiveObserver live(settings);
  float x[7] = {0, 0, 0, 2.f, 0, 0, 0};
  mppi::StepSummary summary;
  auto step = [&](double t) {
    const auto u = controller.step(x, &summary);
    mppi::sim::StepView v;
    v.t_s = t;
    v.model_state = x;
    v.output = {u[0], u[1]};
    v.summary = &summary;
    v.controller = &controller;
    live.after_step(v);
  };
  mppi::ocs::LiveFrame got;
  std::uint64_t seen = 0;
  step(0.0);
  CHECK_FALSE(live.take_frame(&got, &seen));  // nobody connected: nothing captured
  live.add_client();
  step(0.05);
  REQUIRE(live.take_frame(&got, &seen));
  CHECK(got.t_s == 0.05);
  CHECK(got.paths == 64);
  step(0.10);  // within 0.5 s of the last frame: skipped
  CHECK_FALSE(live.take_frame(&got, &seen));
  std::this_thread::sleep_for(std::chrono::milliseconds(550));
  step(0.15);
  REQUIRE(live.take_frame(&got, &seen));
  CHECK(got.t_s == 0.15);
  const mppi::ocs::TimingSplit timing = live.timing();
  CHECK(timing.without_page_ms.size() == 1);
  CHECK(timing.with_page_ms.size() == 3);

  live.request_target_speed(7.5);
  live.request_motion_enabled(false);
  auto r = live.poll_requests(0.2);
  CHECK(r.target_speed_mps == 7.5);
  CHECK(r.motion_enabled == false);
  r = live.poll_requests(0.25);
  CHECK_FALSE(r.target_speed_mps.has_value());
  CHECK_FALSE(r.motion_enabled.has_value());
  CHECK_FALSE(r.stop);
  live.request_stop();
  CHECK(live.poll_requests(0.3).stop);

  // the frame as JSON: every value as captured, the commander names from the priorities
  got.chassis.present = true;
  got.chassis.steering_commander = 0;
  got.chassis.throttle_commander = -2;
  const auto j = nlohmann::json::parse(mppi::ocs::frame_json(got, {}, {{"mppi", 0}}, true));
  CHECK(j["t"] == Approx(0.15));
  CHECK(j["chassis"]["steering"] == "mppi");
  CHECK(j["chassis"]["throttle"] == "runstop");
  CHECK(j["chassis"]["front_brake"] == "watchdog");
  CHECK(j["paused"] == true);
  CHECK(j["rollouts"].empty());  // no predictor given
}

TEST_CASE("the server answers good and bad requests and a replay has no controls", "[ocs]") {
  mppi::ocs::LiveObserver live;
  mppi::ocs::ServerSettings s;
  s.port = 0;
  s.access.token = "secret";  // given, not drawn: the page's controls send it back
  mppi::ocs::OcsServer server(s, &live, "", "");
  server.start();
  CHECK(server.page_url() == "http://127.0.0.1:" + std::to_string(server.port()) + "/?token=secret");
  httplib::Client client("127.0.0.1", server.port());
  client.set_default_headers({{"X-MPPI-Token", "secret"}});
  auto info = client.Get("/api/info");
  REQUIRE(info);
  CHECK(info->status == 200);
  CHECK(nlohmann::json::parse(info->body)["mode"] == "live");
  CHECK(client.Get("/api/track")->status == 404);
  CHECK(client.Get("/")->status == 200);
  CHECK(client.Get("/uPlot.iife.min.js")->body.size() > 10000);
  auto bad = client.Post("/api/control", "target_speed=-1", "application/x-www-form-urlencoded");
  CHECK(bad->status == 400);
  CHECK(bad->body.find("target_speed") != std::string::npos);
  auto good = client.Post("/api/control", "target_speed=7&runstop=1", "application/x-www-form-urlencoded");
  CHECK(good->status == 200);
  const auto r = live.poll_requests(0.0);
  CHECK(r.target_speed_mps == 7.0);
  CHECK(r.motion_enabled == false);
  // a request with one bad parameter changes nothing
  CHECK(client.Post("/api/control", "pause=1&runstop=maybe", "application/x-www-form-urlencoded")->status == 400);
  CHECK_FALSE(live.paused());
  server.stop();

  mppi::ocs::OcsServer replay(s, nullptr, "", "{\"rows\": 0}");
  replay.start();
  httplib::Client rc("127.0.0.1", replay.port());
  rc.set_default_headers({{"X-MPPI-Token", "secret"}});
  CHECK(rc.Get("/api/recording")->body == "{\"rows\": 0}");
  CHECK(rc.Post("/api/control", "pause=1", "application/x-www-form-urlencoded")->status == 404);
  CHECK(rc.Get("/api/stream")->status == 404);
}
