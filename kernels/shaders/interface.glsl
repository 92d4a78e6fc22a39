// The descriptor set every shader of the backend sees (kernels/vulkan_backend.cpp fills it).
#ifndef MPPI_INTERFACE_GLSL
#define MPPI_INTERFACE_GLSL

// Per-step data, written by the host before each submit (std140; see StepUbo in the host code).
layout(std140, set = 0, binding = 0) uniform StepBlock {
  uvec4 sizes;        // K (samples used), T, padded K (row stride of controls), iteration
  uvec4 seed;         // seed low word, seed high word, unused, unused
  vec4 scalars;       // dt [s], gamma, 1 / lambda, unused
  vec4 noise_std;     // per control channel (x, y)
  vec4 control_min;   // per control channel
  vec4 control_max;   // per control channel
  vec4 x0[4];         // start state, up to 16 entries
} step_data;

layout(std430, set = 0, binding = 1) readonly buffer Nominal { float nominal[]; };   // T x nu
layout(std430, set = 0, binding = 2) buffer Controls { float controls[]; };          // T x nu x padded
layout(std430, set = 0, binding = 3) buffer Costs { float costs[]; };                // padded
layout(std430, set = 0, binding = 4) readonly buffer CostMap { float map_values[]; };
// Cost and model parameters (constant for the backend's life): a uniform buffer, read ~5x
// faster than a storage buffer on lavapipe. Float i is params[i / 4][i % 4].
layout(std140, set = 0, binding = 5) uniform ParamBlock { vec4 params[1024]; };
layout(std430, set = 0, binding = 6) readonly buffer CrashCost { float crash_cost[]; };  // T
layout(std430, set = 0, binding = 7) buffer Weights { float weights[]; };            // padded
// stats: min cost, eta (sum of unnormalised weights), sum of squared normalised weights,
// valid (finite) samples, sum of finite costs.
layout(std430, set = 0, binding = 8) buffer Stats { float stats[8]; };
layout(std430, set = 0, binding = 9) buffer Next { float next_nominal[]; };        // T x nu

#define PARAM(i) params[(i) >> 2][(i) & 3]

// Layout of the parameter block's first 16 floats (the cost; see pack_cost()).
#define P_TRACK_W 0
#define P_SPEED_W 1
#define P_SLIP_W 3
#define P_TARGET_SPEED 4
#define P_BOUNDARY 5
#define P_MAX_ROLL 6
#define P_MAX_YAW_RATE 7
#define P_SLIP_MIN_SPEED 8
#define P_MAP_X_MIN 9
#define P_MAP_Y_MIN 10
#define P_MAP_PPM 11
#define P_MAP_MAX_COL 12
#define P_MAP_MAX_ROW 13
#define P_MAP_WIDTH 14
#define P_MODEL 16  // model parameters start here

#endif
