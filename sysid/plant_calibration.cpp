#include "sysid/plant_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include <Eigen/Dense>

#include "base/error.hpp"
#include "base/least_squares.hpp"
#include "sysid/real_data.hpp"

namespace mppi::sysid {

namespace {

constexpr double kDivergedResidual = 10.0;  // normalised residual of a non-finite prediction

// Where the rollouts start and which model state each channel is.
struct RolloutPlan {
  std::vector<std::size_t> starts;
  int steps = 0;                    // samples predicted per rollout (leads 1..steps)
  std::vector<int> state_index;     // per channel
  std::vector<const std::vector<double>*> measured;
  double dt_s = 0;                  // the recording's sample interval (median step)
};

double sample_interval_s(const std::vector<double>& t) {
  std::vector<double> steps(t.size() - 1);
  for (std::size_t i = 1; i < t.size(); ++i) steps[i - 1] = t[i] - t[i - 1];
  std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2), steps.end());
  return steps[steps.size() / 2];
}

RolloutPlan make_plan(const VehicleModelSpec& spec, const PreparedRecording& rec, const PredictionErrorOptions& o) {
  std::string why;
  if (!o.is_valid(&why)) throw Error("prediction error: " + why);
  RolloutPlan p;
  for (const auto& c : o.channels) {
    auto it = std::find_if(spec.measurable.begin(), spec.measurable.end(),
                           [&](const auto& m) { return m.first == c; });
    if (it == spec.measurable.end())
      throw Error("prediction error: the " + spec.kind + " model does not predict channel '" + c + "'");
    p.state_index.push_back(it->second);
    p.measured.push_back(&rec.column(c));
  }
  const std::size_t n = rec.rows();
  if (n < 3) throw Error("prediction error: the recording has fewer than 3 rows");
  p.dt_s = rec.dt_s;
  p.steps = std::max(1, static_cast<int>(std::lround(o.horizon_s / p.dt_s)));
  const int stride = std::max(1, static_cast<int>(std::lround(o.stride_s / p.dt_s)));
  if (static_cast<std::size_t>(p.steps) >= n) throw Error("prediction error: the recording is shorter than one horizon");
  // A rollout stays inside one continuous piece of the recording (no gap, no seam between joined
  // recordings, no screened-out value): the segments of a prepared recording. None starts on a
  // piece's first row, where the command before the start (the actuators' state) is not known.
  for (const Segment& s : make_segments(rec, {}, p.steps, stride))
    if (s.start > 0 && rec.continuous(s.start - 1, 1)) p.starts.push_back(s.start);
  if (p.starts.empty()) throw Error("prediction error: the recording has no gap-free stretch of one horizon");
  return p;
}

// Normalised residuals, [rollout][lead 1..steps][channel] flattened; NaN where not recorded.
void residuals(const VehicleModelSpec& spec, const std::vector<double>& values, const PreparedRecording& rec,
               const RolloutPlan& p, const std::vector<double>& scales, std::vector<double>& out) {
  const std::size_t nc = p.state_index.size();
  out.assign(p.starts.size() * static_cast<std::size_t>(p.steps) * nc, 0.0);
  std::vector<double> x(static_cast<std::size_t>(spec.nx));
  std::size_t k = 0;
  for (std::size_t s : p.starts) {
    spec.init_state(rec, s, x.data());
    if (spec.prime) spec.prime(values, rec, s, x.data());
    bool diverged = false;
    for (int lead = 1; lead <= p.steps; ++lead) {
      const std::size_t i = s + static_cast<std::size_t>(lead);
      if (!diverged) {
        const double u[2] = {rec.steer_over(i - 1), rec.throttle_over(i - 1)};
        spec.step(values, x.data(), u, rec.t[i] - rec.t[i - 1]);
        for (double v : x) diverged = diverged || !std::isfinite(v);
      }
      for (std::size_t c = 0; c < nc; ++c, ++k) {
        const double m = (*p.measured[c])[i];
        out[k] = diverged ? kDivergedResidual : (x[static_cast<std::size_t>(p.state_index[c])] - m) / scales[c];
      }
    }
  }
}

double mean_square(const std::vector<double>& r) {
  double s = 0;
  std::size_t n = 0;
  for (double v : r)
    if (std::isfinite(v)) {
      s += v * v;
      ++n;
    }
  return n ? s / static_cast<double>(n) : std::numeric_limits<double>::infinity();
}

}  // namespace

