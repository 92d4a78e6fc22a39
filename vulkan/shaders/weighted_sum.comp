#version 450
// U <- sum_k w_k V_k: one workgroup per row (t, channel) of the plan; each invocation sums a
// stride of the K samples, then a shared-memory tree adds the partial sums.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#define GROUP 256
layout(local_size_x = GROUP) in;
#include "common.glsl"
#include "interface.glsl"

shared float s_sum[GROUP];

void main() {
  uint row = gl_WorkGroupID.x;
  uint lid = gl_LocalInvocationID.x;
  uint num_samples = step_data.sizes.x;
  uint padded = step_data.sizes.z;
  float acc = 0.0;
  for (uint k = lid; k < num_samples; k += GROUP) acc += weights[k] * controls[row * padded + k];
  s_sum[lid] = acc;
  barrier();
  [[unroll]] for (uint w = GROUP / 2; w > 0; w >>= 1) {
    if (lid < w) s_sum[lid] += s_sum[lid + w];
    barrier();
  }
  if (lid == 0) next_nominal[row] = s_sum[0];
}
