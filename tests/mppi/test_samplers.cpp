// The samplers (mppi/sampler.hpp) against independent oracles: the draws equal a scalar
// reference built in the test from mppi::normal_at (the scalar Philox normal) and the
// recursion written out here; the low-pass noise has the closed-form spectrum of a first-order
// autoregression (and so its slope); the derivative-space noise has the variance of a random
// walk and continuous sequences.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <vector>

#include "mppi/controller.hpp"
#include "mppi/noise.hpp"
#include "mppi/sampler.hpp"
#include "tests/mppi/linear_system.hpp"

using mppi::test::DoubleIntegrator;
using mppi::test::QuadraticCost;

namespace {

constexpr double kPi = 3.14159265358979323846;

mppi::ControllerOptions sampler_options(mppi::SamplerKind kind, int k, int t, float limit) {
  mppi::ControllerOptions o;
  o.num_samples = k;
  o.horizon = t;
  o.dt_s = 0.02f;
  o.lambda = 1.f;
  o.noise_std = {0.5f};
  o.control_min = {-limit};
  o.control_max = {limit};
  o.safe_control = {0.f};
  o.seed = 77;
  o.sampler.kind = kind;
  o.sampler.cutoff_hz = 1.5f;
  o.sampler.smooth_time_s = 0.4f;
  return o;
}

// The first step's draws of a CPU controller (the plan is all zeros, so V = clamp(std * eps)):
// v[t][k], K samples, T steps.
std::vector<std::vector<float>> first_draws(const mppi::ControllerOptions& o) {
  auto c = mppi::make_cpu_controller(DoubleIntegrator{}, QuadraticCost{}, o);
  const float x0[2] = {0.5f, 0.f};
  mppi::StepSummary s;
  c.step(x0, &s);
  REQUIRE(s.status == mppi::StepStatus::kOk);
  const auto v = c.sampled_controls();
  const auto padded = static_cast<std::size_t>(c.backend().shape().padded_samples);
  std::vector<std::vector<float>> out(static_cast<std::size_t>(o.horizon),
                                      std::vector<float>(static_cast<std::size_t>(o.num_samples)));
  for (int t = 0; t < o.horizon; ++t)
    for (int k = 0; k < o.num_samples; ++k) out[t][k] = v[static_cast<std::size_t>(t) * padded + k];
  return out;
}

// The oracle: eps from scalar normals through the recursion, written out for each kind.
double reference_eps_next(mppi::SamplerKind kind, double prev, double n, int t, double dt,
                          const mppi::SamplerOptions& s) {
  switch (kind) {
    case mppi::SamplerKind::kGaussian: return n;
    case mppi::SamplerKind::kLowPass: {
      const double a = std::exp(-2 * kPi * s.cutoff_hz * dt);
      return t == 0 ? n : a * prev + std::sqrt(1 - a * a) * n;
    }
    case mppi::SamplerKind::kSmooth: return (t == 0 ? 0.0 : prev) + std::sqrt(dt / s.smooth_time_s) * n;
  }
  return 0;
}

}  // namespace

TEST_CASE("each sampler draws what its recursion over the scalar normals gives", "[core][mppi][sampler]") {
  for (auto kind : {mppi::SamplerKind::kGaussian, mppi::SamplerKind::kLowPass, mppi::SamplerKind::kSmooth}) {
    INFO(mppi::sampler_name(kind));
    const auto o = sampler_options(kind, 200, 60, 0.7f);  // K not a multiple of 64; clamps active
    const auto v = first_draws(o);
    double worst = 0;
    int clamped = 0;
    for (int k = 0; k < o.num_samples; ++k) {
      double eps = 0;
      for (int t = 0; t < o.horizon; ++t) {
        const double n = mppi::normal_at(mppi::NoiseKey{o.seed}, 0, static_cast<std::uint32_t>(k),
                                         static_cast<std::uint32_t>(t), 0);
        eps = reference_eps_next(kind, eps, n, t, o.dt_s, o.sampler);
        const double want = std::clamp(o.noise_std[0] * eps, -0.7, 0.7);
        clamped += std::abs(want) == 0.7;
        worst = std::max(worst, std::abs(want - v[t][k]));
      }
    }
    CHECK(worst < 2e-5);  // float recursion against double: rounding over at most 60 steps
    CHECK(clamped > 0);
  }
}

