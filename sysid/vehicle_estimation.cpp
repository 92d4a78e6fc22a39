#include "sysid/vehicle_estimation.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>

#include "dynamics/double_track.hpp"
#include "dynamics/model_registry.hpp"
#include "dynamics/full_vehicle.hpp"
#include "dynamics/single_track.hpp"
#include "base/error.hpp"
#include "mppi/vehicle_state.hpp"

namespace mppi::sysid {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Field tables: YAML key -> member. Only the keys an estimator may sensibly change.
double* single_track_field(SingleTrackParams& p, const std::string& n) {
  static const std::map<std::string, double SingleTrackParams::*> m = {
      {"mass_kg", &SingleTrackParams::mass_kg},
      {"yaw_inertia_kgm2", &SingleTrackParams::yaw_inertia_kgm2},
      {"cg_to_front_axle_m", &SingleTrackParams::cg_to_front_axle_m},
      {"cg_to_rear_axle_m", &SingleTrackParams::cg_to_rear_axle_m},
      {"cg_height_m", &SingleTrackParams::cg_height_m},
      {"wheel_radius_m", &SingleTrackParams::wheel_radius_m},
      {"front_wheel_inertia_kgm2", &SingleTrackParams::front_wheel_inertia_kgm2},
      {"rear_wheel_inertia_kgm2", &SingleTrackParams::rear_wheel_inertia_kgm2},
      {"max_steer_rad", &SingleTrackParams::max_steer_rad},
      {"stall_torque_Nm", &SingleTrackParams::stall_torque_Nm},
      {"no_load_speed_mps", &SingleTrackParams::no_load_speed_mps},
      {"brake_torque_ratio", &SingleTrackParams::brake_torque_ratio},
      {"rolling_resistance", &SingleTrackParams::rolling_resistance},
      {"aero_drag_kgpm", &SingleTrackParams::aero_drag_kgpm},
      {"slip_speed_floor_mps", &SingleTrackParams::slip_speed_floor_mps},
      {"slip_blend", &SingleTrackParams::slip_blend},
      {"rear_tyre_B_scale", &SingleTrackParams::rear_tyre_B_scale},
      {"rear_tyre_C_scale", &SingleTrackParams::rear_tyre_C_scale},
      {"rear_tyre_D_scale", &SingleTrackParams::rear_tyre_D_scale}};
  static const std::map<std::string, double PacejkaParams::*> t = {
      {"tyre.B", &PacejkaParams::B}, {"tyre.C", &PacejkaParams::C}, {"tyre.D", &PacejkaParams::D},
      {"tyre.E", &PacejkaParams::E}, {"tyre.Sh", &PacejkaParams::Sh}, {"tyre.Sv", &PacejkaParams::Sv}};
  if (auto it = m.find(n); it != m.end()) return &(p.*(it->second));
  if (auto it = t.find(n); it != t.end()) return &(p.tyre.*(it->second));
  return nullptr;
}

double* full_vehicle_field(FullVehicleParams& p, const std::string& n) {
  static const std::map<std::string, double FullVehicleParams::*> m = {
      {"front_track_m", &FullVehicleParams::front_track_m},
      {"rear_track_m", &FullVehicleParams::rear_track_m},
      {"front_spring_Npm", &FullVehicleParams::front_spring_Npm},
      {"rear_spring_Npm", &FullVehicleParams::rear_spring_Npm},
      {"front_damper_Nspm", &FullVehicleParams::front_damper_Nspm},
      {"rear_damper_Nspm", &FullVehicleParams::rear_damper_Nspm},
      {"sprung_cg_height_m", &FullVehicleParams::sprung_cg_height_m},
      {"roll_centre_height_m", &FullVehicleParams::roll_centre_height_m},
      {"roll_inertia_kgm2", &FullVehicleParams::roll_inertia_kgm2},
      {"pitch_inertia_kgm2", &FullVehicleParams::pitch_inertia_kgm2},
      {"drag_coefficient", &FullVehicleParams::drag_coefficient}};
  if (auto it = m.find(n); it != m.end()) return &(p.*(it->second));
  if (n == "aero_drag_kgpm") return nullptr;  // the full vehicle's drag is drag_coefficient
  return single_track_field(p.base, n);
}

double* double_track_field(DoubleTrackParams& p, const std::string& n) {
  if (n == "front_track_m") return &p.front_track_m;
  if (n == "rear_track_m") return &p.rear_track_m;
  if (n == "front_roll_share") return &p.front_roll_share;
  return single_track_field(p.base, n);
}

// The single-track's actuators as the calibration models them (the steering servo and the drive's
// response; the same terms as the effects steer_lag, throttle_lag, steer_cubic and steer_offset of
// WithEffects, dynamics/effects.hpp): first-order lags of the commands, then the steering map
// s -> s + k s^3 + offset.
struct Actuators {
  double steer_lag_s = 0;     // [s] first-order time constant of the steering servo
  double throttle_lag_s = 0;  // [s] first-order time constant of the drive
  double steer_cubic = 0;     // [-] k in s -> s + k s^3
  double steer_offset = 0;    // [-] added to the applied steer
};
struct SingleTrackWithActuators {
  SingleTrackParams car;
  Actuators act;
};
constexpr double kActuatorPrime_s = 1.0;  // command history run through the lags before a start

double* actuator_field(Actuators& a, const std::string& n) {
  if (n == "steer_lag_s") return &a.steer_lag_s;
  if (n == "throttle_lag_s") return &a.throttle_lag_s;
  if (n == "steer_cubic") return &a.steer_cubic;
  if (n == "steer_offset") return &a.steer_offset;
  return nullptr;
}
bool is_actuator_param(const std::string& n) {
  Actuators a;
  return actuator_field(a, n) != nullptr;
}
double* single_track_or_actuator_field(SingleTrackWithActuators& p, const std::string& n) {
  if (double* f = actuator_field(p.act, n)) return f;
  return single_track_field(p.car, n);
}

// Advances the two lag states y (steer, throttle) over h with commands u held: y += (1 - e^(-h/tau)) (u - y).
void advance_actuators(const Actuators& a, const double* u, double h, double* y) {
  const double as = a.steer_lag_s > 0 ? 1 - std::exp(-h / a.steer_lag_s) : 1.0;
  const double at = a.throttle_lag_s > 0 ? 1 - std::exp(-h / a.throttle_lag_s) : 1.0;
  y[0] += as * (u[0] - y[0]);
  y[1] += at * (u[1] - y[1]);
}
double applied_steer(const Actuators& a, double s) { return s + a.steer_cubic * s * s * s + a.steer_offset; }

bool is_linear_param(const std::string& n) {
  return n == "tyre.E" || n == "tyre.Sh" || n == "tyre.Sv" || is_actuator_param(n);
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

template <class P, class FieldFn>
void prepare(VehicleModelSpec& spec, const P& base, const std::vector<std::string>& estimated,
             const std::vector<std::string>& known, FieldFn field) {
  P copy = base;
  for (const auto& n : estimated) {
    const double* f = field(copy, n);
    if (!f) throw Error("unknown parameter '" + n + "' for the " + spec.kind + " model (known: " + join(known) + ")");
    if (std::count(estimated.begin(), estimated.end(), n) > 1) throw Error("parameter '" + n + "' given twice");
    spec.estimated.push_back(n);
    spec.nominal.push_back(*f);
    const bool lin = is_linear_param(n);
    if (!lin && !(*f > 0)) throw Error("parameter '" + n + "' must be > 0 to be estimated (log scale)");
    spec.log_scale.push_back(!lin);
  }
}

// Integrates `dt` in equal substeps of at most max_sub.
template <class StepFn>
void substep(double dt, double max_sub, StepFn&& fn) {
  const int n = std::max(1, static_cast<int>(std::ceil(dt / max_sub - 1e-9)));
  for (int i = 0; i < n; ++i) fn(dt / n);
}

double value_or(const sim::Recording& rec, const char* col, std::size_t row, double fallback) {
  if (!rec.has_column(col)) return fallback;
  const double v = rec.column(col)[row];
  return std::isfinite(v) ? v : fallback;
}

}  // namespace

std::vector<std::string> single_track_param_names() {
  return {"mass_kg", "yaw_inertia_kgm2", "cg_to_front_axle_m", "cg_to_rear_axle_m", "cg_height_m",
          "wheel_radius_m", "front_wheel_inertia_kgm2", "rear_wheel_inertia_kgm2", "max_steer_rad",
          "stall_torque_Nm", "no_load_speed_mps", "brake_torque_ratio", "rolling_resistance", "aero_drag_kgpm",
          "tyre.B", "tyre.C", "tyre.D", "tyre.E", "tyre.Sh", "tyre.Sv", "slip_speed_floor_mps", "slip_blend",
          "rear_tyre_B_scale", "rear_tyre_C_scale", "rear_tyre_D_scale", "steer_lag_s", "throttle_lag_s",
          "steer_cubic", "steer_offset"};
}

std::vector<std::string> full_vehicle_param_names() {
  auto v = single_track_param_names();
  v.erase(std::find(v.begin(), v.end(), "aero_drag_kgpm"));
  v.erase(std::remove_if(v.begin(), v.end(), is_actuator_param), v.end());  // single-track only
  for (const char* n : {"front_track_m", "rear_track_m", "front_spring_Npm", "rear_spring_Npm",
                        "front_damper_Nspm", "rear_damper_Nspm", "sprung_cg_height_m",
                        "roll_centre_height_m", "roll_inertia_kgm2", "pitch_inertia_kgm2", "drag_coefficient"})
    v.push_back(n);
  return v;
}

VehicleModelSpec single_track_spec(const SingleTrackParams& base, const std::vector<std::string>& estimated,
                                   bool keep_wheelbase) {
  std::string why;
  if (!base.is_valid(&why)) throw Error("single-track base parameters: " + why);
  VehicleModelSpec s;
  s.kind = mppi::models::SingleTrackModel::kName;
  s.nx = SingleTrack::kNx;
  s.state_names = {"x", "y", "yaw", "vx", "vy", "yaw_rate", "roll", "omega_front", "omega_rear"};
  s.measurable = {{"x", 0}, {"y", 1}, {"yaw", 2}, {"vx", 3}, {"vy", 4}, {"yaw_rate", 5},
                  {"omega_front", 7}, {"omega_rear", 8}};
  const SingleTrackWithActuators base_all{base, {}};
  prepare(s, base_all, estimated, single_track_param_names(), single_track_or_actuator_field);
  const bool actuators = std::any_of(s.estimated.begin(), s.estimated.end(),
                                     [](const std::string& n) { return is_actuator_param(n); });
  if (actuators) {  // the steer and throttle actuator outputs become states
    s.nx = SingleTrack::kNx + 2;
    s.state_names.push_back("steer_applied");
    s.state_names.push_back("throttle_applied");
  }
  const double wheelbase = base.wheelbase_m();
  const std::vector<std::string> names = s.estimated;
  auto with = [base_all, names, keep_wheelbase, wheelbase](const std::vector<double>& v) {
    SingleTrackWithActuators p = base_all;
    for (std::size_t i = 0; i < names.size(); ++i) *single_track_or_actuator_field(p, names[i]) = v[i];
    if (keep_wheelbase) p.car.cg_to_rear_axle_m = std::max(1e-3, wheelbase - p.car.cg_to_front_axle_m);
    return p;
  };
  s.step = [with, actuators](const std::vector<double>& v, double* x, const double* u, double dt) {
    const SingleTrackWithActuators p = with(v);
    const SingleTrackCoeffs<double> k = SingleTrackCoeffs<double>::from(p.car);
    substep(dt, 0.002, [&](double h) {
      double steer = u[0], throttle = u[1];
      if (actuators) {
        advance_actuators(p.act, u, h, x + SingleTrack::kNx);
        steer = applied_steer(p.act, x[SingleTrack::kNx]);
        throttle = x[SingleTrack::kNx + 1];
      }
      SingleTrackTerms<double> e;
      single_track_terms(k, x[3], x[4], x[5], x[7], x[8], steer, throttle, &e);
      const double sy = std::sin(x[2]), cy = std::cos(x[2]);
      x[0] += (cy * x[3] - sy * x[4]) * h;
      x[1] += (sy * x[3] + cy * x[4]) * h;
      x[2] += x[5] * h;
      x[3] += e.dvx_mps2 * h;
      x[4] += e.dvy_mps2 * h;
      x[5] += e.dyaw_rate_radps2 * h;
      x[7] += e.domega_front_radps2 * h;
      x[8] += e.domega_rear_radps2 * h;
    });
  };
  const double radius = base.wheel_radius_m;
  s.init_state = [radius, actuators](const sim::Recording& rec, std::size_t row, double* x) {
    const char* cols[6] = {"x", "y", "yaw", "vx", "vy", "yaw_rate"};
    for (int i = 0; i < 6; ++i) x[i] = value_or(rec, cols[i], row, 0.0);
    x[6] = 0;
    const double w = value_or(rec, "wheel_speed", row, x[3]) / radius;
    x[7] = value_or(rec, "omega_front", row, w);
    x[8] = value_or(rec, "omega_rear", row, w);
    if (actuators) {  // steady at the last command until prime() runs the history through them
      x[SingleTrack::kNx] = row > 0 ? rec.column("steer")[row - 1] : 0.0;
      x[SingleTrack::kNx + 1] = row > 0 ? rec.column("throttle")[row - 1] : 0.0;
    }
  };
  if (actuators)
    s.prime = [with](const std::vector<double>& v, const sim::Recording& rec, std::size_t row, double* x) {
      const SingleTrackWithActuators p = with(v);
      const auto& t = rec.column("t");
      const auto& steer = rec.column("steer");
      const auto& throttle = rec.column("throttle");
      std::size_t first = row;
      while (first > 0 && t[row] - t[first - 1] <= kActuatorPrime_s) --first;
      if (first == row) return;
      x[SingleTrack::kNx] = steer[first];
      x[SingleTrack::kNx + 1] = throttle[first];
      for (std::size_t i = first; i < row; ++i) {
        const double u[2] = {steer[i], throttle[i]};
        advance_actuators(p.act, u, t[i + 1] - t[i], x + SingleTrack::kNx);
      }
    };
  s.to_yaml = [with](const std::vector<double>& v) { return to_yaml(with(v).car); };
  s.process_std_per_sqrt_s = {0.01, 0.01, 0.005, 0.2, 0.2, 0.2, 1e-6, 5.0, 5.0};
  if (actuators) s.process_std_per_sqrt_s.insert(s.process_std_per_sqrt_s.end(), {0.01, 0.01});
  return s;
}

std::vector<std::string> double_track_param_names() {
  auto v = single_track_param_names();
  v.erase(std::remove_if(v.begin(), v.end(), is_actuator_param), v.end());  // single-track only
  for (const char* n : {"front_track_m", "rear_track_m", "front_roll_share"}) v.push_back(n);
  return v;
}

VehicleModelSpec double_track_spec(const DoubleTrackParams& base, const std::vector<std::string>& estimated,
                                   bool keep_wheelbase) {
  std::string why;
  if (!base.is_valid(&why)) throw Error("double-track base parameters: " + why);
  VehicleModelSpec s;
  s.kind = mppi::models::DoubleTrackModel::kName;
  s.nx = DoubleTrack::kNx;
  s.state_names = {"x", "y", "yaw", "vx", "vy", "yaw_rate", "roll", "omega_lf", "omega_rf", "omega_lr", "omega_rr"};
  s.measurable = {{"x", 0}, {"y", 1}, {"yaw", 2}, {"vx", 3}, {"vy", 4}, {"yaw_rate", 5},
                  {"omega_lf", 7}, {"omega_rf", 8}, {"omega_lr", 9}, {"omega_rr", 10}};
  prepare(s, base, estimated, double_track_param_names(), double_track_field);
  const double wheelbase = base.base.wheelbase_m();
  const std::vector<std::string> names = s.estimated;
  auto with = [base, names, keep_wheelbase, wheelbase](const std::vector<double>& v) {
    DoubleTrackParams p = base;
    for (std::size_t i = 0; i < names.size(); ++i) *double_track_field(p, names[i]) = v[i];
    if (keep_wheelbase) p.base.cg_to_rear_axle_m = std::max(1e-3, wheelbase - p.base.cg_to_front_axle_m);
    return p;
  };
  s.step = [with](const std::vector<double>& v, double* x, const double* u, double dt) {
    const FourWheelCoeffs<double> k = double_track_coeffs(with(v));
    substep(dt, 0.002, [&](double h) {  // explicit Euler, as DoubleTrack::step
      double dx[DoubleTrack::kNx];
      DoubleTrack::derivatives(k, x, u, dx);
      for (int i = 0; i < DoubleTrack::kNx; ++i) x[i] += dx[i] * h;
    });
  };
  const double radius = base.base.wheel_radius_m;
  s.init_state = [radius](const sim::Recording& rec, std::size_t row, double* x) {
    const char* cols[11] = {"x", "y", "yaw", "vx", "vy", "yaw_rate", "roll", "omega_lf", "omega_rf",
                            "omega_lr", "omega_rr"};
    for (int i = 0; i < 6; ++i) x[i] = value_or(rec, cols[i], row, 0.0);
    x[6] = 0;
    const double w = value_or(rec, "wheel_speed", row, x[3]) / radius;
    for (int i = 7; i <= 10; ++i) x[i] = value_or(rec, cols[i], row, w);
  };
  s.to_yaml = [with](const std::vector<double>& v) { return to_yaml(with(v)); };
  s.process_std_per_sqrt_s = {0.01, 0.01, 0.005, 0.2, 0.2, 0.2, 1e-6, 5, 5, 5, 5};
  return s;
}

VehicleModelSpec full_vehicle_spec(const FullVehicleParams& base, const std::vector<std::string>& estimated,
                                   bool keep_wheelbase) {
  std::string why;
  if (!base.is_valid(&why)) throw Error("full-vehicle base parameters: " + why);
  VehicleModelSpec s;
  s.kind = mppi::models::FullVehicleModel::kName;
  s.nx = FullVehicle::kNx;
  s.state_names = {"x", "y", "yaw", "vx", "vy", "yaw_rate", "roll", "omega_lf", "omega_rf", "omega_lr",
                   "omega_rr", "pitch", "heave", "roll_rate", "pitch_rate", "vz"};
  s.measurable = {{"x", 0}, {"y", 1}, {"yaw", 2}, {"vx", 3}, {"vy", 4}, {"yaw_rate", 5}, {"roll", 6},
                  {"omega_lf", 7}, {"omega_rf", 8}, {"omega_lr", 9}, {"omega_rr", 10}, {"pitch", 11},
                  {"roll_rate", 13}, {"pitch_rate", 14}, {"vz", 15}};
  prepare(s, base, estimated, full_vehicle_param_names(), full_vehicle_field);
  const double wheelbase = base.base.wheelbase_m();
  const std::vector<std::string> names = s.estimated;
  auto with = [base, names, keep_wheelbase, wheelbase](const std::vector<double>& v) {
    FullVehicleParams p = base;
    for (std::size_t i = 0; i < names.size(); ++i) *full_vehicle_field(p, names[i]) = v[i];
    if (keep_wheelbase) p.base.cg_to_rear_axle_m = std::max(1e-3, wheelbase - p.base.cg_to_front_axle_m);
    return p;
  };
  s.step = [with](const std::vector<double>& v, double* x, const double* u, double dt) {
    const FullVehicleCoeffs<double> k = full_vehicle_coeffs(with(v));
    substep(dt, 0.002, [&](double h) { FullVehicle::step_double(k, x, u, h); });
  };
  const double radius = base.base.wheel_radius_m;
  s.init_state = [radius](const sim::Recording& rec, std::size_t row, double* x) {
    const char* cols[16] = {"x", "y", "yaw", "vx", "vy", "yaw_rate", "roll", "omega_lf", "omega_rf",
                            "omega_lr", "omega_rr", "pitch", "heave", "roll_rate", "pitch_rate", "vz"};
    for (int i = 0; i < 16; ++i) x[i] = value_or(rec, cols[i], row, 0.0);
    const double w = value_or(rec, "wheel_speed", row, x[3]) / radius;
    for (int i = 7; i <= 10; ++i)
      if (!rec.has_column(cols[i]) || !std::isfinite(rec.column(cols[i])[row])) x[i] = w;
  };
  s.to_yaml = [with](const std::vector<double>& v) { return to_yaml(with(v)); };
  s.process_std_per_sqrt_s = {0.01, 0.01, 0.005, 0.2, 0.2, 0.2, 0.005, 5, 5, 5, 5, 0.005, 0.001, 0.1, 0.1, 0.05};
  return s;
}

bool EstimateSettings::is_valid(std::string* why) const {
  auto fail = [&](const char* m) {
    if (why) *why = m;
    return false;
  };
  if (!ukf.is_valid(why)) return false;
  if (!(alm_window_s > 0)) return fail("alm_window_s must be > 0");
  if (!(param_initial_std > 0)) return fail("param_initial_std must be > 0");
  if (!(param_walk_std_per_s >= 0)) return fail("param_walk_std_per_s must be >= 0");
  if (!(process_noise_scale > 0)) return fail("process_noise_scale must be > 0");
  if (!(t_end_s > t_begin_s)) return fail("the fit window is empty (t_end_s <= t_begin_s)");
  if (record_every < 1) return fail("record_every must be >= 1");
  for (const auto& [name, sd] : measurement_std)
    if (!(sd > 0)) return fail("every measurement standard deviation must be > 0");
  return true;
}

namespace {
double default_measurement_std(const std::string& c) {
  if (c == "x" || c == "y") return 0.05;
  if (c == "yaw") return 0.02;
  if (c == "vx" || c == "vy" || c == "vz") return 0.1;
  if (c == "yaw_rate" || c == "roll_rate" || c == "pitch_rate") return 0.03;
  if (c == "roll" || c == "pitch") return 0.01;
  return 1.0;  // wheel speeds [rad/s]
}
double to_internal(double v, bool log_scale) { return log_scale ? std::log(v) : v; }
double to_physical(double v, bool log_scale) { return log_scale ? std::exp(v) : v; }
}  // namespace

EstimateResult estimate_parameters(const VehicleModelSpec& spec, const sim::Recording& rec,
                                   const EstimateSettings& st, const std::vector<double>& initial_values) {
  std::string why;
  if (!st.is_valid(&why)) throw Error("estimate settings: " + why);
  const auto t0_wall = std::chrono::steady_clock::now();
  const auto& t = rec.column("t");
  const auto& steer = rec.column("steer");
  const auto& throttle = rec.column("throttle");
  std::vector<std::size_t> rows;
  for (std::size_t i = 0; i < rec.rows(); ++i)
    if (t[i] >= st.t_begin_s && t[i] < st.t_end_s) rows.push_back(i);
  if (rows.size() < 10) throw Error("estimate: fewer than 10 rows in the fit window");
  // Measured channels.
  EstimateResult res;
  std::vector<int> state_index;
  std::vector<const std::vector<double>*> cols;
  for (const auto& [col, idx] : spec.measurable) {
    const bool wanted = st.measure.empty() ? true
                                           : std::find(st.measure.begin(), st.measure.end(), col) != st.measure.end();
    if (!wanted || !rec.has_column(col)) continue;
    res.measured.push_back(col);
    state_index.push_back(idx);
    cols.push_back(&rec.column(col));
  }
  for (const auto& m : st.measure)
    if (std::find(res.measured.begin(), res.measured.end(), m) == res.measured.end())
      throw Error("estimate: cannot measure '" + m + "' (not in the recording or not a state of the " +
                  spec.kind + " model)");
  if (res.measured.empty()) throw Error("estimate: no measured channel in the recording");
  const int ny = static_cast<int>(res.measured.size());
  const int nx = spec.nx, np = static_cast<int>(spec.estimated.size());
  const std::vector<bool> logs = spec.log_scale;
  const std::vector<std::size_t>* rows_ptr = &rows;
  (void)rows_ptr;

  JointModel m;
  m.nx = nx;
  m.np = np;
  m.ny = ny;
  // u = (steer, throttle, dt): the sample interval travels with the control.
  m.f = [&spec, logs, np](const Vec& x, const Vec& p, const Vec& u) -> Vec {
    std::vector<double> v(np);
    for (int i = 0; i < np; ++i) v[i] = to_physical(p(i), logs[i]);
    Vec out = x;
    const double uu[2] = {u(0), u(1)};
    spec.step(v, out.data(), uu, u(2));
    for (int i = 0; i < out.size(); ++i)
      if (!std::isfinite(out(i))) out(i) = x(i);  // a diverged sigma point: keep it finite
    return out;
  };
  m.h = [state_index](const Vec& x, const Vec&, const Vec&) -> Vec {
    Vec y(static_cast<int>(state_index.size()));
    for (std::size_t i = 0; i < state_index.size(); ++i) y(i) = x(state_index[i]);
    return y;
  };
  std::vector<double> init = initial_values.empty() ? spec.nominal : initial_values;
  if (static_cast<int>(init.size()) != np) throw Error("estimate: wrong number of initial values");
  Vec p0(np), pstd(np);
  Mat Pp0 = Mat::Zero(np, np);
  double dt_med;
  {
    std::vector<double> d;
    for (std::size_t k = 1; k < rows.size(); ++k) d.push_back(t[rows[k]] - t[rows[k - 1]]);
    std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
    dt_med = d[d.size() / 2];
  }
  for (int i = 0; i < np; ++i) {
    p0(i) = to_internal(init[i], logs[i]);
    const double sd0 = logs[i] ? st.param_initial_std : st.param_initial_std * std::max(0.3, std::abs(init[i]));
    Pp0(i, i) = sd0 * sd0;
    pstd(i) = st.param_walk_std_per_s * std::sqrt(dt_med) * (logs[i] ? 1.0 : std::max(0.3, std::abs(init[i])));
  }
  Vec x0(nx);
  spec.init_state(rec, rows[0], x0.data());
  Mat Px0 = Mat::Zero(nx, nx), Qx = Mat::Zero(nx, nx);
  for (int i = 0; i < nx; ++i) {
    const double q = spec.process_std_per_sqrt_s[i] * st.process_noise_scale * std::sqrt(dt_med);
    Qx(i, i) = q * q;
    Px0(i, i) = std::max(1e-6, 100 * q * q);
  }
  Mat R = Mat::Zero(ny, ny);
  for (int i = 0; i < ny; ++i) {
    double sd = default_measurement_std(res.measured[i]);
    for (const auto& [name, v] : st.measurement_std)
      if (name == res.measured[i]) sd = v;
    R(i, i) = sd * sd;
  }
  JointFilterSettings fs;
  fs.ukf = st.ukf;
  fs.adaptive = st.adaptive;
  fs.alm.window = std::max(10, static_cast<int>(std::lround(st.alm_window_s / dt_med)));
  fs.alm.min_samples = std::min(fs.alm.window, std::max(10, fs.alm.window / 5));
  fs.alm.estimate_process = st.alm_process;
  fs.alm.estimate_measurement = st.alm_measurement;
  fs.alm.estimate_means = false;  // a constant bias is not separable from the state (docs)
  JointStateFilter filt(m, fs, x0, Px0, p0, Pp0, Qx, R, pstd);

  res.names = spec.estimated;
  res.initial = init;
  auto record = [&](double time) {
    const Vec p = filt.params(), sd = filt.param_std();
    std::vector<double> v(np), s(np);
    for (int i = 0; i < np; ++i) {
      v[i] = to_physical(p(i), logs[i]);
      s[i] = logs[i] ? v[i] * sd(i) : sd(i);
    }
    res.t.push_back(time);
    res.history.push_back(v);
    res.history_std.push_back(s);
  };
  record(t[rows[0]]);
  std::vector<double> innov_sq(ny, 0.0);
  std::vector<int> innov_n(ny, 0);
  for (std::size_t k = 1; k < rows.size(); ++k) {
    const std::size_t prev = rows[k - 1], cur = rows[k];
    Vec u_prev(3), u(3), y(ny);
    u_prev << steer[prev], throttle[prev], t[cur] - t[prev];
    u << steer[cur], throttle[cur], 0.0;
    if (!std::isfinite(u_prev(0))) u_prev(0) = 0;
    if (!std::isfinite(u_prev(1))) u_prev(1) = 0;
    for (int i = 0; i < ny; ++i) y(i) = (*cols[i])[cur];
    filt.step(u_prev, y, u);
    const UpdateInfo& up = filt.last_update();
    for (std::size_t a = 0; a < up.rows.size(); ++a) {
      innov_sq[up.rows[a]] += up.innovation(a) * up.innovation(a);
      ++innov_n[up.rows[a]];
    }
    ++res.steps;
    if (k % st.record_every == 0 || k + 1 == rows.size()) record(t[cur]);
  }
  res.final_values = res.history.back();
  res.final_std = res.history_std.back();
  for (int i = 0; i < ny; ++i) res.innovation_rms.push_back(innov_n[i] ? std::sqrt(innov_sq[i] / innov_n[i]) : kNaN);
  for (int i = 0; i < ny; ++i) res.measurement_std.push_back(std::sqrt(std::max(0.0, filt.ukf().R()(i, i))));
  res.projections = filt.projections();
  res.rejected_steps = filt.rejected_steps();
  res.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_wall).count();
  return res;
}

