#pragma once
// How an effect of the sim-vs-real tool is described: its parameters (name, unit, the range a
// model accepts, the range a fit searches, a typical size), where it enters the physics (its
// hook), what a recording must contain to identify it, and the actuator or partner it goes with.
// The effect table (dynamics/effects.hpp) holds one EffectSpec per effect. An effect declared in a
// file of its own (dynamics/effects/) states the same in an EffectDecl over its own parameter
// struct; the table converts it.
#include <string>
#include <vector>

#include "base/param_table.hpp"

namespace mppi {

struct EffectParams;  // every effect's parameters (dynamics/effects.hpp)

// Where an effect enters the physics of WithEffects<Model>.
enum class EffectHook {
  kActuator,  // transforms the command before the model sees it
  kChassis,   // changes the model's tyre / chassis parameters (models with a single-track core)
  kForce,     // adds a force along the body axes (inside the force balance where the model
              // offers it, else after the model's step)
  kSensor,    // changes what the recording shows (measured states, time stamps), not the car
};

// One parameter of an effect, a member of Owner: EffectParams in the effect table, the effect's own
// parameter struct in a file of its own (EffectParams derives from it).
template <class Owner>
struct BasicEffectParamSpec {
  const char* name;             // key in the corrected-model file (EffectParams field)
  double Owner::*member;
  const char* unit;
  Range valid;                  // values a model accepts (is_valid)
  double lo, hi;                // range a fit searches (fits are projected onto it)
  double scale;                 // typical size: finite-difference step = 0.01 scale
};
using EffectParamSpec = BasicEffectParamSpec<EffectParams>;

// What a recording must contain for an effect to be identifiable from it (the diagnosis
// measures it on the data; diagnose/identifiability.hpp).
enum class Excitation {
  kAny,         // any driving
  kSteer,       // steering that changes (and turns the car). Also what a steering trim and a
                // gyro bias need: at one steering command the trim, the steering gain, the tyre
                // and a yaw-rate bias all give one number, the steady yaw-rate error there
  kThrottle,    // throttle that changes (and changes the speed)
  kCornering,   // lateral acceleration towards the tyres' limit
  kSpeedRange,  // a range of speeds (speed-dependent forces)
  kBraking,     // longitudinal acceleration and braking (pitch load transfer)
  kSpeedCommand,  // a throttle channel that the recording declares a speed command (its metadata
                  // line `# throttle_command: speed`): a stack that commands speeds, not throttle
};

// Leading parameters that a fit searches over the data instead of fitting them by least squares
// (they move where an effect acts, and the cost is flat far from the right value).
enum class DataGrid {
  kNone,
  kTime,   // params[0] is a time within the recording
  kPlace,  // params[0], params[1] are a place (x, y) the car visited
};
inline int grid_param_count(DataGrid g) { return g == DataGrid::kTime ? 1 : g == DataGrid::kPlace ? 2 : 0; }

// An effect; Owner holds its parameters (as for BasicEffectParamSpec).
template <class Owner>
struct BasicEffectSpec {
  std::string id;               // effect id, e.g. "steer_delay"
  std::string description;      // one line, physical meaning
  EffectHook hook;
  std::vector<BasicEffectParamSpec<Owner>> params;
  std::vector<double> grid;     // start values searched for params[0] (empty: its default)
  DataGrid data_grid = DataGrid::kNone;  // leading params searched over the data (not LM-fitted)
  Excitation needs = Excitation::kAny;
  // The actuator whose dynamics this is ("steer", "throttle"; empty: none). A delay, a lag, a rate
  // limit and a play of one actuator all hold back its response, and a recording with smooth
  // commands may not tell these forms apart.
  std::string dynamics_of = {};
  // An effect fitted together with this one as a joint candidate as well (empty: none): partner
  // terms of one map (a gain and its offset) each take up part of the other's error alone.
  std::string partner = {};
  // In the diagnosis' default candidate library (false: a candidate only where asked for by name).
  bool default_candidate = true;
};
using EffectSpec = BasicEffectSpec<EffectParams>;

// The declaration of an effect in a file of its own: its spec over the members of its own
// parameter struct P; the effect table converts it (effect_spec_of, dynamics/effects.hpp).
template <class P>
using EffectDecl = BasicEffectSpec<P>;

// Body-axis accelerations of a step, per lane, as an effect's force term sees and adds to them:
// the start-of-step velocities and applied steer (normalised), and the sums it adds to.
template <int W>
struct BodyAccelLanes {
  const float* vx_mps;
  const float* vy_mps;
  const float* yaw_rate_radps;
  const float* applied_steer;
  float* ax_mps2;
  float* ay_mps2;
  float* yaw_accel_radps2;
};

}  // namespace mppi
