#pragma once
// CPU backend: OpenMP over chunks of kChunk samples, each chunk rolled out with the model and
// cost inlined over SoA lanes. Scratch memory per thread is allocated once, at construction.
// The chunks go to the threads as the schedule says (mppi/thread_schedule.hpp).
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <memory>
#include <new>
#include <string>
#include <vector>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#endif

#include "base/batch.hpp"
#include "base/error.hpp"
#include "base/multiversion.hpp"
#include "mppi/actuator_chain.hpp"
#include "mppi/backend.hpp"
#include "mppi/concepts.hpp"
#include "mppi/linearize.hpp"
#include "mppi/lqr.hpp"
#include "mppi/noise.hpp"
#include "mppi/sample_step.hpp"
#include "mppi/thread_schedule.hpp"

namespace mppi {

namespace detail {
// Rolls out samples [k0, k0 + kChunk) of `controls` (T x nu x padded) from x0; cost_out gets
// the kChunk total costs. work: D::kNx*kChunk + D::kNu*kChunk + model scratch floats.
template <class D, class C>
MPPI_MULTIVERSION void rollout_chunk(const D& model, const C& cost, const float* x0,
                                     const float* controls, int padded, int horizon, float dt_s,
                                     int k0, float* work, float* cost_out) noexcept {
  constexpr int W = kChunk;
  float* x = work;                 // kNx x W
  float* u = x + D::kNx * W;       // kNu x W
  float* scratch = u + D::kNu * W;
  for (int i = 0; i < D::kNx; ++i) std::fill_n(x + i * W, W, x0[i]);
  std::fill_n(cost_out, W, 0.f);
  for (int t = 0; t < horizon; ++t) {
    for (int c = 0; c < D::kNu; ++c)
      std::memcpy(u + c * W, controls + (static_cast<std::size_t>(t) * D::kNu + c) * padded + k0,
                  sizeof(float) * W);
    model.template step<W>(Batch<D::kNx, W>{x}, ConstBatch<D::kNu, W>{u}, dt_s, scratch);
    cost.template accumulate<D::kNx, D::kNu, W>(ConstBatch<D::kNx, W>{x}, ConstBatch<D::kNu, W>{u},
                                                t, cost_out);
  }
}

// What iterate_chunk leaves for the combination of the chunks (one cache line per chunk).
struct alignas(64) ChunkTotals {
  float min_cost = 0.f;   // min of the chunk's finite S_k (+inf if none)
  float eta = 0.f;        // sum_k exp(-(S_k - min_cost) / lambda) over the finite S_k
  double cost_sum = 0.0;  // sum of the finite S_k
  int valid = 0;          // samples with a finite S_k
};

// The parameters of one iteration, as plain pointers (see IterationInput).
struct IterationArgs {
  const float* x0;
  const float* nominal;  // T x nu
  const float* noise_std;
  const float* lo;
  const float* hi;
  float gamma, inv_lambda, dt_s;
  NoiseKey key;
  std::uint32_t iteration;
  int num_samples, padded, horizon;
  NoiseFilter filter;
  ActuatorPlan actuators;
  // Robust MPPI's augmented sampling (AugmentedSampling; used by iterate_chunk<..., true>)
  const float* real_x0 = nullptr;  // num_states
  const float* gains = nullptr;    // T x nu x nx
  float real_cost_bound = 0.f;
};

// partial[r] = sum_j e[j] v[r * padded + j], j in [0, kChunk), for r in [0, rows): the chunk's
// share of the weighted sum. The portable loop reduces each row across its lanes on its own;
// the AVX-512 one reduces 16 rows together (a transposing tree of 45 shuffles and adds instead
// of ~8 dependent steps per row). The two may differ in the last bit (summation order); each
// is deterministic, so results still do not depend on the thread count.
inline void chunk_partial_sums_portable(const float* e, const float* v, std::size_t padded,
                                        int r0, int rows, float* partial) noexcept {
  for (int r = r0; r < rows; ++r) {
    const float* vr = v + static_cast<std::size_t>(r) * padded;
    float acc = 0.f;
#pragma omp simd reduction(+ : acc)
    for (int j = 0; j < kChunk; ++j) acc += e[j] * vr[j];
    partial[r] = acc;
  }
}
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__)) && !defined(MPPI_NO_SIMD_PHILOX)
#define MPPI_SIMD_PARTIAL_SUMS 1
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"
__attribute__((target("avx512f"))) inline void chunk_partial_sums_avx512(
    const float* e, const float* v, std::size_t padded, int rows, float* partial) noexcept {
  static_assert(kChunk == 64, "four 16-lane vectors per row");
  const __m512 e0 = _mm512_loadu_ps(e), e1 = _mm512_loadu_ps(e + 16), e2 = _mm512_loadu_ps(e + 32),
               e3 = _mm512_loadu_ps(e + 48);
  int r0 = 0;
  for (; r0 + 16 <= rows; r0 += 16) {
    __m512 acc[16];
    for (int i = 0; i < 16; ++i) {
      const float* vr = v + static_cast<std::size_t>(r0 + i) * padded;
      __m512 a = _mm512_mul_ps(e0, _mm512_loadu_ps(vr));
      a = _mm512_fmadd_ps(e1, _mm512_loadu_ps(vr + 16), a);
      a = _mm512_fmadd_ps(e2, _mm512_loadu_ps(vr + 32), a);
      acc[i] = _mm512_fmadd_ps(e3, _mm512_loadu_ps(vr + 48), a);
    }
    // 16 -> 8: per 128-bit lane [a0+a2, b0+b2, a1+a3, b1+b3] for the pairs (a, b)
    __m512 s8[8];
    for (int k = 0; k < 8; ++k)
      s8[k] = _mm512_add_ps(_mm512_unpacklo_ps(acc[2 * k], acc[2 * k + 1]),
                            _mm512_unpackhi_ps(acc[2 * k], acc[2 * k + 1]));
    // 8 -> 4: per 128-bit lane the rows 4m .. 4m + 3 in order
    __m512 s4[4];
    for (int m = 0; m < 4; ++m)
      s4[m] = _mm512_add_ps(_mm512_shuffle_ps(s8[2 * m], s8[2 * m + 1], _MM_SHUFFLE(1, 0, 1, 0)),
                            _mm512_shuffle_ps(s8[2 * m], s8[2 * m + 1], _MM_SHUFFLE(3, 2, 3, 2)));
    // 4 -> 2 -> 1: add the 128-bit lanes, rows 4m .. 4m + 3 in 128-bit lane m
    __m512 s2[2];
    for (int q = 0; q < 2; ++q)
      s2[q] = _mm512_add_ps(_mm512_shuffle_f32x4(s4[2 * q], s4[2 * q + 1], _MM_SHUFFLE(2, 0, 2, 0)),
                            _mm512_shuffle_f32x4(s4[2 * q], s4[2 * q + 1], _MM_SHUFFLE(3, 1, 3, 1)));
    const __m512 sum = _mm512_add_ps(_mm512_shuffle_f32x4(s2[0], s2[1], _MM_SHUFFLE(2, 0, 2, 0)),
                                     _mm512_shuffle_f32x4(s2[0], s2[1], _MM_SHUFFLE(3, 1, 3, 1)));
    _mm512_storeu_ps(partial + r0, sum);
  }
  chunk_partial_sums_portable(e, v, padded, r0, rows, partial);
}
#pragma GCC diagnostic pop
#endif

