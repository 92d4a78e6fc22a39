#pragma once
// The nominal model a diagnosis starts from, as a family of "nominal + effects" models: one
// member per set of effect values: WithEffects<Model> (dynamics/with_effects.hpp) around any of
// CorrectedNominalModels (tyre effects only where there are tyres).
// The replay and the fits see a member through ReplayModel: one state vector stepped one sample
// at a time, or kLanes of them side by side stepped together in SIMD (many segments of a
// recording replayed at once, as the controller's rollouts run). One virtual call per step or
// per row of lanes, never per lane.
#include <memory>
#include <string>
#include <vector>

#include "dynamics/corrected_model.hpp"

namespace mppi::diagnose {

// What a recording's sensors add to the car's true states (the sensor effects of
// dynamics/effects.hpp); the replay reads measurements through it and predicts measurements.
struct SensorFaults {
  double gyro_bias_radps = 0.0;  // measured yaw rate = r + b
  double speed_scale = 1.0;      // measured vx, vy = s x true
  double time_offset_s = 0.0;    // states stamped this late against the commands
  static SensorFaults of(const EffectParams& e) { return {e.gyro_bias_radps, e.speed_scale, e.time_offset_s}; }
};

// Pure command delays [s] that the replay realises exactly, by reading each command that much
// earlier in the recording; the member's own delay stages are then off. (A controller's rollout
// has no recorded past to read and realises the same delay with its chain of delay stages.)
struct CommandDelays {
  double steer_s = 0.0;
  double throttle_s = 0.0;
};

class ReplayModel {
 public:
  static constexpr int kMaxStates = 64;
  static constexpr int kLanes = 16;  // states stepped together by step_lanes
  SensorFaults sensor;
  CommandDelays command_delay;
  virtual ~ReplayModel() = default;
  virtual int states() const = 0;        // <= kMaxStates
  virtual int time_index() const = 0;    // the state that holds time [s] (grip changes)
  virtual void init_state(const VehicleState& s, float* x) const = 0;
  virtual void set_actuators(float* x, float steer, float throttle) const = 0;  // steady command
  virtual void advance_actuators(float* x, float steer, float throttle, float dt_s) const = 0;
  virtual void step(float* x, float steer, float throttle, float dt_s) const = 0;
  // `substeps` steps of dt_s each for kLanes states side by side: state i of lane j at
  // x[i * kLanes + j]; the commands u[j] (steer) and u[kLanes + j] (throttle).
  virtual void step_lanes(float* x, const float* u, float dt_s, int substeps) const = 0;
};

class ModelFamily {
 public:
  virtual ~ModelFamily() = default;
  virtual const std::string& name() const = 0;  // one of kCorrectedNominalModels
  // The member with these effects; throws mppi::Error where the values make the model invalid.
  virtual std::unique_ptr<ReplayModel> make(const EffectParams& effects) const = 0;
  // Whether the candidate effect exists for this base (tyre effects need a tyre model).
  virtual bool supports(const std::string& effect_id) const { (void)effect_id; return true; }
  // The corrected-model file of a member (corrected_model_to_yaml's input).
  virtual CorrectedModelFile file(const EffectParams& effects, const std::vector<std::string>& selected) const = 0;
};

// One of kCorrectedNominalModels with parameters from `params_path`: that model's YAML (for
// autorally-nn the network's .npz), or a corrected-model file whose nominal part is used; empty
// = the library defaults. Throws mppi::Error naming the model or file.
std::unique_ptr<ModelFamily> make_model_family(const std::string& model, const std::string& params_path = "");

// The family of a corrected-model file's nominal model (its effects are ignored).
std::unique_ptr<ModelFamily> model_family_of(const CorrectedModelFile& file);


}  // namespace mppi::diagnose
