#include "diagnose/replay.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "base/error.hpp"

namespace mppi::diagnose {

namespace {

// How a model reads the recording: a measurement as the true state behind it (the member's
// sensor faults), and the commands that acted over a state-stamped interval (shifted by the time
// offset and the pure delays; a shift by a fraction of a row averages two recorded commands).
class RecordingView {
 public:
  RecordingView(const ReplayModel& m, const PreparedRecording& d)
      : d_(d), sf_(m.sensor), inv_scale_(1.0 / m.sensor.speed_scale),
        steer_shift_rows_((m.sensor.time_offset_s + m.command_delay.steer_s) / d.dt_s),
        throttle_shift_rows_((m.sensor.time_offset_s + m.command_delay.throttle_s) / d.dt_s),
        has_roll_(!d.roll.empty()) {}
  float true_vx(std::size_t k) const { return static_cast<float>(d_.vx[k] * inv_scale_); }
  float true_vy(std::size_t k) const { return static_cast<float>(d_.vy[k] * inv_scale_); }
  float true_r(std::size_t k) const { return static_cast<float>(d_.r[k] - sf_.gyro_bias_radps); }
  bool roll_at(std::size_t k) const { return has_roll_ && std::isfinite(d_.roll[k]); }
  void command_over(std::size_t k, float* steer, float* throttle) const {
    *steer = static_cast<float>(shifted(k, steer_shift_rows_, &PreparedRecording::steer_over));
    *throttle = static_cast<float>(shifted(k, throttle_shift_rows_, &PreparedRecording::throttle_over));
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
  // The command `shift_rows` rows before row k's, read inside k's piece: across a gap or an
  // unusable row (a command not yet recorded, a screened value) the command is not known, and the
  // piece's nearest one stands for it.
  double shifted(std::size_t k, double shift_rows, double (PreparedRecording::*over)(std::size_t) const) const {
    if (shift_rows == 0.0) return (d_.*over)(k);
    const double pos = static_cast<double>(k) - shift_rows;
    const double lo = std::floor(pos), w = pos - lo;
    const int piece = d_.piece[k];
    const auto row = [&](double i) {
      auto r = static_cast<std::size_t>(std::clamp(i, 0.0, static_cast<double>(d_.rows() - 1)));
      while (r < k && d_.piece[r] != piece) ++r;
      while (r > k && d_.piece[r] != piece) --r;
      return r;
    };
    return (1 - w) * (d_.*over)(row(lo)) + w * (d_.*over)(row(lo + 1));
  }
  const PreparedRecording& d_;
  SensorFaults sf_;
  double inv_scale_, steer_shift_rows_, throttle_shift_rows_;
  bool has_roll_;
};

// Rows of command history before a start that the priming runs over (those of its own piece).
int history_rows(const PreparedRecording& d, std::size_t k0, const ReplayOptions& o) {
  const int prime_rows = static_cast<int>(std::lround(o.prime_s / d.dt_s));
  int h = 0;
  while (h < prime_rows && k0 > static_cast<std::size_t>(h) && d.piece[k0 - static_cast<std::size_t>(h) - 1] == d.piece[k0]) ++h;
  return h;
}

// Segments of one length replayed in lockstep: `lanes` = 1 (model.step) or ReplayModel::kLanes
// (model.step_lanes; `count` <= kLanes real segments, the rest of the lanes repeat the first).
// Lane j replays segs[j] after histories[j] rows of command history. The rows are counted back
// from the segments' starts, so every lane reaches its start on the same row; a lane with a
// shorter history joins on its first row of history (until then its state is stepped but not
// used). Lanes share each row's step: the mean of the sample intervals of the lanes that have
// joined, so a recording with timing jitter advances a lane by its own interval only on average.
class LockstepReplay {
 public:
  LockstepReplay(const ReplayModel& model, const PreparedRecording& d, const Segment* const* segs, const int* histories,
                 int count, int lanes, const ReplayOptions& o)
      : model_(model), d_(d), view_(model, d), segs_(segs), histories_(histories), count_(count), lanes_(lanes), o_(o),
        nx_(model.states()), time_state_(model.time_index()),
        history_(*std::max_element(histories, histories + count)) {
    // The rows more than o.wheel_prime_s before the start run the actuator chains alone.
    while (wheel_rows_ < history_ && static_cast<double>(history_ - wheel_rows_) * d.dt_s > o.wheel_prime_s)
      ++wheel_rows_;
  }