inline void chunk_partial_sums(const float* e, const float* v, std::size_t padded, int rows,
                               float* partial) noexcept {
#ifdef MPPI_SIMD_PARTIAL_SUMS
  static const bool avx512 = __builtin_cpu_supports("avx512f");
  if (avx512) return chunk_partial_sums_avx512(e, v, padded, rows, partial);
#endif
  chunk_partial_sums_portable(e, v, padded, 0, rows, partial);
}

// The real system's input in Robust MPPI's augmented sampling, per lane j:
//   u_real[c][j] = clamp(u[c][j] + sum_i k[c * Nx + i] (x_real[i][j] - x_nom[i][j]), lo[c], hi[c])
// (k: the T-step's nu x nx gains). A NaN stays NaN.
template <int Nx, int Nu, int W>
inline void feedback_controls(const float* k, const float* u, const float* x_real, const float* x_nom,
                              const float* lo, const float* hi, float* u_real) noexcept {
  for (int c = 0; c < Nu; ++c) {
    float* out = u_real + c * W;
    std::copy_n(u + c * W, W, out);
    for (int i = 0; i < Nx; ++i) {
      const float gain = k[c * Nx + i];
      const float* xr = x_real + i * W;
      const float* xn = x_nom + i * W;
      MPPI_SIMD_LOOP
      for (int j = 0; j < W; ++j) out[j] += gain * (xr[j] - xn[j]);
    }
    const float l = lo[c], h = hi[c];
    MPPI_SIMD_LOOP
    for (int j = 0; j < W; ++j) out[j] = out[j] < l ? l : (out[j] > h ? h : out[j]);
  }
}

