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
}

}  // namespace

MinTimeLap min_time_lap(const sim::Track& track, const SingleTrackParams& vehicle, const MinTimeLapOptions& options) {
  validate(options);
  std::string why;
  if (!vehicle.is_valid(&why)) throw Error("min_time_lap: invalid vehicle parameters: " + why);
  // The start: the fastest QSS racing line, on stations of the collocation's spacing.
  sim::LimitLapOptions qss;
  qss.car_half_width_m = options.car_half_width_m;
  qss.safety_margin_m = options.safety_margin_m;
  qss.station_spacing_m = options.station_spacing_m;
  const sim::LimitLap qss_lap = sim::limit_lap(track, vehicle, qss);
  sim::RacingLineOptions line_options;
  line_options.margin_m = options.car_half_width_m + options.safety_margin_m;
  line_options.station_spacing_m = options.station_spacing_m;
  line_options.length_weight_1pm2 = qss_lap.length_weight_1pm2;
  const sim::RacingLine line = sim::racing_line(track, line_options);
  const sim::LimitLap start_lap = sim::lap_on_line(line.line, sim::car_limits(vehicle));

  const std::size_t n = line.centre.size();
  // Centreline heading per station; interval curvature = heading change / arc; station curvature
  // the mean of its two intervals, so that the trapezoid's sum of kappa ds is the total turn.
  std::vector<double> heading(n), interval_kappa(n), ds(n);
  for (std::size_t i = 0; i < n; ++i) heading[i] = tangent_heading(line.centre, i);
  for (std::size_t i = 0; i < n; ++i) {
    ds[i] = sim::distance(line.centre[i], line.centre[(i + 1) % n]);
    interval_kappa[i] = wrap_angle(heading[(i + 1) % n] - heading[i]) / ds[i];
  }
  std::vector<CollocationStation> stations(n);
  const double margin = line_options.margin_m;
  for (std::size_t i = 0; i < n; ++i) {
    stations[i].kappa_1pm = 0.5 * (interval_kappa[(i + n - 1) % n] + interval_kappa[i]);
    stations[i].ds_m = ds[i];
    stations[i].min_offset_m = -(line.right_m[i] - margin);
    stations[i].max_offset_m = line.left_m[i] - margin;
  }
  const Collocation problem(vehicle, std::move(stations), options.command_smoothing_s);

  std::vector<double> z(static_cast<std::size_t>(problem.variables()));
  const double wheelbase = vehicle.cg_to_front_axle_m + vehicle.cg_to_rear_axle_m;
  for (std::size_t i = 0; i < n; ++i) {
    double* zi = &z[i * var::kCount];
    const double v = start_lap.speed_mps[i], kappa = start_lap.curvature_1pm[i];
    zi[var::kOffset] = line.offset_m[i];
    zi[var::kHeadingError] = wrap_angle(tangent_heading(line.line, i) - heading[i]);
    zi[var::kVx] = v;
    zi[var::kVy] = 0.0;
    zi[var::kYawRate] = v * kappa;
    zi[var::kOmegaFront] = zi[var::kOmegaRear] = v / vehicle.wheel_radius_m;
    zi[var::kSteer] = std::clamp(std::atan(wheelbase * kappa) / vehicle.max_steer_rad, -1.0, 1.0);
    zi[var::kThrottle] = 0.2;
  }

  Ipopt::SmartPtr<MinTimeNlp> nlp = new MinTimeNlp(problem, z);
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
  app->Options()->SetStringValue("hessian_approximation", "limited-memory");
  app->Options()->SetNumericValue("tol", options.tolerance);
  app->Options()->SetIntegerValue("max_iter", options.max_iterations);
  app->Options()->SetIntegerValue("print_level", options.verbose ? 5 : 0);
  app->Options()->SetStringValue("sb", "yes");  // no banner
  app->Options()->SetStringValue("mu_strategy", "adaptive");
  // The limited-memory Hessian converges slowly at the end: on long tracks the lap time settles to
  // 1e-4 s while the dual infeasibility wanders near 1e-4. Stop there; the defects are checked below.
  app->Options()->SetNumericValue("acceptable_tol", 1e-4);
  app->Options()->SetNumericValue("acceptable_dual_inf_tol", 1e-2);
  app->Options()->SetNumericValue("acceptable_constr_viol_tol", options.max_defect);
  app->Options()->SetNumericValue("acceptable_obj_change_tol", 1e-6);
  app->Options()->SetIntegerValue("acceptable_iter", 5);
  if (app->Initialize() != Ipopt::Solve_Succeeded) throw Error("min_time_lap: IPOPT failed to initialise");
  const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(Ipopt::SmartPtr<Ipopt::TNLP>(GetRawPtr(nlp)));

  MinTimeLap out;
  out.qss_lap_time_s = qss_lap.lap_time_s;
  out.solver_status = status_name(status);
  out.converged = status == Ipopt::Solve_Succeeded || status == Ipopt::Solved_To_Acceptable_Level;
  out.iterations = Ipopt::IsValid(app->Statistics()) ? app->Statistics()->IterationCount() : 0;
  if (nlp->solution.size() != z.size()) throw Error("min_time_lap: IPOPT returned no point (" + out.solver_status + ")");
  z = nlp->solution;
  std::vector<double> defects(static_cast<std::size_t>(problem.constraints()));
  problem.defects(z.data(), defects.data());
  for (double d : defects) out.max_defect = std::max(out.max_defect, std::abs(d));
  if (!(out.max_defect <= options.max_defect)) out.converged = false;

  sim::LimitLap& lap = out.lap;
  double t = 0.0, s = 0.0;
  sim::Vec2 previous{};
  for (std::size_t i = 0; i < n; ++i) {
    const double* zi = &z[i * var::kCount];
    const CollocationStation& st = problem.station(static_cast<int>(i));
    const sim::Vec2 p = line.centre[i] + zi[var::kOffset] * line.normal[i];
    if (i > 0) s += sim::distance(previous, p);
    previous = p;
    SingleTrackTerms<double> e;
    single_track_terms(problem.coeffs(), zi[var::kVx], zi[var::kVy], zi[var::kYawRate], zi[var::kOmegaFront],
                       zi[var::kOmegaRear], zi[var::kSteer], zi[var::kThrottle], &e);
    // Accelerations in the body frame, with the rotation of the frame: a = dv/dt + omega x v.
    const double ax = e.dvx_mps2 - zi[var::kVy] * zi[var::kYawRate];
    const double ay = e.dvy_mps2 + zi[var::kVx] * zi[var::kYawRate];
    lap.s_m.push_back(s);
    lap.x_m.push_back(p.x);
    lap.y_m.push_back(p.y);
    lap.speed_mps.push_back(std::hypot(zi[var::kVx], zi[var::kVy]));
    lap.ax_mps2.push_back(ax);
    lap.ay_mps2.push_back(ay);
    const double speed = std::hypot(zi[var::kVx], zi[var::kVy]);
    lap.curvature_1pm.push_back(speed > 0 ? ay / (speed * speed) : 0.0);
    out.offset_m.push_back(zi[var::kOffset]);
    out.heading_error_rad.push_back(zi[var::kHeadingError]);
    out.yaw_rad.push_back(heading[i] + zi[var::kHeadingError]);
    out.vx_mps.push_back(zi[var::kVx]);
    out.vy_mps.push_back(zi[var::kVy]);
    out.yaw_rate_radps.push_back(zi[var::kYawRate]);
    out.omega_front_radps.push_back(zi[var::kOmegaFront]);
    out.omega_rear_radps.push_back(zi[var::kOmegaRear]);
    out.steer.push_back(zi[var::kSteer]);
    out.throttle.push_back(zi[var::kThrottle]);
    out.time_s.push_back(t);
    out.max_body_slip_rad = std::max(out.max_body_slip_rad, std::abs(std::atan2(zi[var::kVy], zi[var::kVx])));
    t += 0.5 * st.ds_m *
         (1.0 / centreline_speed_mps(zi, st.kappa_1pm) +
          1.0 / centreline_speed_mps(&z[((i + 1) % n) * var::kCount], problem.station(static_cast<int>((i + 1) % n)).kappa_1pm));
  }
  lap.length_m = s + sim::distance(previous, sim::Vec2{lap.x_m.front(), lap.y_m.front()});
  lap.lap_time_s = problem.lap_time_s(z.data());
  lap.mean_speed_mps = lap.length_m / lap.lap_time_s;
  lap.max_speed_mps = *std::max_element(lap.speed_mps.begin(), lap.speed_mps.end());
  lap.min_speed_mps = *std::min_element(lap.speed_mps.begin(), lap.speed_mps.end());
  return out;
}

}  // namespace mppi::laptime
