#include "laptime/min_time_lap.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include <IpIpoptApplication.hpp>
#include <IpSolveStatistics.hpp>
#include <IpTNLP.hpp>

#include "base/error.hpp"
#include "laptime/collocation.hpp"
#include "laptime/spatial_single_track.hpp"
#include "sim/racing_line.hpp"

namespace mppi::laptime {
namespace {

constexpr double kPi = 3.14159265358979323846;

double wrap_angle(double a) {
  while (a > kPi) a -= 2 * kPi;
  while (a < -kPi) a += 2 * kPi;
  return a;
}

// IPOPT's view of the programme: sizes, bounds, start, values and derivatives, and the result.
class MinTimeNlp : public Ipopt::TNLP {
 public:
  MinTimeNlp(const Collocation& problem, std::vector<double> start)
      : problem_(problem), start_(std::move(start)) {}

  std::vector<double> solution;

  bool get_nlp_info(Ipopt::Index& n, Ipopt::Index& m, Ipopt::Index& nnz_jac_g, Ipopt::Index& nnz_h_lag,
                    IndexStyleEnum& index_style) override {
    n = problem_.variables();
    m = problem_.constraints();
    nnz_jac_g = problem_.jacobian_nonzeros();
    nnz_h_lag = 0;  // limited-memory Hessian
    index_style = C_STYLE;
    return true;
  }
  bool get_bounds_info(Ipopt::Index, Ipopt::Number* x_l, Ipopt::Number* x_u, Ipopt::Index m, Ipopt::Number* g_l,
                       Ipopt::Number* g_u) override {
    problem_.bounds(x_l, x_u);
    std::fill(g_l, g_l + m, 0.0);
    std::fill(g_u, g_u + m, 0.0);
    return true;
  }
  bool get_starting_point(Ipopt::Index n, bool init_x, Ipopt::Number* x, bool, Ipopt::Number*, Ipopt::Number*,
                          Ipopt::Index, bool, Ipopt::Number*) override {
    if (init_x) std::copy(start_.begin(), start_.begin() + n, x);
    return true;
  }
  bool eval_f(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number& obj_value) override {
    obj_value = problem_.objective(x);
    return std::isfinite(obj_value);
  }
  bool eval_grad_f(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number* grad_f) override {
    problem_.objective_gradient(x, grad_f);
    return true;
  }
  bool eval_g(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Index m, Ipopt::Number* g) override {
    problem_.defects(x, g);
    for (Ipopt::Index i = 0; i < m; ++i)
      if (!std::isfinite(g[i])) return false;
    return true;
  }
  bool eval_jac_g(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Index, Ipopt::Index, Ipopt::Index* iRow,
                  Ipopt::Index* jCol, Ipopt::Number* values) override {
    if (values == nullptr) problem_.jacobian_structure(iRow, jCol);
    else problem_.jacobian_values(x, values);
    return true;
  }
  void finalize_solution(Ipopt::SolverReturn, Ipopt::Index n, const Ipopt::Number* x, const Ipopt::Number*,
                         const Ipopt::Number*, Ipopt::Index, const Ipopt::Number*, const Ipopt::Number*,
                         Ipopt::Number, const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) override {
    solution.assign(x, x + n);
  }

