#include "sysid/prepared_recording.hpp"

#include <algorithm>
#include <cmath>

#include "base/error.hpp"
#include "sysid/real_data.hpp"

namespace mppi::sysid {

namespace {

// The recording's columns and what its metadata says of its command timing and throttle channel.
void read_columns(const sim::Recording& rec, const std::string& source, PreparedRecording* d) {
  for (const auto& c : sim::kRecordingRequiredColumns)
    if (!rec.has_column(c)) throw Error(source + ": missing required column '" + c + "'");
  d->t = rec.column("t");
  d->x = rec.column("x");
  d->y = rec.column("y");
  d->yaw = rec.column("yaw");
  d->vx = rec.column("vx");
  d->vy = rec.column("vy");
  d->r = rec.column("yaw_rate");
  d->steer = rec.column("steer");
  d->throttle = rec.column("throttle");
  if (rec.has_column("roll")) d->roll = rec.column("roll");
  for (std::size_t c = 0; c < rec.columns.size(); ++c)
    if (!d->find_column(rec.columns[c])) d->other_columns[rec.columns[c]] = rec.data[c];
  const auto src = rec.metadata.find("source");
  d->control_lead = (src != rec.metadata.end() &&
                     (src->second == "mppi-sim" || src->second.rfind("mppi-fit synth", 0) == 0))
                        ? 1 : 0;
  const auto command = rec.metadata.find("throttle_command");
  if (command != rec.metadata.end()) {
    if (command->second != "speed" && command->second != "throttle")
      throw Error(source + ": metadata 'throttle_command: " + command->second + "': expected 'speed' or 'throttle'");
    d->speed_command = command->second == "speed";
  }
}

// The median of the intervals between rows (t has at least two).
double median_interval_s(const std::vector<double>& t) {
  std::vector<double> dts;
  for (std::size_t k = 1; k < t.size(); ++k) dts.push_back(t[k] - t[k - 1]);
  std::nth_element(dts.begin(), dts.begin() + dts.size() / 2, dts.end());
  return dts[dts.size() / 2];
}

// Screens every column (screen.hpp) into d->flags; returns the rows screened out.
std::vector<char> screen_recording(const std::string& source, const ScreenOptions& screen, PreparedRecording* d) {
  std::vector<ScreenColumn> columns = {{"t", &d->t},   {"x", &d->x},   {"y", &d->y},
                                       {"yaw", &d->yaw}, {"vx", &d->vx}, {"vy", &d->vy},
                                       {"yaw_rate", &d->r}, {"steer", &d->steer}, {"throttle", &d->throttle}};
  if (!d->roll.empty()) columns.push_back({"roll", &d->roll});
  d->flags = screen_columns(d->t, columns, screen);
  for (ScreenFlag& f : d->flags) f.file = source;
  return screened_rows(d->t.size(), d->flags, screen.guard_rows);
}

// The displacement from row k - 1 to row k that the measured velocities do not account for [m].
double unexplained_displacement_m(const PreparedRecording& d, std::size_t k) {
  const double dt = d.t[k] - d.t[k - 1];
  const double c0 = std::cos(d.yaw[k - 1]), s0 = std::sin(d.yaw[k - 1]);
  const double c1 = std::cos(d.yaw[k]), s1 = std::sin(d.yaw[k]);
  const double px = 0.5 * dt * (c0 * d.vx[k - 1] - s0 * d.vy[k - 1] + c1 * d.vx[k] - s1 * d.vy[k]);
  const double py = 0.5 * dt * (s0 * d.vx[k - 1] + c0 * d.vy[k - 1] + s1 * d.vx[k] + c1 * d.vy[k]);
  return std::hypot(d.x[k] - d.x[k - 1] - px, d.y[k] - d.y[k - 1] - py);
}

// A row not screened out, with every required value finite.
bool row_ok(const PreparedRecording& d, const std::vector<char>& screened, std::size_t k) {
  const double vals[] = {d.t[k], d.x[k], d.y[k], d.yaw[k], d.vx[k], d.vy[k], d.r[k], d.steer[k], d.throttle[k]};
  bool ok = !screened[k];
  for (double v : vals) ok = ok && std::isfinite(v);
  return ok;
}

// The threshold (also the slack of the position-jump rule) scales with the recording's own
// typical disagreement (position noise, a fused estimate's lag), so that noisy positions do
// not cut everywhere.
double teleport_threshold_m(const PreparedRecording& d, const std::vector<char>& screened, const ScreenOptions& o) {
  double teleport_m = o.min_teleport_m;
  std::vector<double> e;
  for (std::size_t k = 1; k < d.t.size(); ++k)
    if (row_ok(d, screened, k) && row_ok(d, screened, k - 1) && d.t[k] - d.t[k - 1] <= o.max_gap_intervals * d.dt_s)
      e.push_back(unexplained_displacement_m(d, k));
  if (!e.empty()) {
    std::nth_element(e.begin(), e.begin() + static_cast<std::ptrdiff_t>(e.size() / 2), e.end());
    teleport_m = std::max(teleport_m, o.teleport_noise_multiple * e[e.size() / 2]);
  }
  return teleport_m;
}

// Numbers the pieces of d->piece (-1: a row in none) and counts d->screened_rows; returns the
// usable rows. Pieces: cut at NaN rows, screened rows, gaps of more than o.max_gap_intervals median
// intervals, position jumps no car makes, and displacements that the measured velocities do not account for (a respawn or a
// teleport: at a low sample rate a jump of a track's half width is within what a car covers
// between two rows, but not in that direction or at that speed).
std::size_t cut_into_pieces(const std::vector<char>& screened, double teleport_m, const ScreenOptions& o,
                            PreparedRecording* d) {
  const std::size_t n = d->t.size();
  d->piece.assign(n, -1);
  int id = -1;
  bool open = false;
  std::size_t usable = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const bool ok = row_ok(*d, screened, k);
    if (screened[k]) ++d->screened_rows;
    if (!ok) {
      open = false;
      continue;
    }
    if (open && k > 0) {
      const double gap = d->t[k] - d->t[k - 1];
      const double jump = std::hypot(d->x[k] - d->x[k - 1], d->y[k] - d->y[k - 1]);
      const double vmax = std::max(std::abs(d->vx[k]), std::abs(d->vx[k - 1])) + 2.0;
      if (gap > o.max_gap_intervals * d->dt_s || jump > o.max_jump_speed_multiple * vmax * gap + teleport_m ||
          unexplained_displacement_m(*d, k) > teleport_m)
        open = false;
    }
    if (!open) {
      ++id;
      open = true;
    }
    d->piece[k] = id;
    ++usable;
  }
  return usable;
}

}  // namespace

