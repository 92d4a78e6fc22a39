#include "sysid/real_data.hpp"

#include <zip.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>
#include <string_view>

#include "base/error.hpp"

namespace mppi::sysid {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kPi = 3.14159265358979323846;

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    if (comma == std::string_view::npos) {
      out.push_back(trim(line.substr(start)));
      return out;
    }
    out.push_back(trim(line.substr(start, comma - start)));
    start = comma + 1;
  }
}

// A raw CSV: header names and numeric columns; every problem names source, line and column.
struct RawTable {
  std::vector<std::string> names;
  std::vector<std::vector<double>> cols;
  std::vector<std::size_t> line_of_row;  // 1-based source line of each row
  std::size_t rows() const { return cols.empty() ? 0 : cols[0].size(); }
  int index(const std::string& n) const {
    for (std::size_t i = 0; i < names.size(); ++i)
      if (names[i] == n) return static_cast<int>(i);
    return -1;
  }
};

RawTable parse_raw_csv(const std::string& text, const std::string& source) {
  RawTable t;
  std::istringstream in(text);
  std::string line;
  std::size_t line_no = 0;
  bool have_header = false;
  while (std::getline(in, line)) {
    ++line_no;
    if (trim(line).empty()) continue;
    const auto fields = split(line);
    if (!have_header) {
      for (auto f : fields) t.names.emplace_back(f);
      t.cols.resize(t.names.size());
      have_header = true;
      continue;
    }
    auto where = [&](std::size_t c) {
      const std::string name = c < t.names.size() ? " (" + t.names[c] + ")" : "";
      return source + ":" + std::to_string(line_no) + ": column " + std::to_string(c + 1) + name + ": ";
    };
    if (fields.size() != t.names.size())
      throw Error(where(std::min(fields.size(), t.names.size())) + "row has " +
                  std::to_string(fields.size()) + " fields, the header has " +
                  std::to_string(t.names.size()));
    for (std::size_t c = 0; c < fields.size(); ++c) {
      std::string_view f = fields[c];
      double v = kNaN;
      if (!f.empty()) {
        if (f.front() == '+') f.remove_prefix(1);
        const auto r = std::from_chars(f.data(), f.data() + f.size(), v);
        if (f.empty() || r.ec != std::errc() || r.ptr != f.data() + f.size())
          throw Error(where(c) + "not a number: '" + std::string(fields[c]) + "'");
      }
      t.cols[c].push_back(v);
    }
    t.line_of_row.push_back(line_no);
  }
  if (!have_header) throw Error(source + ": empty file (no header row)");
  return t;
}

std::vector<double> unwrap(const std::vector<double>& a) {
  std::vector<double> out(a.size(), kNaN);
  double offset = 0, prev = kNaN;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (std::isnan(a[i])) continue;
    if (!std::isnan(prev)) {
      const double d = a[i] - prev;
      if (d > kPi) offset -= 2 * kPi;
      if (d < -kPi) offset += 2 * kPi;
    }
    prev = a[i];
    out[i] = a[i] + offset;
  }
  return out;
}

// d/dt of a local quadratic least-squares fit over +-hw samples (uneven times allowed).
std::vector<double> smooth_derivative(const std::vector<double>& t, const std::vector<double>& v, int hw) {
  const std::size_t n = t.size();
  std::vector<double> d(n, kNaN);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t a = i >= static_cast<std::size_t>(hw) ? i - hw : 0;
    const std::size_t b = std::min(n - 1, i + hw);
    // Normal equations of v = c0 + c1 s + c2 s^2, s = t - t_i; derivative at s = 0 is c1.
    double S[5] = {0, 0, 0, 0, 0}, R[3] = {0, 0, 0};
    for (std::size_t j = a; j <= b; ++j) {
      if (std::isnan(v[j])) continue;
      const double s = t[j] - t[i];
      double p = 1;
      for (int k = 0; k < 5; ++k) {
        S[k] += p;
        if (k < 3) R[k] += p * v[j];
        p *= s;
      }
    }
    if (S[0] < 3) continue;
    const double M[3][3] = {{S[0], S[1], S[2]}, {S[1], S[2], S[3]}, {S[2], S[3], S[4]}};
    auto det3 = [](const double m[3][3]) {
      return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
             m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
             m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    };
    const double det = det3(M);
    if (!(std::abs(det) > 0)) continue;
    double M1[3][3];  // Cramer's rule for c1
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) M1[r][c] = c == 1 ? R[r] : M[r][c];
    d[i] = det3(M1) / det;
  }
  return d;
}

