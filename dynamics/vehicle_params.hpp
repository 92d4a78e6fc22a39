#pragma once
// Parameters of the physics vehicle models, with the AutoRally values as defaults, and their
// YAML loaders (dynamics/vehicle_params_io.cpp). Measured values are from the AutoRally
// paper's robot-parameter, bifilar-pendulum and tyre tables; the rest (steering range,
// drivetrain, resistances, regularisation) the paper does not give: they are chosen to be
// plausible for a 22 kg 1:5 rally car and are meant to be calibrated.
#include <cmath>
#include <string>
#include <string_view>
#include <vector>

#include "base/param_table.hpp"
#include "dynamics/pacejka.hpp"

namespace mppi {

struct SingleTrackParams {
  // --- measured (paper) ---
  double mass_kg = 21.88;                 // total mass m [kg]
  double yaw_inertia_kgm2 = 1.124;        // I_z about the CG [kg m^2] (bifilar)
  double cg_to_front_axle_m = 0.34;       // l_f [m] = wheelbase 0.57 - l_r
  double cg_to_rear_axle_m = 0.23;        // l_r [m] (rear axle to CG, x offset)
  double cg_height_m = 0.12;              // h [m] (rear axle to CG, z offset), for load transfer
  double wheel_radius_m = 0.0975;         // R [m] (wheel diameter 0.195 m)
  double front_wheel_inertia_kgm2 = 0.048;  // I_f [kg m^2], both front wheels together (bifilar)
  double rear_wheel_inertia_kgm2 = 0.044;   // I_r [kg m^2], both rear wheels together (bifilar)
  double gravity_mps2 = 9.81;             // g [m/s^2] (the paper's value)
  PacejkaParams tyre;                     // Magic Formula (paper's identified values)
  // --- chosen (not in the paper) ---
  double max_steer_rad = 0.38;            // front wheel angle at steer = +-1 [rad]
  // Rear-wheel drive, DC-motor-like torque-speed line at the rear axle:
  //   T_rear = stall_torque * (throttle - omega_r R / no_load_speed).
  // Gives engine braking at zero throttle, braking then reverse for negative throttle.
  // With the resistances below: steady 5.3 m/s at throttle 0.3, 13.1 at 0.65, 19.6 at 1.
  double stall_torque_Nm = 10.0;          // rear axle torque at throttle 1, wheel still [N m]
  double no_load_speed_mps = 30.0;        // rim speed where throttle 1 gives zero torque [m/s]
  // Negative throttle (brake) scaled separately: the torque line is
  //   T_rear = stall_torque * (max(throttle, 0) + brake_torque_ratio * min(throttle, 0) - omega_r R / no_load_speed);
  // 1 = the same line for both signs.
  double brake_torque_ratio = 1.0;        // brake torque at throttle -1 / stall torque [-]
  double rolling_resistance = 0.05;       // c_rr [-]: force c_rr m g tanh(vx / v_rr) (loose dirt)
  double rolling_resistance_speed_mps = 0.5;  // v_rr [m/s]: smooths the sign at standstill
  double aero_drag_kgpm = 0.05;           // c_d [N s^2/m^2]: force c_d vx |vx| (~0.5 rho Cd A)
  // Regularisation of the paper's slip formulas (dynamics/pacejka.hpp). Both trade fidelity
  // for a non-stiff model. The floor bounds the slip stiffness d s / d omega <= R / v_floor:
  // the fastest (wheel-slip) mode relaxes at about k R^2 f_z (1/I_wheel + 1/(m R^2)) / v_floor
  // with k the largest slope of the regularised friction curve (3.1 for slip_blend 0.1, from
  // the paper's mu'(0) = 1.52 and mu(0)/eps). Largest -Re(eigenvalue) x 0.02 s over sampled
  // states, from the Jacobian (see tests/dynamics/test_single_track.cpp): 0.78 with these
  // values (explicit Euler: < 1 means no overshoot, < 2 stable); 1.2 at v_floor 2, 2.3 (unstable)
  // at 1 m/s. The 500 Hz plant would be fine with 1 m/s.
  double slip_speed_floor_mps = 3.0;      // v_floor [m/s] in max(|omega R|, v_floor)
  double slip_blend = 0.1;                // eps [-]: force x tanh(s / eps) -> 0 at zero slip
  // Per-axle tyres: the rear tyre is `tyre` with B, C, D scaled by these (E, Sh, Sv shared);
  // 1 = the same tyre on both axles (the paper identifies one tyre for the whole car).
  double rear_tyre_B_scale = 1.0;         // rear stiffness factor / front [-]
  double rear_tyre_C_scale = 1.0;         // rear shape factor / front [-]
  double rear_tyre_D_scale = 1.0;         // rear peak factor / front [-]
  // Drive layout: the share of the motor's torque (drive and brake) that reaches the front
  // axle; 0 = rear-wheel drive (AutoRally), 0.5 = four-wheel drive with an even split. The motor
  // turns at the shares' mean of the axles' wheel speeds (a differential between the axles).
  double front_drive_share = 0.0;         // front axle's share of the motor torque [-]

