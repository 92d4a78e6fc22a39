#pragma once
// The "bare limit" of an MPPI rollout with the AutoRally network: the 6-32-32-4 tanh MLP
// evaluated over the same K x T lanes as the controller, with nothing else - no noise, no cost,
// no kinematics. The network's 4 outputs (d/dt of roll, u_x, u_y, yaw_mder) are Euler-integrated
// back into its 4 state inputs, so every step depends on the last and nothing can be optimised
// away. Hand-tuned: 64-lane chunks as 4 x 16-float vectors (one AVX-512 register each), every
// layer as blocks of 4 units x 4 vectors = 16 accumulators kept in registers with broadcast
// weights, tanh (mppi::fast_tanh96's rational) applied to the accumulators before they are
// stored, OpenMP over chunks, MPPI_MULTIVERSION so the x86-64-v4 clone runs on AVX-512 machines.
// bf16 = true: the same with bf16 hidden layers (bare_limit_bf16.cpp).
// It is the yardstick for BM_MppiIteration: what the hardware can do for the network alone.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace mppi::bench {

// The AutoRally network's weights, (out, in) row-major like the npz, as float.
struct MlpWeights {
  static constexpr int kIn = 6, kHidden = 32, kOut = 4;
  float w1[kHidden][kIn];
  float b1[kHidden];
  float w2[kHidden][kHidden];
  float b2[kHidden];
  float w3[kOut][kHidden];
  float b3[kOut];
};

// Layers 2 and 3 as bf16 pairs for the bf16 bare kernel: word p of row o =
// bf16(w[o][2p]) | bf16(w[o][2p + 1]) << 16, round to nearest even.
struct BareBf16Weights {
  std::uint32_t w2[MlpWeights::kHidden][MlpWeights::kHidden / 2];
  std::uint32_t w3[MlpWeights::kOut][MlpWeights::kHidden / 2];
};

namespace detail {
// bare_limit_bf16.cpp: one chunk of the bf16 bare kernel, and whether this CPU can run it.
void bare_chunk_bf16(const MlpWeights& w, const BareBf16Weights& wb, const float* init, float* out,
                     int padded, int k0, int steps, float dt) noexcept;
bool cpu_has_bf16();
}  // namespace detail

// Reads dynamics_W1..b3 from an AutoRally network npz (throws mppi::Error on a bad file).
MlpWeights load_mlp_weights(const std::string& npz_path);

class BareLimit {
 public:
  static constexpr int kLanes = 64;  // lanes per chunk (one OpenMP work item)

  // bf16: the bf16 kernel (bare_limit_bf16.cpp); throws mppi::Error if the CPU has no
  // AVX512-BF16 (see bf16_supported()).
  BareLimit(const MlpWeights& weights, int num_samples, int horizon, float dt_s, int threads,
            bool bf16 = false);
  static bool bf16_supported() { return detail::cpu_has_bf16(); }

  // Runs the network over every lane for `horizon` steps from the initial inputs (each call
  // starts again from them). Results in final_state().
  void run();
  // Same lanes, naive scalar code in double with std::tanh, for `steps` steps of lane k;
  // returns the 4 states after them.
  std::vector<double> reference(int k, int steps) const;
  // Runs the fast kernel for `steps` steps only (for the check against reference()).
  void run_steps(int steps);

  // State s (0..3: roll, u_x, u_y, yaw_mder) of lane k after the last run.
  float final_state(int s, int k) const { return out_[static_cast<std::size_t>(s) * padded_ + k]; }
  double checksum() const;
  int num_samples() const { return num_samples_; }
  int padded_samples() const { return padded_; }
  int horizon() const { return horizon_; }
  int threads() const { return threads_; }
  // Which code path the run-time dispatch picked ("x86-64-v4 (AVX-512)", ...).
  static const char* dispatched_isa();

 private:
  MlpWeights w_;
  BareBf16Weights wb_{};
  bool bf16_ = false;
  int num_samples_, padded_, horizon_, threads_;
  float dt_s_;
  std::vector<float> init_;  // 6 x padded: initial roll, u_x, u_y, yaw_mder, steer, throttle
  std::vector<float> out_;   // 4 x padded: the states after the last run
};

}  // namespace mppi::bench