sim::Recording make_recording(const std::vector<std::string>& extra_names) {
  sim::Recording rec;
  rec.columns.assign(sim::kRecordingRequiredColumns.begin(), sim::kRecordingRequiredColumns.end());
  rec.columns.insert(rec.columns.end(), extra_names.begin(), extra_names.end());
  rec.data.resize(rec.columns.size());
  return rec;
}

std::vector<double>& col(sim::Recording& rec, const std::string& name) {
  for (std::size_t i = 0; i < rec.columns.size(); ++i)
    if (rec.columns[i] == name) return rec.data[i];
  throw Error("internal: no column " + name);
}

int need(const RawTable& t, const std::string& name, const std::string& source) {
  const int i = t.index(name);
  if (i < 0) throw Error(source + ": missing column '" + name + "' in the header");
  return i;
}

sim::Recording convert_dart(const RawTable& raw, const std::string& source, const RealConvertSettings& s) {
  const bool vicon = raw.index("vicon time") >= 0;
  const int c_sens_t = need(raw, "elapsed time sensors", source);
  const int c_ax = need(raw, "acc x (IMU)", source), c_ay = need(raw, "acc y (IMU)", source);
  const int c_w = need(raw, "W (IMU)", source), c_enc = need(raw, "vel encoder", source);
  const int c_safe = need(raw, "safety_value", source);
  const int c_thr = need(raw, "throttle", source), c_steer = need(raw, "steering", source);
  const int c_time = vicon ? need(raw, "vicon time", source) : c_sens_t;
  sim::Recording rec = make_recording({"ax", "ay", "wheel_speed", "imu_yaw_rate", "safety"});
  rec.metadata["vehicle"] = "dart_jetracer";
  rec.metadata["source"] = source;
  rec.metadata["converter"] = "mppi-fit convert (sysid/real_data.cpp)";
  rec.metadata["mass_kg"] = "1.58";
  rec.metadata["wheelbase_m"] = "0.1735";
  rec.metadata["cg_to_rear_axle_m"] = "0.093";
  // Keep rows whose time increases strictly, with a finite time.
  std::vector<std::size_t> keep;
  double last = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < raw.rows(); ++i) {
    const double ti = raw.cols[c_time][i];
    if (!std::isfinite(ti)) {
      throw Error(source + ":" + std::to_string(raw.line_of_row[i]) + ": column " +
                  std::to_string(c_time + 1) + " (" + raw.names[c_time] + "): time is missing");
    }
    if (ti > last) {
      keep.push_back(i);
      last = ti;
    }
  }
  if (keep.size() < 2) throw Error(source + ": fewer than 2 rows with increasing time");
  const double t0 = raw.cols[c_time][keep.front()];
  std::vector<double> t, x, y, yaw_w;
  for (std::size_t i : keep) {
    t.push_back(raw.cols[c_time][i] - t0);
    if (vicon) {
      x.push_back(raw.cols[need(raw, "vicon x", source)][i]);
      y.push_back(raw.cols[need(raw, "vicon y", source)][i]);
      yaw_w.push_back(raw.cols[need(raw, "vicon yaw", source)][i]);
    }
  }
  const std::size_t n = keep.size();
  std::vector<double> yaw(n, kNaN), vx(n, kNaN), vy(n, kNaN), r(n, kNaN);
  std::vector<double> px(n, kNaN), py(n, kNaN);
  if (vicon) {
    yaw = unwrap(yaw_w);
    for (std::size_t k = 0; k < n; ++k) {
      px[k] = x[k] - s.cog_offset_m * std::cos(yaw[k]);
      py[k] = y[k] - s.cog_offset_m * std::sin(yaw[k]);
    }
    const auto dx = smooth_derivative(t, px, s.smoothing_half_window);
    const auto dy = smooth_derivative(t, py, s.smoothing_half_window);
    r = smooth_derivative(t, yaw, s.smoothing_half_window);
    for (std::size_t k = 0; k < n; ++k) {
      const double c = std::cos(yaw[k]), sn = std::sin(yaw[k]);
      vx[k] = c * dx[k] + sn * dy[k];
      vy[k] = -sn * dx[k] + c * dy[k];
    }
  }
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = keep[k];
    const bool sensors = raw.cols[c_sens_t][i] != 0.0;  // 0 before the first sensor packet
    auto sensor = [&](int c) { return sensors ? raw.cols[c][i] : kNaN; };
    const double safety = raw.cols[c_safe][i];
    col(rec, "t").push_back(t[k]);
    col(rec, "x").push_back(px[k]);
    col(rec, "y").push_back(py[k]);
    col(rec, "yaw").push_back(yaw[k]);
    col(rec, "vx").push_back(vicon ? vx[k] : sensor(c_enc));
    col(rec, "vy").push_back(vy[k]);
    col(rec, "yaw_rate").push_back(vicon ? r[k] : sensor(c_w));
    col(rec, "steer").push_back(std::clamp(raw.cols[c_steer][i], -1.0, 1.0));
    col(rec, "throttle").push_back(safety == 0.0 ? 0.0 : std::clamp(raw.cols[c_thr][i], -1.0, 1.0));
    col(rec, "ax").push_back(sensor(c_ax));
    col(rec, "ay").push_back(sensor(c_ay));
    col(rec, "wheel_speed").push_back(sensor(c_enc));
    col(rec, "imu_yaw_rate").push_back(sensor(c_w));
    col(rec, "safety").push_back(safety);
  }
  if (!vicon) rec.metadata["note"] = "no Vicon in this file: x, y, yaw, vy missing; vx = encoder, yaw_rate = IMU";
  return rec;
}

