// The rollout shader, part 2 (after the model): the cost and main(). See rollout_head.glsl.
#include "cost.glsl"

void main() {
  uint k = gl_GlobalInvocationID.x;
  uint num_samples = step_data.sizes.x;
#ifdef MODEL_PRELUDE
  MODEL_PRELUDE();  // every invocation of the workgroup, before any returns (it may use barrier())
#endif
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
  uvec4 words = uvec4(0u);
  // the sampler: eps_0 = first_gain n_0, eps_t = carry eps_{t-1} + gain n_t (white: eps = n)
  bool white = step_data.noise_filter.w != 0.0;
  precise float carry = step_data.noise_filter.x;
  precise float first_gain = step_data.noise_filter.y;
  precise float gain = step_data.noise_filter.z;
  float eps[NU];
  [[unroll]] for (int ch = 0; ch < NU; ++ch) eps[ch] = 0.0;
  // the actuator chain (mppi/actuator_chain.hpp): the model sees its output, not the command
  bool actuated = step_data.actuator_delay.w != 0.0;
  float rate_out[NU], lag_out[NU];
  [[unroll]] for (int ch = 0; ch < NU; ++ch) {
    rate_out[ch] = step_data.actuator_start[ch];
    lag_out[ch] = step_data.actuator_start[2 + ch];
  }
  for (int t = 0; t < horizon; ++t) {
    float u[NU];
    if (kGenerate) {
      // one Philox call per step pair: counter (sample, t / 2, iteration, channel pair 0); words
      // 0, 1 give channels 0 and 1 at the even step, words 2, 3 at the odd one (NU = 2)
      if ((t & 1) == 0) {
        words = uvec4(k, uint(t) >> 1, iteration, 0u);
        philox4x32_10(words, step_data.seed.x, step_data.seed.y);
      }
      vec2 n = (t & 1) == 0 ? box_muller(words.x, words.y) : box_muller(words.z, words.w);
      if (!white) {
        [[unroll]] for (int ch = 0; ch < NU; ++ch) {
          precise float e = t == 0 ? first_gain * n[ch] : carry * eps[ch] + gain * n[ch];
          eps[ch] = e;
          n[ch] = e;
        }
      }
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
    if (actuated) {
      [[unroll]] for (int ch = 0; ch < NU; ++ch) {
        int delay = int(step_data.actuator_delay[ch]);
        // the command acting now: one sent before this plan, or this sample's own from t - delay
        // (written to controls above by this invocation)
        float cmd = t < delay ? step_data.actuator_pending[(ch * 32 + t) >> 2][t & 3]
                              : (delay == 0 ? u[ch] : controls[(uint(t - delay) * NU + uint(ch)) * padded + k]);
        precise float max_change = step_data.actuator_max_change[ch];
        precise float r = rate_out[ch] + clamp(cmd - rate_out[ch], -max_change, max_change);
        rate_out[ch] = r;
        precise float a = lag_out[ch] + step_data.actuator_alpha[ch] * (r - lag_out[ch]);
        lag_out[ch] = a;
        u[ch] = a;
      }
    }
    model_step(x, u[0], u[1], dt);
    cost += stage_cost(x, t);
  }
  costs[k] = kGenerate ? cost + control_cost : cost;
}