 private:
  const Collocation& problem_;
  std::vector<double> start_;
};

std::string status_name(Ipopt::ApplicationReturnStatus s) {
  switch (s) {
    case Ipopt::Solve_Succeeded: return "solved";
    case Ipopt::Solved_To_Acceptable_Level: return "solved to the acceptable level";
    case Ipopt::Infeasible_Problem_Detected: return "infeasible";
    case Ipopt::Maximum_Iterations_Exceeded: return "maximum iterations";
    case Ipopt::Restoration_Failed: return "restoration failed";
    case Ipopt::Error_In_Step_Computation: return "error in step computation";
    case Ipopt::Maximum_CpuTime_Exceeded: return "maximum CPU time";
    case Ipopt::Invalid_Number_Detected: return "invalid number";
    default: return "failed (IPOPT status " + std::to_string(static_cast<int>(s)) + ")";
  }
}

double tangent_heading(const sim::Polyline& line, std::size_t i) {
  const std::size_t n = line.size();
  const sim::Vec2 t = line[(i + 1) % n] - line[(i + n - 1) % n];
  return std::atan2(t.y, t.x);
}

void validate(const MinTimeLapOptions& o) {
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!(std::isfinite(o.car_half_width_m) && o.car_half_width_m >= 0.0))
    throw Error("min_time_lap: car_half_width_m must be finite and >= 0");
  if (!(std::isfinite(o.safety_margin_m) && o.safety_margin_m >= 0.0))
    throw Error("min_time_lap: safety_margin_m must be finite and >= 0");
  if (!positive(o.station_spacing_m)) throw Error("min_time_lap: station_spacing_m must be finite and > 0");
  if (!positive(o.tolerance)) throw Error("min_time_lap: tolerance must be finite and > 0");
  if (!positive(o.max_defect)) throw Error("min_time_lap: max_defect must be finite and > 0");
  if (o.max_iterations < 1) throw Error("min_time_lap: max_iterations must be >= 1");
  // The dynamic states' box keeps vx >= 0.5 m/s (Collocation::bounds).
  if (!(std::isfinite(o.launch_speed_mps) && o.launch_speed_mps >= 0.5))
    throw Error("min_time_lap: launch_speed_mps must be finite and >= 0.5");
  if (!(std::isfinite(o.launch_station_ratio) && o.launch_station_ratio > 1.0 && o.launch_station_ratio <= 2.0))
    throw Error("min_time_lap: launch_station_ratio must be in (1, 2]");
}

// Where a station lies: its centreline point, left normal and heading.
struct StationFrame {
  sim::Vec2 centre, normal;
  double heading_rad = 0.0;
};

// The closed collocation on the fastest QSS racing line's stations, and the start it is solved from.
struct ClosedSetup {
  sim::RacingLine line;
  sim::LimitLap qss_lap;                   // the limit lap by QSS (its time is reported)
  std::vector<double> heading_rad;         // centreline heading per station
  std::vector<CollocationStation> stations;
  std::vector<double> arc_m;               // of each station along the centre, n + 1 (the last: length)
};

ClosedSetup closed_setup(const sim::Track& track, const SingleTrackParams& vehicle, const MinTimeLapOptions& options) {
  ClosedSetup c;
  sim::LimitLapOptions qss;
  qss.car_half_width_m = options.car_half_width_m;
  qss.safety_margin_m = options.safety_margin_m;
  qss.station_spacing_m = options.station_spacing_m;
  c.qss_lap = sim::limit_lap(track, vehicle, qss);
  sim::RacingLineOptions line_options;
  line_options.margin_m = options.car_half_width_m + options.safety_margin_m;
  line_options.station_spacing_m = options.station_spacing_m;
  line_options.length_weight_1pm2 = c.qss_lap.length_weight_1pm2;
  c.line = sim::racing_line(track, line_options);

  const std::size_t n = c.line.centre.size();
  // Centreline heading per station; interval curvature = heading change / arc; station curvature
  // the mean of its two intervals, so that the trapezoid's sum of kappa ds is the total turn.
  std::vector<double> interval_kappa(n), ds(n);
  c.heading_rad.resize(n);
  for (std::size_t i = 0; i < n; ++i) c.heading_rad[i] = tangent_heading(c.line.centre, i);
  c.arc_m.assign(n + 1, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    ds[i] = sim::distance(c.line.centre[i], c.line.centre[(i + 1) % n]);
    interval_kappa[i] = wrap_angle(c.heading_rad[(i + 1) % n] - c.heading_rad[i]) / ds[i];
    c.arc_m[i + 1] = c.arc_m[i] + ds[i];
  }
  c.stations.resize(n);
  const double margin = line_options.margin_m;
  for (std::size_t i = 0; i < n; ++i) {
    c.stations[i].kappa_1pm = 0.5 * (interval_kappa[(i + n - 1) % n] + interval_kappa[i]);
    c.stations[i].ds_m = ds[i];
    c.stations[i].min_offset_m = -(c.line.right_m[i] - margin);
    c.stations[i].max_offset_m = c.line.left_m[i] - margin;
  }
  return c;
}

// A start for the solver at one station: on the line at offset n and heading error xi, at speed v
// round a path of curvature kappa.
void guess_station(const SingleTrackParams& vehicle, double offset_m, double heading_error_rad, double speed_mps,
                   double path_kappa_1pm, double* zi) {
  const double wheelbase = vehicle.cg_to_front_axle_m + vehicle.cg_to_rear_axle_m;
  zi[var::kOffset] = offset_m;
  zi[var::kHeadingError] = heading_error_rad;
  zi[var::kVx] = speed_mps;
  zi[var::kVy] = 0.0;
  zi[var::kYawRate] = speed_mps * path_kappa_1pm;
  zi[var::kOmegaFront] = zi[var::kOmegaRear] = speed_mps / vehicle.wheel_radius_m;
  zi[var::kSteer] = std::clamp(std::atan(wheelbase * path_kappa_1pm) / vehicle.max_steer_rad, -1.0, 1.0);
  zi[var::kThrottle] = 0.2;
}

struct Solved {
  std::vector<double> z;
  std::string status;
  bool converged = false;
  int iterations = 0;
  double max_defect = 0.0;
};

// mu_strategy: IPOPT's barrier update, "adaptive" (the flying lap) or "monotone" (the standing
// start from the flying lap, a start close to the solution: half the iterations).
Solved solve(const Collocation& problem, const std::vector<double>& start, const MinTimeLapOptions& options,
             const std::string& mu_strategy) {
  Ipopt::SmartPtr<MinTimeNlp> nlp = new MinTimeNlp(problem, start);
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
  app->Options()->SetStringValue("hessian_approximation", "limited-memory");
  app->Options()->SetNumericValue("tol", options.tolerance);
  app->Options()->SetIntegerValue("max_iter", options.max_iterations);
  app->Options()->SetIntegerValue("print_level", options.verbose ? 5 : 0);
  app->Options()->SetStringValue("sb", "yes");  // no banner
  app->Options()->SetStringValue("mu_strategy", mu_strategy);
  // The limited-memory Hessian converges slowly at the end: on long tracks the lap time settles to
  // 1e-4 s while the dual infeasibility wanders near 1e-4. Stop there; the defects are checked below.
  app->Options()->SetNumericValue("acceptable_tol", 1e-4);
  app->Options()->SetNumericValue("acceptable_dual_inf_tol", 1e-2);
  app->Options()->SetNumericValue("acceptable_constr_viol_tol", options.max_defect);
  app->Options()->SetNumericValue("acceptable_obj_change_tol", 1e-6);
  app->Options()->SetIntegerValue("acceptable_iter", 5);
  if (app->Initialize() != Ipopt::Solve_Succeeded) throw Error("min_time_lap: IPOPT failed to initialise");
  const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(Ipopt::SmartPtr<Ipopt::TNLP>(GetRawPtr(nlp)));

  Solved out;
  out.status = status_name(status);
  out.converged = status == Ipopt::Solve_Succeeded || status == Ipopt::Solved_To_Acceptable_Level;
  out.iterations = Ipopt::IsValid(app->Statistics()) ? app->Statistics()->IterationCount() : 0;
  if (nlp->solution.size() != start.size()) throw Error("min_time_lap: IPOPT returned no point (" + out.status + ")");
  out.z = nlp->solution;
  std::vector<double> defects(static_cast<std::size_t>(problem.constraints()));
  problem.defects(out.z.data(), defects.data());
  for (double d : defects) out.max_defect = std::max(out.max_defect, std::abs(d));
  if (!(out.max_defect <= options.max_defect)) out.converged = false;
  return out;
}

// The solution as a lap: per station the path, speeds, accelerations, states and commands.
MinTimeLap collect(const Collocation& problem, const Solved& solved, const std::vector<StationFrame>& frames) {
  MinTimeLap out;
  out.solver_status = solved.status;
  out.converged = solved.converged;
  out.iterations = solved.iterations;
  out.max_defect = solved.max_defect;
  const std::vector<double>& z = solved.z;
  const std::size_t n = frames.size();
  sim::LimitLap& lap = out.lap;
  double t = 0.0, s = 0.0;
  sim::Vec2 previous{};
  for (std::size_t i = 0; i < n; ++i) {
    const double* zi = &z[i * var::kCount];
    const CollocationStation& st = problem.station(static_cast<int>(i));
    const sim::Vec2 p = frames[i].centre + zi[var::kOffset] * frames[i].normal;
    if (i > 0) s += sim::distance(previous, p);
    previous = p;
    SingleTrackTerms<double> e;
    single_track_terms(problem.coeffs(), zi[var::kVx], zi[var::kVy], zi[var::kYawRate], zi[var::kOmegaFront],
                       zi[var::kOmegaRear], zi[var::kSteer], zi[var::kThrottle], &e);
    // Accelerations in the body frame, with the rotation of the frame: a = dv/dt + omega x v.
    const double ax = e.dvx_mps2 - zi[var::kVy] * zi[var::kYawRate];
    const double ay = e.dvy_mps2 + zi[var::kVx] * zi[var::kYawRate];
    const double speed = std::hypot(zi[var::kVx], zi[var::kVy]);
    lap.s_m.push_back(s);
    lap.x_m.push_back(p.x);
    lap.y_m.push_back(p.y);
    lap.speed_mps.push_back(speed);
    lap.ax_mps2.push_back(ax);
    lap.ay_mps2.push_back(ay);
    lap.curvature_1pm.push_back(speed > 0 ? ay / (speed * speed) : 0.0);
    out.offset_m.push_back(zi[var::kOffset]);
    out.heading_error_rad.push_back(zi[var::kHeadingError]);
    out.yaw_rad.push_back(frames[i].heading_rad + zi[var::kHeadingError]);
    out.vx_mps.push_back(zi[var::kVx]);
    out.vy_mps.push_back(zi[var::kVy]);
    out.yaw_rate_radps.push_back(zi[var::kYawRate]);
    out.omega_front_radps.push_back(zi[var::kOmegaFront]);
    out.omega_rear_radps.push_back(zi[var::kOmegaRear]);
    out.steer.push_back(zi[var::kSteer]);
    out.throttle.push_back(zi[var::kThrottle]);
    out.time_s.push_back(t);
    out.max_body_slip_rad = std::max(out.max_body_slip_rad, std::abs(std::atan2(zi[var::kVy], zi[var::kVx])));
    if (static_cast<int>(i) < problem.intervals()) {
      const std::size_t j = (i + 1) % n;
      t += 0.5 * st.ds_m *
           (1.0 / centreline_speed_mps(zi, st.kappa_1pm) +
            1.0 / centreline_speed_mps(&z[j * var::kCount], problem.station(static_cast<int>(j)).kappa_1pm));
    }
  }
  lap.length_m = problem.closed() ? s + sim::distance(previous, sim::Vec2{lap.x_m.front(), lap.y_m.front()}) : s;
  lap.lap_time_s = problem.lap_time_s(z.data());
  lap.mean_speed_mps = lap.length_m / lap.lap_time_s;
  lap.max_speed_mps = *std::max_element(lap.speed_mps.begin(), lap.speed_mps.end());
  lap.min_speed_mps = *std::min_element(lap.speed_mps.begin(), lap.speed_mps.end());
  return out;
}

// Linear interpolation of per-station values of the closed setup at arc length s in [0, length].
struct ArcInterpolation {
  std::size_t i = 0, j = 0;  // the stations either side
  double t = 0.0;            // 0 at i, 1 at j
  double at(const std::vector<double>& v) const { return (1.0 - t) * v[i] + t * v[j]; }
  sim::Vec2 at(const sim::Polyline& p) const { return (1.0 - t) * p[i] + t * p[j]; }
};

ArcInterpolation interpolation_at(const std::vector<double>& arc_m, double s) {
  const std::size_t n = arc_m.size() - 1;
  const auto upper = std::upper_bound(arc_m.begin(), arc_m.end(), s);
  std::size_t i = static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, upper - arc_m.begin() - 1));
  i = std::min(i, n - 1);
  const double t = std::clamp((s - arc_m[i]) / (arc_m[i + 1] - arc_m[i]), 0.0, 1.0);
  return {i, (i + 1) % n, t};
}