sim::Recording convert_eth(const RawTable& raw, const std::string& source, const RealConvertSettings& s) {
  const int c_t = need(raw, "t_nominal_s", source), c_x = need(raw, "x_m", source);
  const int c_y = need(raw, "y_m", source), c_th = need(raw, "theta_rad", source);
  const int c_vx = need(raw, "vx_world_mps", source), c_vy = need(raw, "vy_world_mps", source);
  const int c_om = need(raw, "omega_radps", source);
  const int c_st = need(raw, "steer_cmd", source), c_thr = need(raw, "throttle_cmd", source);
  sim::Recording rec = make_recording({"step"});
  rec.metadata["vehicle"] = "eth_lasgroup_rccar";
  rec.metadata["source"] = source;
  rec.metadata["converter"] = "mppi-fit convert (sysid/real_data.cpp)";
  rec.metadata["note"] = "time is nominal (1/30 s steps): the source stored no timestamps";
  const auto yaw = unwrap(raw.cols[c_th]);
  double last = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < raw.rows(); ++i) {
    const double t = raw.cols[c_t][i];
    if (!(t > last))
      throw Error(source + ":" + std::to_string(raw.line_of_row[i]) + ": column " +
                  std::to_string(c_t + 1) + " (t_nominal_s): time does not increase");
    last = t;
    const double c = std::cos(yaw[i]), sn = std::sin(yaw[i]);
    const double vxw = raw.cols[c_vx][i], vyw = raw.cols[c_vy][i];
    const double om = raw.cols[c_om][i];
    col(rec, "t").push_back(t);
    col(rec, "x").push_back(raw.cols[c_x][i]);
    col(rec, "y").push_back(raw.cols[c_y][i]);
    col(rec, "yaw").push_back(yaw[i]);
    col(rec, "vx").push_back(c * vxw + sn * vyw);
    col(rec, "vy").push_back(-sn * vxw + c * vyw);
    col(rec, "yaw_rate").push_back(std::abs(om) > s.eth_omega_outlier_radps ? kNaN : om);
    col(rec, "steer").push_back(std::clamp(raw.cols[c_st][i], -1.0, 1.0));
    col(rec, "throttle").push_back(std::clamp(raw.cols[c_thr][i], -1.0, 1.0));
    const int c_step = raw.index("step");
    col(rec, "step").push_back(c_step >= 0 ? raw.cols[c_step][i] : kNaN);
  }
  return rec;
}

