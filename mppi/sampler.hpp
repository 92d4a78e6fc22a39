#pragma once
// How the controller draws its perturbations along the horizon. Every sampler filters the same
// counter-based white normals n_t (mppi/noise.hpp) with one linear recursion per channel,
//   eps_0 = first_gain n_0,   eps_t = carry eps_{t-1} + gain n_t,
// and samples V_t = clamp(U_t + std_c eps_t): the same numbers on every thread count and on the
// GPU, which runs the same recursion (vulkan/shaders/rollout_body.glsl).
//   kGaussian  white noise (carry 0, gains 1): the paper's sampler.
//   kLowPass   a first-order low-pass with corner cutoff_hz: carry a = exp(-2 pi f_c dt),
//              gain sqrt(1 - a^2), first gain 1, so eps_t is stationary with unit variance and
//              its spectrum 1 / (1 - 2a cos w + a^2) falls 20 dB per decade above the corner.
//   kSmooth    derivative-space sampling (as SMPPI): the noise is drawn on the controls' rate
//              and integrated, carry 1, gains sqrt(dt / smooth_time_s), so eps_t is a random
//              walk whose standard deviation reaches 1 (noise_std) at smooth_time_s. Sampled
//              sequences are continuous: their step-to-step change has the standard deviation
//              std_c sqrt(dt / smooth_time_s) instead of std_c sqrt(2).
#include <algorithm>
#include <cmath>
#include <string>
#include <string_view>

namespace mppi {

enum class SamplerKind { kGaussian, kLowPass, kSmooth };

struct SamplerOptions {
  SamplerKind kind = SamplerKind::kGaussian;
  float cutoff_hz = 2.0f;      // kLowPass: corner frequency [Hz]
  float smooth_time_s = 1.0f;  // kSmooth: time at which the integrated noise reaches noise_std [s]
};

// The recursion's coefficients (see the top of this file).
struct NoiseFilter {
  float carry = 0.f;
  float first_gain = 1.f;
  float gain = 1.f;
  // White noise: the samplers draw eps_t = n_t exactly, without the recursion.
  bool white() const { return carry == 0.f && first_gain == 1.f && gain == 1.f; }
};

inline NoiseFilter make_noise_filter(const SamplerOptions& s, float dt_s) {
  constexpr float kTwoPi = 6.28318530718f;
  switch (s.kind) {
    case SamplerKind::kLowPass: {
      const float a = std::exp(-kTwoPi * s.cutoff_hz * dt_s);
      return {a, 1.f, std::sqrt(std::max(0.f, 1.f - a * a))};
    }
    case SamplerKind::kSmooth: {
      const float g = std::sqrt(dt_s / s.smooth_time_s);
      return {1.f, g, g};
    }
    case SamplerKind::kGaussian:
      break;
  }
  return {};
}

inline const char* sampler_name(SamplerKind kind) {
  switch (kind) {
    case SamplerKind::kLowPass: return "lowpass";
    case SamplerKind::kSmooth: return "smooth";
    case SamplerKind::kGaussian: break;
  }
  return "gaussian";
}

// "gaussian" | "lowpass" | "smooth"; false for anything else.
inline bool parse_sampler_kind(std::string_view name, SamplerKind* kind) {
  if (name == "gaussian") *kind = SamplerKind::kGaussian;
  else if (name == "lowpass") *kind = SamplerKind::kLowPass;
  else if (name == "smooth") *kind = SamplerKind::kSmooth;
  else return false;
  return true;
}

// Checks the sampler's settings against the control period dt_s; on failure writes why.
inline bool sampler_is_valid(const SamplerOptions& s, float dt_s, std::string* why) {
  auto fail = [&](const std::string& msg) {
    if (why) *why = msg;
    return false;
  };
  if (s.kind == SamplerKind::kLowPass &&
      (!(s.cutoff_hz > 0.f) || !std::isfinite(s.cutoff_hz) || s.cutoff_hz * dt_s >= 0.5f))
    return fail("sampler cutoff_hz must be in (0, the Nyquist frequency 1 / (2 dt)), got " +
                std::to_string(s.cutoff_hz));
  if (s.kind == SamplerKind::kSmooth && (!(s.smooth_time_s >= dt_s) || !std::isfinite(s.smooth_time_s)))
    return fail("sampler smooth_time_s must be finite and >= dt_s, got " + std::to_string(s.smooth_time_s));
  return true;
}

}  // namespace mppi
