#include "diagnose/replay.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "base/error.hpp"

namespace mppi::diagnose {

std::vector<Segment> make_segments(const DiagData& d, const std::vector<char>& mask, int len, int stride) {
  std::vector<Segment> out;
  const std::size_t n = d.rows();
  std::size_t k = 0;
  while (k + static_cast<std::size_t>(len) < n) {
    bool ok = d.continuous(k, static_cast<std::size_t>(len));
    for (int i = 0; ok && !mask.empty() && i <= len; ++i) ok = mask[k + static_cast<std::size_t>(i)] != 0;
    if (ok) {
      out.push_back({k, len});
      k += static_cast<std::size_t>(stride);
    } else {
      ++k;
    }
  }
  return out;
}

namespace {

// How a model reads the recording: a measurement as the true state behind it (the member's
// sensor faults), and the commands that acted over a state-stamped interval (shifted by the time
// offset and the pure delays; a shift by a fraction of a row averages two recorded commands).
class RecordingView {
 public:
  RecordingView(const ReplayModel& m, const DiagData& d)
      : d_(d), sf_(m.sensor), inv_scale_(1.0 / m.sensor.speed_scale),
        steer_shift_rows_((m.sensor.time_offset_s + m.command_delay.steer_s) / d.dt_s),
        throttle_shift_rows_((m.sensor.time_offset_s + m.command_delay.throttle_s) / d.dt_s),
        has_roll_(!d.roll.empty()) {}
  float true_vx(std::size_t k) const { return static_cast<float>(d_.vx[k] * inv_scale_); }
  float true_vy(std::size_t k) const { return static_cast<float>(d_.vy[k] * inv_scale_); }
  float true_r(std::size_t k) const { return static_cast<float>(d_.r[k] - sf_.gyro_bias_radps); }
  bool roll_at(std::size_t k) const { return has_roll_ && std::isfinite(d_.roll[k]); }
  void command_over(std::size_t k, float* steer, float* throttle) const {
    *steer = static_cast<float>(shifted(k, steer_shift_rows_, &DiagData::steer_over));
    *throttle = static_cast<float>(shifted(k, throttle_shift_rows_, &DiagData::throttle_over));
  }
  // The measured states of row k put into a state (element i at x[i * stride]): positions and
  // time as measured, velocities (and roll) blended towards the measurement by `gain`.
  void force_measured(std::size_t k, float* x, int stride, int time_state, float gain) const {
    auto at = [&](int i) -> float& { return x[static_cast<std::ptrdiff_t>(i) * stride]; };
    at(state::kX) = static_cast<float>(d_.x[k]);
    at(state::kY) = static_cast<float>(d_.y[k]);
    at(state::kYaw) = static_cast<float>(d_.yaw[k]);
    at(state::kVx) += gain * (true_vx(k) - at(state::kVx));
    at(state::kVy) += gain * (true_vy(k) - at(state::kVy));
    at(state::kYawRate) += gain * (true_r(k) - at(state::kYawRate));
    if (roll_at(k)) at(state::kRoll) += gain * (static_cast<float>(d_.roll[k]) - at(state::kRoll));
    at(time_state) = static_cast<float>(d_.t[k]);
  }
  // What the sensors would show of a state.
  void measurement_of(const float* x, int stride, double* out5) const {
    auto at = [&](int i) { return x[static_cast<std::ptrdiff_t>(i) * stride]; };
    out5[0] = at(state::kVx) * sf_.speed_scale;
    out5[1] = at(state::kVy) * sf_.speed_scale;
    out5[2] = at(state::kYawRate) + sf_.gyro_bias_radps;
    out5[3] = at(state::kX);
    out5[4] = at(state::kY);
  }