// One chunk of samples [k0, k0 + kChunk) of a whole iteration, fused so that each time step's
// noise and controls are used while they are in L1: per pair of steps t, t + 1 draw
// V = clamp(U + eps) for both (sample_step_pair, the numbers of Controller's sampling pass; one
// Philox call per lane and channel pair serves both steps) into the chunk's own T x nu x kChunk
// block of `work`, then step the model and cost with each. The draws are not kept: writing
// T x nu x K floats costs 6-8% of the iteration, and a counter-based stream can give any of
// them again (regenerate_controls). Then the chunk's share of the
// update, from its own block (in L1/L2), with weights relative to the chunk's own minimum:
//   e_k = exp(-(S_k - m_c) / lambda),  partial[t * nu + c] = sum_k e_k V_k,t,c
// (the caller rescales by exp(-(m_c - min S) / lambda): the same weights as the two-pass form,
// up to rounding). costs, expw: the chunk's S_k and e_k (k - k0 in [0, kChunk)).
// With kAugmented (Robust MPPI's augmented sampling, AugmentedSampling) each lane also rolls
// out the real system from a.real_x0 under clamp(V_t + K_t (x_real_t - x_t)), x_t the lane's
// own nominal rollout, and S_k = 0.5 J_nom + 0.5 max(min(J_real, bound), J_nom) + control cost.
// work: (2 D::kNx + T * D::kNu) * kChunk + model scratch floats.
template <class D, class C, bool kAugmented = false>
MPPI_MULTIVERSION void iterate_chunk(const D& model, const C& cost, const IterationArgs& a,
                                     int k0, float* work, float* costs,
                                     float* expw, float* partial, ChunkTotals* totals) noexcept {
  constexpr int W = kChunk;
  constexpr int Nu = D::kNu;
  constexpr int Nx = D::kNx;
  float* x = work;             // kNx x W
  float* v = x + Nx * W;       // T x kNu x W: the chunk's sampled controls
  float* x_real = v + static_cast<std::size_t>(a.horizon) * Nu * W;  // kNx x W (kAugmented)
  float* scratch = x_real + Nx * W;
  alignas(64) float state_cost[W] = {};
  alignas(64) float control_cost[W] = {};
  alignas(64) float eps_state[Nu * W];  // the sampler's state per channel and lane
  alignas(64) float actuator_rate[Nu * W], actuator_lag[Nu * W], applied[Nu * W];
  alignas(64) float real_cost[W] = {};
  alignas(64) float u_real[Nu * W];
  for (int i = 0; i < Nx; ++i) std::fill_n(x + i * W, W, a.x0[i]);
  if constexpr (kAugmented)
    for (int i = 0; i < Nx; ++i) std::fill_n(x_real + i * W, W, a.real_x0[i]);
  const float valid_lanes = static_cast<float>(a.num_samples - k0);
  for (int t = 0; t < a.horizon; ++t) {
    if (t % 2 == 0) {
      const int steps = std::min(2, a.horizon - t);
      float* vt = v + static_cast<std::size_t>(t) * Nu * W;
      sample_step_pair<W>(a.key, a.iteration, k0, valid_lanes, t, steps, Nu, a.nominal + t * Nu,
                          a.noise_std, a.lo, a.hi, a.gamma, a.filter, eps_state, vt, W,
                          static_cast<std::size_t>(Nu) * W, control_cost);
    }
    const float* u = v + static_cast<std::size_t>(t) * Nu * W;
    if (a.actuators.enabled()) {  // the model sees the actuators' output, not the command
      detail::actuator_inputs<W>(a.actuators, Nu, t, v, W, static_cast<std::size_t>(Nu) * W,
                                 actuator_rate, actuator_lag, applied);
      u = applied;
    }
    if constexpr (kAugmented)  // the feedback on the states at t, before either steps
      feedback_controls<Nx, Nu, W>(a.gains + static_cast<std::size_t>(t) * Nu * Nx, u, x_real, x, a.lo, a.hi,
                                   u_real);
    model.template step<W>(Batch<Nx, W>{x}, ConstBatch<Nu, W>{u}, a.dt_s, scratch);
    cost.template accumulate<Nx, Nu, W>(ConstBatch<Nx, W>{x}, ConstBatch<Nu, W>{u}, t, state_cost);
    if constexpr (kAugmented) {
      model.template step<W>(Batch<Nx, W>{x_real}, ConstBatch<Nu, W>{u_real}, a.dt_s, scratch);
      cost.template accumulate<Nx, Nu, W>(ConstBatch<Nx, W>{x_real}, ConstBatch<Nu, W>{u_real}, t, real_cost);
    }
  }
  if constexpr (kAugmented) {
    // 0.5 J_nom + 0.5 max(min(J_real, bound), J_nom), written so that a NaN J_real stays NaN
    // (the sample is then dropped as any other non-finite one)
    MPPI_SIMD_LOOP
    for (int j = 0; j < W; ++j) {
      const float bounded = real_cost[j] > a.real_cost_bound ? a.real_cost_bound : real_cost[j];
      const float upper = bounded < state_cost[j] ? state_cost[j] : bounded;
      state_cost[j] = 0.5f * state_cost[j] + 0.5f * upper;
    }
  }
  // S_k (the same sum as Controller's two-pass update: rollout cost + control cost)
  alignas(64) float s[W];
  float m = std::numeric_limits<float>::infinity();
  MPPI_SIMD_LOOP
  for (int j = 0; j < W; ++j) {
    s[j] = state_cost[j] + control_cost[j];
    const bool use = static_cast<float>(j) < valid_lanes && std::isfinite(s[j]);
    m = std::min(m, use ? s[j] : std::numeric_limits<float>::infinity());
  }
  std::copy_n(s, W, costs);
  ChunkTotals tot;
  tot.min_cost = m;
  alignas(64) float e[W];
  float eta = 0.f;
  for (int j = 0; j < W; ++j) {
    const bool use = static_cast<float>(j) < valid_lanes && std::isfinite(s[j]);
    e[j] = use ? std::exp(-(s[j] - m) * a.inv_lambda) : 0.f;
    eta += e[j];
    if (use) {
      tot.cost_sum += s[j];
      ++tot.valid;
    }
  }
  tot.eta = eta;
  std::copy_n(e, W, expw);
  *totals = tot;
  // partial sums of e_k V_k, from the chunk's own block (in L1/L2)
  chunk_partial_sums(e, v, W, a.horizon * Nu, partial);
}