// Arc lengths of the standing start's stations: the launch's end, then geometrically growing
// steps (ratio q, from the rest point) until they reach the closed stations' spacing, then the
// closed stations, then the start line again at the centre's length.
std::vector<double> standing_station_arcs(const std::vector<double>& closed_arc_m, double launch_m, double ratio) {
  const double length = closed_arc_m.back();
  const double spacing = length / static_cast<double>(closed_arc_m.size() - 1);
  std::vector<double> arcs{launch_m};
  while (arcs.back() * (ratio - 1.0) < spacing) arcs.push_back(arcs.back() * ratio);
  for (std::size_t i = 1; i + 1 < closed_arc_m.size(); ++i)
    if (closed_arc_m[i] > arcs.back() + 0.5 * spacing) arcs.push_back(closed_arc_m[i]);
  arcs.push_back(length);
  return arcs;
}

double angle_between(double a_rad, double b_rad, double t) { return a_rad + t * wrap_angle(b_rad - a_rad); }

// A start for one station from the flying lap's solution between its stations a.i and a.j, the
// velocities scaled down to at most `speed_mps` (the launch, where the flying car is faster).
void guess_from_flying(const MinTimeLap& flying, const ArcInterpolation& a, double speed_mps, double* zk) {
  zk[var::kOffset] = a.at(flying.offset_m);
  zk[var::kHeadingError] = angle_between(flying.heading_error_rad[a.i], flying.heading_error_rad[a.j], a.t);
  zk[var::kVx] = a.at(flying.vx_mps);
  zk[var::kVy] = a.at(flying.vy_mps);
  zk[var::kYawRate] = a.at(flying.yaw_rate_radps);
  zk[var::kOmegaFront] = a.at(flying.omega_front_radps);
  zk[var::kOmegaRear] = a.at(flying.omega_rear_radps);
  zk[var::kSteer] = a.at(flying.steer);
  zk[var::kThrottle] = a.at(flying.throttle);
  const double scale = std::min(1.0, speed_mps / std::hypot(zk[var::kVx], zk[var::kVy]));
  for (int v : {var::kVx, var::kVy, var::kYawRate, var::kOmegaFront, var::kOmegaRear}) zk[v] *= scale;
}