bool PredictionErrorOptions::is_valid(std::string* why) const {
  auto fail = [&](const char* m) {
    if (why) *why = m;
    return false;
  };
  if (!(horizon_s > 0 && std::isfinite(horizon_s))) return fail("horizon_s must be > 0");
  if (!(stride_s > 0 && std::isfinite(stride_s))) return fail("stride_s must be > 0");
  if (channels.empty()) return fail("at least one channel is needed");
  for (double h : report_horizons_s)
    if (!(h > 0 && h <= horizon_s + 1e-9)) return fail("report horizons must be in (0, horizon_s]");
  return true;
}

bool CalibrationOptions::is_valid(std::string* why) const {
  if (!error.is_valid(why)) return false;
  if (max_iterations < 0 || !(relative_tolerance >= 0) || !(log_range > 1)) {
    if (why) *why = "max_iterations >= 0, relative_tolerance >= 0 and log_range > 1 are required";
    return false;
  }
  return true;
}

std::vector<double> channel_scales(const PreparedRecording& rec, const std::vector<std::string>& channels) {
  std::vector<double> out;
  for (const auto& c : channels) {
    double s = 0, s2 = 0;
    std::size_t n = 0;
    for (double v : rec.column(c))
      if (std::isfinite(v)) {
        s += v;
        s2 += v * v;
        ++n;
      }
    const double mean = n ? s / static_cast<double>(n) : 0;
    const double var = n ? s2 / static_cast<double>(n) - mean * mean : 0;
    if (!(var > 1e-12)) throw Error("channel scales: column '" + c + "' is constant or empty");
    out.push_back(std::sqrt(var));
  }
  return out;
}

PredictionError prediction_error(const VehicleModelSpec& spec, const std::vector<double>& values,
                                 const PreparedRecording& rec, const std::vector<double>& scales,
                                 const PredictionErrorOptions& o) {
  const RolloutPlan p = make_plan(spec, rec, o);
  const std::size_t nc = p.state_index.size();
  if (scales.size() != nc) throw Error("prediction error: one scale per channel is needed");
  std::vector<double> r;
  residuals(spec, values, rec, p, scales, r);
  PredictionError e;
  e.channels = o.channels;
  e.scales = scales;
  e.horizons_s = o.report_horizons_s;
  e.rollouts = static_cast<int>(p.starts.size());
  const double dt = p.dt_s;
  std::vector<int> lead_of;
  for (double h : o.report_horizons_s) lead_of.push_back(std::clamp(static_cast<int>(std::lround(h / dt)), 1, p.steps));
  e.nrmse_at.assign(nc, std::vector<double>(lead_of.size(), 0.0));
  e.nrmse.assign(nc, 0.0);
  for (std::size_t c = 0; c < nc; ++c) {
    std::vector<double> sum_at(lead_of.size(), 0.0);
    std::vector<std::size_t> n_at(lead_of.size(), 0);
    double sum = 0;
    std::size_t n = 0;
    for (std::size_t w = 0; w < p.starts.size(); ++w)
      for (int lead = 1; lead <= p.steps; ++lead) {
        const double v = r[(w * static_cast<std::size_t>(p.steps) + static_cast<std::size_t>(lead - 1)) * nc + c];
        if (!std::isfinite(v)) continue;
        sum += v * v;
        ++n;
        for (std::size_t h = 0; h < lead_of.size(); ++h)
          if (lead == lead_of[h]) {
            sum_at[h] += v * v;
            ++n_at[h];
          }
      }
    e.nrmse[c] = n ? std::sqrt(sum / static_cast<double>(n)) : std::numeric_limits<double>::quiet_NaN();
    for (std::size_t h = 0; h < lead_of.size(); ++h)
      e.nrmse_at[c][h] = n_at[h] ? std::sqrt(sum_at[h] / static_cast<double>(n_at[h]))
                                 : std::numeric_limits<double>::quiet_NaN();
    e.mean_nrmse += e.nrmse[c] / static_cast<double>(nc);
  }
  return e;
}

