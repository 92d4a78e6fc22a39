#pragma once
// A rosbag (format 2.0, as `rosbag record` writes it) opened with librosbag: its topics with their
// message types, and the serialised messages of one topic. All librosbag errors (a file that is
// not a bag, a truncated or unindexed one, a chunk that does not decompress) come out as
// mppi::Error naming the file.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "sysid/rosbag/bag_messages.hpp"

namespace mppi::sysid::bag {

struct TopicInfo {
  std::string topic;     // as recorded, e.g. "/pose_estimate"
  std::string datatype;  // e.g. "nav_msgs/Odometry"
  std::string md5sum;
  std::size_t messages = 0;
};

// One serialised message: the bag's time of it [ns] and its bytes (valid during the call only).
using MessageVisitor = std::function<void(std::int64_t receive_time_ns, const std::vector<std::uint8_t>& bytes)>;

class BagFile {
 public:
  // Throws mppi::Error "<path>: ..." when the file cannot be opened or is not a readable bag.
  explicit BagFile(const std::string& path);
  ~BagFile();
  BagFile(const BagFile&) = delete;
  BagFile& operator=(const BagFile&) = delete;

  const std::string& path() const { return path_; }
  // One entry per topic (several connections on a topic, e.g. two publishers, are merged when
  // they agree on the type; a topic with connections of different types lists the first).
  const std::vector<TopicInfo>& topics() const { return topics_; }
  // The topic as recorded that `name` means: exact, or with / without the leading '/', or else the
  // only topic ending in "/<name>" (a namespaced one). Empty when none (or several) match.
  std::string resolve(const std::string& name) const;
  // "/a (type), /b (type)" for messages.
  std::string topic_list() const;
  // Refuses a topic whose connections are not of `type` (datatype and md5sum), naming the topic,
  // the expected and the found type.
  void check_type(const std::string& topic, const MessageType& type) const;
  // Every message of `topic` in bag time order, one at a time (a long bag is never held whole).
  void for_each_message(const std::string& topic, const MessageVisitor& visit) const;

 private:
  struct Impl;
  std::string path_;
  std::unique_ptr<Impl> impl_;
  std::vector<TopicInfo> topics_;
};

}  // namespace mppi::sysid::bag
