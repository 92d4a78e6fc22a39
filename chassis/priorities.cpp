#include "chassis/priorities.hpp"

#include <algorithm>
#include <set>

#include "base/error.hpp"
#include "chassis/yaml_util.hpp"

namespace mppi::chassis {

Priorities::Priorities(std::vector<PriorityEntry> entries) : entries_(std::move(entries)) {
  std::set<std::string> names;
  std::set<int> numbers;
  for (const auto& e : entries_) {
    if (e.sender.empty()) throw Error("chassis priorities: empty controller name");
    if (e.priority < 0)
      throw Error("chassis priorities: '" + e.sender + "' has a negative priority");
    if (!names.insert(e.sender).second)
      throw Error("chassis priorities: controller '" + e.sender + "' listed twice");
    if (!numbers.insert(e.priority).second)
      throw Error("chassis priorities: priority " + std::to_string(e.priority) +
                  " given to two controllers (ties would be ambiguous)");
  }
  std::sort(entries_.begin(), entries_.end(),
            [](const PriorityEntry& a, const PriorityEntry& b) { return a.priority < b.priority; });
}

int Priorities::index_of(std::string_view sender) const {
  for (std::size_t i = 0; i < entries_.size(); ++i)
    if (entries_[i].sender == sender) return static_cast<int>(i);
  return -1;
}

Priorities Priorities::parse_yaml(const std::string& text, const std::string& source) {
  using namespace detail;
  YAML::Node root = load_document(text, source);
  if (root.IsMap() && root.size() == 1 && root["chassisCommandPriorities"])
    root = root["chassisCommandPriorities"];
  if (!root.IsMap() || root.size() == 0)
    throw Error(where(source, root) + ": chassis priorities must be a non-empty map name: priority");
  std::vector<PriorityEntry> entries;
  std::set<int> numbers;
  for (const auto& kv : root) {
    const std::string name = detail::text(kv.first, "a controller name", source);
    const long p = integer(kv.second, name, source);
    if (p < 0 || p > 1000000)
      throw Error(where(source, kv.second) + ": priority of '" + name + "' must be in [0, 1e6]");
    if (!numbers.insert(static_cast<int>(p)).second)
      throw Error(where(source, kv.second) + ": priority " + std::to_string(p) +
                  " of '" + name + "' is already taken (ties would be ambiguous)");
    entries.push_back({name, static_cast<int>(p)});
  }
  try {
    return Priorities(std::move(entries));
  } catch (const Error& e) {
    throw Error(source + ": " + e.what());
  }
}

Priorities Priorities::load_yaml(const std::string& path) {
  return parse_yaml(detail::read_text_file(path), path);
}

}  // namespace mppi::chassis