  // Writes lane j's predictions to outs[j] (kPredStride values per row of its segment).
  void run(double* const* outs) {
    for (int j = 0; j < lanes_; ++j) start_lane(j);  // a lane that joins later is started again then
    // Unmeasured states (actuator chains, wheel speeds) settle over the history with the measured
    // states forced back to the recording at every sample; the velocities through a constant-gain
    // observer (raw on a lane's first row of the full model, then blended by o.observer_gain),
    // which takes sensor noise off the start state.
    for (int r = wheel_rows_; r <= history_; ++r) {
      for (int j = 0; j < lanes_; ++j) {
        const int first_full_row = std::max(wheel_rows_, joins_at(j));
        if (r < first_full_row) continue;
        if (r == first_full_row && r > wheel_rows_) start_lane(j);  // it joins now
        const float gain = r == first_full_row ? 1.f : static_cast<float>(o_.observer_gain);
        view_.force_measured(data_row(j, r), xs_ + j, lanes_, time_state_, gain);
      }
      if (r == history_) break;
      advance_row(r);
    }
    for (int i = 0; i < segs_[0]->len; ++i) {
      advance_row(history_ + i);
      for (int j = 0; j < count_; ++j)
        view_.measurement_of(xs_ + j, lanes_, outs[j] + static_cast<std::ptrdiff_t>(i) * kPredStride);
    }
  }

 private:
  static constexpr int L = ReplayModel::kLanes;
  const Segment& seg(int j) const { return *segs_[j < count_ ? j : 0]; }
  int joins_at(int j) const { return history_ - histories_[j < count_ ? j : 0]; }
  // The data row of lane j on row r (r = history_: its segment's start).
  std::size_t data_row(int j, int r) const {
    return static_cast<std::size_t>(static_cast<std::ptrdiff_t>(seg(j).start) + r - history_);
  }
  int substeps_of(double dt) const { return std::max(1, static_cast<int>(std::lround(dt / o_.substep_s))); }

  // Lane j's start state at its first row of history: the measured state at its segment's start,
  // the actuators at rest at the command then, run alone over the chain-only rows.
  void start_lane(int j) {
    float lane_state[ReplayModel::kMaxStates];
    const std::size_t k0 = seg(j).start;
    VehicleState vs;
    vs.x_m = static_cast<float>(d_.x[k0]);
    vs.y_m = static_cast<float>(d_.y[k0]);
    vs.yaw_rad = static_cast<float>(d_.yaw[k0]);
    vs.vx_mps = view_.true_vx(k0);
    vs.vy_mps = view_.true_vy(k0);
    vs.yaw_rate_radps = view_.true_r(k0);
    if (view_.roll_at(k0)) vs.roll_rad = static_cast<float>(d_.roll[k0]);
    model_.init_state(vs, lane_state);
    lane_state[time_state_] = static_cast<float>(d_.t[k0]);
    float s, t;
    view_.command_over(data_row(j, joins_at(j)), &s, &t);
    model_.set_actuators(lane_state, s, t);
    for (int r = joins_at(j); r < wheel_rows_; ++r) {
      const std::size_t k = data_row(j, r);
      view_.force_measured(k, lane_state, 1, time_state_, 1.f);
      view_.command_over(k, &s, &t);
      model_.advance_actuators(lane_state, s, t, static_cast<float>(d_.t[k + 1] - d_.t[k]));
    }
    for (int i = 0; i < nx_; ++i) xs_[i * lanes_ + j] = lane_state[i];
  }

