#pragma once
// The single-track car on a surface map (sim/surface_map.hpp): at each step the tyre friction
// at the car's place is the model's Magic Formula times the local grip scale (D and S_v both
// scaled, so every tyre force and its limit mu_peak Fz scale by it), and gravity along the
// local grade adds its body-frame acceleration inside the force balance. For the simulator's
// plant (one lane at a time); the controller keeps its own model.
#include <cmath>
#include <map>
#include <memory>

#include "base/batch.hpp"
#include "dynamics/single_track.hpp"
#include "sim/surface_map.hpp"

namespace mppi::sim {

class SingleTrackOnSurface {
 public:
  static constexpr int kNx = SingleTrack::kNx;
  static constexpr int kNu = SingleTrack::kNu;

  SingleTrackOnSurface(const SingleTrackParams& params, std::shared_ptr<const SurfaceMap> surface)
      : params_(params), surface_(std::move(surface)), flat_model_(params) {
    if (!surface_) throw Error("SingleTrackOnSurface: no surface map");
  }

  std::size_t scratch_floats(int) const { return 0; }
  void init_state(const VehicleState& s, float* x) const { flat_model_.init_state(s, x); }

  template <int W>
  void step(Batch<kNx, W> x, ConstBatch<kNu, W> u, float dt_s, float* scratch) const noexcept {
    for (int j = 0; j < W; ++j) {
      float xs[kNx], us[kNu];
      for (int i = 0; i < kNx; ++i) xs[i] = x[i][j];
      for (int i = 0; i < kNu; ++i) us[i] = u[i][j];
      const double px = xs[state::kX], py = xs[state::kY];
      const Vec2 g = surface_->gravity_body_mps2(px, py, xs[state::kYaw], params_.gravity_mps2);
      const float ax = static_cast<float>(g.x), ay = static_cast<float>(g.y), no_yaw_accel = 0.f;
      model_for(surface_->grip(px, py))
          .template step_with_body_accel<1>(Batch<kNx, 1>{xs}, ConstBatch<kNu, 1>{us}, dt_s, scratch, &ax, &ay, &no_yaw_accel);
      for (int i = 0; i < kNx; ++i) x[i][j] = xs[i];
    }
  }

  // The tyre forces at (x, u) where the car stands (double, for tests and diagnostics).
  SingleTrackForces forces(const double* x, const double* u) const {
    return model_for(surface_->grip(x[state::kX], x[state::kY])).forces(x, u);
  }
  const SurfaceMap& surface() const { return *surface_; }
  const SingleTrackParams& params() const { return params_; }

 private:
  // The single-track model whose tyre is scaled by `grip` (quantised to 1/1000, built once).
  const SingleTrack& model_for(double grip) const noexcept {
    const int key = static_cast<int>(std::lround(grip * 1000));
    if (key == 1000) return flat_model_;
    auto it = scaled_.find(key);
    if (it == scaled_.end()) {
      SingleTrackParams p = params_;
      p.tyre.D *= key / 1000.0;
      p.tyre.Sv *= key / 1000.0;
      it = scaled_.emplace(key, SingleTrack(p)).first;  // valid: D > 0 stays > 0
    }
    return it->second;
  }

  SingleTrackParams params_;
  std::shared_ptr<const SurfaceMap> surface_;
  SingleTrack flat_model_;
  mutable std::map<int, SingleTrack> scaled_;
};

}  // namespace mppi::sim