 private:
  double shifted(std::size_t k, double shift_rows, double (DiagData::*over)(std::size_t) const) const {
    if (shift_rows == 0.0) return (d_.*over)(k);
    const double pos = static_cast<double>(k) - shift_rows;
    const double lo = std::floor(pos), w = pos - lo;
    const auto row = [&](double i) { return static_cast<std::size_t>(std::clamp(i, 0.0, static_cast<double>(d_.rows() - 1))); };
    return (1 - w) * (d_.*over)(row(lo)) + w * (d_.*over)(row(lo + 1));
  }
  const DiagData& d_;
  SensorFaults sf_;
  double inv_scale_, steer_shift_rows_, throttle_shift_rows_;
  bool has_roll_;
};

// Rows of command history before a start that the priming runs over (those of its own piece).
int history_rows(const DiagData& d, std::size_t k0, const ReplayOptions& o) {
  const int prime_rows = static_cast<int>(std::lround(o.prime_s / d.dt_s));
  int h = 0;
  while (h < prime_rows && k0 > static_cast<std::size_t>(h) && d.piece[k0 - static_cast<std::size_t>(h) - 1] == d.piece[k0]) ++h;
  return h;
}

// Segments of one length replayed in lockstep: `lanes` = 1 (model.step) or ReplayModel::kLanes
// (model.step_lanes; `count` <= kLanes real segments, the rest of the lanes repeat the first).
// Lane j replays segs[j] after histories[j] rows of command history and writes its predictions to
// outs[j]. The rows are counted back from the segments' starts, so every lane reaches its start
// on the same row; a lane with a shorter history joins on its first row of history (until then
// its state is stepped but not used). Lanes share each row's step: the mean of the sample
// intervals of the lanes that have joined, so a recording with timing jitter advances a lane by
// its own interval only on average.
void predict_lockstep(const ReplayModel& model, const DiagData& d, const Segment* const* segs, double* const* outs,
                      const int* histories, int count, int lanes, const ReplayOptions& o) {
  constexpr int L = ReplayModel::kLanes;
  const RecordingView view(model, d);
  const int nx = model.states(), time_state = model.time_index(), len = segs[0]->len;
  auto seg = [&](int j) -> const Segment& { return *segs[j < count ? j : 0]; };
  auto history_of = [&](int j) { return histories[j < count ? j : 0]; };
  const int history = *std::max_element(histories, histories + count);
  auto joins_at = [&](int j) { return history - history_of(j); };  // the row a lane joins on
  // The data row of lane j on row r (r = history: its segment's start).
  auto data_row = [&](int j, int r) {
    return static_cast<std::size_t>(static_cast<std::ptrdiff_t>(seg(j).start) + r - history);
  };
  // Unmeasured states (actuator chains, wheel speeds): run the model over the history before the
  // start with its measured states forced back to the recording at every sample, so that they
  // settle where this model puts them; then start from the measured state. The rows more than
  // o.wheel_prime_s before the start run the actuator chains alone, one lane at a time.
  const int wheel_rows = [&] {
    int r = 0;
    while (r < history && static_cast<double>(history - r) * d.dt_s > o.wheel_prime_s) ++r;
    return r;
  }();
  alignas(64) float xs[ReplayModel::kMaxStates * L];
  // Lane j's start state at its first row of history, its chains run over the chain-only rows.
  auto start_lane = [&](int j) {
    float lane_state[ReplayModel::kMaxStates];
    const std::size_t k0 = seg(j).start;
    VehicleState vs;
    vs.x_m = static_cast<float>(d.x[k0]);
    vs.y_m = static_cast<float>(d.y[k0]);
    vs.yaw_rad = static_cast<float>(d.yaw[k0]);
    vs.vx_mps = view.true_vx(k0);
    vs.vy_mps = view.true_vy(k0);
    vs.yaw_rate_radps = view.true_r(k0);
    if (view.roll_at(k0)) vs.roll_rad = static_cast<float>(d.roll[k0]);
    model.init_state(vs, lane_state);
    lane_state[time_state] = static_cast<float>(d.t[k0]);
    float s, t;
    view.command_over(data_row(j, joins_at(j)), &s, &t);
    model.set_actuators(lane_state, s, t);
    for (int r = joins_at(j); r < wheel_rows; ++r) {
      const std::size_t k = data_row(j, r);
      view.force_measured(k, lane_state, 1, time_state, 1.f);
      view.command_over(k, &s, &t);
      model.advance_actuators(lane_state, s, t, static_cast<float>(d.t[k + 1] - d.t[k]));
    }
    for (int i = 0; i < nx; ++i) xs[i * lanes + j] = lane_state[i];
  };
  for (int j = 0; j < lanes; ++j) start_lane(j);  // a lane that joins later is started again then
  float u[2 * L];
  double lane_dt[L];
  bool joined[L];
  float outlier_state[ReplayModel::kMaxStates];
  // Substeps of one row's interval: about o.substep_s each.
  auto substeps_of = [&](double dt) { return std::max(1, static_cast<int>(std::lround(dt / o.substep_s))); };
  // Row r of every lane: the commands and interval of its data row (lanes that have not joined:
  // no command, the shared step).
  auto advance_row = [&](int r) {
    for (int j = 0; j < lanes; ++j) {
      joined[j] = r >= joins_at(j);
      if (!joined[j]) {
        u[j] = u[lanes + j] = 0.f;
        continue;
      }
      const std::size_t k = data_row(j, r);
      view.command_over(k, &u[j], &u[lanes + j]);
      lane_dt[j] = d.t[k + 1] - d.t[k];
    }
    if (lanes == 1) {
      const int n = substeps_of(lane_dt[0]);
      for (int i = 0; i < n; ++i) model.step(xs, u[0], u[1], static_cast<float>(lane_dt[0] / n));
      return;
    }
    // The lanes whose interval is within kSharedStepTolerance of the median share one step, the
    // mean of their intervals (timing jitter); a lane whose interval differs more (a missing row
    // doubles it) takes its own steps from the same start, one lane at a time.
    double sorted[L];
    int joined_count = 0;
    for (int j = 0; j < lanes; ++j)
      if (joined[j]) sorted[joined_count++] = lane_dt[j];
    const auto [min_dt, max_dt] = std::minmax_element(sorted, sorted + joined_count);
    double median = *min_dt;  // when max - min <= tolerance x min, every lane is within it of the median
    if (*max_dt - *min_dt > kSharedStepTolerance * *min_dt) {
      std::nth_element(sorted, sorted + joined_count / 2, sorted + joined_count);
      median = sorted[joined_count / 2];
    }
    auto shares = [&](int j) { return !joined[j] || std::abs(lane_dt[j] - median) <= kSharedStepTolerance * median; };
    double shared = 0;
    int sharing = 0;
    for (int j = 0; j < lanes; ++j)
      if (joined[j] && shares(j)) {
        shared += lane_dt[j];
        ++sharing;
      }
    shared /= sharing;
    int outliers[L], outlier_count = 0;
    float before[ReplayModel::kMaxStates * L];
    for (int j = 0; j < lanes; ++j)
      if (!shares(j)) outliers[outlier_count++] = j;
    if (outlier_count > 0) std::copy(xs, xs + nx * lanes, before);
    const int n = substeps_of(shared);
    model.step_lanes(xs, u, static_cast<float>(shared / n), n);
    for (int i = 0; i < outlier_count; ++i) {
      const int j = outliers[i];
      for (int c = 0; c < nx; ++c) outlier_state[c] = before[c * lanes + j];
      const int m = substeps_of(lane_dt[j]);
      for (int q = 0; q < m; ++q) model.step(outlier_state, u[j], u[lanes + j], static_cast<float>(lane_dt[j] / m));
      for (int c = 0; c < nx; ++c) xs[c * lanes + j] = outlier_state[c];
    }
  };
  // Velocities: a constant-gain observer (blend of the model's value and the measurement) once
  // the full model runs, which takes sensor noise off the start state: raw on a lane's first row
  // of the full model, then blended by o.observer_gain.
  for (int r = wheel_rows; r <= history; ++r) {
    for (int j = 0; j < lanes; ++j) {
      const int first_full_row = std::max(wheel_rows, joins_at(j));
      if (r < first_full_row) continue;
      if (r == first_full_row && r > wheel_rows) start_lane(j);  // it joins now
      const float gain = r == first_full_row ? 1.f : static_cast<float>(o.observer_gain);
      view.force_measured(data_row(j, r), xs + j, lanes, time_state, gain);
    }
    if (r == history) break;
    advance_row(r);
  }
  for (int i = 0; i < len; ++i) {
    advance_row(history + i);
    for (int j = 0; j < count; ++j)
      view.measurement_of(xs + j, lanes, outs[j] + static_cast<std::ptrdiff_t>(i) * kPredStride);
  }
}

}  // namespace

void predict_segment(const ReplayModel& model, const DiagData& d, const Segment& s,
                     const ReplayOptions& o, double* out) {
  const Segment* seg = &s;
  const int history = history_rows(d, s.start, o);
  predict_lockstep(model, d, &seg, &out, &history, 1, 1, o);
}

void predict_segments(const ReplayModel& model, const DiagData& d, const std::vector<Segment>& segs,
                      const ReplayOptions& o, double* out) {
  // Segments of one length go together, kLanes at a time, longest history first (so that the
  // lanes of a group wait as little as possible for each other); a group of fewer than
  // kMinLockstepSegments is replayed one segment at a time.
  struct Job {
    int len, history;
    const Segment* seg;
    double* out;
  };
  std::vector<Job> jobs;
  jobs.reserve(segs.size());
  for (const Segment& s : segs) {
    jobs.push_back({s.len, history_rows(d, s.start, o), &s, out});
    out += static_cast<std::ptrdiff_t>(s.len) * kPredStride;
  }
  std::stable_sort(jobs.begin(), jobs.end(),
                   [](const Job& a, const Job& b) { return a.len != b.len ? a.len < b.len : a.history > b.history; });
  constexpr int L = ReplayModel::kLanes;
  const Segment* lane_segs[L];
  double* lane_outs[L];
  int lane_histories[L];
  for (std::size_t i = 0; i < jobs.size();) {
    std::size_t n = 1;
    while (i + n < jobs.size() && n < static_cast<std::size_t>(L) && jobs[i + n].len == jobs[i].len) ++n;
    for (std::size_t j = 0; j < n; ++j) {
      lane_segs[j] = jobs[i + j].seg;
      lane_outs[j] = jobs[i + j].out;
      lane_histories[j] = jobs[i + j].history;
    }
    if (n >= kMinLockstepSegments) {
      predict_lockstep(model, d, lane_segs, lane_outs, lane_histories, static_cast<int>(n), L, o);
    } else {
      for (std::size_t j = 0; j < n; ++j)
        predict_lockstep(model, d, &lane_segs[j], &lane_outs[j], &lane_histories[j], 1, 1, o);
    }
    i += n;
  }
}

void segment_residuals(const ReplayModel& model, const DiagData& d,
                       const std::vector<Segment>& segs, const std::array<double, kChannels>& scale,
                       const ReplayOptions& o, std::vector<double>* res) {
  std::size_t total = 0;
  for (const auto& s : segs) total += static_cast<std::size_t>(s.len) * kChannels;
  res->resize(total);
  std::vector<double> pred(total / kChannels * kPredStride);
  predict_segments(model, d, segs, o, pred.data());
  std::size_t w = 0, p = 0;
  for (const auto& s : segs) {
    for (int i = 0; i < s.len; ++i, p += kPredStride) {
      const std::size_t k = s.start + static_cast<std::size_t>(i) + 1;
      for (int c = 0; c < kChannels; ++c) {
        double e = (pred[p + static_cast<std::size_t>(c)] - d.channel(c, k)) / scale[c];
        if (!std::isfinite(e)) e = 1e3;  // a model that blew up: large, finite
        (*res)[w++] = std::clamp(e, -1e3, 1e3);
      }
    }
  }
}

std::array<double, kChannels> channel_scales(const DiagData& d, const std::vector<char>& mask) {
  const double floor[kChannels] = {0.05, 0.02, 0.02};
  std::array<double, kChannels> out{};
  for (int c = 0; c < kChannels; ++c) {
    double s = 0, s2 = 0;
    std::size_t n = 0;
    for (std::size_t k = 0; k < d.rows(); ++k) {
      if ((!mask.empty() && !mask[k]) || d.piece[k] < 0) continue;
      const double v = d.channel(c, k);
      s += v;
      s2 += v * v;
      ++n;
    }
    const double mean = n ? s / n : 0;
    out[c] = std::max(floor[c], n ? std::sqrt(std::max(0.0, s2 / n - mean * mean)) : 0.0);
  }
  return out;
}

std::vector<HorizonMetrics> horizon_metrics(const ReplayModel& model, const DiagData& d,
                                            const std::vector<char>& mask,
                                            const std::vector<double>& horizons_s, int stride,
                                            const ReplayOptions& o, const DiagData* reference) {
  if (reference && reference->rows() != d.rows())
    throw Error("horizon_metrics: the reference states have " + std::to_string(reference->rows()) +
                " rows, the recording " + std::to_string(d.rows()));
  const DiagData& ref = reference ? *reference : d;
  std::vector<HorizonMetrics> out;
  const auto scale = channel_scales(d, mask);
  for (double hs : horizons_s) {
    HorizonMetrics m;
    m.horizon_s = hs;
    const int len = std::max(1, static_cast<int>(std::lround(hs / d.dt_s)));
    const auto segs = make_segments(d, mask, len, stride);
    m.starts = static_cast<int>(segs.size());
    if (segs.empty()) {
      out.push_back(m);
      continue;
    }
    std::vector<double> pred(segs.size() * static_cast<std::size_t>(len) * kPredStride);
    predict_segments(model, d, segs, o, pred.data());
    std::array<double, kChannels> se{}, sy{}, sy2{};
    double pos = 0;
    for (std::size_t n = 0; n < segs.size(); ++n) {
      const Segment& s = segs[n];
      const std::size_t k = s.start + static_cast<std::size_t>(len);
      const double* p = pred.data() + ((n + 1) * static_cast<std::size_t>(len) - 1) * kPredStride;
      for (int c = 0; c < kChannels; ++c) {
        const double y = ref.channel(c, k);
        const double e = std::isfinite(p[c]) ? p[c] - y : 1e3;
        se[c] += e * e;
        sy[c] += y;
        sy2[c] += y * y;
      }
      const double ex = p[3] - ref.x[k], ey = p[4] - ref.y[k];
      pos += std::isfinite(ex + ey) ? ex * ex + ey * ey : 1e6;
    }
    const double n = static_cast<double>(segs.size());
    double nr = 0;
    for (int c = 0; c < kChannels; ++c) {
      m.rmse[c] = std::sqrt(se[c] / n);
      const double var = std::max(1e-12, sy2[c] / n - (sy[c] / n) * (sy[c] / n));
      m.fit_percent[c] = 100.0 * (1.0 - std::sqrt(se[c] / n) / std::sqrt(var));
      nr += (m.rmse[c] / scale[c]) * (m.rmse[c] / scale[c]);
    }
    m.normalized_rmse = std::sqrt(nr / kChannels);
    m.position_rmse_m = std::sqrt(pos / n);
    out.push_back(m);
  }
  return out;
}

}  // namespace mppi::diagnose
