#pragma once
// The AutoRally running cost (Goldfain et al., "AutoRally", IEEE CSM 2019, MPPI sidebar):
//   q(x, t) = w . ( C_M(p_x, p_y), (v_x - v_x^d)^2, 0.9^t I, (v_y / v_x)^2 ),  w = (100, 4.25, 10000, 1.75)
// a sum of terms declared in costs/autorally_cost_terms.hpp, weights as parameters.
// C_M is the cost map at the body position; I is 1 when the car counts as crashed (cost-map
// value at/above the boundary threshold, roll too large, or yaw rate too large), else 0.
// Stateless per step: unlike upstream costs.cu the crash flag does not latch over a rollout.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <vector>
#include <utility>

#include "costs/autorally_cost_terms.hpp"
#include "mppi/cost_map.hpp"
#include "base/batch.hpp"
#include "base/param_table.hpp"
#include "base/error.hpp"
#include "mppi/vehicle_state.hpp"

namespace mppi {

struct AutoRallyCostParams {
  float track_weight = 100.f;    // w1: per unit of cost-map value C_M (0 centreline, ~1 track edge)
  float speed_weight = 4.25f;    // w2: per (m/s)^2 of (v_x - target_speed_mps)^2
  float crash_weight = 10000.f;  // w3: cost of the crash indicator at t = 0
  float slip_weight = 1.75f;     // w4: per unit of (v_y / v_x)^2 (tan^2 of the slip angle)
  float target_speed_mps = 6.f;  // v_x^d, the desired forward speed
  float crash_discount = 0.9f;   // the crash term is crash_weight * crash_discount^t, t = step index
  float boundary_threshold = 0.65f;  // cost-map value at/above which the car has left the track (AutoRally default)
  // |roll| above which the car counts as rolled over. AutoRally's costs.cu uses 1.57 (pi/2):
  // it only kills rollouts whose model state has diverged; real driving stays below ~0.2 rad.
  float max_roll_rad = 1.57f;
  // |yaw rate| above which the car counts as spinning out. At the 10 m/s top speed of the
  // training data a 4.5 m-radius GT-ARF turn needs 2.2 rad/s; 5 rad/s only flags spins.
  float max_yaw_rate_radps = 5.f;
  // The slip term uses v_y^2 / max(v_x^2, slip_min_speed_mps^2): near standstill v_y / v_x is
  // not a slip angle but noise over ~0, and would blow up at v_x = 0. 1 m/s keeps the term
  // <= w4 * v_y^2 there (upstream instead drops the term below |v_x| = 0.001 m/s).
  float slip_min_speed_mps = 1.f;

  // True if every weight is finite and >= 0, the target speed finite, the discount in (0, 1],
  // the boundary threshold not NaN, the roll / yaw-rate limits > 0 (may be +inf = off) and
  // slip_min_speed_mps finite and > 0. Otherwise false with the reason in *why (if given).
  bool is_valid(std::string* why = nullptr) const {
    auto fail = [why](const std::string& reason) {
      if (why) *why = reason;
      return false;
    };
    const std::pair<const char*, float> weights[] = {{"track_weight", track_weight},
                                                     {"speed_weight", speed_weight},
                                                     {"crash_weight", crash_weight},
                                                     {"slip_weight", slip_weight}};
    for (const auto& [name, w] : weights)
      if (!std::isfinite(w) || w < 0.f) return fail(std::string(name) + " must be finite and >= 0");
    if (!std::isfinite(target_speed_mps)) return fail("target_speed_mps must be finite");
    if (!(crash_discount > 0.f && crash_discount <= 1.f)) return fail("crash_discount must be in (0, 1]");
    if (std::isnan(boundary_threshold)) return fail("boundary_threshold must not be NaN");
    if (!(max_roll_rad > 0.f)) return fail("max_roll_rad must be > 0 (+inf turns the check off)");
    if (!(max_yaw_rate_radps > 0.f)) return fail("max_yaw_rate_radps must be > 0 (+inf turns the check off)");
    if (!std::isfinite(slip_min_speed_mps) || !(slip_min_speed_mps > 0.f))
      return fail("slip_min_speed_mps must be finite and > 0");
    return true;
  }
};

// The cost's parameter table (YAML key, unit, range, doc): the YAML loader (costs/cost_config.cpp),
// set_param() and help text come from it. Its ranges are those is_valid() checks. An array, so
// that set_param() allocates nothing (a speed governor changes the target speed inside step()).
inline std::array<ParamField, 10> cost_param_array(AutoRallyCostParams& p) {
  return {{
      param("track_weight", &p.track_weight, "1/cost-map unit", non_negative(), "w1: weight of the cost-map value C_M"),
      param("speed_weight", &p.speed_weight, "s^2/m^2", non_negative(), "w2: weight of (v_x - v_x^d)^2"),
      param("crash_weight", &p.crash_weight, "-", non_negative(), "w3: cost of a crash at t = 0"),
      param("slip_weight", &p.slip_weight, "-", non_negative(), "w4: weight of (v_y / v_x)^2"),
      param("target_speed_mps", &p.target_speed_mps, "m/s", any_finite(), "v_x^d, the desired forward speed"),
      param("crash_discount", &p.crash_discount, "-", open_low(0, 1), "crash term x crash_discount^t"),
      param("boundary_threshold", &p.boundary_threshold, "cost-map unit", not_nan(),
            "cost-map value at/above which the car has left the track"),
      param("max_roll_rad", &p.max_roll_rad, "rad", positive_or_inf(), "|roll| above which the car rolled over"),
      param("max_yaw_rate_radps", &p.max_yaw_rate_radps, "rad/s", positive_or_inf(), "|yaw rate| above which the car spins"),
      param("slip_min_speed_mps", &p.slip_min_speed_mps, "m/s", positive(), "v_x floor of the slip term"),
  }};
}
inline std::vector<ParamField> param_table(AutoRallyCostParams& p) {
  const auto fields = cost_param_array(p);
  return {fields.begin(), fields.end()};
}

class AutoRallyCost {
 public:
  // Throws mppi::Error if map is null or params are invalid (message says which field).
  explicit AutoRallyCost(std::shared_ptr<const CostMap> map, AutoRallyCostParams params = {})
      : map_(std::move(map)), params_(params) {
    if (!map_) throw Error("AutoRallyCost: cost map is null");
    std::string why;
    if (!params_.is_valid(&why)) throw Error("AutoRallyCost: invalid parameters: " + why);
  }

