#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "costs/autorally_cost.hpp"
#include "mppi/concepts.hpp"
#include "mppi/cost_map.hpp"
#include "test_data.hpp"

namespace {

namespace st = mppi::state;
constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

// 4 x 4 px over [0, 4) x [0, 4) at 1 px/m: 0.1 everywhere except
//   (row 1, col 2) = 0.3 at (2.5, 1.5), (row 3, col 0) = 0.7 at (0.5, 3.5), (row 0, col 0) = 0.65 at (0.5, 0.5).
std::shared_ptr<const mppi::CostMap> small_map() {
  std::vector<float> v(16, 0.1f);
  v[1 * 4 + 2] = 0.3f;
  v[3 * 4 + 0] = 0.7f;
  v[0] = 0.65f;
  return std::make_shared<const mppi::CostMap>(0.f, 4.f, 0.f, 4.f, 1.f, v);
}

std::array<float, st::kCommonStates> state(float x, float y, float vx, float vy, float yaw_rate, float roll) {
  std::array<float, st::kCommonStates> s{};
  s[st::kX] = x;
  s[st::kY] = y;
  s[st::kYaw] = 0.3f;
  s[st::kVx] = vx;
  s[st::kVy] = vy;
  s[st::kYawRate] = yaw_rate;
  s[st::kRoll] = roll;
  return s;
}

struct NineStateModel {  // only for the concept check: 7 common states + 2 extra
  static constexpr int kNx = 9, kNu = 2;
  std::size_t scratch_floats(int) const { return 0; }
  template <int W> void step(mppi::Batch<kNx, W>, mppi::ConstBatch<kNu, W>, float, float*) const noexcept {}
};
static_assert(mppi::StageCost<mppi::AutoRallyCost, NineStateModel>);

}  // namespace

TEST_CASE("AutoRallyCost: each term against hand computation", "[costs]") {
  const mppi::AutoRallyCost cost(small_map());
  mppi::CostTerms c;
  // On 0.3 at t = 0: track 100 * 0.3 = 30; speed 4.25 * (5 - 6)^2 = 4.25; no crash;
  // slip 1.75 * 0.5^2 / 5^2 = 0.0175. Total 34.2675.
  auto s = state(2.5f, 1.5f, 5.f, 0.5f, 1.f, 0.1f);
  CHECK(cost.evaluate(s.data(), 0, &c) == Approx(34.2675f).epsilon(1e-6));
  CHECK(c.map_value == Approx(0.3f));
  CHECK(c.track == Approx(30.f));
  CHECK(c.speed == Approx(4.25f));
  CHECK(c.crash == 0.f);
  CHECK_FALSE(c.crashed);
  CHECK(c.slip == Approx(0.0175f));

  // Off track on 0.7 >= 0.65 at 6 m/s: track 70 + crash 10000 * 0.9^t.
  s = state(0.5f, 3.5f, 6.f, 0.f, 0.f, 0.f);
  CHECK(cost.evaluate(s.data(), 0, &c) == Approx(10070.f));
  CHECK(c.crashed);
  CHECK(c.crash == Approx(10000.f));
  CHECK(cost.evaluate(s.data(), 1, &c) == Approx(9070.f));
  CHECK(c.crash == Approx(9000.f));
  CHECK(cost.evaluate(s.data(), 10, &c) == Approx(70.f + 3486.784401f).epsilon(1e-6));  // 0.9^10 = 0.3486784401
  CHECK(c.crash == Approx(3486.784401f).epsilon(1e-6));

  // Exactly at the threshold counts as crashed (AutoRally's >=): 65 + 10000.
  s = state(0.5f, 0.5f, 6.f, 0.f, 0.f, 0.f);
  CHECK(cost.evaluate(s.data(), 0, &c) == Approx(10065.f));
  CHECK(c.crashed);
}

TEST_CASE("AutoRallyCost: roll and yaw-rate crash indicators", "[costs]") {
  const mppi::AutoRallyCost cost(small_map());
  mppi::CostTerms c;
  // On 0.1 at target speed, t = 2: track 10; a crash adds 10000 * 0.81 = 8100.
  for (float roll : {1.6f, -1.6f}) {
    const auto s = state(3.5f, 3.5f, 6.f, 0.f, 0.f, roll);
    CHECK(cost.evaluate(s.data(), 2, &c) == Approx(8110.f));
    CHECK(c.crashed);
  }
  auto s = state(3.5f, 3.5f, 6.f, 0.f, 0.f, 1.5f);
  CHECK(cost.evaluate(s.data(), 2, &c) == Approx(10.f));
  CHECK_FALSE(c.crashed);
  for (float r : {5.5f, -5.5f}) {
    s = state(3.5f, 3.5f, 6.f, 0.f, r, 0.f);
    CHECK(cost.evaluate(s.data(), 2, &c) == Approx(8110.f));
    CHECK(c.crashed);
  }
  s = state(3.5f, 3.5f, 6.f, 0.f, -4.9f, 0.f);
  CHECK(cost.evaluate(s.data(), 2) == Approx(10.f));
  // Several reasons at once still count once.
  s = state(0.5f, 3.5f, 6.f, 0.f, 9.f, 2.f);
  CHECK(cost.evaluate(s.data(), 0) == Approx(10070.f));
}