// The controls that iterate_chunk drew for samples [k0, k0 + W), again, bit for bit (the same
// sample_step_pair on the same inputs, in a clone chosen the same way):
// v[t * v_step_stride + c * v_stride + j] for sample k0 + j. a.x0 is not read.
template <int W>
MPPI_MULTIVERSION void regenerate_controls(const IterationArgs& a, int nu, int k0, float* v,
                                           std::size_t v_stride, std::size_t v_step_stride) noexcept {
  alignas(64) float control_cost[W] = {};  // summed as in iterate_chunk, not used
  alignas(64) float eps_state[kMaxNoiseChannels * W];
  const float valid_lanes = static_cast<float>(a.num_samples - k0);
  for (int t = 0; t < a.horizon; t += 2)
    sample_step_pair<W>(a.key, a.iteration, k0, valid_lanes, t, std::min(2, a.horizon - t), nu,
                        a.nominal + t * nu, a.noise_std, a.lo, a.hi, a.gamma, a.filter, eps_state,
                        v + static_cast<std::size_t>(t) * v_step_stride, v_stride, v_step_stride,
                        control_cost);
}

// The chunks' shares combined in chunk order (so independent of the thread count): weights
// w_k = e_k exp(-(m_c - m) / lambda) / eta, next = sum_c exp(-(m_c - m) / lambda) partial_c / eta,
// accumulated in double. rows = T * nu; partial_stride: floats between two chunks' partials;
// sums: rows doubles and scales: chunks doubles of scratch.
MPPI_MULTIVERSION inline void combine_chunks(const ChunkTotals* totals, const float* partial,
                                             std::size_t partial_stride, int chunks, int rows,
                                             int num_samples, float inv_lambda, const float* expw,
                                             double* sums, double* scales,
                                             IterationOutput& out) noexcept {
  float m = std::numeric_limits<float>::infinity();
  int valid = 0;
  double cost_sum = 0.0;
  for (int c = 0; c < chunks; ++c) {
    m = std::min(m, totals[c].min_cost);
    valid += totals[c].valid;
    cost_sum += totals[c].cost_sum;
  }
  out.valid_samples = valid;
  if (valid == 0) {
    std::fill(out.weights.begin(), out.weights.end(), 0.f);
    return;
  }
  std::fill_n(sums, rows, 0.0);
  double eta = 0.0;
  for (int c = 0; c < chunks; ++c) {
    scales[c] = totals[c].valid == 0 ? 0.0 : std::exp(-static_cast<double>(totals[c].min_cost - m) * inv_lambda);
    if (totals[c].valid == 0) continue;
    const double scale = scales[c];
    eta += scale * totals[c].eta;
    const float* p = partial + static_cast<std::size_t>(c) * partial_stride;
    MPPI_SIMD_LOOP
    for (int r = 0; r < rows; ++r) sums[r] += scale * p[r];
  }
  const double inv_eta = 1.0 / eta;  // eta >= 1: the best sample has e = 1 and scale = 1
  for (int r = 0; r < rows; ++r) out.next[r] = static_cast<float>(sums[r] * inv_eta);
  double sum_sq = 0.0;
  for (int c = 0; c < chunks; ++c) {
    const auto f = static_cast<float>(scales[c] * inv_eta);
    const int k_end = std::min(num_samples, (c + 1) * kChunk);
    float* w = out.weights.data();
    for (int k = c * kChunk; k < k_end; ++k) {
      w[k] = expw[k] * f;
      sum_sq += static_cast<double>(w[k]) * w[k];
    }
  }
  out.min_cost = m;
  out.mean_cost = static_cast<float>(cost_sum / valid);
  out.sum_sq_weights = static_cast<float>(sum_sq);
}
}  // namespace detail