  const AutoRallyCostParams& params() const noexcept { return params_; }

  // Changes one parameter by its YAML key (e.g. "target_speed_mps") while the controller runs.
  // False, with the reason in *why, for an unknown key or a value out of range; nothing changes.
  bool set_param(std::string_view key, double value, std::string* why) {
    AutoRallyCostParams p = params_;
    for (const ParamField& f : cost_param_array(p)) {
      if (key != f.key) continue;
      f.set(value);
      if (!in_range(f) || !p.is_valid(why)) {
        if (why) *why = "cost parameter " + std::string(f.key) + " must be " + range_text(f);
        return false;
      }
      params_ = p;
      return true;
    }
    if (why) *why = "unknown cost parameter '" + std::string(key) + "'";
    return false;
  }
  // A new cost map (e.g. a changed region) while the controller runs.
  bool set_map(std::shared_ptr<const CostMap> map, std::string* why) {
    if (!map) {
      if (why) *why = "the cost map is null";
      return false;
    }
    map_ = std::move(map);
    return true;
  }
  const CostMap& map() const noexcept { return *map_; }
  const std::shared_ptr<const CostMap>& map_ptr() const noexcept { return map_; }

  // The terms in the list's order, (t1 + t2) + t3 + ..., each also reported in c.
  template <class... Term>
  static float sum_of_terms(TypeList<Term...>, const AutoRallyCostParams& p, const CostState& state,
                            CostTerms& c) noexcept {
    return (... + (c.*(Term::kOut) = Term::value(p, state)));
  }

  // crash_weight * crash_discount^t: the crash term's value at step t.
  float crash_cost_at(int t) const noexcept {
    return params_.crash_weight * std::pow(params_.crash_discount, static_cast<float>(t));
  }

  // All terms at one state. Branch-free; inlined into the lane loop below. A NaN or infinite
  // x, y, v_x, v_y, yaw rate or roll makes total = +inf (the controller gives a non-finite
  // total cost weight 0); the individual terms may then be NaN.
  static CostTerms terms(const AutoRallyCostParams& p, const CostMap::View& map, float x_m, float y_m,
                         float vx_mps, float vy_mps, float yaw_rate_radps, float roll_rad,
                         float crash_cost) noexcept {
    CostTerms c;
    c.map_value = map.lookup(x_m, y_m);
    c.crashed = (c.map_value >= p.boundary_threshold) | (std::fabs(roll_rad) > p.max_roll_rad) |
                (std::fabs(yaw_rate_radps) > p.max_yaw_rate_radps);
    // bool -> int -> float: GCC 12 does not vectorise a direct bool -> float conversion.
    const CostState state{c.map_value, static_cast<float>(static_cast<int>(c.crashed)), vx_mps, vy_mps, crash_cost};
    float sum = sum_of_terms(AutoRallyCostTerms{}, p, state, c);
    // 0 * (a + b + ...) is 0 for finite inputs and NaN if any is NaN or infinite: it carries
    // non-finite inputs that the clamped lookup and the comparisons would hide into the sum.
    const float poison = 0.f * (x_m + y_m + yaw_rate_radps + roll_rad);
    sum += poison;
    // std::min(a, b) is (b < a) ? b : a, so a NaN sum yields +inf; a finite one itself.
    c.total = std::min(std::numeric_limits<float>::infinity(), sum);
    return c;
  }

  // cost[j] += q(x_j, t) for every lane j. u is not used (AutoRally's control cost is the
  // controller's job).
  template <int Nx, int Nu, int W>
  void accumulate(ConstBatch<Nx, W> x, ConstBatch<Nu, W> /*u*/, int t, float* cost) const noexcept {
    static_assert(Nx >= state::kCommonStates, "AutoRallyCost needs the common vehicle state layout");
    const AutoRallyCostParams p = params_;
    const CostMap::View map = map_->view();
    const float crash_cost = crash_cost_at(t);  // once per call, not per lane
    const float* px = x[state::kX];
    const float* py = x[state::kY];
    const float* pvx = x[state::kVx];
    const float* pvy = x[state::kVy];
    const float* pr = x[state::kYawRate];
    const float* proll = x[state::kRoll];
    MPPI_SIMD_LOOP for (int j = 0; j < W; ++j) {
      cost[j] += terms(p, map, px[j], py[j], pvx[j], pvy[j], pr[j], proll[j], crash_cost).total;
    }
  }

  // q at one state (the common layout, at least state::kCommonStates floats) at step t.
  float evaluate(const float* s, int t, CostTerms* terms_out = nullptr) const noexcept {
    const CostTerms c = terms(params_, map_->view(), s[state::kX], s[state::kY], s[state::kVx], s[state::kVy],
                              s[state::kYawRate], s[state::kRoll], crash_cost_at(t));
    if (terms_out) *terms_out = c;
    return c.total;
  }

 private:
  std::shared_ptr<const CostMap> map_;  // immutable and shared: copies of the cost are cheap
  AutoRallyCostParams params_;
};

}  // namespace mppi
