#pragma once
// A recording prepared for sim-vs-real diagnosis: the required columns as arrays, the split
// into continuous pieces (gaps, NaNs and respawn jumps cut it), training / held-out parts.
#include <map>
#include <string>
#include <vector>

#include "diagnose/screen.hpp"
#include "sim/recording.hpp"

namespace mppi::diagnose {

// Channels compared between model and measurement.
inline constexpr int kChannels = 3;
inline const char* const kChannelNames[kChannels] = {"vx", "vy", "yaw_rate"};
inline const char* const kChannelUnits[kChannels] = {"m/s", "m/s", "rad/s"};

struct DiagData {
  std::string source;                       // file name, for messages
  std::map<std::string, std::string> metadata;  // the recording's "# key: value" lines (vehicle, mass_kg, ...)
  std::vector<double> t, x, y, yaw, vx, vy, r, steer, throttle;
  // Optional `roll` column [rad] (empty when the recording has none): the start state of
  // models that carry roll (the AutoRally network takes it as an input).
  std::vector<double> roll;
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
DiagData prepare(const sim::Recording& rec, const std::string& source, std::size_t min_rows = 250,
                 const ScreenOptions& screen = {});

// Reads and prepares a recording file (sim::RecordingReader, then prepare()).
DiagData load_recording(const std::string& path);

// Rows [first, last) of d as a recording of their own (pieces and screening flags kept;
// throws mppi::Error if the range is empty or beyond d).
DiagData slice_rows(const DiagData& d, std::size_t first, std::size_t last);

// Training recording followed by a validation recording (separate pieces, the second's times
// shifted to follow the first); rows of `b` start at index a.rows().
DiagData concat(const DiagData& a, const DiagData& b);

// Reads a recording in the project format, or converts a real recording (DART / ETH, plain CSV
// or "ARCHIVE.zip:MEMBER.csv") through sysid::load_any_recording, then prepare().
DiagData load_any(const std::string& spec);

// Held-out split: rows [0, split) train, [split, rows) held out. `holdout` is "0.3" (fraction at
// the end) or "T0:T1" (a time range in s, held out; the training part is everything else, so
// the split is then expressed as a row mask). Throws mppi::Error for malformed text.
struct Split {
  std::vector<char> heldout;  // per row: 1 = held out
};
Split make_split(const DiagData& d, const std::string& holdout);

}  // namespace mppi::diagnose