std::string base_name(const std::string& spec) {
  const std::size_t p = spec.find_last_of("/:");
  return p == std::string::npos ? spec : spec.substr(p + 1);
}

}  // namespace

bool RealConvertSettings::is_valid(std::string* why) const {
  auto fail = [&](const char* m) {
    if (why) *why = m;
    return false;
  };
  if (smoothing_half_window < 1 || smoothing_half_window > 200)
    return fail("smoothing_half_window must be in [1, 200]");
  if (!std::isfinite(cog_offset_m) || std::abs(cog_offset_m) > 1) return fail("cog_offset_m must be in [-1, 1]");
  if (!(eth_omega_outlier_radps > 0)) return fail("eth_omega_outlier_radps must be > 0");
  return true;
}

std::vector<std::string> zip_members(const std::string& zip_path) {
  int err = 0;
  zip_t* z = zip_open(zip_path.c_str(), ZIP_RDONLY, &err);
  if (!z) throw Error(zip_path + ": cannot open as a zip archive (libzip error " + std::to_string(err) + ")");
  std::vector<std::string> out;
  const zip_int64_t n = zip_get_num_entries(z, 0);
  for (zip_int64_t i = 0; i < n; ++i) out.emplace_back(zip_get_name(z, i, 0));
  zip_close(z);
  return out;
}

std::string read_text_or_zip_member(const std::string& spec) {
  const std::size_t zpos = spec.find(".zip:");
  if (zpos == std::string::npos) {
    std::ifstream in(spec, std::ios::binary);
    if (!in) throw Error(spec + ": cannot open");
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }
  const std::string archive = spec.substr(0, zpos + 4), member = spec.substr(zpos + 5);
  int err = 0;
  std::unique_ptr<zip_t, int (*)(zip_t*)> z(zip_open(archive.c_str(), ZIP_RDONLY, &err), zip_close);
  if (!z) throw Error(archive + ": cannot open as a zip archive (libzip error " + std::to_string(err) + ")");
  zip_stat_t st;
  if (zip_stat(z.get(), member.c_str(), 0, &st) != 0 || !(st.valid & ZIP_STAT_SIZE)) {
    std::string names;
    for (const auto& m : zip_members(archive)) names += (names.empty() ? "" : ", ") + m;
    throw Error(archive + ": no member '" + member + "' (has: " + names + ")");
  }
  std::unique_ptr<zip_file_t, int (*)(zip_file_t*)> f(zip_fopen(z.get(), member.c_str(), 0), zip_fclose);
  if (!f) throw Error(spec + ": cannot open the member");
  std::string out(static_cast<std::size_t>(st.size), '\0');
  const zip_int64_t got = zip_fread(f.get(), out.data(), st.size);
  if (got != static_cast<zip_int64_t>(st.size)) throw Error(spec + ": truncated or corrupt member");
  return out;
}

sim::Recording convert_real_recording(const std::string& text, const std::string& source_name,
                                      const RealConvertSettings& settings) {
  std::string why;
  if (!settings.is_valid(&why)) throw Error("RealConvertSettings: " + why);
  const RawTable raw = parse_raw_csv(text, source_name);
  RealSource src = settings.source;
  if (src == RealSource::kAuto) {
    if (raw.index("elapsed time sensors") >= 0)
      src = RealSource::kDartJetracer;
    else if (raw.index("t_nominal_s") >= 0)
      src = RealSource::kEthRccar;
    else
      throw Error(source_name + ":1: header is neither the DART JetRacer layout ('elapsed time "
                  "sensors', ...) nor the ETH RC-car layout ('t_nominal_s', ...)");
  }
  return src == RealSource::kDartJetracer ? convert_dart(raw, source_name, settings)
                                          : convert_eth(raw, source_name, settings);
}