double convergence_time_to(const EstimateResult& r, std::size_t param, double band, double reference) {
  if (r.t.empty() || r.history.size() != r.t.size()) throw Error("convergence_time: empty or inconsistent history");
  const double tol = band * std::max(std::abs(reference), 1e-9);
  for (std::size_t k = r.t.size(); k-- > 0;)
    if (!(std::abs(r.history[k][param] - reference) <= tol))
      return k + 1 < r.t.size() ? r.t[k + 1] : std::numeric_limits<double>::infinity();
  return r.t.front();
}

double convergence_time(const EstimateResult& r, std::size_t param, double band) {
  return convergence_time_to(r, param, band, r.final_values.at(param));
}

ValidationResult validate_parameters(const VehicleModelSpec& spec, const std::vector<double>& values,
                                     const sim::Recording& rec, std::size_t begin, std::size_t end,
                                     double horizon_s) {
  ValidationResult v;
  v.channels = {"x", "y", "yaw", "vx", "vy", "yaw_rate"};
  end = std::min(end, rec.rows());
  if (end < begin + 2) throw Error("validate: fewer than 2 rows");
  const auto& t = rec.column("t");
  const auto& steer = rec.column("steer");
  const auto& throttle = rec.column("throttle");
  std::vector<const std::vector<double>*> meas;
  for (const auto& c : v.channels) meas.push_back(&rec.column(c));
  const int nc = static_cast<int>(v.channels.size());
  v.simulated.assign(nc, {});
  v.measured.assign(nc, {});
  std::vector<double> x(spec.nx);
  auto run = [&](bool open_loop, std::vector<double>& sq, std::vector<int>& cnt) {
    double chunk_start = t[begin];
    spec.init_state(rec, begin, x.data());
    if (spec.prime) spec.prime(values, rec, begin, x.data());
    for (std::size_t i = begin; i < end; ++i) {
      if (!open_loop && t[i] - chunk_start >= horizon_s - 1e-9) {
        spec.init_state(rec, i, x.data());
        if (spec.prime) spec.prime(values, rec, i, x.data());
        chunk_start = t[i];
      }
      for (int c = 0; c < nc; ++c) {
        const double m = (*meas[c])[i];
        if (open_loop) {
          v.simulated[c].push_back(x[c]);
          v.measured[c].push_back(m);
        }
        if (std::isfinite(m) && std::isfinite(x[c])) {
          sq[c] += (x[c] - m) * (x[c] - m);
          ++cnt[c];
        }
      }
      if (open_loop) v.t.push_back(t[i]);
      if (i + 1 < end) {
        const double u[2] = {std::isfinite(steer[i]) ? steer[i] : 0.0, std::isfinite(throttle[i]) ? throttle[i] : 0.0};
        spec.step(values, x.data(), u, t[i + 1] - t[i]);
      }
    }
  };
  std::vector<double> sq(nc, 0.0), sq2(nc, 0.0);
  std::vector<int> n(nc, 0), n2(nc, 0);
  run(true, sq, n);
  run(false, sq2, n2);
  for (int c = 0; c < nc; ++c) {
    v.open_loop_rms.push_back(n[c] ? std::sqrt(sq[c] / n[c]) : kNaN);
    v.horizon_rms.push_back(n2[c] ? std::sqrt(sq2[c] / n2[c]) : kNaN);
  }
  return v;
}

}  // namespace mppi::sysid