// The closed loop's start pose relative to the centreline's first station (vertex 0 of both).
struct StartPose {
  double offset_m = 0.0, heading_error_rad = 0.0;
};

StartPose start_pose_on(const sim::Track& track, const ClosedSetup& setup) {
  const sim::Pose2 start = track.start_pose();
  const sim::Vec2 start_point{start.x_m, start.y_m};
  return {sim::dot(start_point - setup.line.centre[0], setup.line.normal[0]),
          wrap_angle(start.yaw_rad - setup.heading_rad[0])};
}

// The standing start's stations at the arc lengths `arcs`, their geometry interpolated between
// the closed setup's stations.
struct StandingStart {
  std::vector<CollocationStation> stations;
  std::vector<StationFrame> frames;
};

StandingStart standing_stations(const ClosedSetup& setup, const std::vector<double>& arcs) {
  const std::size_t m = arcs.size();
  StandingStart out;
  out.stations.resize(m);
  out.frames.resize(m);
  for (std::size_t k = 0; k < m; ++k) {
    const ArcInterpolation a = interpolation_at(setup.arc_m, arcs[k]);
    const CollocationStation& si = setup.stations[a.i];
    const CollocationStation& sj = setup.stations[a.j];
    CollocationStation& st = out.stations[k];
    st.kappa_1pm = (1.0 - a.t) * si.kappa_1pm + a.t * sj.kappa_1pm;
    st.ds_m = k + 1 < m ? arcs[k + 1] - arcs[k] : 0.0;
    st.min_offset_m = (1.0 - a.t) * si.min_offset_m + a.t * sj.min_offset_m;
    st.max_offset_m = (1.0 - a.t) * si.max_offset_m + a.t * sj.max_offset_m;
    sim::Vec2 normal = a.at(setup.line.normal);
    normal = (1.0 / std::hypot(normal.x, normal.y)) * normal;
    out.frames[k] = {a.at(setup.line.centre), normal, angle_between(setup.heading_rad[a.i], setup.heading_rad[a.j], a.t)};
  }
  return out;
}

