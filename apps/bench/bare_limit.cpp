#include "bare_limit.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "base/batch.hpp"
#include "base/error.hpp"
#include "base/fast_math.hpp"
#include "base/multiversion.hpp"
#include "base/npz.hpp"
#include "dynamics/mlp.hpp"

namespace mppi::bench {

MlpWeights load_mlp_weights(const std::string& npz_path) {
  const NpzFile f = NpzFile::load(npz_path);
  MlpWeights w{};
  auto copy = [&](const char* key, std::vector<std::size_t> shape, float* dst) {
    const NpyArray& a = f.at(key, shape);
    for (std::size_t i = 0; i < a.size(); ++i) dst[i] = static_cast<float>(a.values[i]);
  };
  constexpr auto H = static_cast<std::size_t>(MlpWeights::kHidden);
  copy("dynamics_W1", {H, MlpWeights::kIn}, &w.w1[0][0]);
  copy("dynamics_b1", {H}, w.b1);
  copy("dynamics_W2", {H, H}, &w.w2[0][0]);
  copy("dynamics_b2", {H}, w.b2);
  copy("dynamics_W3", {MlpWeights::kOut, H}, &w.w3[0][0]);
  copy("dynamics_b3", {MlpWeights::kOut}, w.b3);
  return w;
}

namespace detail {

constexpr int kW = BareLimit::kLanes;  // lanes per chunk
constexpr int kV = 16;                  // lanes per vector (one zmm)
constexpr int kNV = kW / kV;            // vectors per chunk row
// 16 floats as one GCC vector: a zmm register in the x86-64-v4 clone, 2 ymm in the v3 one.
typedef float v16 __attribute__((vector_size(64)));

// (by reference: vectors passed by value would change the ABI between the clones)
inline void load(v16& v, const float* p) { __builtin_memcpy(&v, p, sizeof v); }
inline void store(float* p, const v16& v) { __builtin_memcpy(p, &v, sizeof v); }

// mppi::fast_tanh96 on 16 lanes at once, in place (the same rational, as GCC vector operations;
// by reference for the same ABI reason as load/store).
inline void tanh_v16(v16& v) {
  const v16 c = v16{} + kTanhClamp;
  v16 x = v < c ? v : c;
  x = x > -c ? x : -c;
  const v16 x2 = x * x;
  v16 p = x2 * kTanhP[4] + kTanhP[3];
  p = p * x2 + kTanhP[2];
  p = p * x2 + kTanhP[1];
  p = (p * x2 + kTanhP[0]) * x;
  v16 q = x2 + kTanhQ[2];
  q = q * x2 + kTanhQ[1];
  q = q * x2 + kTanhQ[0];
  v = p / q;
}

// y[o] = act(b[o] + sum_i w[o][i] x[i]) over the 64 lanes, in blocks of 4 outputs x 4 vectors:
// 16 accumulators held in registers, each weight broadcast once per block row; tanh (Tanh) is
// applied to the accumulators before they are stored.
template <int In, int Out, bool Tanh>
inline void dense(const float (*w)[In], const float* b, const float (*x)[kW], float (*y)[kW]) {
  static_assert(Out % 4 == 0);
  for (int ob = 0; ob < Out; ob += 4) {
    v16 acc[4][kNV];
#pragma GCC unroll 4
    for (int o = 0; o < 4; ++o)
#pragma GCC unroll 4
      for (int v = 0; v < kNV; ++v) acc[o][v] = v16{} + b[ob + o];
#pragma GCC unroll 32
    for (int i = 0; i < In; ++i) {
      v16 xv[kNV];
#pragma GCC unroll 4
      for (int v = 0; v < kNV; ++v) load(xv[v], x[i] + v * kV);
#pragma GCC unroll 4
      for (int o = 0; o < 4; ++o) {
        const float wo = w[ob + o][i];
#pragma GCC unroll 4
        for (int v = 0; v < kNV; ++v) acc[o][v] += wo * xv[v];
      }
    }
#pragma GCC unroll 4
    for (int o = 0; o < 4; ++o)
#pragma GCC unroll 4
      for (int v = 0; v < kNV; ++v) {
        if (Tanh) tanh_v16(acc[o][v]);
        store(y[ob + o] + v * kV, acc[o][v]);
      }
  }
}

// One chunk of 64 lanes for `steps` steps. init/out: rows of `padded` floats, from lane k0.
MPPI_MULTIVERSION void bare_chunk(const MlpWeights& w, const float* init, float* out, int padded,
                                  int k0, int steps, float dt) noexcept {
  constexpr int H = MlpWeights::kHidden;
  alignas(64) float in[MlpWeights::kIn][kW];
  alignas(64) float h1[H][kW];
  alignas(64) float h2[H][kW];
  alignas(64) float d[MlpWeights::kOut][kW];
  for (int r = 0; r < MlpWeights::kIn; ++r)
    std::memcpy(in[r], init + static_cast<std::size_t>(r) * padded + k0, sizeof in[r]);
  for (int t = 0; t < steps; ++t) {
    dense<MlpWeights::kIn, H, true>(w.w1, w.b1, in, h1);
    dense<H, H, true>(w.w2, w.b2, h1, h2);
    dense<H, MlpWeights::kOut, false>(w.w3, w.b3, h2, d);
    // Euler: the outputs are d/dt of the first 4 inputs; steering and throttle stay.
    for (int s = 0; s < MlpWeights::kOut; ++s) {
      MPPI_SIMD_LOOP
      for (int j = 0; j < kW; ++j) in[s][j] += dt * d[s][j];
    }
  }
  for (int s = 0; s < MlpWeights::kOut; ++s)
    std::memcpy(out + static_cast<std::size_t>(s) * padded + k0, in[s], sizeof in[s]);
}

}  // namespace detail

BareLimit::BareLimit(const MlpWeights& weights, int num_samples, int horizon, float dt_s,
                     int threads, bool bf16)
    : w_(weights),
      bf16_(bf16),
      num_samples_(num_samples),
      padded_((num_samples + kLanes - 1) / kLanes * kLanes),
      horizon_(horizon),
      threads_(threads > 0 ? threads : omp_get_max_threads()),
      dt_s_(dt_s) {
  if (num_samples < 1 || horizon < 1) throw Error("BareLimit: need num_samples, horizon >= 1");
  if (bf16 && !bf16_supported()) throw Error("BareLimit: this CPU has no AVX512-BF16");
  auto pack = [](float lo, float hi) {
    return static_cast<std::uint32_t>(to_bf16_bits(lo)) | static_cast<std::uint32_t>(to_bf16_bits(hi)) << 16;
  };
  for (int o = 0; o < MlpWeights::kHidden; ++o)
    for (int p = 0; p < MlpWeights::kHidden / 2; ++p) wb_.w2[o][p] = pack(w_.w2[o][2 * p], w_.w2[o][2 * p + 1]);
  for (int o = 0; o < MlpWeights::kOut; ++o)
    for (int p = 0; p < MlpWeights::kHidden / 2; ++p) wb_.w3[o][p] = pack(w_.w3[o][2 * p], w_.w3[o][2 * p + 1]);
  init_.assign(static_cast<std::size_t>(MlpWeights::kIn) * padded_, 0.f);
  out_.assign(static_cast<std::size_t>(MlpWeights::kOut) * padded_, 0.f);
  // Lanes differ: a spread of speeds, steering and throttle around driving at ~5 m/s.
  for (int k = 0; k < padded_; ++k) {
    const float a = static_cast<float>(k % 97) / 96.f;  // [0, 1]
    const float b = static_cast<float>(k % 61) / 60.f;
    init_[0 * static_cast<std::size_t>(padded_) + k] = 0.02f * (a - 0.5f);  // roll
    init_[1 * static_cast<std::size_t>(padded_) + k] = 4.f + 2.f * b;       // u_x
    init_[2 * static_cast<std::size_t>(padded_) + k] = 0.2f * (b - 0.5f);   // u_y
    init_[3 * static_cast<std::size_t>(padded_) + k] = 0.5f * (a - 0.5f);   // yaw_mder
    init_[4 * static_cast<std::size_t>(padded_) + k] = 1.6f * (a - 0.5f);   // steering
    init_[5 * static_cast<std::size_t>(padded_) + k] = 0.6f * b;            // throttle
  }
}

void BareLimit::run() { run_steps(horizon_); }

void BareLimit::run_steps(int steps) {
  const int chunks = padded_ / kLanes;
  const float* init = init_.data();
  float* out = out_.data();
  const int padded = padded_;
  const float dt = dt_s_;
  const MlpWeights& w = w_;
  const BareBf16Weights& wb = wb_;
  if (bf16_) {
#pragma omp parallel for schedule(static) num_threads(threads_)
    for (int c = 0; c < chunks; ++c) detail::bare_chunk_bf16(w, wb, init, out, padded, c * kLanes, steps, dt);
    return;
  }
#pragma omp parallel for schedule(static) num_threads(threads_)
  for (int c = 0; c < chunks; ++c) detail::bare_chunk(w, init, out, padded, c * kLanes, steps, dt);
}

std::vector<double> BareLimit::reference(int k, int steps) const {
  constexpr int H = MlpWeights::kHidden;
  double in[MlpWeights::kIn];
  for (int r = 0; r < MlpWeights::kIn; ++r) in[r] = init_[static_cast<std::size_t>(r) * padded_ + k];
  for (int t = 0; t < steps; ++t) {
    double h1[H], h2[H], d[MlpWeights::kOut];
    for (int o = 0; o < H; ++o) {
      double s = w_.b1[o];
      for (int i = 0; i < MlpWeights::kIn; ++i) s += static_cast<double>(w_.w1[o][i]) * in[i];
      h1[o] = std::tanh(s);
    }
    for (int o = 0; o < H; ++o) {
      double s = w_.b2[o];
      for (int i = 0; i < H; ++i) s += static_cast<double>(w_.w2[o][i]) * h1[i];
      h2[o] = std::tanh(s);
    }
    for (int o = 0; o < MlpWeights::kOut; ++o) {
      double s = w_.b3[o];
      for (int i = 0; i < H; ++i) s += static_cast<double>(w_.w3[o][i]) * h2[i];
      d[o] = s;
    }
    for (int s = 0; s < MlpWeights::kOut; ++s) in[s] += static_cast<double>(dt_s_) * d[s];
  }
  return {in[0], in[1], in[2], in[3]};
}

double BareLimit::checksum() const {
  double s = 0.0;
  for (int r = 0; r < MlpWeights::kOut; ++r)
    for (int k = 0; k < num_samples_; ++k) s += out_[static_cast<std::size_t>(r) * padded_ + k];
  return s;
}

const char* BareLimit::dispatched_isa() {
#if defined(__x86_64__) && defined(__GNUC__)
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
      __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512vl"))
    return "x86-64-v4 (AVX-512)";
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return "x86-64-v3 (AVX2+FMA)";
  return "x86-64 baseline (SSE2)";
#else
  return "single version";
#endif
}

}  // namespace mppi::bench