TEST_CASE("AutoRallyCost: slip term stays finite near standstill and in reverse", "[costs]") {
  const mppi::AutoRallyCost cost(small_map());
  mppi::CostTerms c;
  // v_x = 0, v_y = 0.5: 1.75 * 0.25 / max(0, 1^2) = 0.4375; speed 4.25 * 36 = 153; track 10.
  auto s = state(3.5f, 3.5f, 0.f, 0.5f, 0.f, 0.f);
  CHECK(cost.evaluate(s.data(), 0, &c) == Approx(163.4375f));
  CHECK(c.slip == Approx(0.4375f));
  s = state(3.5f, 3.5f, 0.5f, 0.5f, 0.f, 0.f);  // |v_x| < 1 m/s: still divided by 1
  cost.evaluate(s.data(), 0, &c);
  CHECK(c.slip == Approx(0.4375f));
  // Reverse, v_x = -3, v_y = 1: slip 1.75 / 9; speed 4.25 * 81 = 344.25.
  s = state(3.5f, 3.5f, -3.f, 1.f, 0.f, 0.f);
  CHECK(cost.evaluate(s.data(), 0, &c) == Approx(10.f + 344.25f + 1.75f / 9.f));
  CHECK(c.slip == Approx(0.1944444f));
}

TEST_CASE("AutoRallyCost: NaN or infinite states cost +inf, never crash the program", "[costs]") {
  const mppi::AutoRallyCost cost(small_map());
  for (int k : {st::kX, st::kY, st::kVx, st::kVy, st::kYawRate, st::kRoll}) {
    for (float bad : {kNan, kInf, -kInf}) {
      auto s = state(2.5f, 1.5f, 5.f, 0.5f, 1.f, 0.1f);
      s[k] = bad;
      INFO("state index " << k << " = " << bad);
      CHECK(cost.evaluate(s.data(), 3) == kInf);
    }
  }
  // Yaw is not used by the cost (single-point lookup): a NaN there changes nothing.
  auto s = state(2.5f, 1.5f, 5.f, 0.5f, 1.f, 0.1f);
  s[st::kYaw] = kNan;
  CHECK(cost.evaluate(s.data(), 0) == Approx(34.2675f));
}

TEST_CASE("AutoRallyCost: batch accumulate equals scalar evaluate lane by lane", "[costs]") {
  constexpr int W = 8, Nx = 9, Nu = 2;
  const mppi::AutoRallyCost cost(small_map());
  const std::array<std::array<float, st::kCommonStates>, W> states = {
      state(2.5f, 1.5f, 5.f, 0.5f, 1.f, 0.1f),    state(0.5f, 3.5f, 6.f, 0.f, 0.f, 0.f),
      state(3.5f, 3.5f, 6.f, 0.f, 0.f, 1.6f),     state(3.5f, 3.5f, 0.f, 0.5f, 0.f, 0.f),
      state(-9.f, 100.f, 7.f, -0.3f, 6.f, 0.f),   state(kNan, 1.f, 5.f, 0.f, 0.f, 0.f),
      state(1.2f, 2.7f, 8.5f, 1.5f, -2.f, -0.2f), state(3.9f, 0.2f, -1.f, 0.f, 0.f, 0.f)};
  std::array<float, Nx * W> x{};
  std::array<float, Nu * W> u{};
  for (int j = 0; j < W; ++j) {
    for (int i = 0; i < st::kCommonStates; ++i) x[i * W + j] = states[j][i];
    x[7 * W + j] = 1e3f;  // extra model states are ignored
    x[8 * W + j] = kNan;
  }
  std::array<float, W> total{};
  for (int j = 0; j < W; ++j) total[j] = 0.5f * j;
  for (int t = 0; t < 3; ++t) cost.accumulate<Nx, Nu, W>(x.data(), u.data(), t, total.data());
  for (int j = 0; j < W; ++j) {
    float expected = 0.5f * j;
    for (int t = 0; t < 3; ++t) expected += cost.evaluate(states[j].data(), t);
    INFO("lane " << j);
    if (std::isinf(expected)) {
      CHECK(total[j] == kInf);
    } else {
      CHECK(total[j] == Approx(expected).epsilon(1e-6));
    }
  }
  // Lane 0 by hand: 3 * 34.2675 (no crash) on top of 0.
  CHECK(total[0] == Approx(3 * 34.2675f).epsilon(1e-6));
  // Lane 1: 3 * 70 + 10000 * (1 + 0.9 + 0.81) + 0.5.
  CHECK(total[1] == Approx(0.5f + 210.f + 27100.f).epsilon(1e-6));
  CHECK(total[5] == kInf);
}