  double wheelbase_m() const { return cg_to_front_axle_m + cg_to_rear_axle_m; }
  // The rear axle's tyre: `tyre` with the rear scales applied.
  PacejkaParams rear_tyre() const {
    PacejkaParams t = tyre;
    t.B *= rear_tyre_B_scale;
    t.C *= rear_tyre_C_scale;
    t.D *= rear_tyre_D_scale;
    return t;
  }
  bool is_valid(std::string* why) const;
};

// The kinematic bicycle: no tyre slip, reference point at the rear-axle centre (the only
// point of a kinematic bicycle whose velocity has no lateral component, hence vy = 0).
//   yaw_rate = v tan(delta) / L,  dv/dt = max_accel * throttle - speed_damping * v.
// Defaults: steady speed 20 m/s x throttle (6 at 0.3, 13 at 0.65), close to the single-track
// defaults' 5.3 and 13.1; 2.6 m/s^2 from rest at throttle 0.65.
struct KinematicBicycleParams {
  double wheelbase_m = 0.57;          // L [m] (paper)
  double max_steer_rad = 0.38;        // front wheel angle at steer = +-1 [rad]
  double max_accel_mps2 = 4.0;        // dv/dt at throttle 1 and v = 0 [m/s^2]
  double speed_damping_per_s = 0.2;   // linear speed damping [1/s]: v_ss = max_accel u / this

  bool is_valid(std::string* why) const;
};

// The double-track (four-wheel) model: the single-track's parameters plus track widths and
// the quasi-static lateral load transfer (dynamics/double_track.hpp).
struct DoubleTrackParams {
  SingleTrackParams base;                  // mass, inertias, l_f, l_r, h, tyres, drivetrain, ...
  double front_track_m = 0.395;            // w_f [m] (paper: front track)
  double rear_track_m = 0.405;             // w_r [m] (paper: rear track)
  // Share of the roll moment m a_y h carried by the front axle. Chosen: the suspension's
  // roll-stiffness share K_f w_f^2 / (K_f w_f^2 + K_r w_r^2) with K_f = K_r (the paper fixes
  // K_f = K_r = 2000 N/m), i.e. 0.395^2 / (0.395^2 + 0.405^2).
  double front_roll_share = 0.487502;
  // Scale of the lateral load transfer [-]: 1 = physical, 0 = none (the single-track limit).
  double lateral_load_transfer = 1.0;

