#pragma once
// The AutoRally running cost as a sum of terms, each declared once here: its name, the value it
// adds at one state (its weight is a parameter of AutoRallyCostParams, i.e. data), the field of
// CostTerms that reports it, and the GLSL function of its GPU twin (vulkan/shaders/cost.glsl).
// AutoRallyCost::terms() sums the list in its order on the CPU; the build writes the same sum
// for the shader (COST_TERMS_SUM in layout_cost.glsl), so both add the terms in one order.
//
// A new term: a struct here with kName, kGlsl, kOut and value(), its place in
// AutoRallyCostTerms, its weight (and any parameter) in AutoRallyCostParams with a row in its
// parameter table and in gpu_cost_fields() (costs/autorally_cost_gpu.hpp), and its GLSL
// function in vulkan/shaders/cost.glsl reading a CostState.
#include <algorithm>

#include "base/type_list.hpp"

namespace mppi {

struct AutoRallyCostParams;

// What the terms read at one state, computed once per state (the map lookup and the crash
// indicator are shared by several terms).
struct CostState {
  float map_value;   // C_M(p_x, p_y)
  float crashed;     // the crash indicator I: 0 or 1
  float vx_mps, vy_mps;
  float crash_cost;  // crash_weight * crash_discount^t at this step
};

// One evaluation split into its weighted terms (total = the sum of the terms, except that a
// NaN/inf state gives total = +inf).
struct CostTerms {
  float map_value = 0.f;  // C_M(p_x, p_y), unweighted
  bool crashed = false;   // the indicator I
  float track = 0.f;      // track_weight * C_M
  float speed = 0.f;      // speed_weight * (v_x - v_x^d)^2
  float crash = 0.f;      // crash_weight * discount^t * I
  float slip = 0.f;       // slip_weight * v_y^2 / max(v_x^2, v_min^2)
  float total = 0.f;
};

namespace cost_terms {

// w1 C_M: stay near the centre line of the track.
struct Track {
  static constexpr const char* kName = "track";
  static constexpr const char* kGlsl = "track_term";
  static constexpr float CostTerms::*kOut = &CostTerms::track;
  template <class P>
  static float value(const P& p, const CostState& s) noexcept {
    return p.track_weight * s.map_value;
  }
};

// w2 (v_x - v_x^d)^2: hold the desired speed.
struct Speed {
  static constexpr const char* kName = "speed";
  static constexpr const char* kGlsl = "speed_term";
  static constexpr float CostTerms::*kOut = &CostTerms::speed;
  template <class P>
  static float value(const P& p, const CostState& s) noexcept {
    const float dv = s.vx_mps - p.target_speed_mps;
    return p.speed_weight * dv * dv;
  }
};

// w3 0.9^t I: a crash, discounted over the horizon.
struct Crash {
  static constexpr const char* kName = "crash";
  static constexpr const char* kGlsl = "crash_term";
  static constexpr float CostTerms::*kOut = &CostTerms::crash;
  template <class P>
  static float value(const P&, const CostState& s) noexcept {
    return s.crash_cost * s.crashed;
  }
};

// w4 (v_y / v_x)^2: the tangent of the body slip angle, squared (v_x floored).
struct Slip {
  static constexpr const char* kName = "slip";
  static constexpr const char* kGlsl = "slip_term";
  static constexpr float CostTerms::*kOut = &CostTerms::slip;
  template <class P>
  static float value(const P& p, const CostState& s) noexcept {
    const float vmin = p.slip_min_speed_mps;
    return p.slip_weight * (s.vy_mps * s.vy_mps) / std::max(s.vx_mps * s.vx_mps, vmin * vmin);
  }
};

}  // namespace cost_terms

using AutoRallyCostTerms = TypeList<cost_terms::Track, cost_terms::Speed, cost_terms::Crash, cost_terms::Slip>;

}  // namespace mppi
