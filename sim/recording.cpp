#include "sim/recording.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <istream>
#include <limits>
#include <set>
#include <string_view>

#include "base/error.hpp"

namespace mppi::sim {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Values that are exact floats (the simulator's state) get the shortest digits that read back
// to the same float; anything else the shortest digits for the double. Lossless either way.
void append_number(std::string& out, double v) {
  if (std::isnan(v)) return;  // missing = empty field
  char buf[64];
  std::to_chars_result r;
  const auto f = static_cast<float>(v);
  if (std::isfinite(v) && static_cast<double>(f) == v)
    r = std::to_chars(buf, buf + sizeof buf, f);
  else
    r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

// Time to the nanosecond, so 0.1 + 0.2 is written "0.3".
void append_time(std::string& out, double t) {
  append_number(out, std::isfinite(t) ? std::round(t * 1e9) / 1e9 : t);
}

std::string_view trim(std::string_view s) {
  const auto is_space = [](char c) { return c == ' ' || c == '\t' || c == '\r'; };
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> split_commas(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    if (comma == std::string_view::npos) {
      fields.push_back(trim(line.substr(start)));
      return fields;
    }
    fields.push_back(trim(line.substr(start, comma - start)));
    start = comma + 1;
  }
}

void check_name(const std::string& s, const std::string& what, const std::string& path) {
  if (s.find_first_of("\r\n") != std::string::npos)
    throw Error(path + ": " + what + " '" + s + "' holds a line break");
}

}  // namespace

RecordingWriter::RecordingWriter(const std::string& path, std::vector<std::string> extra_columns,
                                 const std::vector<std::pair<std::string, std::string>>& metadata,
                                 std::size_t flush_every_rows)
    : path_(path), flush_every_(std::max<std::size_t>(1, flush_every_rows)) {
  columns_.assign(kRecordingRequiredColumns.begin(), kRecordingRequiredColumns.end());
  std::set<std::string> seen(columns_.begin(), columns_.end());
  for (std::string& c : extra_columns) {
    check_name(c, "column name", path);
    if (c.empty() || c.find(',') != std::string::npos || trim(c) != c)
      throw Error(path + ": bad column name '" + c + "' (empty, a comma or surrounding spaces)");
    if (!seen.insert(c).second) throw Error(path + ": column '" + c + "' given twice");
    columns_.push_back(std::move(c));
  }
  for (const auto& [key, value] : metadata) {
    check_name(key, "metadata key", path);
    check_name(value, "metadata value", path);
    if (key.empty() || key.find(':') != std::string::npos)
      throw Error(path + ": bad metadata key '" + key + "' (empty or holds ':')");
  }
  out_.open(path, std::ios::out | std::ios::trunc);
  if (!out_) throw Error(path + ": cannot open for writing");
  for (const auto& [key, value] : metadata) out_ << "# " << key << ": " << value << '\n';
  for (std::size_t i = 0; i < columns_.size(); ++i) out_ << (i ? "," : "") << columns_[i];
  out_ << '\n';
  out_.flush();
  row_.resize(columns_.size());
}

RecordingWriter::~RecordingWriter() {
  if (out_.is_open()) out_.flush();
}

void RecordingWriter::write(double t_s, const VehicleState& s, const Control& u,
                            std::span<const double> extras) {
  const std::size_t n_extra = columns_.size() - kRecordingRequiredColumns.size();
  if (extras.size() != n_extra)
    throw Error(path_ + ": write() got " + std::to_string(extras.size()) + " extra values for " +
                std::to_string(n_extra) + " extra columns");
  row_[0] = t_s;
  row_[1] = s.x_m;
  row_[2] = s.y_m;
  row_[3] = s.yaw_rad;
  row_[4] = s.vx_mps;
  row_[5] = s.vy_mps;
  row_[6] = s.yaw_rate_radps;
  row_[7] = u.steer;
  row_[8] = u.throttle;
  std::copy(extras.begin(), extras.end(), row_.begin() + 9);
  write_row(row_);
}

void RecordingWriter::write_row(std::span<const double> values) {
  if (!out_.is_open()) throw Error(path_ + ": write after close()");
  if (values.size() != columns_.size())
    throw Error(path_ + ": row has " + std::to_string(values.size()) + " values for " +
                std::to_string(columns_.size()) + " columns");
  line_.clear();
  append_time(line_, values[0]);
  for (std::size_t i = 1; i < values.size(); ++i) {
    line_ += ',';
    append_number(line_, values[i]);
  }
  line_ += '\n';
  out_ << line_;
  if (++rows_ % flush_every_ == 0) out_.flush();
}

void RecordingWriter::flush() {
  if (out_.is_open()) out_.flush();
}

void RecordingWriter::close() {
  if (!out_.is_open()) return;
  out_.flush();
  const bool ok = static_cast<bool>(out_);
  out_.close();
  if (!ok) throw Error(path_ + ": write failed");
}

bool Recording::has_column(const std::string& name) const {
  return std::find(columns.begin(), columns.end(), name) != columns.end();
}

const std::vector<double>& Recording::column(const std::string& name) const {
  const auto it = std::find(columns.begin(), columns.end(), name);
  if (it == columns.end()) {
    std::string have;
    for (const auto& c : columns) have += (have.empty() ? "" : ", ") + c;
    throw Error("recording has no column '" + name + "' (has: " + have + ")");
  }
  return data[static_cast<std::size_t>(it - columns.begin())];
}

Recording RecordingReader::read(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot open recording");
  return read(in, path);
}

Recording RecordingReader::read(std::istream& in, const std::string& source) {
  Recording rec;
  std::string raw;
  std::size_t line_no = 0;
  bool have_header = false;
  std::size_t t_col = 0;
  double last_t = -std::numeric_limits<double>::infinity();
  const auto where = [&](std::size_t col) {
    std::string s = source + ":" + std::to_string(line_no) + ": column " + std::to_string(col + 1);
    if (col < rec.columns.size()) s += " (" + rec.columns[col] + ")";
    return s + ": ";
  };
  while (std::getline(in, raw)) {
    ++line_no;
    const std::string_view line = trim(raw);
    if (line.empty()) continue;
    if (line.front() == '#') {
      const std::string_view body = trim(line.substr(1));
      const std::size_t colon = body.find(':');
      if (colon != std::string_view::npos && colon > 0)
        rec.metadata[std::string(trim(body.substr(0, colon)))] =
            std::string(trim(body.substr(colon + 1)));
      continue;
    }
    const auto fields = split_commas(line);
    if (!have_header) {
      std::set<std::string> seen;
      for (std::size_t c = 0; c < fields.size(); ++c) {
        const std::string name(fields[c]);
        if (name.empty())
          throw Error(source + ":" + std::to_string(line_no) + ": column " +
                      std::to_string(c + 1) + ": empty column name in the header");
        if (!seen.insert(name).second)
          throw Error(source + ":" + std::to_string(line_no) + ": column " +
                      std::to_string(c + 1) + ": column '" + name + "' appears twice");
        rec.columns.push_back(name);
      }
      for (const std::string& required : kRecordingRequiredColumns)
        if (!seen.count(required))
          throw Error(source + ": missing required column '" + required + "' (header on line " +
                      std::to_string(line_no) + ")");
      t_col = static_cast<std::size_t>(
          std::find(rec.columns.begin(), rec.columns.end(), "t") - rec.columns.begin());
      rec.data.resize(rec.columns.size());
      have_header = true;
      continue;
    }
    if (fields.size() != rec.columns.size()) {
      const std::size_t col = std::min(fields.size(), rec.columns.size());
      throw Error(where(col) + "row has " + std::to_string(fields.size()) +
                  " fields, the header has " + std::to_string(rec.columns.size()));
    }
    for (std::size_t c = 0; c < fields.size(); ++c) {
      const std::string_view f = fields[c];
      double v = kNaN;
      if (!f.empty()) {
        // from_chars takes no leading '+'; accept it as CSV writers may emit one.
        const std::string_view digits = f.front() == '+' ? f.substr(1) : f;
        const auto r = std::from_chars(digits.data(), digits.data() + digits.size(), v);
        if (r.ec != std::errc() || r.ptr != digits.data() + digits.size() || digits.empty())
          throw Error(where(c) + "not a number: '" + std::string(f) + "'");
      }
      if (c == t_col) {
        if (std::isnan(v)) throw Error(where(c) + "time t is missing");
        if (!(v > last_t))
          throw Error(where(c) + "time t = " + std::string(f) +
                      " does not increase (previous row has " + std::to_string(last_t) + ")");
        last_t = v;
      }
      rec.data[c].push_back(v);
    }
  }
  if (!have_header) throw Error(source + ": no header row (empty recording)");
  return rec;
}

}  // namespace mppi::sim