inline int padded_sample_count(int num_samples) {
  return (num_samples + kChunk - 1) / kChunk * kChunk;
}

template <Dynamics D, StageCost<D> C>
class CpuBackend final : public Backend {
 public:
  CpuBackend(D model, C cost, int num_samples, int horizon, float dt_s, int num_threads,
             ThreadSchedule schedule = ThreadSchedule::kDynamic)
      : model_(std::move(model)), cost_(std::move(cost)), dt_s_(dt_s), runner_(num_threads, schedule) {
    if (num_samples < 1 || horizon < 1) throw Error("CpuBackend: need num_samples, horizon >= 1");
    static_assert(D::kNu <= detail::kMaxNoiseChannels, "the samplers filter at most kMaxNoiseChannels channels");
    shape_ = {num_samples, padded_sample_count(num_samples), horizon, D::kNx, D::kNu};
    threads_ = runner_.threads();
    // state, the chunk's T steps of controls (iterate_chunk; rollout_chunk uses one), the
    // real system's state (augmented sampling), model scratch
    work_floats_ = static_cast<std::size_t>(2 * D::kNx + horizon * D::kNu) * kChunk +
                   model_.scratch_floats(kChunk);
    // Round each thread's slice to a cache line (16 floats) so threads never share one.
    work_floats_ = (work_floats_ + 15) / 16 * 16;
    work_.assign(work_floats_ * static_cast<std::size_t>(threads_), 0.f);
    const int chunks = shape_.padded_samples / kChunk;
    const std::size_t rows = static_cast<std::size_t>(horizon) * D::kNu;
    controls_ = aligned_floats(rows * static_cast<std::size_t>(shape_.padded_samples));
    block_ = aligned_floats(rows * kSampleBlock);
    drawn_nominal_.assign(rows, 0.f);
    drawn_std_.assign(D::kNu, 0.f);
    drawn_lo_.assign(D::kNu, 0.f);
    drawn_hi_.assign(D::kNu, 0.f);
    expw_ = aligned_floats(static_cast<std::size_t>(shape_.padded_samples));
    partial_stride_ = (rows + 15) / 16 * 16;  // a whole number of cache lines per chunk
    partial_ = aligned_floats(partial_stride_ * static_cast<std::size_t>(chunks));
    totals_.assign(static_cast<std::size_t>(chunks), detail::ChunkTotals{});
    sums_.assign(rows, 0.0);
    scales_.assign(static_cast<std::size_t>(chunks), 0.0);
    plan_lanes_ = aligned_floats(rows * kChunk);
  }

  const char* name() const override { return "cpu"; }
  const RolloutShape& shape() const override { return shape_; }
  int num_threads() const { return threads_; }
  const D& model() const { return model_; }
  const C& cost() const { return cost_; }

  bool set_cost_param(std::string_view key, double value, std::string* why) override {
    if constexpr (requires { cost_.set_param(key, value, why); }) return cost_.set_param(key, value, why);
    else return Backend::set_cost_param(key, value, why);
  }
  bool set_cost_map(std::shared_ptr<const CostMap> map, std::string* why) override {
    if constexpr (requires { cost_.set_map(map, why); }) return cost_.set_map(std::move(map), why);
    else return Backend::set_cost_map(std::move(map), why);
  }
  bool set_model_param(std::string_view key, double value, std::string* why) override {
    if constexpr (requires { model_.set_param(key, value, why); }) return model_.set_param(key, value, why);
    else return Backend::set_model_param(key, value, why);
  }
  // One step of the model in a chunk whose lanes all hold x0 and u (lane 0 is taken). Uses the
  // first thread's work slice (iterate() is not running).
  bool predict_step(std::span<const float> x0, std::span<const float> u, std::span<float> x1,
                    std::string* why) override {
    if (x0.size() != static_cast<std::size_t>(D::kNx) || u.size() != static_cast<std::size_t>(D::kNu) ||
        x1.size() != static_cast<std::size_t>(D::kNx)) {
      if (why) *why = "cpu backend: predict_step needs x0 and x1 of num_states and u of num_controls";
      return false;
    }
    constexpr int W = kChunk;
    float* x = work_.data();
    float* in = x + D::kNx * W;
    for (int i = 0; i < D::kNx; ++i) std::fill_n(x + i * W, W, x0[i]);
    for (int c = 0; c < D::kNu; ++c) std::fill_n(in + c * W, W, u[c]);
    model_.template step<W>(Batch<D::kNx, W>{x}, ConstBatch<D::kNu, W>{in}, dt_s_, in + D::kNu * W);
    for (int i = 0; i < D::kNx; ++i) x1[i] = x[i * W];
    return true;
  }

