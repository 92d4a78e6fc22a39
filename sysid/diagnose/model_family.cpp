#include "sysid/diagnose/model_family.hpp"

#include <fstream>
#include <sstream>

#include "dynamics/with_effects.hpp"
#include "mppi/error.hpp"

namespace mppi::diagnose {
namespace {

template <class M>
class ReplayModelOf final : public ReplayModel {
 public:
  explicit ReplayModelOf(M m) : m_(std::move(m)) {
    static_assert(M::kNx <= kMaxStates, "raise ReplayModel::kMaxStates");
    if (m_.scratch_floats(1) != 0) throw Error("ReplayModel: models that need scratch memory are not supported");
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
    m_.template step<1>(Batch<M::kNx, 1>{x}, ConstBatch<2, 1>{u}, dt_s, nullptr);
  }

 private:
  M m_;
};

class SingleTrackFamily final : public ModelFamily {
 public:
  explicit SingleTrackFamily(const SingleTrackParams& p) : p_(p) { CorrectedSingleTrack check(p_); }
  const std::string& name() const override { return name_; }
  std::unique_ptr<ReplayModel> make(const EffectParams& e) const override {
    return std::make_unique<ReplayModelOf<CorrectedSingleTrack>>(CorrectedSingleTrack(p_, e));
  }
  CorrectedModelFile file(const EffectParams& e, const std::vector<std::string>& selected) const override {
    CorrectedModelFile f;
    f.nominal = p_;
    f.effects = e;
    f.selected = selected;
    return f;
  }

 private:
  SingleTrackParams p_;
  std::string name_ = "single-track";
};

template <class Base>
class FourWheelFamily final : public ModelFamily {
 public:
  using Params = typename WithEffects<Base>::Params;
  FourWheelFamily(const Params& p, std::string name) : p_(p), name_(std::move(name)) { WithEffects<Base> check(p_); }
  const std::string& name() const override { return name_; }
  std::unique_ptr<ReplayModel> make(const EffectParams& e) const override {
    return std::make_unique<ReplayModelOf<WithEffects<Base>>>(WithEffects<Base>(p_, e));
  }
  CorrectedModelFile file(const EffectParams& e, const std::vector<std::string>& selected) const override {
    CorrectedModelFile f;
    f.nominal_model = name_;
    f.nominal = p_.base;
    if constexpr (std::is_same_v<Base, DoubleTrack>) f.double_track = p_;
    else f.full_vehicle = p_;
    f.effects = e;
    f.selected = selected;
    return f;
  }

 private:
  Params p_;
  std::string name_;
};

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error("cannot open nominal parameter file '" + path + "'");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

std::unique_ptr<ModelFamily> model_family_of(const CorrectedModelFile& f) {
  if (f.nominal_model == "double-track") return std::make_unique<FourWheelFamily<DoubleTrack>>(f.double_track, f.nominal_model);
  if (f.nominal_model == "full-vehicle") return std::make_unique<FourWheelFamily<FullVehicle>>(f.full_vehicle, f.nominal_model);
  return std::make_unique<SingleTrackFamily>(f.nominal);
}

std::unique_ptr<ModelFamily> make_model_family(const std::string& model, const std::string& params_path) {
  if (model != "single-track" && model != "double-track" && model != "full-vehicle")
    throw Error("nominal model '" + model + "' cannot be diagnosed (valid: " + kDiagnoseModels + ")");
  CorrectedModelFile f;
  f.nominal_model = model;
  if (!params_path.empty()) {
    const std::string text = read_text(params_path);
    if (text.find("nominal_params") != std::string::npos) {  // a corrected-model file: its nominal part
      f = corrected_model_from_yaml(text, params_path);
      if (f.nominal_model != model)
        throw Error(params_path + ": a corrected model of a " + f.nominal_model + " nominal, but --model is " + model);
    } else if (model == "double-track") {
      f.double_track = double_track_params_from_yaml(text, params_path);
    } else if (model == "full-vehicle") {
      f.full_vehicle = full_vehicle_params_from_yaml(text, params_path);
    } else {
      f.nominal = single_track_params_from_yaml(text, params_path);
    }
  }
  return model_family_of(f);
}

}  // namespace mppi::diagnose