sim::Recording convert_real_file(const std::string& spec, const RealConvertSettings& settings) {
  sim::Recording rec = convert_real_recording(read_text_or_zip_member(spec), spec, settings);
  // Metadata names the archive and member, not this machine's absolute path.
  const std::size_t z = spec.find(".zip:");
  rec.metadata["source"] = z == std::string::npos ? base_name(spec)
                                                  : base_name(spec.substr(0, z + 4)) + ":" + base_name(spec);
  return rec;
}

namespace {
std::vector<std::pair<std::string, RecordingFileReader>>& file_readers() {
  static std::vector<std::pair<std::string, RecordingFileReader>> readers;
  return readers;
}
bool has_ending(const std::string& s, const std::string& ending) {
  return s.size() >= ending.size() && s.compare(s.size() - ending.size(), ending.size(), ending) == 0;
}
}  // namespace

void register_recording_reader(const std::string& extension, RecordingFileReader reader) {
  if (extension.empty() || !reader) throw Error("register_recording_reader: an extension and a reader are needed");
  for (auto& r : file_readers())
    if (r.first == extension) {
      r.second = std::move(reader);
      return;
    }
  file_readers().emplace_back(extension, std::move(reader));
}

sim::Recording load_any_recording(const std::string& spec) {
  for (const auto& [extension, reader] : file_readers())
    if (has_ending(spec, extension)) return reader(spec);
  if (has_ending(spec, ".bag"))
    throw Error(spec + ": a rosbag, and this build reads no rosbags (configure with librosbag-dev installed and "
                       "MPPI_WITH_ROSBAG=ON; docs/ROSBAG.md)");
  const std::string text = read_text_or_zip_member(spec);
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (trim(line).empty() || line[0] == '#') continue;
    const auto names = split(line);
    const bool project = std::find(names.begin(), names.end(), "t") != names.end() &&
                         std::find(names.begin(), names.end(), "yaw_rate") != names.end();
    if (project) {
      std::istringstream again(text);
      return sim::RecordingReader::read(again, spec);
    }
    break;
  }
  sim::Recording rec = convert_real_recording(text, spec);
  const std::size_t z = spec.find(".zip:");
  rec.metadata["source"] = z == std::string::npos ? base_name(spec)
                                                  : base_name(spec.substr(0, z + 4)) + ":" + base_name(spec);
  return rec;
}

void write_recording(const sim::Recording& rec, const std::string& path) {
  std::vector<std::string> extras;
  std::vector<const std::vector<double>*> order;
  for (const auto& name : sim::kRecordingRequiredColumns) order.push_back(&rec.column(name));
  for (std::size_t c = 0; c < rec.columns.size(); ++c) {
    const auto& name = rec.columns[c];
    if (std::find(sim::kRecordingRequiredColumns.begin(), sim::kRecordingRequiredColumns.end(), name) !=
        sim::kRecordingRequiredColumns.end())
      continue;
    extras.push_back(name);
    order.push_back(&rec.data[c]);
  }
  std::vector<std::pair<std::string, std::string>> meta(rec.metadata.begin(), rec.metadata.end());
  sim::RecordingWriter w(path, extras, meta, 2000);
  std::vector<double> row(order.size());
  for (std::size_t i = 0; i < rec.rows(); ++i) {
    for (std::size_t c = 0; c < order.size(); ++c) row[c] = (*order[c])[i];
    w.write_row(row);
  }
  w.close();
}

sim::Recording slice_recording(const sim::Recording& rec, std::size_t begin, std::size_t end) {
  sim::Recording out;
  out.metadata = rec.metadata;
  out.columns = rec.columns;
  end = std::min(end, rec.rows());
  begin = std::min(begin, end);
  for (const auto& c : rec.data) out.data.emplace_back(c.begin() + begin, c.begin() + end);
  return out;
}

std::size_t row_at_time(const sim::Recording& rec, double t_s) {
  const auto& t = rec.column("t");
  return static_cast<std::size_t>(std::lower_bound(t.begin(), t.end(), t_s) - t.begin());
}

}  // namespace mppi::sysid
