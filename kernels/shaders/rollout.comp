#version 450
// One invocation = one sample k: draws its perturbed controls with Philox (kGenerate) or reads
// them (kGenerate = false), steps the model over the horizon and sums the AutoRally running
// cost, as CpuBackend + Controller::sample do. The model is picked at compile time:
// -DMODEL_KINEMATIC, -DMODEL_NETWORK or -DMODEL_SINGLE_TRACK (see the *.glsl next to this).
// Every loop inside a time step has a compile-time trip count and is unrolled, so one
// invocation runs only T loop iterations (lavapipe silently stops loops after 65,535 in all).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require

layout(local_size_x_id = 0) in;
layout(constant_id = 1) const bool kGenerate = true;  // sample the controls on the device
layout(constant_id = 2) const int kHidden1 = 32;      // network hidden sizes (network only)
layout(constant_id = 3) const int kHidden2 = 32;

#include "common.glsl"
#include "interface.glsl"

#define NU 2
#if defined(MODEL_KINEMATIC)
#include "model_kinematic.glsl"
#elif defined(MODEL_NETWORK)
#include "model_network.glsl"
#elif defined(MODEL_SINGLE_TRACK)
#include "model_single_track.glsl"
#else
#error "define MODEL_KINEMATIC, MODEL_NETWORK or MODEL_SINGLE_TRACK"
#endif
#include "cost.glsl"

void main() {
  uint k = gl_GlobalInvocationID.x;
  uint num_samples = step_data.sizes.x;
  if (k >= num_samples) return;
  int horizon = int(step_data.sizes.y);
  uint padded = step_data.sizes.z;
  uint iteration = step_data.sizes.w;
  precise float dt = step_data.scalars.x;
  precise float gamma = step_data.scalars.y;

  float x[NX];
  [[unroll]] for (int i = 0; i < NX; ++i) x[i] = step_data.x0[i >> 2][i & 3];
  precise float cost = 0.0;
  precise float control_cost = 0.0;
  for (int t = 0; t < horizon; ++t) {
    float u[NU];
    if (kGenerate) {
      uvec4 c = uvec4(k, uint(t), iteration, 0u);  // (sample, t, iteration, channel block)
      philox4x32_10(c, step_data.seed.x, step_data.seed.y);
      vec2 n = box_muller(c.x, c.y);  // channels 0 and 1 (NU = 2: one block)
      [[unroll]] for (int ch = 0; ch < NU; ++ch) {
        precise float un = nominal[t * NU + ch];
        precise float sd = step_data.noise_std[ch];
        precise float inv_var = 1.0 / (sd * sd);
        precise float v = clampf(un + 1.0 * sd * n[ch], step_data.control_min[ch], step_data.control_max[ch]);
        controls[(uint(t) * NU + uint(ch)) * padded + k] = v;
        control_cost += gamma * un * inv_var * (v - un);
        u[ch] = v;
      }
    } else {
      [[unroll]] for (int ch = 0; ch < NU; ++ch) u[ch] = controls[(uint(t) * NU + uint(ch)) * padded + k];
    }
    model_step(x, u[0], u[1], dt);
    cost += stage_cost(x, t);
  }
  costs[k] = kGenerate ? cost + control_cost : cost;
}
