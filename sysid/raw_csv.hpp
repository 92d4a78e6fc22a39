#pragma once
// The raw CSV files of the shipped real recordings: a header row of names, then numeric rows
// (an empty field is NaN); every problem names the source, line and column.
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace mppi::sysid::detail {

// The field without surrounding spaces, tabs and carriage returns.
std::string_view trim(std::string_view s);
// The trimmed fields of a comma-separated line.
std::vector<std::string_view> split(std::string_view line);

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

// Throws mppi::Error "<source>:<line>: column <c> (<name>): <problem>" for a row of another
// field count or a field that is not a number, and for a file with no header row.
RawTable parse_raw_csv(const std::string& text, const std::string& source);
// The index of column `name`; throws mppi::Error naming the source when the header lacks it.
int need(const RawTable& t, const std::string& name, const std::string& source);

}  // namespace mppi::sysid::detail
