#pragma once
// Controller priorities (AutoRally's chassisCommandPriorities.yaml): each controller allowed to
// command the chassis has a name and a priority, lower number wins. Only listed controllers
// may command the chassis.
#include <string>
#include <string_view>
#include <vector>

namespace mppi::chassis {

struct PriorityEntry {
  std::string sender;  // controller name, as it signs its commands
  int priority = 0;    // lower wins; >= 0, unique
};

class Priorities {
 public:
  Priorities() = default;
  // Throws mppi::Error on an empty or repeated name or a repeated or negative priority.
  explicit Priorities(std::vector<PriorityEntry> entries);

  // Sorted best (lowest number) first.
  const std::vector<PriorityEntry>& entries() const { return entries_; }
  int size() const { return static_cast<int>(entries_.size()); }
  // Index into entries() (0 = best), or -1 for a controller not in the list.
  int index_of(std::string_view sender) const;

  // Reads a YAML map `name: priority` (AutoRally's file), optionally under a top-level key
  // `chassisCommandPriorities`. Throws mppi::Error with file:line:column.
  static Priorities load_yaml(const std::string& path);
  static Priorities parse_yaml(const std::string& text, const std::string& source);

 private:
  std::vector<PriorityEntry> entries_;
};

}  // namespace mppi::chassis
