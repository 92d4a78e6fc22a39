#pragma once
// The AutoRally cost's GPU twin (vulkan/shaders/cost.glsl): the floats at the start of the
// parameter block, named as the GLSL code reads them. The build generates the GLSL offsets
// (layout_cost.glsl) from this table and the Vulkan backend packs the block with it, so the
// two cannot drift apart.
#include <vector>

#include "costs/autorally_cost.hpp"

namespace mppi {

struct GpuCostField {
  const char* name;
  float (*value)(const AutoRallyCost&);
};

// The model's floats start at this offset (the cost block is padded to it).
inline constexpr int kGpuCostFloats = 16;

inline std::vector<GpuCostField> gpu_cost_fields() {
  return {
      {"P_TRACK_W", [](const AutoRallyCost& c) { return c.params().track_weight; }},
      {"P_SPEED_W", [](const AutoRallyCost& c) { return c.params().speed_weight; }},
      {"P_CRASH_W", [](const AutoRallyCost& c) { return c.params().crash_weight; }},
      {"P_SLIP_W", [](const AutoRallyCost& c) { return c.params().slip_weight; }},
      {"P_TARGET_SPEED", [](const AutoRallyCost& c) { return c.params().target_speed_mps; }},
      {"P_BOUNDARY", [](const AutoRallyCost& c) { return c.params().boundary_threshold; }},
      {"P_MAX_ROLL", [](const AutoRallyCost& c) { return c.params().max_roll_rad; }},
      {"P_MAX_YAW_RATE", [](const AutoRallyCost& c) { return c.params().max_yaw_rate_radps; }},
      {"P_SLIP_MIN_SPEED", [](const AutoRallyCost& c) { return c.params().slip_min_speed_mps; }},
      {"P_MAP_X_MIN", [](const AutoRallyCost& c) { return c.map().view().x_min_m; }},
      {"P_MAP_Y_MIN", [](const AutoRallyCost& c) { return c.map().view().y_min_m; }},
      {"P_MAP_PPM", [](const AutoRallyCost& c) { return c.map().view().pixels_per_meter; }},
      {"P_MAP_MAX_COL", [](const AutoRallyCost& c) { return static_cast<float>(c.map().view().max_col); }},
      {"P_MAP_MAX_ROW", [](const AutoRallyCost& c) { return static_cast<float>(c.map().view().max_row); }},
      {"P_MAP_WIDTH", [](const AutoRallyCost& c) { return static_cast<float>(c.map().view().width); }},
  };
}

}  // namespace mppi