// IPOPT's start for the standing start: the flying lap's solution (else the racing line's), its
// speeds no higher than the QSS lap's from rest on the racing line (`qss`, per closed station and
// the start line again), its offsets and headings faded in from the start pose over the first metres.
std::vector<double> standing_guess(const SingleTrackParams& vehicle, const ClosedSetup& setup, const sim::LimitLap& qss,
                                   const std::vector<double>& arcs, const StartPose& start, double launch_speed_mps,
                                   const MinTimeLap* flying) {
  constexpr double kFadeInM = 10.0;
  std::vector<double> heading_error(setup.heading_rad.size());
  for (std::size_t i = 0; i < heading_error.size(); ++i)
    heading_error[i] = wrap_angle(tangent_heading(setup.line.line, i) - setup.heading_rad[i]);
  std::vector<double> z(arcs.size() * var::kCount);
  for (std::size_t k = 0; k < arcs.size(); ++k) {
    const ArcInterpolation a = interpolation_at(setup.arc_m, arcs[k]);
    // The QSS profile has a station more than the closed line: index it from 0 to n, not wrapped.
    const double qss_speed = (1.0 - a.t) * qss.speed_mps[a.i] + a.t * qss.speed_mps[a.j == 0 ? a.i + 1 : a.j];
    const double speed = std::max(launch_speed_mps, qss_speed);
    double* zk = &z[k * var::kCount];
    if (flying) guess_from_flying(*flying, a, speed, zk);
    else guess_station(vehicle, a.at(setup.line.offset_m), a.at(heading_error), speed, a.at(qss.curvature_1pm), zk);
    const double fade = std::min(1.0, arcs[k] / kFadeInM);
    zk[var::kOffset] = start.offset_m + fade * (zk[var::kOffset] - start.offset_m);
    zk[var::kHeadingError] = start.heading_error_rad + fade * (zk[var::kHeadingError] - start.heading_error_rad);
  }
  return z;
}