  bool is_valid(std::string* why) const;
};

// The full vehicle (dynamics/full_vehicle.hpp): the double-track's planar motion with
// per-wheel loads from a sprung mass in heave, roll and pitch on four spring-damper corners,
// and aerodynamic drag 0.5 C_D rho A V_x |V_x|. base.aero_drag_kgpm must be 0 (the drag is
// given by drag_coefficient, air_density_kgpm3, frontal_area_m2).
struct FullVehicleParams {
  FullVehicleParams() { base.aero_drag_kgpm = 0.0; }
  SingleTrackParams base;                  // mass, I_z, l_f, l_r, h, tyres, drivetrain, ...
  // --- measured (paper, robot-parameter table) ---
  double front_track_m = 0.395;            // w_f [m]
  double rear_track_m = 0.405;             // w_r [m]
  double front_wheel_mass_kg = 0.82;       // unsprung mass per front wheel [kg]
  double rear_wheel_mass_kg = 0.89;        // unsprung mass per rear wheel [kg]
  // --- the paper's ALM-UKF setting: K_f = K_r = 2000 N/m (fixed for observability) ---
  double front_spring_Npm = 2000.0;        // K_f per wheel [N/m]
  double rear_spring_Npm = 2000.0;         // K_r per wheel [N/m]
  // --- chosen (the paper estimates but does not print them) ---
  double front_damper_Nspm = 115.0;        // C_f per wheel [N s/m]: heave damping ratio ~0.6
  double rear_damper_Nspm = 115.0;         // C_r per wheel [N s/m]
  double sprung_cg_height_m = 0.12;        // h^s [m] above the pitch centre (ground); = h
  double roll_centre_height_m = 0.05;      // h^c [m] roll-centre height
  // Sprung-mass inertias about the roll axis and the pitch centre: the bifilar I_x = 0.347 and
  // I_y = 1.131 (about the CG) moved by the parallel-axis theorem with m^s = 18.46 kg:
  // I_x + m^s (h^s - h^c)^2 = 0.437, I_y + m^s (h^s)^2 = 1.397.
  double roll_inertia_kgm2 = 0.437;        // I^R_x [kg m^2]
  double pitch_inertia_kgm2 = 1.397;       // I^P_y [kg m^2]
  double drag_coefficient = 0.57;          // C_D [-]
  double air_density_kgpm3 = 1.2;          // rho_air [kg/m^3]
  double frontal_area_m2 = 0.147;          // A [m^2] = overall width 0.46 x height 0.32 (paper)

