#include "sysid/vehicle_estimation.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "base/error.hpp"

namespace mppi::sysid {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

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

// The rows of the fit window.
std::vector<std::size_t> fit_rows(const std::vector<double>& t, const EstimateSettings& st) {
  std::vector<std::size_t> rows;
  for (std::size_t i = 0; i < t.size(); ++i)
    if (t[i] >= st.t_begin_s && t[i] < st.t_end_s) rows.push_back(i);
  if (rows.size() < 10) throw Error("estimate: fewer than 10 rows in the fit window");
  return rows;
}

double median_interval_s(const std::vector<double>& t, const std::vector<std::size_t>& rows) {
  std::vector<double> d;
  for (std::size_t k = 1; k < rows.size(); ++k) d.push_back(t[rows[k]] - t[rows[k - 1]]);
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return d[d.size() / 2];
}

// The recording columns the filter measures, and the state each one is.
struct MeasuredChannels {
  std::vector<std::string> names;
  std::vector<int> state_index;
  std::vector<const std::vector<double>*> columns;
};

MeasuredChannels measured_channels(const VehicleModelSpec& spec, const PreparedRecording& rec,
                                   const EstimateSettings& st) {
  MeasuredChannels out;
  for (const auto& [col, idx] : spec.measurable) {
    const bool wanted = st.measure.empty() ? true
                                           : std::find(st.measure.begin(), st.measure.end(), col) != st.measure.end();
    if (!wanted || !rec.has_column(col)) continue;
    out.names.push_back(col);
    out.state_index.push_back(idx);
    out.columns.push_back(&rec.column(col));
  }
  for (const auto& m : st.measure)
    if (std::find(out.names.begin(), out.names.end(), m) == out.names.end())
      throw Error("estimate: cannot measure '" + m + "' (not in the recording or not a state of the " +
                  spec.kind + " model)");
  if (out.names.empty()) throw Error("estimate: no measured channel in the recording");
  return out;
}

// The spec as the filter's process and measurement model; u = (steer, throttle, dt): the sample
// interval travels with the control.
JointModel joint_model(const VehicleModelSpec& spec, const std::vector<int>& state_index) {
  const int np = static_cast<int>(spec.estimated.size());
  const std::vector<bool> logs = spec.log_scale;
  JointModel m;
  m.nx = spec.nx;
  m.np = np;
  m.ny = static_cast<int>(state_index.size());
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
  return m;
}

// The filter's start: parameters (internal units) and states with their covariances, the noises.
struct FilterStart {
  Vec p0, param_walk_std, x0;
  Mat Pp0, Px0, Qx, R;
};

FilterStart filter_start(const VehicleModelSpec& spec, const PreparedRecording& rec, const EstimateSettings& st,
                         const std::vector<double>& init, const std::vector<std::string>& measured,
                         std::size_t first_row, double dt_med) {
  const int np = static_cast<int>(spec.estimated.size()), nx = spec.nx, ny = static_cast<int>(measured.size());
  const std::vector<bool>& logs = spec.log_scale;
  FilterStart f{Vec(np), Vec(np), Vec(nx), Mat::Zero(np, np), Mat::Zero(nx, nx), Mat::Zero(nx, nx), Mat::Zero(ny, ny)};
  for (int i = 0; i < np; ++i) {
    f.p0(i) = to_internal(init[i], logs[i]);
    const double sd0 = logs[i] ? st.param_initial_std : st.param_initial_std * std::max(0.3, std::abs(init[i]));
    f.Pp0(i, i) = sd0 * sd0;
    f.param_walk_std(i) =
        st.param_walk_std_per_s * std::sqrt(dt_med) * (logs[i] ? 1.0 : std::max(0.3, std::abs(init[i])));
  }
  spec.init_state(rec, first_row, f.x0.data());
  for (int i = 0; i < nx; ++i) {
    const double q = spec.process_std_per_sqrt_s[i] * st.process_noise_scale * std::sqrt(dt_med);
    f.Qx(i, i) = q * q;
    f.Px0(i, i) = std::max(1e-6, 100 * q * q);
  }
  for (int i = 0; i < ny; ++i) {
    double sd = default_measurement_std(measured[i]);
    for (const auto& [name, v] : st.measurement_std)
      if (name == measured[i]) sd = v;
    f.R(i, i) = sd * sd;
  }
  return f;
}

JointFilterSettings filter_settings(const EstimateSettings& st, double dt_med) {
  JointFilterSettings fs;
  fs.ukf = st.ukf;
  fs.adaptive = st.adaptive;
  fs.alm.window = std::max(10, static_cast<int>(std::lround(st.alm_window_s / dt_med)));
  fs.alm.min_samples = std::min(fs.alm.window, std::max(10, fs.alm.window / 5));
  fs.alm.estimate_process = st.alm_process;
  fs.alm.estimate_measurement = st.alm_measurement;
  fs.alm.estimate_means = false;  // a constant bias is not separable from the state (docs)
  return fs;
}

// Appends the filter's parameters and their standard deviations (physical units) at `time`.
void record_params(const JointStateFilter& filt, const std::vector<bool>& logs, double time, EstimateResult& res) {
  const int np = static_cast<int>(logs.size());
  const Vec p = filt.params(), sd = filt.param_std();
  std::vector<double> v(np), s(np);
  for (int i = 0; i < np; ++i) {
    v[i] = to_physical(p(i), logs[i]);
    s[i] = logs[i] ? v[i] * sd(i) : sd(i);
  }
  res.t.push_back(time);
  res.history.push_back(v);
  res.history_std.push_back(s);
}

}  // namespace

