#pragma once
// AutoRally's basis-function dynamics model (basis_function_09_12_2018.npz, AutoRally's
// GeneralizedLinear<CarBasisFuncs, 7, 2, 25, CarKinematics, 3>): the time derivatives of the
// body states are a linear combination of 25 hand-made basis functions of the state and the
// controls,
//   d/dt [roll, u_x, u_y, yaw_mder] = W phi(s, u),   W: 4 x 25 (the npz's "W"),
// and the pose follows by kinematics; explicit Euler at dt, every derivative from the state at
// the start of the step (as the network model, dynamics/autorally_nn.hpp).
//
// The basis functions are written in AutoRally's conventions: s = [x, y, yaw, roll, u_x, u_y,
// yaw_mder] with yaw_mder = minus the yaw rate, and steering u_0 positive to the RIGHT, used
// as an angle [rad]. step() maps the library's state (yaw rate CCW positive, steer positive
// left) into them and the derivative of yaw_mder back. With beta = atan((u_y + 0.45 yaw_mder)
// / u_x) (the front-axle slip direction), t = tan(beta - u_0), q = (u_y - 0.35 yaw_mder) / u_x:
//   phi =  throttle, u_x/10, sin(u_0) t/1200, sin(u_0) t|t|/1200^2, sin(u_0) t^3/1200^3 ... (see
//   dynamics/autorally_bf_features.hpp for all 25, in order); below u_x = 0.1 m/s the ratios
//   are replaced by 0.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <string>

#include "base/batch.hpp"
#include "base/error.hpp"
#include "base/npz.hpp"
#include "dynamics/fast_trig.hpp"
#include "mppi/vehicle_state.hpp"

namespace mppi {

class AutoRallyBasisFunctionModel {
 public:
  static constexpr int kNx = state::kCommonStates;  // 7: x, y, yaw, vx, vy, yaw_rate, roll
  static constexpr int kNu = 2;
  static constexpr int kBasis = 25;
  static constexpr int kOutputs = 4;  // d/dt roll, u_x, u_y, yaw_mder
  using Weights = std::array<float, kOutputs * kBasis>;  // row-major, AutoRally's conventions

  explicit AutoRallyBasisFunctionModel(const Weights& weights) : w_(weights) {
    for (float v : w_)
      if (!std::isfinite(v)) throw Error("AutoRallyBasisFunctionModel: a weight is NaN or infinite");
  }

  // Reads "W" (4 x 25) of an AutoRally basis-function npz; its other arrays (b = 0, P, Q) are
  // not used by the model. Throws mppi::Error naming the file and the array.
  static AutoRallyBasisFunctionModel load(const std::string& npz_path) {
    const NpzFile file = NpzFile::load(npz_path);
    const NpyArray& w = file.at("W", {kOutputs, kBasis});
    Weights weights{};
    for (std::size_t i = 0; i < weights.size(); ++i) {
      if (!std::isfinite(w.values[i]))
        throw Error(npz_path + ": array 'W' entry " + std::to_string(i) + " is NaN or infinite");
      weights[i] = static_cast<float>(w.values[i]);
    }
    if (file.contains("b")) {
      for (double b : file.at("b").values)
        if (b != 0.0) throw Error(npz_path + ": array 'b' is not zero (the model has no bias term)");
    }
    return AutoRallyBasisFunctionModel(weights);
  }

  const Weights& weights() const { return w_; }
  std::size_t scratch_floats(int) const { return 0; }

  // The 25 basis functions in AutoRally's conventions (s4 = u_x, s5 = u_y, s6 = yaw_mder,
  // s3 = roll, u0 = steering right-positive, u1 = throttle). Branch-free: one lane each.
  static void basis(float roll, float ux, float uy, float yaw_mder, float u0, float u1,
                    float* phi) noexcept {
    const bool moving = ux > 0.1f;
    const float inv_ux = 1.f / (moving ? ux : 1.f);
    const float beta = moving ? fast_atan((uy + 0.45f * yaw_mder) * inv_ux) : 0.f;
    float sa, ca, su, cu;
    fast_sincos(beta - u0, &sa, &ca);
    fast_sincos(u0, &su, &cu);
    const float t = sa / ca;  // tan(beta - u0)
    const float t_abs = t * std::abs(t);
    const float t3 = t * t * t;
    const float q = moving ? (uy - 0.35f * yaw_mder) * inv_ux : 0.f;
    using std::abs;  // the float one, for the shared list
#include "dynamics/autorally_bf_features.hpp"
  }

  template <int W>
  void step(Batch<kNx, W> x, ConstBatch<kNu, W> u, float dt_s, float* /*scratch*/) const noexcept {
    float* px = x[state::kX];
    float* py = x[state::kY];
    float* pyaw = x[state::kYaw];
    float* pvx = x[state::kVx];
    float* pvy = x[state::kVy];
    float* pr = x[state::kYawRate];
    float* proll = x[state::kRoll];
    const float* ps = u[control::kSteer];
    const float* pt = u[control::kThrottle];
    const float* w = w_.data();
    MPPI_SIMD_LOOP
    for (int j = 0; j < W; ++j) {
      const float vx = pvx[j], vy = pvy[j], r = pr[j], roll = proll[j];
      float phi[kBasis];
      basis(roll, vx, vy, -r, -ps[j], pt[j], phi);
      float d[kOutputs];
      for (int o = 0; o < kOutputs; ++o) {
        float acc = 0.f;
        for (int b = 0; b < kBasis; ++b) acc += w[o * kBasis + b] * phi[b];
        d[o] = acc;
      }
      float s, c;
      fast_sincos(pyaw[j], &s, &c);
      px[j] += (c * vx - s * vy) * dt_s;
      py[j] += (s * vx + c * vy) * dt_s;
      pyaw[j] += r * dt_s;
      proll[j] = roll + d[0] * dt_s;
      pvx[j] = vx + d[1] * dt_s;
      pvy[j] = vy + d[2] * dt_s;
      pr[j] = r - d[3] * dt_s;  // d yaw_mder / dt = - d yaw_rate / dt
    }
  }

  // The model's state is exactly the common state.
  void init_state(const VehicleState& s, float* x) const {
    const auto common = s.to_array();
    std::copy(common.begin(), common.end(), x);
  }

 private:
  Weights w_;
};

}  // namespace mppi
