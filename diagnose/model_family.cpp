#include "diagnose/model_family.hpp"

#include <fstream>
#include <sstream>
#include <type_traits>

#include "base/multiversion.hpp"
#include "dynamics/with_effects.hpp"
#include "dynamics/model_registry.hpp"
#include "base/error.hpp"
#include "sim/data_dir.hpp"

namespace mppi::diagnose {
namespace {

// The lanes' steps, compiled for AVX-512, AVX2 and the baseline and chosen at load time.
template <class M>
MPPI_MULTIVERSION void step_lanes_kernel(const M& m, float* x, const float* u, float dt_s, int substeps,
                                         float* scratch) {
  constexpr int W = ReplayModel::kLanes;
  for (int i = 0; i < substeps; ++i) m.template step<W>(Batch<M::kNx, W>{x}, ConstBatch<2, W>{u}, dt_s, scratch);
}

template <class M>
class ReplayModelOf final : public ReplayModel {
 public:
  explicit ReplayModelOf(M m)
      : m_(std::move(m)), scratch_(m_.scratch_floats(1)), lane_scratch_(m_.scratch_floats(kLanes)) {
    static_assert(M::kNx <= kMaxStates, "raise ReplayModel::kMaxStates");
  }
  int states() const override { return M::kNx; }
  int time_index() const override { return M::kTime; }
  void init_state(const VehicleState& s, float* x) const override { m_.init_state(s, x); }
  void set_actuators(float* x, float steer, float throttle) const override { M::set_actuators(x, steer, throttle); }
  void advance_actuators(float* x, float steer, float throttle, float dt_s) const override {
    m_.advance_actuators(x, steer, throttle, dt_s);
  }
  void step(float* x, float steer, float throttle, float dt_s) const override {
    const float u[2] = {steer, throttle};
    m_.template step<1>(Batch<M::kNx, 1>{x}, ConstBatch<2, 1>{u}, dt_s, scratch_.data());
  }
  void step_lanes(float* x, const float* u, float dt_s, int substeps) const override {
    step_lanes_kernel(m_, x, u, dt_s, substeps, lane_scratch_.data());
  }

 private:
  M m_;
  mutable std::vector<float> scratch_, lane_scratch_;  // the model's per-step work space (the network's layers)
};

// WithEffects<Base> around the nominal model; `file` carries its parameters.
template <class Base>
class WrappedFamily final : public ModelFamily {
 public:
  WrappedFamily(Base nominal, CorrectedModelFile file) : nominal_(std::move(nominal)), file_(std::move(file)) {
    WithEffects<Base> check(nominal_);
  }
  const std::string& name() const override { return file_.nominal_model; }
  std::unique_ptr<ReplayModel> make(const EffectParams& e) const override {
    EffectParams chained = e;  // the delays are the replay's (exact); the rest is the member's
    chained.steer_delay_s = 0.0;
    chained.throttle_delay_s = 0.0;
    auto m = std::make_unique<ReplayModelOf<WithEffects<Base>>>(WithEffects<Base>(nominal_, chained));
    m->sensor = SensorFaults::of(e);
    m->command_delay = {e.steer_delay_s, e.throttle_delay_s};
    return m;
  }
  bool supports(const std::string& effect_id) const override {
    // Only the single-track can drive its front axle; the four-wheel models refuse a drive split.
    if (effect_id == "drive_split") return requires { Base::kOmegaFront; };
    return WithEffects<Base>::kChassisEffects || effect_spec(effect_id).hook != EffectHook::kChassis;
  }
  CorrectedModelFile file(const EffectParams& e, const std::vector<std::string>& selected) const override {
    CorrectedModelFile f = file_;
    f.effects = e;
    f.selected = selected;
    return f;
  }

 private:
  Base nominal_;
  CorrectedModelFile file_;
};

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error("cannot open nominal parameter file '" + path + "'");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A parameter file's text into the section of `f` the nominal model D is built from (as
// corrected_nominal reads them; the single-track's for the others).
template <class D>
void read_nominal_params(CorrectedModelFile& f, const std::string& text, const std::string& source) {
  using M = typename D::Model;
  if constexpr (std::is_constructible_v<M, const DoubleTrackParams&>)
    f.double_track = double_track_params_from_yaml(text, source);
  else if constexpr (std::is_constructible_v<M, const FullVehicleParams&>)
    f.full_vehicle = full_vehicle_params_from_yaml(text, source);
  else if constexpr (std::is_constructible_v<M, const KinematicBicycleParams&>)
    f.kinematic = kinematic_bicycle_params_from_yaml(text, source);
  else
    f.nominal = single_track_params_from_yaml(text, source);
}

}  // namespace

std::unique_ptr<ModelFamily> model_family_of(const CorrectedModelFile& file) {
  CorrectedModelFile f = file;
  f.effects = {};
  f.selected.clear();
  std::unique_ptr<ModelFamily> family;
  const bool known = visit_by_name(CorrectedNominalModels{}, f.nominal_model, [&]<class D>() {
    using Base = typename D::Model;
    family = std::make_unique<WrappedFamily<Base>>(corrected_nominal<D>(f, sim::network_file_or_default(f.network_npz)), f);
  });
  if (!known)
    throw Error("nominal model '" + f.nominal_model + "' cannot be diagnosed (valid: " + kCorrectedNominalModels + ")");
  return family;
}

std::unique_ptr<ModelFamily> make_model_family(const std::string& model, const std::string& params_path) {
  if (!is_corrected_nominal_model(model))
    throw Error("nominal model '" + model + "' cannot be diagnosed (valid: " + kCorrectedNominalModels + ")");
  CorrectedModelFile f;
  f.nominal_model = model;
  bool weights_model = false;  // its data are weights (.npz), not a parameter table
  visit_by_name(CorrectedNominalModels{}, model, [&]<class D>() { weights_model = !HasParamTable<D>; });
  if (weights_model && !params_path.empty() && params_path.size() > 4 &&
      params_path.substr(params_path.size() - 4) == ".npz") {
    f.network_npz = params_path;  // the network's weights
  } else if (!params_path.empty()) {
    const std::string text = read_text(params_path);
    if (text.find("nominal_params") != std::string::npos) {  // a corrected-model file: its nominal part
      f = corrected_model_from_yaml(text, params_path);
      if (f.nominal_model != model)
        throw Error(params_path + ": a corrected model of a " + f.nominal_model + " nominal, but --model is " + model);
    } else {
      visit_by_name(CorrectedNominalModels{}, model, [&]<class D>() { read_nominal_params<D>(f, text, params_path); });
    }
  }
  return model_family_of(f);
}

}  // namespace mppi::diagnose