sim::Recording join_recordings(const std::vector<sim::Recording>& pieces, double gap_s) {
  if (pieces.empty()) throw Error("join recordings: no recordings");
  if (!(gap_s > 1.0 && std::isfinite(gap_s))) throw Error("join recordings: the gap must be > 1 s");
  std::vector<double> interval_s;
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    if (pieces[k].rows() < 2)
      throw Error("join recordings: recording " + std::to_string(k + 1) + " has fewer than 2 rows");
    interval_s.push_back(sample_interval_s(pieces[k].column("t")));
    if (std::abs(interval_s[k] - interval_s[0]) > 0.01 * interval_s[0])
      throw Error("join recordings: recording " + std::to_string(k + 1) + " is sampled every " +
                  std::to_string(interval_s[k]) + " s, recording 1 every " + std::to_string(interval_s[0]) +
                  " s (resample it first)");
  }
  sim::Recording out;
  out.metadata = pieces.front().metadata;
  for (const std::string& c : pieces.front().columns)
    if (std::all_of(pieces.begin(), pieces.end(), [&](const sim::Recording& r) { return r.has_column(c); }))
      out.columns.push_back(c);
  out.data.resize(out.columns.size());
  const std::size_t t_col = static_cast<std::size_t>(std::find(out.columns.begin(), out.columns.end(), "t") -
                                                     out.columns.begin());
  for (const sim::Recording& r : pieces) {
    const double shift_s = out.rows() > 0 ? out.data[t_col].back() + gap_s - r.column("t").front() : 0.0;
    for (std::size_t c = 0; c < out.columns.size(); ++c) {
      const std::vector<double>& src = r.column(out.columns[c]);
      std::vector<double>& dst = out.data[c];
      const std::size_t first = dst.size();
      dst.insert(dst.end(), src.begin(), src.end());
      if (c == t_col)
        for (std::size_t i = first; i < dst.size(); ++i) dst[i] += shift_s;
    }
  }
  return out;
}

sim::Recording read_learned_model_log(const std::string& path) {
  // A rosbag goes through the registered reader (load_any_recording); other files are read as the
  // project's format.
  sim::Recording rec = path.size() > 4 && path.compare(path.size() - 4, 4, ".bag") == 0
                           ? load_any_recording(path)
                           : sim::RecordingReader::read(path);
  if (rec.has_column("applied_steer") && rec.has_column("applied_throttle")) {
    const std::vector<double> steer = rec.column("applied_steer"), throttle = rec.column("applied_throttle");
    for (std::size_t c = 0; c < rec.columns.size(); ++c) {
      if (rec.columns[c] == "steer") rec.data[c] = steer;
      if (rec.columns[c] == "throttle") rec.data[c] = throttle;
    }
  }
  for (const char* c : {"steer", "throttle", "vx", "vy", "yaw_rate"}) {
    const std::vector<double>& v = rec.column(c);
    for (std::size_t i = 0; i < v.size(); ++i)
      if (!std::isfinite(v[i]))
        throw Error(path + ": data row " + std::to_string(i + 1) + ": " + c +
                    " is missing or not finite (a calibration rolls out through every row)");
  }
  return rec;
}

namespace {

// The box of parameter `i` in physical units (CalibrationOptions documents the defaults).
std::pair<double, double> physical_bounds(const VehicleModelSpec& spec, const CalibrationOptions& o, std::size_t i) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const std::string& n = spec.estimated[i];
  if (!o.bounds.empty()) return o.bounds[i];
  if (spec.log_scale[i]) return {spec.nominal[i] / o.log_range, spec.nominal[i] * o.log_range};
  if (n == "tyre.C") return {0.05, 1.99};
  if (n == "tyre.E") return {-10, 0.99};
  if (n == "rear_tyre_C_scale") return {0.3, 1.6};  // keeps the rear C inside (0, 2) for front C up to 1.2
  if (n == "rear_tyre_B_scale" || n == "rear_tyre_D_scale") return {0.3, 3.0};
  if (n == "steer_lag_s" || n == "throttle_lag_s") return {0, 0.5};
  if (n == "steer_cubic") return {-0.9, 1.9};
  if (n == "steer_offset") return {-0.3, 0.3};
  return {-kInf, kInf};
}

// The search space: z = log(p) for positive parameters, z = p otherwise.
double to_search(const VehicleModelSpec& spec, std::size_t i, double value) {
  return spec.log_scale[i] ? std::log(value) : value;
}
std::vector<double> to_values(const VehicleModelSpec& spec, const Eigen::VectorXd& z) {
  std::vector<double> v(spec.estimated.size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    const double zi = z[static_cast<Eigen::Index>(i)];
    v[i] = spec.log_scale[i] ? std::exp(zi) : zi;
  }
  return v;
}

