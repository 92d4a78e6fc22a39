#pragma once
// A recording prepared for fitting models to it (calibration, diagnosis): the required columns as
// arrays, its values screened (screen.hpp), the split into continuous pieces (gaps, NaNs and
// respawn jumps cut it), the command timing, training / held-out parts, and the segments that
// open-loop predictions run over.
#include <map>
#include <string>
#include <vector>

#include "sysid/screen.hpp"
#include "sim/recording.hpp"

namespace mppi::sysid {

// Channels compared between model and measurement.
inline constexpr int kChannels = 3;
inline const char* const kChannelNames[kChannels] = {"vx", "vy", "yaw_rate"};
inline const char* const kChannelUnits[kChannels] = {"m/s", "m/s", "rad/s"};

struct PreparedRecording {
  std::string source;                       // file name, for messages
  std::map<std::string, std::string> metadata;  // the recording's "# key: value" lines (vehicle, mass_kg, ...)
  std::vector<double> t, x, y, yaw, vx, vy, r, steer, throttle;
  // Optional `roll` column [rad] (empty when the recording has none): the start state of
  // models that carry roll (the AutoRally network takes it as an input).
  std::vector<double> roll;
  // Every other column of the recording (wheel speeds, applied commands, ...), by name: what a
  // model reads beyond the required columns (its wheel spin at the start of a rollout).
  std::map<std::string, std::vector<double>> other_columns;
  // The command that acts over (t[k], t[k+1]]: index k + control_lead. mppi-sim logs hold in
  // row k+1 the command that produced it (lead 1); real recordings the command sent at t[k] (0).
  int control_lead = 0;
  // The throttle column holds the stack's speed command, which a low-level loop in the car turns
  // into throttle (the recording's metadata line `# throttle_command: speed`).
  bool speed_command = false;
  std::vector<int> piece;                   // piece id per row (-1 = unusable row)
  // Values screened out (screen.hpp): each flag's row and its guard rows have piece -1.
  std::vector<ScreenFlag> flags;
  std::size_t screened_rows = 0;            // rows made unusable by the flags
  double dt_s = 0.02;                       // median sample interval
  std::size_t rows() const { return t.size(); }
  // A column by its recording name (t, x, y, yaw, vx, vy, yaw_rate, steer, throttle, roll or any
  // other): nullptr where the recording has none; column() throws mppi::Error naming the source.
  const std::vector<double>* find_column(const std::string& name) const;
  const std::vector<double>& column(const std::string& name) const;
  bool has_column(const std::string& name) const { return find_column(name) != nullptr; }
  double channel(int c, std::size_t k) const { return c == 0 ? vx[k] : c == 1 ? vy[k] : r[k]; }
  // Command acting over (t[k], t[k+1]].
  double steer_over(std::size_t k) const { return steer[std::min(k + control_lead, rows() - 1)]; }
  double throttle_over(std::size_t k) const { return throttle[std::min(k + control_lead, rows() - 1)]; }
  // True if rows k .. k+n are in the same piece.
  bool continuous(std::size_t k, std::size_t n) const {
    return k + n < rows() && piece[k] >= 0 && piece[k] == piece[k + n];
  }
};

// Throws mppi::Error naming the file for missing columns, fewer than `min_rows` (at least 2) usable rows.
// Screens the values first (screen.hpp): flagged rows are listed in `flags` and kept out.
PreparedRecording prepare(const sim::Recording& rec, const std::string& source, std::size_t min_rows = 250,
                 const ScreenOptions& screen = {});

// Reads and prepares a recording file (sim::RecordingReader, then prepare()).
PreparedRecording load_recording(const std::string& path);

// Rows [first, last) of d as a recording of their own (pieces and screening flags kept;
// throws mppi::Error if the range is empty or beyond d).
PreparedRecording slice_rows(const PreparedRecording& d, std::size_t first, std::size_t last);

// Training recording followed by a validation recording (separate pieces, the second's times
// shifted to follow the first); rows of `b` start at index a.rows().
PreparedRecording concat(const PreparedRecording& a, const PreparedRecording& b);

// Reads a recording in the project format, or converts a real recording (DART / ETH, plain CSV
// or "ARCHIVE.zip:MEMBER.csv") through sysid::load_any_recording, then prepare().
PreparedRecording load_any(const std::string& spec);

// Held-out split: rows [0, split) train, [split, rows) held out. `holdout` is "0.3" (fraction at
// the end) or "T0:T1" (a time range in s, held out; the training part is everything else, so
// the split is then expressed as a row mask). Throws mppi::Error for malformed text.
struct Split {
  std::vector<char> heldout;  // per row: 1 = held out
};
Split make_split(const PreparedRecording& d, const std::string& holdout);

// Predict rows start+1 .. start+len from the measured state at row start.
struct Segment {
  std::size_t start = 0;
  int len = 0;
};

// The first row at or after t_s (rows() if none).
std::size_t row_at_time(const PreparedRecording& d, double t_s);

// Segments of `len` samples every `stride` rows, fully inside one piece and inside `mask`
// (mask[k] != 0 for every row used; empty mask = all rows).
std::vector<Segment> make_segments(const PreparedRecording& d, const std::vector<char>& mask, int len, int stride);

}  // namespace mppi::sysid
