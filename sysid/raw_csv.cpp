#include "sysid/raw_csv.hpp"

#include <algorithm>
#include <charconv>
#include <limits>
#include <sstream>

#include "base/error.hpp"

namespace mppi::sysid::detail {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

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

int need(const RawTable& t, const std::string& name, const std::string& source) {
  const int i = t.index(name);
  if (i < 0) throw Error(source + ": missing column '" + name + "' in the header");
  return i;
}

}  // namespace mppi::sysid::detail