TEST_CASE("low-pass sampling has the spectrum of a first-order autoregression", "[core][mppi][sampler]") {
  const int k = 1024, n = 256;
  auto o = sampler_options(mppi::SamplerKind::kLowPass, k, n, 1e3f);
  const auto v = first_draws(o);
  const double dt = o.dt_s, a = std::exp(-2 * kPi * o.sampler.cutoff_hz * dt);
  const double sd = o.noise_std[0];
  // Averaged periodogram with a Hann window, one-sided, as power per bin over the window energy.
  std::vector<double> hann(n), psd(n / 2 + 1, 0.0);
  double energy = 0;
  for (int t = 0; t < n; ++t) {
    hann[t] = 0.5 - 0.5 * std::cos(2 * kPi * t / n);
    energy += hann[t] * hann[t];
  }
  std::vector<std::complex<double>> twiddle(n), x(n);
  for (int i = 0; i < n; ++i) twiddle[i] = std::polar(1.0, -2 * kPi * i / n);
  for (int s = 0; s < k; ++s) {
    for (int t = 0; t < n; ++t) x[t] = hann[t] * v[t][s] / sd;
    for (int f = 1; f <= n / 2; ++f) {  // a plain DFT bin
      std::complex<double> acc = 0;
      for (int t = 0; t < n; ++t) acc += x[t] * twiddle[(f * t) % n];
      psd[f] += std::norm(acc) / energy / k;
    }
  }
  auto closed_form = [&](int f) {  // S(w) = (1 - a^2) / (1 - 2 a cos w + a^2), unit variance
    const double w = 2 * kPi * f / n;
    return (1 - a * a) / (1 - 2 * a * std::cos(w) + a * a);
  };
  // Within 12% over the band from 0.5 Hz to 20 Hz (bins 3 .. 102 of 0.195 Hz): 1024 averaged
  // periodograms have a relative standard error of about 3%, and the Hann window smooths the
  // spectrum over 2 bins, which bends it by less than 2% here.
  double worst = 0;
  for (int f = 3; f <= 102; ++f) worst = std::max(worst, std::abs(psd[f] / closed_form(f) - 1));
  INFO("worst relative PSD error " << worst);
  CHECK(worst < 0.12);
  // The log-log slope over 4-12 Hz (above the 1.5-Hz corner) is the closed form's, about -1.7
  // (white noise: 0; the continuous first-order low-pass: -2).
  auto slope = [&](auto&& spectrum) {
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    int m = 0;
    for (int f = 21; f <= 61; ++f) {
      const double x = std::log(f), y = std::log(spectrum(f));
      sx += x, sy += y, sxx += x * x, sxy += x * y, ++m;
    }
    return (m * sxy - sx * sy) / (m * sxx - sx * sx);
  };
  const double measured = slope([&](int f) { return psd[f]; });
  const double expected = slope(closed_form);
  INFO("slope measured " << measured << " closed form " << expected);
  CHECK(std::abs(measured - expected) < 0.1);
  CHECK(expected < -1.5);
}