  // Row r of every lane: the commands and interval of its data row (a lane that has not joined:
  // no command, the shared step).
  void advance_row(int r) {
    for (int j = 0; j < lanes_; ++j) {
      joined_[j] = r >= joins_at(j);
      if (!joined_[j]) {
        u_[j] = u_[lanes_ + j] = 0.f;
        continue;
      }
      const std::size_t k = data_row(j, r);
      view_.command_over(k, &u_[j], &u_[lanes_ + j]);
      lane_dt_[j] = d_.t[k + 1] - d_.t[k];
    }
    if (lanes_ == 1) {
      const int n = substeps_of(lane_dt_[0]);
      for (int i = 0; i < n; ++i) model_.step(xs_, u_[0], u_[1], static_cast<float>(lane_dt_[0] / n));
      return;
    }
    const double shared = shared_step();
    int outliers[L], outlier_count = 0;
    float before[ReplayModel::kMaxStates * L];
    for (int j = 0; j < lanes_; ++j)
      if (!shares_[j]) outliers[outlier_count++] = j;
    if (outlier_count > 0) std::copy(xs_, xs_ + nx_ * lanes_, before);
    const int n = substeps_of(shared);
    model_.step_lanes(xs_, u_, static_cast<float>(shared / n), n);
    // A lane whose interval is not shared takes its own steps from the same start.
    float lane_state[ReplayModel::kMaxStates];
    for (int i = 0; i < outlier_count; ++i) {
      const int j = outliers[i];
      for (int c = 0; c < nx_; ++c) lane_state[c] = before[c * lanes_ + j];
      const int m = substeps_of(lane_dt_[j]);
      for (int q = 0; q < m; ++q) model_.step(lane_state, u_[j], u_[lanes_ + j], static_cast<float>(lane_dt_[j] / m));
      for (int c = 0; c < nx_; ++c) xs_[c * lanes_ + j] = lane_state[c];
    }
  }

  // The lanes whose interval is within kSharedStepTolerance of the joined lanes' median share one
  // step, the mean of their intervals (timing jitter); a lane whose interval differs more (a
  // missing row doubles it) does not (shares_[j] false). Lanes that have not joined share it.
  double shared_step() {
    double sorted[L];
    int joined_count = 0;
    for (int j = 0; j < lanes_; ++j)
      if (joined_[j]) sorted[joined_count++] = lane_dt_[j];
    const auto [min_dt, max_dt] = std::minmax_element(sorted, sorted + joined_count);
    double median = *min_dt;  // when max - min <= tolerance x min, every lane is within it of the median
    if (*max_dt - *min_dt > kSharedStepTolerance * *min_dt) {
      std::nth_element(sorted, sorted + joined_count / 2, sorted + joined_count);
      median = sorted[joined_count / 2];
    }
    double shared = 0;
    int sharing = 0;
    for (int j = 0; j < lanes_; ++j) {
      shares_[j] = !joined_[j] || std::abs(lane_dt_[j] - median) <= kSharedStepTolerance * median;
      if (joined_[j] && shares_[j]) {
        shared += lane_dt_[j];
        ++sharing;
      }
    }
    return shared / sharing;
  }

  const ReplayModel& model_;
  const PreparedRecording& d_;
  const RecordingView view_;
  const Segment* const* segs_;
  const int* histories_;
  const int count_, lanes_;
  const ReplayOptions& o_;
  const int nx_, time_state_, history_;
  int wheel_rows_ = 0;
  alignas(64) float xs_[ReplayModel::kMaxStates * L];
  float u_[2 * L];
  double lane_dt_[L];
  bool joined_[L], shares_[L];
};

void predict_lockstep(const ReplayModel& model, const PreparedRecording& d, const Segment* const* segs, double* const* outs,
                      const int* histories, int count, int lanes, const ReplayOptions& o) {
  LockstepReplay(model, d, segs, histories, count, lanes, o).run(outs);
}

}  // namespace

void predict_segment(const ReplayModel& model, const PreparedRecording& d, const Segment& s,
                     const ReplayOptions& o, double* out) {
  const Segment* seg = &s;
  const int history = history_rows(d, s.start, o);
  predict_lockstep(model, d, &seg, &out, &history, 1, 1, o);
}

void predict_segments(const ReplayModel& model, const PreparedRecording& d, const std::vector<Segment>& segs,
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

void segment_residuals(const ReplayModel& model, const PreparedRecording& d,
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

std::array<double, kChannels> channel_scales(const PreparedRecording& d, const std::vector<char>& mask) {
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

std::vector<HorizonMetrics> horizon_metrics(const ReplayModel& model, const PreparedRecording& d,
                                            const std::vector<char>& mask,
                                            const std::vector<double>& horizons_s, int stride,
                                            const ReplayOptions& o, const PreparedRecording* reference) {
  if (reference && reference->rows() != d.rows())
    throw Error("horizon_metrics: the reference states have " + std::to_string(reference->rows()) +
                " rows, the recording " + std::to_string(d.rows()));
  const PreparedRecording& ref = reference ? *reference : d;
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