  double sprung_mass_kg() const { return base.mass_kg - 2 * (front_wheel_mass_kg + rear_wheel_mass_kg); }
  // Roll stiffness share of the front axle, K_f w_f^2 / (K_f w_f^2 + K_r w_r^2).
  double front_roll_share() const {
    const double f = front_spring_Npm * front_track_m * front_track_m;
    return f / (f + rear_spring_Npm * rear_track_m * rear_track_m);
  }
  // The double-track that this model tends to as the suspension stiffens (same planar
  // parameters, the suspension's roll-stiffness share, drag as base.aero_drag_kgpm).
  DoubleTrackParams rigid_limit() const;
  bool is_valid(std::string* why) const;
};

// YAML loaders. Keys not given keep their defaults; an unknown key, a value that is not a
// number, or parameters that fail is_valid() throw mppi::Error naming the file, key and line.
// The single-track file has the fields above as top-level keys and a `tyre:` map with
// B, C, D, E, Sh, Sv (see data/config/autorally_single_track.yaml).
SingleTrackParams load_single_track_params(const std::string& path);
KinematicBicycleParams load_kinematic_bicycle_params(const std::string& path);
// The same from YAML text; `source` names it in error messages.
SingleTrackParams single_track_params_from_yaml(const std::string& text, const std::string& source);
KinematicBicycleParams kinematic_bicycle_params_from_yaml(const std::string& text,
                                                          const std::string& source);
// Double-track / full-vehicle files: the single-track keys (full vehicle: without
// aero_drag_kgpm) plus the fields of DoubleTrackParams / FullVehicleParams as top-level keys
// (data/config/autorally_double_track.yaml, autorally_full_vehicle.yaml).
DoubleTrackParams load_double_track_params(const std::string& path);
FullVehicleParams load_full_vehicle_params(const std::string& path);
DoubleTrackParams double_track_params_from_yaml(const std::string& text, const std::string& source);
FullVehicleParams full_vehicle_params_from_yaml(const std::string& text, const std::string& source);
// Every numeric field by its YAML key (tyre fields as "tyre.B", ...), pointing into `p`: for
// estimators that treat a chosen set of parameters as a vector. Order as in the YAML files.
struct NamedParam {
  std::string key;
  double* value;
};
std::vector<NamedParam> named_parameters(SingleTrackParams& p);
std::vector<NamedParam> named_parameters(DoubleTrackParams& p);
std::vector<NamedParam> named_parameters(FullVehicleParams& p);
// A YAML document of every field (same keys as the loaders), e.g. for estimated parameters.
std::string to_yaml(const SingleTrackParams& p);
std::string to_yaml(const DoubleTrackParams& p);
std::string to_yaml(const FullVehicleParams& p);

// ---------------------------------------------------------------------------------------------

// ---- the parameter tables (YAML key, unit, valid range, doc), one per parameter struct -------
// The loaders, writers, estimators' parameter vectors and --help text come from these; is_valid()
// checks their ranges, then the conditions that tie several fields together.

inline std::vector<ParamField> param_table(PacejkaParams& t) {
  return {
      param("tyre.B", &t.B, "-", positive(), "Magic Formula stiffness factor"),
      param("tyre.C", &t.C, "-", open(0, 2), "Magic Formula shape factor"),
      param("tyre.D", &t.D, "-", positive(), "Magic Formula peak factor (peak friction coefficient)"),
      param("tyre.E", &t.E, "-", open(-kInf, 1), "Magic Formula curvature factor"),
      param("tyre.Sh", &t.Sh, "-", any_finite(), "Magic Formula horizontal shift (slip)"),
      param("tyre.Sv", &t.Sv, "-", any_finite(), "Magic Formula vertical shift (friction)"),
  };
}

// The single-track keys; the full vehicle has no aero_drag_kgpm (its drag has its own terms).
inline std::vector<ParamField> param_table(SingleTrackParams& p, bool with_aero_drag = true) {
  std::vector<ParamField> f = {
      param("mass_kg", &p.mass_kg, "kg", positive(), "total mass m"),
      param("yaw_inertia_kgm2", &p.yaw_inertia_kgm2, "kg m^2", positive(), "yaw inertia I_z about the CG"),
      param("cg_to_front_axle_m", &p.cg_to_front_axle_m, "m", positive(), "CG to front axle l_f"),
      param("cg_to_rear_axle_m", &p.cg_to_rear_axle_m, "m", positive(), "CG to rear axle l_r"),
      param("cg_height_m", &p.cg_height_m, "m", non_negative(), "CG height h (load transfer)"),
      param("wheel_radius_m", &p.wheel_radius_m, "m", positive(), "wheel radius R"),
      param("front_wheel_inertia_kgm2", &p.front_wheel_inertia_kgm2, "kg m^2", positive(),
            "both front wheels' spin inertia I_f"),
      param("rear_wheel_inertia_kgm2", &p.rear_wheel_inertia_kgm2, "kg m^2", positive(),
            "both rear wheels' spin inertia I_r"),
      param("gravity_mps2", &p.gravity_mps2, "m/s^2", positive(), "gravity g"),
      param("max_steer_rad", &p.max_steer_rad, "rad", open(0, 1.5), "front wheel angle at steer = +-1"),
      param("stall_torque_Nm", &p.stall_torque_Nm, "N m", non_negative(), "rear axle torque at throttle 1, wheel still"),
      param("no_load_speed_mps", &p.no_load_speed_mps, "m/s", positive(), "rim speed where throttle 1 gives no torque"),
      param("brake_torque_ratio", &p.brake_torque_ratio, "-", non_negative(),
            "torque at throttle -1 (brake) relative to the stall torque"),
      param("rolling_resistance", &p.rolling_resistance, "-", non_negative(), "rolling resistance c_rr (force c_rr m g)"),
      param("rolling_resistance_speed_mps", &p.rolling_resistance_speed_mps, "m/s", positive(),
            "speed v_rr smoothing the resistance's sign at standstill"),
      param("aero_drag_kgpm", &p.aero_drag_kgpm, "N s^2/m^2", non_negative(), "drag c_d (force c_d vx |vx|)"),
      param("slip_speed_floor_mps", &p.slip_speed_floor_mps, "m/s", positive(), "slip denominator floor v_floor"),
      param("slip_blend", &p.slip_blend, "-", positive(), "slip blend eps: force x tanh(s / eps)"),
      param("rear_tyre_B_scale", &p.rear_tyre_B_scale, "-", positive(), "rear tyre stiffness factor B / front B"),
      param("rear_tyre_C_scale", &p.rear_tyre_C_scale, "-", positive(), "rear tyre shape factor C / front C"),
      param("rear_tyre_D_scale", &p.rear_tyre_D_scale, "-", positive(), "rear tyre peak factor D / front D"),
      param("front_drive_share", &p.front_drive_share, "-", closed(0, 1),
            "share of the motor torque on the front axle (0 rear-wheel drive, 0.5 even four-wheel drive)"),
  };
  if (!with_aero_drag) f.erase(f.begin() + 15);  // aero_drag_kgpm
  for (const ParamField& t : param_table(p.tyre)) f.push_back(t);
  return f;
}

// The single-track keys of a four-wheel model's base: those models drive the rear axle only, so
// front_drive_share is not among their keys (their is_valid refuses a value other than 0).
inline std::vector<ParamField> rear_drive_param_table(SingleTrackParams& p, bool with_aero_drag = true) {
  std::vector<ParamField> f = param_table(p, with_aero_drag);
  std::erase_if(f, [](const ParamField& q) { return std::string_view(q.key) == "front_drive_share"; });
  return f;
}

inline std::vector<ParamField> param_table(KinematicBicycleParams& p) {
  return {
      param("wheelbase_m", &p.wheelbase_m, "m", positive(), "wheelbase L"),
      param("max_steer_rad", &p.max_steer_rad, "rad", open(0, 1.5), "front wheel angle at steer = +-1"),
      param("max_accel_mps2", &p.max_accel_mps2, "m/s^2", non_negative(), "dv/dt at throttle 1 and v = 0"),
      param("speed_damping_per_s", &p.speed_damping_per_s, "1/s", non_negative(), "linear speed damping"),
  };
}

inline std::vector<ParamField> param_table(DoubleTrackParams& p) {
  std::vector<ParamField> f = rear_drive_param_table(p.base);
  f.insert(f.end() - 6,  // before the tyre map
           {param("front_track_m", &p.front_track_m, "m", positive(), "front track width w_f"),
            param("rear_track_m", &p.rear_track_m, "m", positive(), "rear track width w_r"),
            param("front_roll_share", &p.front_roll_share, "-", closed(0, 1),
                  "share of the roll moment carried by the front axle"),
            param("lateral_load_transfer", &p.lateral_load_transfer, "-", closed(0, 1),
                  "scale of the lateral load transfer (0 = single-track limit)")});
  return f;
}

inline std::vector<ParamField> param_table(FullVehicleParams& p) {
  std::vector<ParamField> f = rear_drive_param_table(p.base, /*with_aero_drag=*/false);
  f.insert(f.end() - 6,
           {param("front_track_m", &p.front_track_m, "m", positive(), "front track width w_f"),
            param("rear_track_m", &p.rear_track_m, "m", positive(), "rear track width w_r"),
            param("front_wheel_mass_kg", &p.front_wheel_mass_kg, "kg", non_negative(), "unsprung mass per front wheel"),
            param("rear_wheel_mass_kg", &p.rear_wheel_mass_kg, "kg", non_negative(), "unsprung mass per rear wheel"),
            param("front_spring_Npm", &p.front_spring_Npm, "N/m", positive(), "spring rate K_f per front wheel"),
            param("rear_spring_Npm", &p.rear_spring_Npm, "N/m", positive(), "spring rate K_r per rear wheel"),
            param("front_damper_Nspm", &p.front_damper_Nspm, "N s/m", non_negative(), "damper C_f per front wheel"),
            param("rear_damper_Nspm", &p.rear_damper_Nspm, "N s/m", non_negative(), "damper C_r per rear wheel"),
            param("sprung_cg_height_m", &p.sprung_cg_height_m, "m", non_negative(), "sprung CG height h^s"),
            param("roll_centre_height_m", &p.roll_centre_height_m, "m", any_finite(), "roll-centre height h^c"),
            param("roll_inertia_kgm2", &p.roll_inertia_kgm2, "kg m^2", positive(), "sprung roll inertia I^R_x"),
            param("pitch_inertia_kgm2", &p.pitch_inertia_kgm2, "kg m^2", positive(), "sprung pitch inertia I^P_y"),
            param("drag_coefficient", &p.drag_coefficient, "-", non_negative(), "drag coefficient C_D"),
            param("air_density_kgpm3", &p.air_density_kgpm3, "kg/m^3", non_negative(), "air density rho"),
            param("frontal_area_m2", &p.frontal_area_m2, "m^2", non_negative(), "frontal area A")});
  return f;
}

inline bool SingleTrackParams::is_valid(std::string* why) const {
  auto fail = [&](const std::string& msg) {
    if (why) *why = msg;
    return false;
  };
  SingleTrackParams copy = *this;
  std::vector<ParamField> fields = param_table(copy);
  fields.resize(fields.size() - 6);  // the tyre: checked whole by PacejkaParams::is_valid
  if (const std::string e = first_range_error(fields); !e.empty()) return fail(e);
  if (!tyre.is_valid(why)) return false;
  if (std::string rear_why; !rear_tyre().is_valid(&rear_why))
    return fail("rear tyre (tyre scaled by rear_tyre_*_scale): " + rear_why);
  // The load-transfer denominator l_f + l_r + h (mu_Fx cos d - mu_Fy sin d - mu_Rx) stays
  // positive for any slips when h * 2 * max|mu| < wheelbase.
  const double mu_bound = std::abs(tyre.D) * std::max(1.0, rear_tyre_D_scale) + std::abs(tyre.Sv);
  if (!(2 * cg_height_m * mu_bound < wheelbase_m()))
    return fail("cg_height_m too large for the wheelbase and tyre grip (need 2 h (|D| max(1, rear_tyre_D_scale) + "
                "|Sv|) < l_f + l_r)");
  return true;
}

inline bool DoubleTrackParams::is_valid(std::string* why) const {
  if (!base.is_valid(why)) return false;
  if (base.front_drive_share != 0) {
    if (why) *why = "front_drive_share must be 0 for the double-track model (it drives the rear axle only)";
    return false;
  }
  DoubleTrackParams copy = *this;
  if (const std::string e = first_range_error(param_table(copy)); !e.empty()) {
    if (why) *why = e;
    return false;
  }
  return true;
}

inline DoubleTrackParams FullVehicleParams::rigid_limit() const {
  DoubleTrackParams d;
  d.base = base;
  d.base.aero_drag_kgpm = 0.5 * drag_coefficient * air_density_kgpm3 * frontal_area_m2;
  d.front_track_m = front_track_m;
  d.rear_track_m = rear_track_m;
  d.front_roll_share = front_roll_share();
  d.lateral_load_transfer = 1.0;
  return d;
}

inline bool FullVehicleParams::is_valid(std::string* why) const {
  auto fail = [&](const std::string& msg) {
    if (why) *why = msg;
    return false;
  };
  if (!base.is_valid(why)) return false;
  if (base.front_drive_share != 0)
    return fail("front_drive_share must be 0 for the full vehicle (it drives the rear axle only)");
  if (base.aero_drag_kgpm != 0)
    return fail("aero_drag_kgpm must be 0 for the full vehicle (drag is drag_coefficient, "
                "air_density_kgpm3, frontal_area_m2)");
  FullVehicleParams copy = *this;
  if (const std::string e = first_range_error(param_table(copy)); !e.empty()) return fail(e);
  if (!(sprung_mass_kg() > 0)) return fail("the wheel masses must leave a sprung mass > 0");
  if (!(roll_centre_height_m <= sprung_cg_height_m))
    return fail("roll_centre_height_m must be <= sprung_cg_height_m");
  // Gravity must not beat the springs (the sprung mass would tip over at rest).
  const double ms = sprung_mass_kg(), g = base.gravity_mps2;
  const double roll_k = 0.5 * (front_spring_Npm * front_track_m * front_track_m +
                               rear_spring_Npm * rear_track_m * rear_track_m);
  const double lf = base.cg_to_front_axle_m, lr = base.cg_to_rear_axle_m;
  const double pitch_k = 2 * (front_spring_Npm * lf * lf + rear_spring_Npm * lr * lr);
  if (!(roll_k > ms * g * (sprung_cg_height_m - roll_centre_height_m)))
    return fail("roll stiffness (K_f w_f^2 + K_r w_r^2) / 2 must exceed m^s g (h^s - h^c)");
  if (!(pitch_k > ms * g * sprung_cg_height_m))
    return fail("pitch stiffness 2 (K_f l_f^2 + K_r l_r^2) must exceed m^s g h^s");
  return true;
}

inline bool KinematicBicycleParams::is_valid(std::string* why) const {
  KinematicBicycleParams copy = *this;
  if (const std::string e = first_range_error(param_table(copy)); !e.empty()) {
    if (why) *why = e;
    return false;
  }
  return true;
}

}  // namespace mppi