double launch_grip_N(const SingleTrackParams& p) {
  const sim::CarLimits c = sim::car_limits(p);
  if (p.front_drive_share > 0.0) return c.traction_grip_N;  // static loads: no more than the car has
  // Rear-wheel drive, front wheel rolling: the model's quasi-static pitch transfer
  // (dynamics/single_track.hpp) with mu_Rx = mu_R gives f_Rz = m g l_f / (L - h mu_R).
  const double mu_rear = sim::tyre_peak_friction(p.rear_tyre(), p.slip_blend);
  const double den = p.wheelbase_m() - p.cg_height_m * mu_rear;
  if (!(den > 0.0)) throw Error("launch_from_rest: the pitch transfer would lift the front wheels (L - h mu <= 0)");
  return mu_rear * p.mass_kg * p.gravity_mps2 * p.cg_to_front_axle_m / den;
}

}  // namespace

Launch launch_from_rest(const SingleTrackParams& vehicle, double speed_mps) {
  if (!(std::isfinite(speed_mps) && speed_mps >= 0.0)) throw Error("launch_from_rest: speed_mps must be finite and >= 0");
  const sim::CarLimits c = sim::car_limits(vehicle);
  const double grip_N = launch_grip_N(vehicle);
  const double motor_N = c.drive_force_N * (1.0 - speed_mps / c.no_load_speed_mps);
  if (!(motor_N >= grip_N))
    throw Error("launch_from_rest: the motor's drive line (" + std::to_string(motor_N) + " N at " +
                std::to_string(speed_mps) + " m/s) is below the driven axle's grip (" + std::to_string(grip_N) +
                " N): the grip-limited closed form does not hold; lower launch_speed_mps");
  const double g_N = grip_N - c.rolling_force_N, drag = c.drag_kgpm, m = c.mass_kg;
  if (!(g_N > drag * speed_mps * speed_mps))
    throw Error("launch_from_rest: the grip does not beat rolling resistance and drag up to " +
                std::to_string(speed_mps) + " m/s");
  Launch l;
  if (drag > 0.0) {
    l.time_s = m / std::sqrt(g_N * drag) * std::atanh(speed_mps * std::sqrt(drag / g_N));
    l.distance_m = m / (2.0 * drag) * std::log(g_N / (g_N - drag * speed_mps * speed_mps));
  } else {
    l.time_s = m * speed_mps / g_N;
    l.distance_m = m * speed_mps * speed_mps / (2.0 * g_N);
  }
  return l;
}

