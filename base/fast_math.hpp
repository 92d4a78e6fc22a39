#pragma once
// Branch-free float helpers that vectorise inside MPPI_SIMD_LOOP loops.
#include <algorithm>

namespace mppi {

inline float clampf(float v, float lo, float hi) noexcept { return std::min(std::max(v, lo), hi); }

// tanh as an odd [13/6] rational minimax approximant on a clamped argument (beyond
// |x| = 7.905 tanh rounds to +-1 in float). Max abs error 3.5e-7 over the real line,
// checked against std::tanh in tests/base/test_fast_math.cpp.
inline float fast_tanh(float x) noexcept {
  x = clampf(x, -7.90531110763549805f, 7.90531110763549805f);
  const float x2 = x * x;
  float p = -2.76076847742355e-16f;
  p = p * x2 + 2.00018790482477e-13f;
  p = p * x2 - 8.60467152213735e-11f;
  p = p * x2 + 5.12229709037114e-08f;
  p = p * x2 + 1.48572235717979e-05f;
  p = p * x2 + 6.37261928875436e-04f;
  p = p * x2 + 4.89352455891786e-03f;
  p = p * x;
  float q = 1.19825839466702e-06f;
  q = q * x2 + 1.18534705686654e-04f;
  q = q * x2 + 2.26843463243900e-03f;
  q = q * x2 + 4.89352518554385e-03f;
  return p / q;
}

// The same function with fewer operations, for the network kernels (dynamics/mlp.hpp,
// dynamics/mlp_avx512_kernels.hpp): x P(x^2) / Q(x^2), an odd [9/6] minimax rational (Q
// monic), same clamp: 8 multiplies or FMAs, one add and a division against 11 and one. Max abs
// error 4.5e-7 (tests/base/test_fast_math.cpp). fast_tanh stays as it is: the GPU shaders
// (vulkan/shaders/common.glsl) repeat its operations for CPU/GPU parity.
inline constexpr float kTanhClamp = 7.90531110763549805f;
inline constexpr float kTanhP[5] = {5091.705421197275f, 647.0683863962777f, 13.712402210685147f,
                                    0.036392489380047646f, -3.1233200292516504e-05f};
inline constexpr float kTanhQ[3] = {5091.709733929966f, 2344.2891382644502f, 116.26454563674616f};  // + x^6
inline float fast_tanh96(float x) noexcept {
  x = clampf(x, -kTanhClamp, kTanhClamp);
  const float x2 = x * x;
  const float p = ((((kTanhP[4] * x2 + kTanhP[3]) * x2 + kTanhP[2]) * x2 + kTanhP[1]) * x2 + kTanhP[0]) * x;
  const float q = ((x2 + kTanhQ[2]) * x2 + kTanhQ[1]) * x2 + kTanhQ[0];
  return p / q;
}

// A cheaper tanh for the reduced-precision (bf16) network path, whose activations are rounded
// to bf16 (relative error up to 2^-9 = 2e-3) right after it: x P(x^2) / Q(x^2), an odd [5/4]
// minimax rational (Q monic), argument clamped to +-5. Max abs error 4.8e-5 over the real line
// (tests/base/test_fast_math.cpp), 40x below the bf16 rounding that follows it. 5 multiplies or
// FMAs, one add and a division, against 8, one and one for fast_tanh96.
inline constexpr float kTanhLowpClamp = 5.0f;
inline constexpr float kTanhLowpP[3] = {79.1047588133683f, 8.048281203772188f, 0.05181811641204074f};
inline constexpr float kTanhLowpQ[2] = {79.1197826557108f, 34.377830018572396f};  // + x^4
inline float fast_tanh_lowp(float x) noexcept {
  x = clampf(x, -kTanhLowpClamp, kTanhLowpClamp);
  const float x2 = x * x;
  const float p = ((kTanhLowpP[2] * x2 + kTanhLowpP[1]) * x2 + kTanhLowpP[0]) * x;
  const float q = (x2 + kTanhLowpQ[1]) * x2 + kTanhLowpQ[0];
  return p / q;
}

}  // namespace mppi

#include <bit>
#include <cstdint>

namespace mppi {

// Natural log for x > 0 (normal floats): exponent by bit manipulation, then an odd series in
// s = (m - 1)/(m + 1) for the mantissa m in [sqrt(1/2), sqrt(2)). Max rel. error ~1e-7.
inline float fast_log(float x) noexcept {
  const auto bits = static_cast<std::int32_t>(std::bit_cast<std::uint32_t>(x));
  // Shift the mantissa range to [sqrt(1/2), sqrt(2)) so that |s| < 0.172.
  const std::int32_t exponent = (bits - 0x3f3504f3) >> 23;  // 0x3f3504f3 = sqrt(1/2)
  const float m = std::bit_cast<float>(static_cast<std::uint32_t>(bits - exponent * (1 << 23)));
  const float s = (m - 1.f) / (m + 1.f);
  const float s2 = s * s;
  // log(m) = 2 atanh(s) = 2 (s + s^3/3 + s^5/5 + s^7/7 + s^9/9)
  const float poly = 2.f + s2 * (0.666666667f + s2 * (0.4f + s2 * (0.285714286f + s2 * 0.222222222f)));
  return static_cast<float>(exponent) * 0.693147181f + s * poly;
}

// sin and cos of 2*pi*u for u in [0, 1): reduce to a quarter turn, then minimax-like Taylor
// polynomials on [-pi/4, pi/4]. Max abs error ~2e-7. Branch-free (selects only).
inline void fast_sincos_turns(float u, float* sin_out, float* cos_out) noexcept {
  // quadrant q = round(4u) in {0..4}; r = 2 pi (u - q/4) in [-pi/4, pi/4]
  const float q = static_cast<float>(static_cast<int>(u * 4.f + 0.5f));
  const float r = (u - 0.25f * q) * 6.28318530718f;
  const float r2 = r * r;
  const float s = r * (1.f + r2 * (-1.f / 6 + r2 * (1.f / 120 + r2 * (-1.f / 5040 + r2 * (1.f / 362880)))));
  const float c = 1.f + r2 * (-0.5f + r2 * (1.f / 24 + r2 * (-1.f / 720 + r2 * (1.f / 40320))));
  const int qi = static_cast<int>(q) & 3;
  // rotate (c, s) by q quarter turns: q=0:(c,s) 1:(-s,c) 2:(-c,-s) 3:(s,-c)
  const float cos_v = qi == 0 ? c : (qi == 1 ? -s : (qi == 2 ? -c : s));
  const float sin_v = qi == 0 ? s : (qi == 1 ? c : (qi == 2 ? -s : -c));
  *sin_out = sin_v;
  *cos_out = cos_v;
}

}  // namespace mppi
