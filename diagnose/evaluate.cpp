// mppi-fit evaluate: a written corrected model against its nominal model on a recording.
#include "diagnose/evaluate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <type_traits>

#include "base/error.hpp"
#include "diagnose/model_family.hpp"
#include "dynamics/corrected_model.hpp"
#include "dynamics/model_registry.hpp"

namespace mppi::diagnose {

namespace {

std::string number_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

// The recording's metadata value as a number; false where absent or not a positive number.
bool metadata_number(const PreparedRecording& d, const std::string& key, double* value) {
  const auto it = d.metadata.find(key);
  if (it == d.metadata.end()) return false;
  try {
    std::size_t used = 0;
    *value = std::stod(it->second, &used);
    return used == it->second.size() && std::isfinite(*value) && *value > 0;
  } catch (const std::exception&) {
    return false;
  }
}

// Models built from the single-track parameters or from a four-wheel set around them (as
// corrected_nominal builds them): the file's `nominal` holds their mass and geometry.
template <class D>
constexpr bool kHasSingleTrackCore = std::is_constructible_v<typename D::Model, const SingleTrackParams&> ||
                                     std::is_constructible_v<typename D::Model, const DoubleTrackParams&> ||
                                     std::is_constructible_v<typename D::Model, const FullVehicleParams&>;

// The single-track parameters that carry the model's mass and geometry, or nullptr where the
// model has none (the network, the kinematic bicycle: its wheelbase is returned apart).
const SingleTrackParams* vehicle_core(const CorrectedModelFile& m) {
  bool has_core = true;
  visit_by_name(CorrectedNominalModels{}, m.nominal_model, [&]<class D>() { has_core = kHasSingleTrackCore<D>; });
  return has_core ? &m.nominal : nullptr;
}

// The wheelbase of a model built from the kinematic bicycle's parameters; empty for the others.
std::optional<double> kinematic_wheelbase(const CorrectedModelFile& m) {
  std::optional<double> wheelbase;
  visit_by_name(CorrectedNominalModels{}, m.nominal_model, [&]<class D>() {
    if constexpr (std::is_constructible_v<typename D::Model, const KinematicBicycleParams&>)
      wheelbase = m.kinematic.wheelbase_m;
  });
  return wheelbase;
}

void check_close(const std::string& what, double model_value, double recording_value, double tolerance,
                 const std::string& model_source, const PreparedRecording& d) {
  if (std::abs(model_value - recording_value) <= tolerance * recording_value) return;
  throw Error(model_source + " and " + d.source + " are not of the same car: " + what + " " +
              number_text(model_value) + " in the model, " + number_text(recording_value) +
              " in the recording's metadata (more than " + number_text(100 * tolerance) + " % apart)");
}

}  // namespace

std::map<std::string, std::string> fitted_on_of(const PreparedRecording& d) {
  std::map<std::string, std::string> f;
  f["source"] = d.source;
  const auto vehicle = d.metadata.find("vehicle");
  if (vehicle != d.metadata.end()) f["vehicle"] = vehicle->second;
  f["throttle_command"] = d.speed_command ? "speed" : "throttle";
  f["dt_s"] = number_text(d.dt_s);
  return f;
}

void check_model_matches_recording(const CorrectedModelFile& model, const std::string& model_source,
                                   const PreparedRecording& d, const EvaluateOptions& o) {
  const auto fitted_vehicle = model.fitted_on.find("vehicle");
  const auto recorded_vehicle = d.metadata.find("vehicle");
  if (fitted_vehicle != model.fitted_on.end() && recorded_vehicle != d.metadata.end() &&
      fitted_vehicle->second != recorded_vehicle->second)
    throw Error(model_source + " and " + d.source + " are not of the same car: the model was fitted on vehicle '" +
                fitted_vehicle->second + "' (fitted_on.vehicle), the recording is of '" + recorded_vehicle->second +
                "' (# vehicle:)");
  const auto command = model.fitted_on.find("throttle_command");
  const std::string recorded_command = d.speed_command ? "speed" : "throttle";
  if (command != model.fitted_on.end() && command->second != recorded_command)
    throw Error(model_source + " and " + d.source + " do not match: the model was fitted on a throttle column that "
                "holds " + command->second + " commands (fitted_on.throttle_command), the recording's holds " +
                recorded_command + " commands (# throttle_command:)");
  double recorded = 0;
  if (const SingleTrackParams* car = vehicle_core(model)) {
    if (metadata_number(d, "mass_kg", &recorded))
      check_close("mass [kg]", car->mass_kg, recorded, o.geometry_tolerance, model_source, d);
    if (metadata_number(d, "wheelbase_m", &recorded))
      check_close("wheelbase [m]", car->cg_to_front_axle_m + car->cg_to_rear_axle_m, recorded, o.geometry_tolerance,
                  model_source, d);
  } else if (const std::optional<double> wheelbase = kinematic_wheelbase(model);
             wheelbase && metadata_number(d, "wheelbase_m", &recorded)) {
    check_close("wheelbase [m]", *wheelbase, recorded, o.geometry_tolerance, model_source, d);
  }
}

EvaluateResult evaluate_corrected_model(const CorrectedModelFile& model, const std::string& model_source,
                                        const PreparedRecording& d, const EvaluateOptions& o) {
  check_model_matches_recording(model, model_source, d, o);
  std::vector<char> mask(d.rows(), 1);
  if (o.rows != "all") mask = make_split(d, o.rows).heldout;
  const auto rows_scored = static_cast<std::size_t>(std::count(mask.begin(), mask.end(), 1));
  if (rows_scored == 0) throw Error(d.source + ": no rows to score for --rows '" + o.rows + "'");
  const auto family = model_family_of(model);
  return {compare_models(*family->make({}), *family->make(model.effects), d, mask, o.horizons_s,
                         o.headline_horizon_s, o.replay),
          rows_scored};
}

}  // namespace mppi::diagnose
