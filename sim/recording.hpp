#pragma once
// Driving logs in the project's CSV recording format (docs: RECORDING_FORMAT.md):
//   # key: value          <- optional metadata lines
//   t,x,y,yaw,vx,vy,yaw_rate,steer,throttle[,extra columns]
//   0,1.5,...             <- one row per sample, t strictly increasing, empty field = missing
// SI units, ISO 8855 frames (x forward, y left, yaw CCW positive).
#include <array>
#include <cstddef>
#include <fstream>
#include <iosfwd>
#include <map>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "mppi/vehicle_state.hpp"

namespace mppi::sim {

// The columns every recording has, in this order when we write one.
inline const std::array<std::string, 9> kRecordingRequiredColumns = {
    "t", "x", "y", "yaw", "vx", "vy", "yaw_rate", "steer", "throttle"};

class RecordingWriter {
 public:
  // Creates (truncates) `path` and writes the metadata lines and the header: the required
  // columns, then `extra_columns` (e.g. "roll", "ax", "wheel_speed", or custom names).
  // Throws mppi::Error if the file cannot be opened, or a column name is empty, holds a comma
  // or a line break, or repeats another; or a metadata key/value holds a line break.
  RecordingWriter(const std::string& path, std::vector<std::string> extra_columns = {},
                  const std::vector<std::pair<std::string, std::string>>& metadata = {},
                  std::size_t flush_every_rows = 200);
  ~RecordingWriter();
  RecordingWriter(const RecordingWriter&) = delete;
  RecordingWriter& operator=(const RecordingWriter&) = delete;

  // One row from the common state and the applied control; `extras` must hold one value per
  // extra column (NaN = missing, written as an empty field). Throws on a size mismatch.
  void write(double t_s, const VehicleState& state, const Control& control,
             std::span<const double> extras = {});
  // One row of all columns, in header order.
  void write_row(std::span<const double> values);

  const std::vector<std::string>& columns() const { return columns_; }
  std::size_t rows_written() const { return rows_; }
  const std::string& path() const { return path_; }
  void flush();
  void close();  // flushes; later writes throw

 private:
  std::string path_;
  std::ofstream out_;
  std::vector<std::string> columns_;
  std::size_t flush_every_;
  std::size_t rows_ = 0;
  std::vector<double> row_;
  std::string line_;
};

// A recording in memory: values by column (NaN = missing).
struct Recording {
  std::map<std::string, std::string> metadata;  // from "# key: value" lines
  std::vector<std::string> columns;             // header order
  std::vector<std::vector<double>> data;        // data[c][row] for column columns[c]

  std::size_t rows() const { return data.empty() ? 0 : data[0].size(); }
  bool has_column(const std::string& name) const;
  // Throws mppi::Error naming the column and the available ones if absent.
  const std::vector<double>& column(const std::string& name) const;
};

class RecordingReader {
 public:
  // Reads a recording. Throws mppi::Error "<file>:<line>: column <c> (<name>): <problem>" for
  // a row with the wrong number of fields, a non-numeric value, a missing or non-increasing t;
  // "<file>: missing required column '<name>'" for an incomplete header.
  static Recording read(const std::string& path);
  // Same from a stream; `source` names it in error messages.
  static Recording read(std::istream& in, const std::string& source);
};

}  // namespace mppi::sim
