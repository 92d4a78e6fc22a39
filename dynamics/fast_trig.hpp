#pragma once
// Branch-free float sin/cos and atan for per-lane dynamics code (they vectorise inside
// MPPI_SIMD_LOOP loops; libm's sinf/cosf/atanf do not). Accuracy ~1e-7 absolute, checked
// against libm in tests/dynamics/test_pacejka.cpp.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

namespace mppi {

// sin and cos of x [rad], |x| <= 1e5 (a heading unwrapped over many laps stays far below).
// Range reduction x = n pi/2 + r, |r| <= pi/4, with pi/2 split in three parts (Cody-Waite,
// the first two with few mantissa bits so that n * part is exact); then Taylor polynomials
// (sin to r^9, cos to r^8: truncation < 3e-8 on |r| <= pi/4) and a quadrant rotation done
// with integer bit operations (exact, no branches).
inline void fast_sincos(float x, float* s, float* c) noexcept {
  const float n = static_cast<float>(static_cast<std::int32_t>(x * 0.636619772367581343f +
                                                               std::copysign(0.5f, x)));
  const float r = ((x - n * 1.5703125f) - n * 4.837512969970703125e-4f) - n * 7.54978995489188216e-8f;
  const float r2 = r * r;
  const float ps = r + r * r2 * (-1.f / 6 + r2 * (1.f / 120 + r2 * (-1.f / 5040 + r2 * (1.f / 362880))));
  const float pc = 1.f + r2 * (-0.5f + r2 * (1.f / 24 + r2 * (-1.f / 720 + r2 * (1.f / 40320))));
  // quadrant q = n mod 4: sin = (s, c, -s, -c)[q], cos = (c, -s, -c, s)[q]
  const auto q = static_cast<std::uint32_t>(static_cast<std::int32_t>(n));
  const std::uint32_t swap_mask = 0u - (q & 1u);  // all ones when q is odd
  const std::uint32_t bs = std::bit_cast<std::uint32_t>(ps);
  const std::uint32_t bc = std::bit_cast<std::uint32_t>(pc);
  const std::uint32_t sin_bits = ((bs & ~swap_mask) | (bc & swap_mask)) ^ ((q & 2u) << 30);
  const std::uint32_t cos_bits = ((bc & ~swap_mask) | (bs & swap_mask)) ^ (((q + 1u) & 2u) << 30);
  *s = std::bit_cast<float>(sin_bits);
  *c = std::bit_cast<float>(cos_bits);
}

// atan(x) for any finite x. Reduce to t = min(|x|,1)/max(|x|,1) in [0, 1]; atan(t) by the
// odd polynomial of Abramowitz & Stegun 4.4.49 (|error| <= 2e-8 on [0, 1]); for |x| > 1 use
// atan|x| = pi/2 - atan(1/|x|), written as pi/4 +- (p - pi/4) so that no select is needed.
inline float fast_atan(float x) noexcept {
  const float a = std::abs(x);
  const float t = std::min(a, 1.f) / std::max(a, 1.f);
  const float t2 = t * t;
  float p = 0.0028662257f;
  p = p * t2 - 0.0161657367f;
  p = p * t2 + 0.0429096138f;
  p = p * t2 - 0.0752896400f;
  p = p * t2 + 0.1065626393f;
  p = p * t2 - 0.1420889944f;
  p = p * t2 + 0.1999355085f;
  p = p * t2 - 0.3333314528f;
  p = t + t * t2 * p;
  constexpr float kQuarterPi = 0.785398163397448310f;
  const float mag = kQuarterPi + std::copysign(1.f, 1.f - a) * (p - kQuarterPi);
  return std::copysign(mag, x);
}

// sqrt(x) for x >= 0 (0 -> 0). std::sqrt does not vectorise unless built with
// -fno-math-errno (it keeps a branch to set errno), so: the classic bit-trick estimate of
// 1/sqrt(x), three Newton steps (relative error ~2e-7, float rounding), times x.
inline float fast_sqrt(float x) noexcept {
  float y = std::bit_cast<float>(0x5f375a86u - (std::bit_cast<std::uint32_t>(x) >> 1));
  const float half_x = 0.5f * x;
  y = y * (1.5f - half_x * y * y);
  y = y * (1.5f - half_x * y * y);
  y = y * (1.5f - half_x * y * y);
  return x * y;
}

}  // namespace mppi