// The box in the search space, into `problem`.
void set_search_box(const VehicleModelSpec& spec, const CalibrationOptions& o, LeastSquaresProblem& problem) {
  const std::size_t np = spec.estimated.size();
  problem.lower.resize(static_cast<Eigen::Index>(np));
  problem.upper.resize(static_cast<Eigen::Index>(np));
  for (std::size_t i = 0; i < np; ++i) {
    const auto [lo, hi] = physical_bounds(spec, o, i);
    if (spec.log_scale[i] && !(lo > 0))
      throw Error("calibrate: the lower bound of " + spec.estimated[i] + " must be > 0");
    problem.lower[static_cast<Eigen::Index>(i)] = to_search(spec, i, lo);
    problem.upper[static_cast<Eigen::Index>(i)] = to_search(spec, i, hi);
  }
}

// The start in the search space, inside the box. A lag of 0 has no derivative (a forward step of
// 1e-4 s is far below the 2-ms substep): lags that would begin at 0 start at 0.05 s.
Eigen::VectorXd search_start(const VehicleModelSpec& spec, const LeastSquaresProblem& problem,
                             std::vector<double>& initial) {
  const std::size_t np = spec.estimated.size();
  for (std::size_t i = 0; i < np; ++i)
    if ((spec.estimated[i] == "steer_lag_s" || spec.estimated[i] == "throttle_lag_s") && initial[i] == 0)
      initial[i] = 0.05;
  Eigen::VectorXd z(static_cast<Eigen::Index>(np));
  for (std::size_t i = 0; i < np; ++i) {
    if (spec.log_scale[i] && !(initial[i] > 0)) throw Error("calibrate: " + spec.estimated[i] + " must start > 0");
    const auto k = static_cast<Eigen::Index>(i);
    z[k] = std::clamp(to_search(spec, i, initial[i]), problem.lower[k], problem.upper[k]);
  }
  return z;
}

}  // namespace

CalibrationResult calibrate(const VehicleModelSpec& spec, const PreparedRecording& rec, const std::vector<double>& scales,
                            const CalibrationOptions& o, std::vector<double> initial) {
  std::string why;
  if (!o.is_valid(&why)) throw Error("calibrate: " + why);
  const std::size_t np = spec.estimated.size();
  if (initial.empty()) initial = spec.nominal;
  if (initial.size() != np) throw Error("calibrate: one initial value per estimated parameter is needed");
  if (!o.bounds.empty() && o.bounds.size() != np) throw Error("calibrate: one bound pair per parameter is needed");
  const RolloutPlan plan = make_plan(spec, rec, o.error);
  if (scales.size() != plan.state_index.size()) throw Error("calibrate: one scale per channel is needed");

  LeastSquaresProblem problem;
  set_search_box(spec, o, problem);
  problem.difference_step = Eigen::VectorXd::Constant(static_cast<Eigen::Index>(np), 1e-4);
  problem.step_scales_with_value = true;
  // Residuals that were not recorded (NaN) do not count: zeroed for the least squares.
  problem.residuals = [&](const Eigen::VectorXd& z, std::vector<double>* out) {
    residuals(spec, to_values(spec, z), rec, plan, scales, *out);
    const double cost = mean_square(*out);
    for (double& v : *out)
      if (!std::isfinite(v)) v = 0;
    return cost;
  };
  const Eigen::VectorXd start = search_start(spec, problem, initial);
  LevenbergMarquardtOptions lm;
  lm.max_iterations = o.max_iterations;
  lm.tries_per_iteration = 12;
  lm.initial_damping = 1e-3;
  lm.damping_down = 3.0;
  lm.min_damping = 1e-9;
  lm.damping_up = 10.0;
  lm.relative_tolerance = o.relative_tolerance;
  const LeastSquaresResult fit = levenberg_marquardt(problem, start, lm);

  CalibrationResult res;
  res.names = spec.estimated;
  res.initial = initial;
  res.values = to_values(spec, fit.params);
  res.cost_history = fit.cost_history;
  res.iterations = fit.iterations;
  res.evaluations = fit.evaluations;
  res.at_bound.resize(np);
  for (std::size_t i = 0; i < np; ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    const double z = fit.params[k];
    res.at_bound[i] = std::abs(z - problem.lower[k]) < 1e-9 || std::abs(z - problem.upper[k]) < 1e-9;
  }
  return res;
}

}  // namespace mppi::sysid