  // The whole iteration in one parallel pass over the chunks (detail::iterate_chunk), then
  // the chunks combined in order (detail::combine_chunks).
  bool has_iterate() const override { return true; }
  bool supports_actuators() const override { return true; }
  bool supports_augmented_sampling() const override { return true; }
  void iterate(const IterationInput& in, IterationOutput& out) override {
    const int padded = shape_.padded_samples;
    const int chunks = padded / kChunk;
    detail::IterationArgs args{in.x0.data(), in.nominal.data(), in.noise_std.data(),
                               in.control_min.data(), in.control_max.data(), in.gamma,
                               1.f / in.lambda, dt_s_, NoiseKey{in.seed}, in.iteration,
                               shape_.num_samples, padded, shape_.horizon, in.noise_filter,
                               in.actuators};
    const bool augmented = in.augmented.enabled();
    if (augmented) {
      if (in.augmented.real_x0.size() != static_cast<std::size_t>(D::kNx) ||
          in.augmented.gains.size() != static_cast<std::size_t>(shape_.horizon) * D::kNu * D::kNx)
        throw Error("cpu backend: augmented sampling needs real_x0 of num_states and gains of T x nu x nx");
      if (in.actuators.enabled()) throw Error("cpu backend: augmented sampling rolls out without an actuator chain");
      args.real_x0 = in.augmented.real_x0.data();
      args.gains = in.augmented.gains.data();
      args.real_cost_bound = in.augmented.real_cost_bound;
    }
    remember_draw_inputs(in);
    float* work = work_.data();
    const std::size_t work_floats = work_floats_;
    float* costs = out.costs.data();
    float* expw = expw_.get();
    float* partial = partial_.get();
    const std::size_t stride = partial_stride_;
    detail::ChunkTotals* totals = totals_.data();
    runner_.run(chunks, 1, [&](int chunk, int slot) {
      const int k0 = chunk * kChunk;
      float* chunk_work = work + work_floats * static_cast<std::size_t>(slot);
      float* chunk_partial = partial + stride * static_cast<std::size_t>(chunk);
      if (augmented)
        detail::iterate_chunk<D, C, true>(model_, cost_, args, k0, chunk_work, costs + k0, expw + k0, chunk_partial,
                                          totals + chunk);
      else
        detail::iterate_chunk<D, C, false>(model_, cost_, args, k0, chunk_work, costs + k0, expw + k0, chunk_partial,
                                           totals + chunk);
    });
    detail::combine_chunks(totals, partial, stride, chunks, shape_.horizon * D::kNu,
                           shape_.num_samples, 1.f / in.lambda, expw, sums_.data(), scales_.data(), out);
  }
  // The last iteration's draws are not stored by iterate(); they are drawn again here, bit for
  // bit, on the first call after it (one noise pass, about half of a cheap model's iteration).
  std::span<const float> sampled_controls() const override {
    const std::size_t padded = static_cast<std::size_t>(shape_.padded_samples);
    if (!controls_fresh_ && drawn_) {
      const detail::IterationArgs a = drawn_args();
      for (int k0 = 0; k0 < shape_.padded_samples; k0 += kChunk)
        detail::regenerate_controls<kChunk>(a, D::kNu, k0, controls_.get() + k0, padded, D::kNu * padded);
      controls_fresh_ = true;
    }
    return {controls_.get(), static_cast<std::size_t>(shape_.horizon) * D::kNu * padded};
  }
  // A few samples' draws, in blocks of kSampleBlock lanes (the operator view picks ~20).
  bool copy_sampled_controls(std::span<const int> samples, std::span<float> out) const override {
    const std::size_t n = samples.size();
    const std::size_t rows = static_cast<std::size_t>(shape_.horizon) * D::kNu;
    if (!drawn_ || out.size() < rows * n) return false;
    for (int k : samples)
      if (k < 0 || k >= shape_.num_samples) return false;
    if (controls_fresh_)
      return copy_sample_columns({controls_.get(), rows * static_cast<std::size_t>(shape_.padded_samples)}, rows,
                                 static_cast<std::size_t>(shape_.padded_samples), shape_.num_samples, samples, out);
    const detail::IterationArgs a = drawn_args();
    int block = -1;
    for (std::size_t j = 0; j < n; ++j) {
      const int first = samples[j] / kSampleBlock * kSampleBlock;
      if (first != block) {
        detail::regenerate_controls<kSampleBlock>(a, D::kNu, first, block_.get(), kSampleBlock,
                                                  D::kNu * kSampleBlock);
        block = first;
      }
      for (std::size_t r = 0; r < rows; ++r)
        out[r * n + j] = block_[r * kSampleBlock + static_cast<std::size_t>(samples[j] - first)];
    }
    return true;
  }