const std::vector<double>* PreparedRecording::find_column(const std::string& name) const {
  const std::pair<const char*, const std::vector<double>*> named[] = {
      {"t", &t},   {"x", &x},   {"y", &y},   {"yaw", &yaw}, {"vx", &vx}, {"vy", &vy}, {"yaw_rate", &r},
      {"steer", &steer}, {"throttle", &throttle}};
  for (const auto& [n, v] : named)
    if (name == n) return v;
  if (name == "roll") return roll.empty() ? nullptr : &roll;
  const auto other = other_columns.find(name);
  return other == other_columns.end() ? nullptr : &other->second;
}

const std::vector<double>& PreparedRecording::column(const std::string& name) const {
  const std::vector<double>* v = find_column(name);
  if (!v) throw Error(source + ": no column '" + name + "'");
  return *v;
}

PreparedRecording prepare(const sim::Recording& rec, const std::string& source, std::size_t min_rows,
                 const ScreenOptions& screen) {
  PreparedRecording d;
  d.source = source;
  d.metadata = rec.metadata;
  read_columns(rec, source, &d);
  const std::size_t n = d.t.size();
  min_rows = std::max<std::size_t>(min_rows, 2);  // the sample interval needs two rows
  if (n < min_rows)
    throw Error(source + ": too short for diagnosis: " + std::to_string(n) + " rows, need at least " +
                std::to_string(min_rows));
  d.dt_s = median_interval_s(d.t);
  if (!(d.dt_s > 0)) throw Error(source + ": cannot determine the sample interval");
  const std::vector<char> screened = screen_recording(source, screen, &d);
  const double teleport_m = teleport_threshold_m(d, screened, screen);
  const std::size_t usable = cut_into_pieces(screened, teleport_m, screen, &d);
  if (usable < min_rows)
    throw Error(source + ": only " + std::to_string(usable) + " usable rows (no empty fields), need " +
                std::to_string(min_rows));
  return d;
}

PreparedRecording load_recording(const std::string& path) {
  return prepare(sim::RecordingReader::read(path), path);
}

