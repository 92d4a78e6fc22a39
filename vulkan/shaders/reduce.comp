#version 450
// The weights of MPPI in one workgroup: min of the finite costs, w_k = exp(-(S_k - min)/lambda)
// (0 for a non-finite cost), eta = sum w, w_k /= eta; also the sum of w^2 (effective sample
// size), the count and sum of finite costs. Each invocation strides over K (K / 256 loop
// iterations per pass), then a shared-memory tree combines the partial results.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#define GROUP 256
layout(local_size_x = GROUP) in;
#include "common.glsl"
#include "interface.glsl"

shared float s_a[GROUP];
shared float s_b[GROUP];
shared float s_c[GROUP];

bool finite_cost(float s) { return !isnan(s) && !isinf(s); }

void main() {
  uint lid = gl_LocalInvocationID.x;
  uint num_samples = step_data.sizes.x;
  float inv_lambda = step_data.scalars.z;

  float m = MPPI_INF, count = 0.0, sum = 0.0;
  for (uint k = lid; k < num_samples; k += GROUP) {
    float s = costs[k];
    if (finite_cost(s)) { m = min(m, s); count += 1.0; sum += s; }
  }
  s_a[lid] = m; s_b[lid] = count; s_c[lid] = sum;
  barrier();
  [[unroll]] for (uint w = GROUP / 2; w > 0; w >>= 1) {
    if (lid < w) {
      s_a[lid] = min(s_a[lid], s_a[lid + w]);
      s_b[lid] += s_b[lid + w];
      s_c[lid] += s_c[lid + w];
    }
    barrier();
  }
  float min_cost = s_a[0];
  float valid = s_b[0];
  float cost_sum = s_c[0];
  barrier();

  float eta = 0.0;
  for (uint k = lid; k < num_samples; k += GROUP) {
    float s = costs[k];
    float w = finite_cost(s) ? exp(-(s - min_cost) * inv_lambda) : 0.0;
    weights[k] = w;
    eta += w;
  }
  s_a[lid] = eta;
  barrier();
  [[unroll]] for (uint w = GROUP / 2; w > 0; w >>= 1) {
    if (lid < w) s_a[lid] += s_a[lid + w];
    barrier();
  }
  float inv_eta = valid > 0.0 ? 1.0 / s_a[0] : 0.0;
  float total_eta = s_a[0];
  barrier();

  float sum_sq = 0.0;
  for (uint k = lid; k < num_samples; k += GROUP) {
    float w = weights[k] * inv_eta;
    weights[k] = w;
    sum_sq += w * w;
  }
  s_a[lid] = sum_sq;
  barrier();
  [[unroll]] for (uint w = GROUP / 2; w > 0; w >>= 1) {
    if (lid < w) s_a[lid] += s_a[lid + w];
    barrier();
  }
  if (lid == 0) {
    stats[0] = min_cost;
    stats[1] = total_eta;
    stats[2] = s_a[0];
    stats[3] = valid;
    stats[4] = cost_sum;
  }
}