MinTimeLap min_time_lap(const sim::Track& track, const SingleTrackParams& vehicle, const MinTimeLapOptions& options) {
  validate(options);
  std::string why;
  if (!vehicle.is_valid(&why)) throw Error("min_time_lap: invalid vehicle parameters: " + why);
  // The start: the fastest QSS racing line, on stations of the collocation's spacing.
  ClosedSetup setup = closed_setup(track, vehicle, options);
  const sim::LimitLap start_lap = sim::lap_on_line(setup.line.line, sim::car_limits(vehicle));
  const std::size_t n = setup.line.centre.size();
  std::vector<StationFrame> frames(n);
  for (std::size_t i = 0; i < n; ++i) frames[i] = {setup.line.centre[i], setup.line.normal[i], setup.heading_rad[i]};
  const Collocation problem(vehicle, std::move(setup.stations), options.command_smoothing_s);

  std::vector<double> z(static_cast<std::size_t>(problem.variables()));
  for (std::size_t i = 0; i < n; ++i)
    guess_station(vehicle, setup.line.offset_m[i], wrap_angle(tangent_heading(setup.line.line, i) - setup.heading_rad[i]),
                  start_lap.speed_mps[i], start_lap.curvature_1pm[i], &z[i * var::kCount]);

  MinTimeLap out = collect(problem, solve(problem, z, options, "adaptive"), frames);
  out.qss_lap_time_s = setup.qss_lap.lap_time_s;
  return out;
}

MinTimeLap standing_start_lap(const sim::Track& track, const SingleTrackParams& vehicle,
                              const MinTimeLapOptions& options, const MinTimeLap* flying) {
  validate(options);
  std::string why;
  if (!vehicle.is_valid(&why)) throw Error("min_time_lap: invalid vehicle parameters: " + why);
  const ClosedSetup setup = closed_setup(track, vehicle, options);
  if (flying && flying->vx_mps.size() != setup.line.centre.size())
    throw Error("min_time_lap: the flying lap to start from has " + std::to_string(flying->vx_mps.size()) +
                " stations, the standing start's track " + std::to_string(setup.line.centre.size()) +
                " (solve it with the same options)");
  const Launch launch = launch_from_rest(vehicle, options.launch_speed_mps);
  if (!(launch.distance_m < 0.5 * setup.arc_m[1]))
    throw Error("min_time_lap: the launch to " + std::to_string(options.launch_speed_mps) + " m/s takes " +
                std::to_string(launch.distance_m) + " m, more than half the first station's spacing; lower launch_speed_mps");
  const StartPose start = start_pose_on(track, setup);
  const std::vector<double> arcs = standing_station_arcs(setup.arc_m, launch.distance_m, options.launch_station_ratio);
  StandingStart standing = standing_stations(setup, arcs);
  const sim::LimitLap qss = sim::standing_lap_on_line(setup.line.line, sim::car_limits(vehicle));
  std::vector<double> z = standing_guess(vehicle, setup, qss, arcs, start, options.launch_speed_mps, flying);

  Collocation problem(vehicle, std::move(standing.stations), options.command_smoothing_s, /*closed=*/false);
  // The first station: the start pose, launched straight ahead to the launch speed, the wheels
  // rolling with the road (free, the solver would start with the rear wheel spinning: energy a car
  // from rest does not have).
  const double v0 = options.launch_speed_mps;
  problem.fix(0, var::kOffset, start.offset_m);
  problem.fix(0, var::kHeadingError, start.heading_error_rad);
  problem.fix(0, var::kVx, v0);
  problem.fix(0, var::kVy, 0.0);
  problem.fix(0, var::kYawRate, 0.0);
  problem.fix(0, var::kOmegaFront, v0 / vehicle.wheel_radius_m);
  problem.fix(0, var::kOmegaRear, v0 / vehicle.wheel_radius_m);
  guess_station(vehicle, start.offset_m, start.heading_error_rad, v0, 0.0, &z[0]);

  MinTimeLap out = collect(problem, solve(problem, z, options, "monotone"), standing.frames);
  out.qss_lap_time_s = qss.lap_time_s;
  // The launch from rest, in closed form, before the first station.
  out.lap.standing_start = true;
  out.lap.launch_time_s = launch.time_s;
  out.lap.lap_time_s += launch.time_s;
  out.lap.length_m += launch.distance_m;
  out.lap.mean_speed_mps = out.lap.length_m / out.lap.lap_time_s;
  for (double& t : out.time_s) t += launch.time_s;
  return out;
}

}  // namespace mppi::laptime