TEST_CASE("AutoRallyCost: on the gazebo map", "[costs]") {
  auto map = std::make_shared<const mppi::CostMap>(
      mppi::CostMap::load_npz(mppi::test::data_path("autorally/maps/gazebo/gazebo_costmap.npz")));
  const mppi::AutoRallyCost cost(map);
  // numpy: channel0[299, 147] = 0.39215687 (x -17.625, y -0.025); channel0[299, 178] = 0.78431374.
  auto s = state(-17.625f, -0.025f, 6.f, 0.f, 0.f, 0.f);
  CHECK(cost.evaluate(s.data(), 0) == Approx(39.215687f));
  s = state(-16.075f, -0.025f, 6.f, 0.f, 0.f, 0.f);
  CHECK(cost.evaluate(s.data(), 0) == Approx(78.431374f + 10000.f));
}

TEST_CASE("AutoRallyCostParams: defaults are the paper's and validation catches bad values", "[costs]") {
  const mppi::AutoRallyCostParams p;
  CHECK(p.track_weight == 100.f);
  CHECK(p.speed_weight == 4.25f);
  CHECK(p.crash_weight == 10000.f);
  CHECK(p.slip_weight == 1.75f);
  CHECK(p.crash_discount == 0.9f);
  CHECK(p.boundary_threshold == 0.65f);
  std::string why;
  CHECK(p.is_valid(&why));
  auto bad = p;
  bad.speed_weight = -1.f;
  CHECK_FALSE(bad.is_valid(&why));
  CHECK_THAT(why, Catch::Contains("speed_weight"));
  bad = p;
  bad.crash_discount = 1.5f;
  CHECK_FALSE(bad.is_valid(&why));
  CHECK_THAT(why, Catch::Contains("crash_discount"));
  bad = p;
  bad.slip_min_speed_mps = 0.f;
  CHECK_FALSE(bad.is_valid(&why));
  bad = p;
  bad.max_roll_rad = kNan;
  CHECK_FALSE(bad.is_valid());
  bad = p;
  bad.max_yaw_rate_radps = kInf;  // inf turns the check off
  CHECK(bad.is_valid());
  CHECK_THROWS_AS(mppi::AutoRallyCost(nullptr), mppi::Error);
  bad = p;
  bad.track_weight = kNan;
  CHECK_THROWS_AS(mppi::AutoRallyCost(small_map(), bad), mppi::Error);
}

TEST_CASE("the cost is the sum of its declared terms, each a closed form of its weight", "[cost]") {
  mppi::AutoRallyCostParams p;
  p.target_speed_mps = 7.f;
  const mppi::AutoRallyCost cost(small_map(), p);
  const auto s = state(2.5f, 1.5f, 5.f, 0.8f, 0.2f, 0.f);  // map value 0.3, no crash
  mppi::CostTerms c;
  const float total = cost.evaluate(s.data(), 3, &c);
  // Closed forms of the paper's four terms at this state.
  CHECK(c.track == Approx(100.0 * 0.3));
  CHECK(c.speed == Approx(4.25 * 4.0));
  CHECK(c.crash == 0.f);
  CHECK(c.slip == Approx(1.75 * 0.64 / 25.0));
  // One term per CostTerms field, names unique, and the total adds exactly these.
  std::vector<std::string> names;
  float sum = 0.f;
  mppi::for_each_type(mppi::AutoRallyCostTerms{}, [&]<class Term>() {
    names.emplace_back(Term::kName);
    sum += c.*(Term::kOut);
  });
  CHECK(names == std::vector<std::string>{"track", "speed", "crash", "slip"});
  CHECK(total == Approx(sum).epsilon(1e-6));
  // A term's weight is data: zero it and the total drops by exactly that term.
  mppi::AutoRallyCost no_speed = cost;
  std::string why;
  REQUIRE(no_speed.set_param("speed_weight", 0.0, &why));
  CHECK(no_speed.evaluate(s.data(), 3) == Approx(total - c.speed).epsilon(1e-6));
}