  void rollout(std::span<const float> x0, std::span<const float> controls,
               std::span<float> costs) override {
    const int padded = shape_.padded_samples;
    const int chunks = padded / kChunk;
    const float* x0p = x0.data();
    const float* vp = controls.data();
    float* sp = costs.data();
    float* work = work_.data();
    const std::size_t work_floats = work_floats_;
    runner_.run(chunks, 1, [&](int chunk, int slot) {
      detail::rollout_chunk(model_, cost_, x0p, vp, padded, shape_.horizon, dt_s_, chunk * kChunk,
                            work + work_floats * static_cast<std::size_t>(slot), sp + chunk * kChunk);
    });
  }

 private:
  struct AlignedFree {
    void operator()(float* p) const noexcept { ::operator delete[](p, std::align_val_t{64}); }
  };
  using AlignedFloats = std::unique_ptr<float[], AlignedFree>;
  // n zeroed floats on a cache-line boundary (so that chunks written by different threads
  // never share a line).
  static AlignedFloats aligned_floats(std::size_t n) {
    AlignedFloats p(static_cast<float*>(::operator new[](n * sizeof(float), std::align_val_t{64})));
    std::fill_n(p.get(), n, 0.f);
    return p;
  }

  static constexpr int kSampleBlock = 16;

  // What the draws of the last iterate() depend on besides the key and iteration (its nominal
  // changes after the update), kept so they can be drawn again.
  void remember_draw_inputs(const IterationInput& in) {
    std::copy(in.nominal.begin(), in.nominal.end(), drawn_nominal_.begin());
    std::copy(in.noise_std.begin(), in.noise_std.end(), drawn_std_.begin());
    std::copy(in.control_min.begin(), in.control_min.end(), drawn_lo_.begin());
    std::copy(in.control_max.begin(), in.control_max.end(), drawn_hi_.begin());
    drawn_gamma_ = in.gamma;
    drawn_key_ = NoiseKey{in.seed};
    drawn_iteration_ = in.iteration;
    drawn_filter_ = in.noise_filter;
    drawn_ = true;
    controls_fresh_ = false;
  }
  detail::IterationArgs drawn_args() const {
    return {nullptr, drawn_nominal_.data(), drawn_std_.data(), drawn_lo_.data(), drawn_hi_.data(),
            drawn_gamma_, 0.f, dt_s_, drawn_key_, drawn_iteration_, shape_.num_samples,
            shape_.padded_samples, shape_.horizon, drawn_filter_, ActuatorPlan{}};
  }

  D model_;
  C cost_;
  float dt_s_;
  ParallelRunner runner_;
  RolloutShape shape_;
  int threads_ = 1;
  std::size_t work_floats_ = 0;
  std::vector<float> work_;  // threads x work_floats_
  // iterate(): the sampled controls (T x nu x padded), e_k per sample, each chunk's partial sums
  // (partial_stride_ floats per chunk) and totals, and the combination's scratch
  AlignedFloats expw_, partial_;
  // sampled_controls(): the last iteration's draws, drawn again on demand (T x nu x padded);
  // copy_sampled_controls(): one block of kSampleBlock samples (T x nu x kSampleBlock)
  AlignedFloats controls_, block_;
  mutable bool controls_fresh_ = false;
  bool drawn_ = false;
  std::vector<float> drawn_nominal_, drawn_std_, drawn_lo_, drawn_hi_;
  float drawn_gamma_ = 0.f;
  NoiseKey drawn_key_{};
  std::uint32_t drawn_iteration_ = 0;
  NoiseFilter drawn_filter_;
  std::size_t partial_stride_ = 0;
  std::vector<detail::ChunkTotals> totals_;
  std::vector<double> sums_, scales_;

