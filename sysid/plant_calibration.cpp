#include "sysid/plant_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <Eigen/Dense>

#include "base/error.hpp"
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
  const std::vector<double>* t = nullptr;
  const std::vector<double>* steer = nullptr;
  const std::vector<double>* throttle = nullptr;
  double dt_s = 0;                  // the recording's sample interval (median step)
};

double sample_interval_s(const std::vector<double>& t) {
  std::vector<double> steps(t.size() - 1);
  for (std::size_t i = 1; i < t.size(); ++i) steps[i - 1] = t[i] - t[i - 1];
  std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2), steps.end());
  return steps[steps.size() / 2];
}

RolloutPlan make_plan(const VehicleModelSpec& spec, const sim::Recording& rec, const PredictionErrorOptions& o) {
  std::string why;
  if (!o.is_valid(&why)) throw Error("prediction error: " + why);
  RolloutPlan p;
  p.t = &rec.column("t");
  p.steer = &rec.column("steer");
  p.throttle = &rec.column("throttle");
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
  p.dt_s = sample_interval_s(*p.t);
  p.steps = std::max(1, static_cast<int>(std::lround(o.horizon_s / p.dt_s)));
  const std::size_t stride = std::max<std::size_t>(1, static_cast<std::size_t>(std::lround(o.stride_s / p.dt_s)));
  // A rollout never spans a gap (a dropout, or the seam between joined recordings): its
  // window, and the sample before it (the actuators' last command), must last no longer than
  // their samples at the recording's interval.
  const auto steps = static_cast<std::size_t>(p.steps);
  const auto& t = *p.t;
  if (steps >= n) throw Error("prediction error: the recording is shorter than one horizon");
  for (std::size_t s = 0; s + steps < n; s += stride) {
    const bool after_gap = s > 0 && t[s] - t[s - 1] > 1.5 * p.dt_s;
    if (!after_gap && t[s + steps] - t[s] <= (static_cast<double>(steps) + 0.5) * p.dt_s) p.starts.push_back(s);
  }
  if (p.starts.empty()) throw Error("prediction error: the recording has no gap-free stretch of one horizon");
  return p;
}

