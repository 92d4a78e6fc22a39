#include "sysid/rosbag/bag_file.hpp"

#include <exception>
#include <fstream>
#include <map>

#include <ros/serialization.h>
#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <rosbag/view.h>

#include "base/error.hpp"
#include "sysid/rosbag/bag_structure.hpp"

namespace mppi::sysid::bag {

struct BagFile::Impl {
  ::rosbag::Bag bag;
  std::map<std::string, std::vector<std::pair<std::string, std::string>>> types;  // topic -> (datatype, md5)
};

namespace {
// librosbag reports a truncated or damaged file with its own exceptions, ros::Exception or std ones.
template <class F>
auto guarded(const std::string& path, const char* doing, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const mppi::Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(path + ": not a readable rosbag (" + doing + ": " + e.what() + ")");
  }
}
}  // namespace

BagFile::BagFile(const std::string& path) : path_(path), impl_(std::make_unique<Impl>()) {
  {
    std::ifstream probe(path, std::ios::binary);
    if (!probe) throw Error(path + ": cannot open the file");
    char magic[13] = {};
    probe.read(magic, 13);
    if (probe.gcount() < 13 || std::string(magic, 13) != "#ROSBAG V2.0\n")
      throw Error(path + ": not a rosbag (format 2.0 starts with '#ROSBAG V2.0')");
  }
  check_bag_structure(path);  // librosbag reads past its buffers on damaged chunks
  guarded(path_, "opening", [&] {
    impl_->bag.open(path_, ::rosbag::bagmode::Read);
    ::rosbag::View all(impl_->bag);
    std::map<std::string, TopicInfo> by_topic;
    for (const ::rosbag::ConnectionInfo* c : all.getConnections()) {
      TopicInfo& t = by_topic[c->topic];
      if (t.topic.empty()) {
        t.topic = c->topic;
        t.datatype = c->datatype;
        t.md5sum = c->md5sum;
      }
      impl_->types[c->topic].emplace_back(c->datatype, c->md5sum);
    }
    for (auto& [name, info] : by_topic) {
      ::rosbag::View one(impl_->bag, ::rosbag::TopicQuery(name));
      info.messages = one.size();
      topics_.push_back(info);
    }
    return 0;
  });
}

BagFile::~BagFile() = default;

std::string BagFile::resolve(const std::string& name) const {
  if (name.empty()) return "";
  const std::string bare = name[0] == '/' ? name.substr(1) : name;
  for (const auto& t : topics_)
    if (t.topic == name || t.topic == "/" + bare || t.topic == bare) return t.topic;
  std::string found;
  for (const auto& t : topics_) {
    const std::string ending = "/" + bare;
    if (t.topic.size() > ending.size() && t.topic.compare(t.topic.size() - ending.size(), ending.size(), ending) == 0) {
      if (!found.empty()) return "";  // ambiguous
      found = t.topic;
    }
  }
  return found;
}

std::string BagFile::topic_list() const {
  if (topics_.empty()) return "no topics";
  std::string s;
  for (const auto& t : topics_) s += (s.empty() ? "" : ", ") + t.topic + " (" + t.datatype + ")";
  return s;
}

void BagFile::check_type(const std::string& topic, const MessageType& type) const {
  const auto it = impl_->types.find(topic);
  if (it == impl_->types.end()) throw Error(path_ + ": no topic '" + topic + "'");
  for (const auto& [datatype, md5] : it->second) {
    if (datatype != type.datatype)
      throw Error(path_ + ": topic '" + topic + "' is " + datatype + ", expected " + std::string(type.datatype));
    if (md5 != type.md5sum && md5 != "*")
      throw Error(path_ + ": topic '" + topic + "' is " + datatype + " with md5sum " + md5 + ", expected " +
                  std::string(type.datatype) + " with md5sum " + std::string(type.md5sum) +
                  " (another definition of the message)");
  }
}

void BagFile::for_each_message(const std::string& topic, const MessageVisitor& visit) const {
  guarded(path_, ("reading topic " + topic).c_str(), [&] {
    std::vector<std::uint8_t> bytes;
    ::rosbag::View view(impl_->bag, ::rosbag::TopicQuery(topic));
    for (const ::rosbag::MessageInstance& m : view) {
      bytes.resize(m.size());
      ros::serialization::OStream stream(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
      m.write(stream);
      visit(static_cast<std::int64_t>(m.getTime().toNSec()), bytes);
    }
    return 0;
  });
}

}  // namespace mppi::sysid::bag