  // ---- the ancillary feedback: the model linearised along the plan (mppi/linearize.hpp) and
  // the time-varying LQR on it (mppi/lqr.hpp)
 public:
  bool supports_feedback() const override { return true; }
  // One chunk rolled out with the plan in every lane (lane 0's cost is taken): a thirtieth of
  // an iteration at K = 1920. Uses the first thread's work slice (iterate() is not running).
  bool plan_cost(std::span<const float> x0, std::span<const float> plan, float* cost, std::string* why) override {
    const std::size_t rows = static_cast<std::size_t>(shape_.horizon) * D::kNu;
    if (x0.size() != static_cast<std::size_t>(D::kNx) || plan.size() != rows) {
      if (why) *why = "cpu backend: plan_cost needs x0 of num_states and a T x nu plan";
      return false;
    }
    for (std::size_t r = 0; r < rows; ++r) std::fill_n(plan_lanes_.get() + r * kChunk, kChunk, plan[r]);
    alignas(64) float lane_costs[kChunk];
    detail::rollout_chunk(model_, cost_, x0.data(), plan_lanes_.get(), kChunk, shape_.horizon, dt_s_, 0,
                          work_.data(), lane_costs);
    *cost = lane_costs[0];
    return true;
  }

  bool ancillary_gains(std::span<const float> x0, std::span<const float> nominal,
                       const AncillaryWeights& w, std::span<float> states_out,
                       std::span<float> gains_out, std::string* why) override {
    constexpr int Nx = D::kNx, Nu = D::kNu;
    const int T = shape_.horizon;
    auto fail = [&](const std::string& reason) {
      if (why) *why = std::string(name()) + " backend: ancillary gains: " + reason;
      return false;
    };
    auto size_error = [&](const char* arg, std::size_t got, std::size_t need, const char* layout) {
      return fail(std::string(arg) + " has " + std::to_string(got) + " floats, need " + layout + " = " +
                  std::to_string(need));
    };
    const auto t_count = static_cast<std::size_t>(T);
    if (x0.size() != Nx) return size_error("x0", x0.size(), Nx, "num_states");
    if (nominal.size() != t_count * Nu) return size_error("nominal", nominal.size(), t_count * Nu, "T x nu");
    if (states_out.size() != (t_count + 1) * Nx)
      return size_error("states_out", states_out.size(), (t_count + 1) * Nx, "(T+1) x nx");
    if (gains_out.size() != t_count * Nu * Nx)
      return size_error("gains_out", gains_out.size(), t_count * Nu * Nx, "T x nu x nx");
    for (std::size_t i = 0; i < x0.size(); ++i)
      if (!std::isfinite(x0[i])) return fail("x0[" + std::to_string(i) + "] is not finite");
    for (std::size_t i = 0; i < nominal.size(); ++i)
      if (!std::isfinite(nominal[i]))
        return fail("nominal[" + std::to_string(i) + "] (t = " + std::to_string(i / Nu) + ") is not finite");
    std::string reason;  // empty (no allocation) unless a check fails
    if (!check_ancillary_weights(w, Nx, Nu, &reason)) return fail(reason);
    if (ancillary_.scratch.empty()) {  // first call: everything the later calls need
      ancillary_.scratch.assign(linearize_scratch_floats(model_), 0.f);
      ancillary_.a.assign(t_count * Nx * Nx, 0.f);
      ancillary_.b.assign(t_count * Nx * Nu, 0.f);
      ancillary_.q.assign(Nx, 0.f);
      ancillary_.qf.assign(Nx, 0.f);
      ancillary_.r.assign(Nu, 0.f);
      ancillary_.lqr.resize(Nx, Nu);
    }
    linearize_along(model_, x0.data(), nominal.data(), T, dt_s_, states_out.data(), ancillary_.a.data(),
                    ancillary_.b.data(), ancillary_.scratch.data());
    for (std::size_t i = 0; i < states_out.size(); ++i)
      if (!std::isfinite(states_out[i]))
        return fail("the rollout of the nominal is not finite at t = " + std::to_string(i / Nx));
    for (int i = 0; i < Nx; ++i) {
      ancillary_.q[i] = w.q_diag.empty() ? 1.f : w.q_diag[i];
      ancillary_.qf[i] = w.terminal_scale * ancillary_.q[i];
    }
    for (int c = 0; c < Nu; ++c) ancillary_.r[c] = w.r_diag.empty() ? 1.f : w.r_diag[c];
    const LqrProblem<float> problem{T, Nx, Nu, ancillary_.a, ancillary_.b, ancillary_.q, ancillary_.r,
                                    ancillary_.qf};
    if (!solve_lqr(problem, ancillary_.lqr, gains_out, &reason)) return fail(reason);
    return true;
  }

 private:
  // ancillary_gains(): sized on its first call, reused after (no allocation then).
  struct AncillaryWork {
    std::vector<float> scratch;   // linearize_scratch_floats(model_)
    std::vector<float> a, b;      // T x nx x nx, T x nx x nu
    std::vector<float> q, qf, r;  // the weights' diagonals
    LqrWorkspace lqr;
  };
  AncillaryWork ancillary_;
  AlignedFloats plan_lanes_;  // plan_cost(): the plan in every lane (T x nu x kChunk)
};

}  // namespace mppi