EstimateResult estimate_parameters(const VehicleModelSpec& spec, const PreparedRecording& rec,
                                   const EstimateSettings& st, const std::vector<double>& initial_values) {
  std::string why;
  if (!st.is_valid(&why)) throw Error("estimate settings: " + why);
  const auto t0_wall = std::chrono::steady_clock::now();
  const auto& t = rec.t;
  const std::vector<std::size_t> rows = fit_rows(t, st);
  const MeasuredChannels measured = measured_channels(spec, rec, st);
  EstimateResult res;
  res.measured = measured.names;
  const int ny = static_cast<int>(res.measured.size());
  const std::vector<double> init = initial_values.empty() ? spec.nominal : initial_values;
  if (init.size() != spec.estimated.size()) throw Error("estimate: wrong number of initial values");
  const double dt_med = median_interval_s(t, rows);
  const FilterStart f = filter_start(spec, rec, st, init, res.measured, rows[0], dt_med);
  JointStateFilter filt(joint_model(spec, measured.state_index), filter_settings(st, dt_med), f.x0, f.Px0, f.p0,
                        f.Pp0, f.Qx, f.R, f.param_walk_std);

  res.names = spec.estimated;
  res.initial = init;
  record_params(filt, spec.log_scale, t[rows[0]], res);
  std::vector<double> innov_sq(ny, 0.0);
  std::vector<int> innov_n(ny, 0);
  for (std::size_t k = 1; k < rows.size(); ++k) {
    const std::size_t prev = rows[k - 1], cur = rows[k];
    Vec u_prev(3), u(3), y(ny);
    u_prev << rec.steer_over(prev), rec.throttle_over(prev), t[cur] - t[prev];
    u << rec.steer_over(cur), rec.throttle_over(cur), 0.0;
    if (!std::isfinite(u_prev(0))) u_prev(0) = 0;
    if (!std::isfinite(u_prev(1))) u_prev(1) = 0;
    for (int i = 0; i < ny; ++i) y(i) = (*measured.columns[i])[cur];
    filt.step(u_prev, y, u);
    const UpdateInfo& up = filt.last_update();
    for (std::size_t a = 0; a < up.rows.size(); ++a) {
      innov_sq[up.rows[a]] += up.innovation(a) * up.innovation(a);
      ++innov_n[up.rows[a]];
    }
    ++res.steps;
    if (k % st.record_every == 0 || k + 1 == rows.size()) record_params(filt, spec.log_scale, t[cur], res);
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
                                     const PreparedRecording& rec, std::size_t begin, std::size_t end,
                                     double horizon_s) {
  ValidationResult v;
  v.channels = {"x", "y", "yaw", "vx", "vy", "yaw_rate"};
  end = std::min(end, rec.rows());
  if (end < begin + 2) throw Error("validate: fewer than 2 rows");
  const auto& t = rec.t;
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
        const double steer = rec.steer_over(i), throttle = rec.throttle_over(i);
        const double u[2] = {std::isfinite(steer) ? steer : 0.0, std::isfinite(throttle) ? throttle : 0.0};
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