// Normalised residuals, [rollout][lead 1..steps][channel] flattened; NaN where not recorded.
void residuals(const VehicleModelSpec& spec, const std::vector<double>& values, const sim::Recording& rec,
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
        const double u[2] = {(*p.steer)[i - 1], (*p.throttle)[i - 1]};
        spec.step(values, x.data(), u, (*p.t)[i] - (*p.t)[i - 1]);
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

std::vector<double> channel_scales(const sim::Recording& rec, const std::vector<std::string>& channels) {
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
                                 const sim::Recording& rec, const std::vector<double>& scales,
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

std::vector<double> step_response(const RolloutStep& step, std::vector<double> x, const double u[2],
                                  std::size_t channel, const std::vector<double>& leads_s, double dt_s) {
  if (!(dt_s > 0) || leads_s.empty() || channel >= x.size())
    throw Error("step response: dt_s > 0, at least one lead and a channel of the state are needed");
  std::vector<double> out;
  double t = 0;
  for (double lead : leads_s) {
    for (; t < lead - 0.5 * dt_s; t += dt_s) step(x, u, dt_s);
    out.push_back(x[channel]);
  }
  return out;
}

std::vector<double> steering_step_yaw_rate(const VehicleModelSpec& spec, const std::vector<double>& values,
                                           double speed_mps, double steer, double throttle,
                                           const std::vector<double>& leads_s, double dt_s) {
  if (!(dt_s > 0)) throw Error("steering step: dt_s must be > 0");
  // 1 s of straight driving, then the step: a recording to start (and prime) the plant from.
  const int before = static_cast<int>(std::lround(1.0 / dt_s));
  sim::Recording rec;
  rec.columns = {"t", "x", "y", "yaw", "vx", "vy", "yaw_rate", "steer", "throttle"};
  rec.data.assign(rec.columns.size(), {});
  for (int i = 0; i <= before; ++i) {
    const double row[9] = {i * dt_s, 0, 0, 0, speed_mps, 0, 0, i < before ? 0.0 : steer, throttle};
    for (std::size_t c = 0; c < 9; ++c) rec.data[c].push_back(row[c]);
  }
  std::vector<double> x(static_cast<std::size_t>(spec.nx));
  spec.init_state(rec, static_cast<std::size_t>(before), x.data());
  if (spec.prime) spec.prime(values, rec, static_cast<std::size_t>(before), x.data());
  const auto m = std::find_if(spec.measurable.begin(), spec.measurable.end(),
                              [](const auto& c) { return c.first == "yaw_rate"; });
  if (m == spec.measurable.end()) throw Error("steering step: the " + spec.kind + " model has no yaw rate");
  const RolloutStep plant = [&](std::vector<double>& s, const double u[2], double dt) {
    spec.step(values, s.data(), u, dt);
  };
  const double u[2] = {steer, throttle};
  return step_response(plant, std::move(x), u, static_cast<std::size_t>(m->second), leads_s, dt_s);
}

CalibrationResult calibrate(const VehicleModelSpec& spec, const sim::Recording& rec, const std::vector<double>& scales,
                            const CalibrationOptions& o, std::vector<double> initial) {
  std::string why;
  if (!o.is_valid(&why)) throw Error("calibrate: " + why);
  const std::size_t np = spec.estimated.size();
  if (initial.empty()) initial = spec.nominal;
  if (initial.size() != np) throw Error("calibrate: one initial value per estimated parameter is needed");
  if (!o.bounds.empty() && o.bounds.size() != np) throw Error("calibrate: one bound pair per parameter is needed");
  const RolloutPlan plan = make_plan(spec, rec, o.error);
  if (scales.size() != plan.state_index.size()) throw Error("calibrate: one scale per channel is needed");

  // Search space: z = log(p) for positive parameters, z = p otherwise; box in z.
  std::vector<double> lo(np), hi(np);
  for (std::size_t i = 0; i < np; ++i) {
    const std::string& n = spec.estimated[i];
    if (!o.bounds.empty()) {
      lo[i] = o.bounds[i].first;
      hi[i] = o.bounds[i].second;
    } else if (spec.log_scale[i]) {
      lo[i] = spec.nominal[i] / o.log_range;
      hi[i] = spec.nominal[i] * o.log_range;
    } else if (n == "tyre.C") {
      lo[i] = 0.05, hi[i] = 1.99;
    } else if (n == "tyre.E") {
      lo[i] = -10, hi[i] = 0.99;
    } else if (n == "rear_tyre_C_scale") {  // keeps the rear C inside (0, 2) for front C up to 1.2
      lo[i] = 0.3, hi[i] = 1.6;
    } else if (n == "rear_tyre_B_scale" || n == "rear_tyre_D_scale") {
      lo[i] = 0.3, hi[i] = 3.0;
    } else if (n == "steer_lag_s" || n == "throttle_lag_s") {
      lo[i] = 0, hi[i] = 0.5;
    } else if (n == "steer_cubic") {
      lo[i] = -0.9, hi[i] = 1.9;
    } else if (n == "steer_offset") {
      lo[i] = -0.3, hi[i] = 0.3;
    } else {
      lo[i] = -std::numeric_limits<double>::infinity(), hi[i] = std::numeric_limits<double>::infinity();
    }
    if (spec.log_scale[i]) {
      if (!(lo[i] > 0)) throw Error("calibrate: the lower bound of " + n + " must be > 0");
      lo[i] = std::log(lo[i]);
      hi[i] = std::log(hi[i]);
    }
  }
  auto to_values = [&](const Eigen::VectorXd& z) {
    std::vector<double> v(np);
    for (std::size_t i = 0; i < np; ++i) v[i] = spec.log_scale[i] ? std::exp(z[static_cast<Eigen::Index>(i)]) : z[static_cast<Eigen::Index>(i)];
    return v;
  };
  auto project = [&](Eigen::VectorXd& z) {
    for (std::size_t i = 0; i < np; ++i) z[static_cast<Eigen::Index>(i)] = std::clamp(z[static_cast<Eigen::Index>(i)], lo[i], hi[i]);
  };
  // A lag of 0 has no derivative (a forward step of 1e-4 s is far below the 2-ms substep): start
  // lags that would begin at 0 at 0.05 s.
  for (std::size_t i = 0; i < np; ++i)
    if ((spec.estimated[i] == "steer_lag_s" || spec.estimated[i] == "throttle_lag_s") && initial[i] == 0)
      initial[i] = 0.05;
  Eigen::VectorXd z(static_cast<Eigen::Index>(np));
  for (std::size_t i = 0; i < np; ++i) {
    if (spec.log_scale[i] && !(initial[i] > 0)) throw Error("calibrate: " + spec.estimated[i] + " must start > 0");
    z[static_cast<Eigen::Index>(i)] = spec.log_scale[i] ? std::log(initial[i]) : initial[i];
  }
  project(z);

  CalibrationResult res;
  res.names = spec.estimated;
  res.initial = initial;
  std::vector<double> r, r2;
  // Residuals that were not recorded (NaN) do not count: zero them for the least squares.
  auto eval = [&](const Eigen::VectorXd& zz, std::vector<double>& out) {
    residuals(spec, to_values(zz), rec, plan, scales, out);
    ++res.evaluations;
    const double c = mean_square(out);
    for (double& v : out)
      if (!std::isfinite(v)) v = 0;
    return c;
  };
  double cost = eval(z, r);
  res.cost_history.push_back(cost);
  const Eigen::Index m = static_cast<Eigen::Index>(r.size());
  Eigen::MatrixXd J(m, static_cast<Eigen::Index>(np));
  double lambda = 1e-3;
  for (int it = 0; it < o.max_iterations; ++it) {
    for (std::size_t j = 0; j < np; ++j) {
      const Eigen::Index jj = static_cast<Eigen::Index>(j);
      Eigen::VectorXd zp = z;
      double h = 1e-4 * std::max(1.0, std::abs(z[jj]));
      if (zp[jj] + h > hi[j]) h = -h;  // stay inside the box
      zp[jj] += h;
      eval(zp, r2);
      for (Eigen::Index k = 0; k < m; ++k) J(k, jj) = (r2[static_cast<std::size_t>(k)] - r[static_cast<std::size_t>(k)]) / h;
    }
    const Eigen::Map<const Eigen::VectorXd> rv(r.data(), m);
    const Eigen::MatrixXd JtJ = J.transpose() * J;
    const Eigen::VectorXd g = J.transpose() * rv;
    bool improved = false;
    for (int tries = 0; tries < 12 && !improved; ++tries) {
      Eigen::MatrixXd A = JtJ;
      for (Eigen::Index d = 0; d < A.rows(); ++d) A(d, d) += lambda * std::max(JtJ(d, d), 1e-12);
      Eigen::VectorXd zn = z - A.ldlt().solve(g);
      project(zn);
      const double cn = eval(zn, r2);
      if (std::isfinite(cn) && cn < cost) {
        const double rel = (cost - cn) / cost;
        z = zn;
        r.swap(r2);
        cost = cn;
        lambda = std::max(lambda / 3, 1e-9);
        improved = true;
        res.cost_history.push_back(cost);
        if (rel < o.relative_tolerance) it = o.max_iterations;  // converged
      } else {
        lambda *= 10;
      }
    }
    res.iterations = it + 1;
    if (!improved) break;
  }
  res.values = to_values(z);
  res.at_bound.resize(np);
  for (std::size_t i = 0; i < np; ++i) {
    const double zi = z[static_cast<Eigen::Index>(i)];
    res.at_bound[i] = std::abs(zi - lo[i]) < 1e-9 || std::abs(zi - hi[i]) < 1e-9;
  }
  res.iterations = std::min(res.iterations, o.max_iterations);
  return res;
}

}  // namespace mppi::sysid