TEST_CASE("derivative-space sampling is a random walk with continuous sequences", "[core][mppi][sampler]") {
  const int k = 4096, n = 50;
  auto o = sampler_options(mppi::SamplerKind::kSmooth, k, n, 1e3f);
  const auto v = first_draws(o);
  const double sd = o.noise_std[0], rate = std::sqrt(o.dt_s / o.sampler.smooth_time_s);
  for (int t : {0, 9, 19, 49}) {
    double var = 0;
    for (int s = 0; s < k; ++s) var += static_cast<double>(v[t][s]) * v[t][s];
    var /= k;
    const double want = sd * sd * (t + 1) * o.dt_s / o.sampler.smooth_time_s;  // (t + 1) steps of rate^2
    INFO("t " << t << " variance " << var << " random walk " << want);
    CHECK(std::abs(var / want - 1) < 0.08);  // 4096 samples: relative standard error 2.2%
  }
  // Step-to-step change: std * sqrt(dt / T_s), against std * sqrt(2) for white noise.
  double var = 0;
  for (int t = 0; t + 1 < n; ++t)
    for (int s = 0; s < k; ++s) var += std::pow(static_cast<double>(v[t + 1][s]) - v[t][s], 2);
  var /= (n - 1.0) * k;
  CHECK(std::sqrt(var) == Approx(sd * rate).epsilon(0.03));
}

TEST_CASE("filtered samples do not depend on the thread count", "[core][mppi][sampler]") {
  for (auto kind : {mppi::SamplerKind::kLowPass, mppi::SamplerKind::kSmooth}) {
    auto o = sampler_options(kind, 300, 40, 2.f);
    o.num_threads = 1;
    const auto one = first_draws(o);
    o.num_threads = 2;
    o.schedule = mppi::ThreadSchedule::kDynamic;
    CHECK(first_draws(o) == one);
  }
}

TEST_CASE("sampler settings out of range are refused with a reason", "[core][mppi][sampler]") {
  auto o = sampler_options(mppi::SamplerKind::kLowPass, 64, 10, 1.f);
  std::string why;
  o.sampler.cutoff_hz = 30.f;  // above the 25-Hz Nyquist frequency of dt = 0.02 s
  CHECK_FALSE(o.is_valid(1, &why));
  CHECK(why.find("cutoff_hz") != std::string::npos);
  o.sampler.cutoff_hz = std::nanf("");
  CHECK_FALSE(o.is_valid(1, &why));
  o.sampler = {mppi::SamplerKind::kSmooth, 1.f, 0.f};
  CHECK_FALSE(o.is_valid(1, &why));
  CHECK(why.find("smooth_time_s") != std::string::npos);
  mppi::SamplerKind kind{};
  CHECK(mppi::parse_sampler_kind("smooth", &kind));
  CHECK(kind == mppi::SamplerKind::kSmooth);
  CHECK_FALSE(mppi::parse_sampler_kind("pink", &kind));
}

TEST_CASE("the fused iteration scores the filtered sequences it reports", "[core][mppi][sampler]") {
  // The CPU backend draws and rolls out in one pass and draws the sequences again on demand:
  // rolling the reported sequences out once more must give the reported costs.
  for (auto kind : {mppi::SamplerKind::kGaussian, mppi::SamplerKind::kLowPass, mppi::SamplerKind::kSmooth}) {
    INFO(mppi::sampler_name(kind));
    auto o = sampler_options(kind, 300, 40, 2.f);
    auto c = mppi::make_cpu_controller(DoubleIntegrator{}, QuadraticCost{}, o);
    const float x0[2] = {0.5f, -0.2f};
    c.step(x0);
    c.step(x0);  // around a plan that is no longer zero
    const std::vector<float> v(c.sampled_controls().begin(), c.sampled_controls().end());
    const std::vector<float> reported(c.sampled_costs().begin(), c.sampled_costs().end());
    std::vector<float> again(static_cast<std::size_t>(c.backend().shape().padded_samples));
    c.backend().rollout(x0, v, again);
    double worst = 0;
    for (int k = 0; k < o.num_samples; ++k)
      worst = std::max(worst, std::abs(static_cast<double>(again[k]) - reported[k]) / std::max(1.0, std::abs(reported[k] * 1.0)));
    CHECK(worst < 1e-5);
  }
}
