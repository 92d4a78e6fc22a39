// Shared by the compute shaders: the branch-free float math and the Philox4x32-10 noise of the
// CPU backend (base/fast_math.hpp, dynamics/fast_trig.hpp, mppi/noise.hpp), written with the
// same operations in the same order, so that the device agrees with the CPU to float rounding.
#ifndef MPPI_COMMON_GLSL
#define MPPI_COMMON_GLSL

#define MPPI_INF uintBitsToFloat(0x7f800000u)

float clampf(float v, float lo, float hi) {
  // std::min(std::max(v, lo), hi) with std::max(a, b) = (a < b) ? b : a
  precise float m = (v < lo) ? lo : v;
  return (hi < m) ? hi : m;
}

float fast_tanh(float x) {
  x = clampf(x, -7.90531110763549805, 7.90531110763549805);
  precise float x2 = x * x;
  precise float p = -2.76076847742355e-16;
  p = p * x2 + 2.00018790482477e-13;
  p = p * x2 - 8.60467152213735e-11;
  p = p * x2 + 5.12229709037114e-08;
  p = p * x2 + 1.48572235717979e-05;
  p = p * x2 + 6.37261928875436e-04;
  p = p * x2 + 4.89352455891786e-03;
  p = p * x;
  precise float q = 1.19825839466702e-06;
  q = q * x2 + 1.18534705686654e-04;
  q = q * x2 + 2.26843463243900e-03;
  q = q * x2 + 4.89352518554385e-03;
  return p / q;
}

float fast_log(float x) {
  int bits = floatBitsToInt(x);
  int exponent = (bits - 0x3f3504f3) >> 23;
  precise float m = intBitsToFloat(bits - exponent * (1 << 23));
  precise float s = (m - 1.0) / (m + 1.0);
  precise float s2 = s * s;
  precise float poly = 2.0 + s2 * (0.666666667 + s2 * (0.4 + s2 * (0.285714286 + s2 * 0.222222222)));
  return float(exponent) * 0.693147181 + s * poly;
}

// sin and cos of 2 pi u, u in [0, 1)
void fast_sincos_turns(float u, out float sin_out, out float cos_out) {
  precise float q = float(int(u * 4.0 + 0.5));
  precise float r = (u - 0.25 * q) * 6.28318530718;
  precise float r2 = r * r;
  precise float s = r * (1.0 + r2 * (-1.0 / 6.0 + r2 * (1.0 / 120.0 + r2 * (-1.0 / 5040.0 + r2 * (1.0 / 362880.0)))));
  precise float c = 1.0 + r2 * (-0.5 + r2 * (1.0 / 24.0 + r2 * (-1.0 / 720.0 + r2 * (1.0 / 40320.0))));
  int qi = int(q) & 3;
  cos_out = qi == 0 ? c : (qi == 1 ? -s : (qi == 2 ? -c : s));
  sin_out = qi == 0 ? s : (qi == 1 ? c : (qi == 2 ? -s : -c));
}

void fast_sincos(float x, out float s, out float c) {
  precise float half_signed = (floatBitsToUint(x) >> 31) != 0u ? -0.5 : 0.5;  // copysign(0.5, x)
  precise float n = float(int(x * 0.636619772367581343 + half_signed));
  precise float r = ((x - n * 1.5703125) - n * 4.837512969970703125e-4) - n * 7.54978995489188216e-8;
  precise float r2 = r * r;
  precise float ps = r + r * r2 * (-1.0 / 6.0 + r2 * (1.0 / 120.0 + r2 * (-1.0 / 5040.0 + r2 * (1.0 / 362880.0))));
  precise float pc = 1.0 + r2 * (-0.5 + r2 * (1.0 / 24.0 + r2 * (-1.0 / 720.0 + r2 * (1.0 / 40320.0))));
  uint q = uint(int(n));
  uint swap_mask = 0u - (q & 1u);
  uint bs = floatBitsToUint(ps);
  uint bc = floatBitsToUint(pc);
  uint sin_bits = ((bs & ~swap_mask) | (bc & swap_mask)) ^ ((q & 2u) << 30);
  uint cos_bits = ((bc & ~swap_mask) | (bs & swap_mask)) ^ (((q + 1u) & 2u) << 30);
  s = uintBitsToFloat(sin_bits);
  c = uintBitsToFloat(cos_bits);
}

float copysign_f(float mag, float sgn) {
  return uintBitsToFloat((floatBitsToUint(mag) & 0x7fffffffu) | (floatBitsToUint(sgn) & 0x80000000u));
}

float fast_atan(float x) {
  precise float a = abs(x);
  precise float t = min(a, 1.0) / max(a, 1.0);
  precise float t2 = t * t;
  precise float p = 0.0028662257;
  p = p * t2 - 0.0161657367;
  p = p * t2 + 0.0429096138;
  p = p * t2 - 0.0752896400;
  p = p * t2 + 0.1065626393;
  p = p * t2 - 0.1420889944;
  p = p * t2 + 0.1999355085;
  p = p * t2 - 0.3333314528;
  p = t + t * t2 * p;
  const float kQuarterPi = 0.785398163397448310;
  precise float mag = kQuarterPi + copysign_f(1.0, 1.0 - a) * (p - kQuarterPi);
  return copysign_f(mag, x);
}

float fast_sqrt(float x) {
  precise float y = uintBitsToFloat(0x5f375a86u - (floatBitsToUint(x) >> 1));
  precise float half_x = 0.5 * x;
  y = y * (1.5 - half_x * y * y);
  y = y * (1.5 - half_x * y * y);
  y = y * (1.5 - half_x * y * y);
  return x * y;
}

// Philox4x32-10 on counter c with key (k0, k1), in place.
void philox4x32_10(inout uvec4 c, uint k0, uint k1) {
  [[unroll]] for (int r = 0; r < 10; ++r) {
    uint hi0, lo0, hi1, lo1;
    umulExtended(0xD2511F53u, c.x, hi0, lo0);
    umulExtended(0xCD9E8D57u, c.z, hi1, lo1);
    c = uvec4(hi1 ^ c.y ^ k0, lo1, hi0 ^ c.w ^ k1, lo0);
    k0 += 0x9E3779B9u;
    k1 += 0xBB67AE85u;
  }
}

// Two standard normals from two random words (Box-Muller), as mppi::box_muller.
vec2 box_muller(uint a, uint b) {
  precise float u1 = (float(a >> 8) + 0.5) * (1.0 / 16777216.0);
  precise float u2 = float(b >> 8) * (1.0 / 16777216.0);
  precise float r = sqrt(-2.0 * fast_log(u1));
  precise float s, c;
  fast_sincos_turns(u2, s, c);
  return vec2(r * c, r * s);
}

#endif
