#include "sysid/real_data.hpp"

#include <algorithm>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "base/error.hpp"
#include "sysid/raw_csv.hpp"

namespace mppi::sysid {

namespace {

std::string base_name(const std::string& spec) {
  const std::size_t p = spec.find_last_of("/:");
  return p == std::string::npos ? spec : spec.substr(p + 1);
}

}  // namespace

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
    if (detail::trim(line).empty() || line[0] == '#') continue;
    const auto names = detail::split(line);
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