PreparedRecording concat(const PreparedRecording& a, const PreparedRecording& b) {
  if (a.control_lead != b.control_lead)
    throw Error(a.source + " and " + b.source + ": recordings of different kinds (command timing) cannot be combined");
  if (a.speed_command != b.speed_command)
    throw Error(a.source + " and " + b.source + ": one declares its throttle column a speed command "
                "('# throttle_command: speed'), the other not; they cannot be combined");
  PreparedRecording d = a;
  d.source = a.source + " + " + b.source;
  const double shift = a.t.back() + 10.0 - b.t.front();
  int max_piece = -1;
  for (int p : a.piece) max_piece = std::max(max_piece, p);
  auto append = [](std::vector<double>& to, const std::vector<double>& from, double add) {
    for (double v : from) to.push_back(v + add);
  };
  append(d.t, b.t, shift);
  append(d.x, b.x, 0);
  append(d.y, b.y, 0);
  append(d.yaw, b.yaw, 0);
  append(d.vx, b.vx, 0);
  append(d.vy, b.vy, 0);
  append(d.r, b.r, 0);
  append(d.steer, b.steer, 0);
  append(d.throttle, b.throttle, 0);
  if (!a.roll.empty() && !b.roll.empty()) append(d.roll, b.roll, 0);
  else d.roll.clear();  // roll only where both recordings have it
  for (auto it = d.other_columns.begin(); it != d.other_columns.end();) {  // the same for the others
    const auto in_b = b.other_columns.find(it->first);
    if (in_b == b.other_columns.end()) {
      it = d.other_columns.erase(it);
    } else {
      append(it->second, in_b->second, 0);
      ++it;
    }
  }
  for (int p : b.piece) d.piece.push_back(p < 0 ? -1 : p + max_piece + 1);
  for (ScreenFlag f : b.flags) {
    f.row += a.rows();
    d.flags.push_back(std::move(f));
  }
  d.screened_rows += b.screened_rows;
  return d;
}

PreparedRecording slice_rows(const PreparedRecording& d, std::size_t first, std::size_t last) {
  if (!(first < last && last <= d.rows()))
    throw Error(d.source + ": rows " + std::to_string(first) + ".." + std::to_string(last) + " are not a part of its " +
                std::to_string(d.rows()) + " rows");
  PreparedRecording s = d;
  auto cut = [&](std::vector<double>& v) {
    if (!v.empty()) v = std::vector<double>(v.begin() + static_cast<std::ptrdiff_t>(first), v.begin() + static_cast<std::ptrdiff_t>(last));
  };
  for (auto* v : {&s.t, &s.x, &s.y, &s.yaw, &s.vx, &s.vy, &s.r, &s.steer, &s.throttle, &s.roll}) cut(*v);
  for (auto& [name, v] : s.other_columns) cut(v);
  s.piece = std::vector<int>(d.piece.begin() + static_cast<std::ptrdiff_t>(first), d.piece.begin() + static_cast<std::ptrdiff_t>(last));
  s.flags.clear();
  s.screened_rows = 0;
  for (ScreenFlag f : d.flags)
    if (f.row >= first && f.row < last) {
      f.row -= first;
      s.flags.push_back(std::move(f));
    }
  for (int p : s.piece) s.screened_rows += p < 0;
  return s;
}

PreparedRecording load_any(const std::string& spec) {
  return prepare(load_any_recording(spec), spec);
}

Split make_split(const PreparedRecording& d, const std::string& holdout) {
  Split s;
  s.heldout.assign(d.rows(), 0);
  const auto colon = holdout.find(':');
  try {
    if (colon == std::string::npos) {
      std::size_t used = 0;
      const double f = std::stod(holdout, &used);
      if (used != holdout.size() || !(f > 0.05 && f < 0.95)) throw std::invalid_argument(holdout);
      const auto first = static_cast<std::size_t>((1.0 - f) * static_cast<double>(d.rows()));
      for (std::size_t k = first; k < d.rows(); ++k) s.heldout[k] = 1;
    } else {
      const double t0 = std::stod(holdout.substr(0, colon));
      const double t1 = std::stod(holdout.substr(colon + 1));
      if (!(t1 > t0)) throw std::invalid_argument(holdout);
      for (std::size_t k = 0; k < d.rows(); ++k) s.heldout[k] = d.t[k] >= t0 && d.t[k] < t1;
    }
  } catch (const std::logic_error&) {
    throw Error("--holdout: expected a fraction in (0.05, 0.95) or a time range T0:T1 in s, got '" +
                holdout + "'");
  }
  std::size_t h = 0;
  for (char c : s.heldout) h += c;
  if (h < 100 || d.rows() - h < 150)
    throw Error(d.source + ": --holdout " + holdout + " leaves " + std::to_string(d.rows() - h) +
                " training and " + std::to_string(h) + " held-out rows (need >= 150 and >= 100)");
  return s;
}

std::size_t row_at_time(const PreparedRecording& d, double t_s) {
  return static_cast<std::size_t>(std::lower_bound(d.t.begin(), d.t.end(), t_s) - d.t.begin());
}

std::vector<Segment> make_segments(const PreparedRecording& d, const std::vector<char>& mask, int len, int stride) {
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

}  // namespace mppi::sysid
