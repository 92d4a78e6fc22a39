#include "sysid/rosbag/bag_structure.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <vector>

#include "base/error.hpp"

namespace mppi::sysid::bag {

namespace {

constexpr std::uint8_t kOpChunk = 0x05, kOpIndexData = 0x04, kOpBagHeader = 0x03;

std::uint32_t u32_at(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
         static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
}
std::uint64_t u64_at(const std::uint8_t* p) {
  return static_cast<std::uint64_t>(u32_at(p)) | static_cast<std::uint64_t>(u32_at(p + 4)) << 32;
}

class Checker {
 public:
  explicit Checker(const std::string& path) : path_(path), in_(path, std::ios::binary) {
    if (!in_) throw Error(path + ": cannot open the file");
    in_.seekg(0, std::ios::end);
    size_ = static_cast<std::uint64_t>(in_.tellg());
  }

  void run() {
    std::uint64_t pos = 13;  // after "#ROSBAG V2.0\n"
    while (pos < size_) {
      record_ = pos;
      const std::uint32_t header_len = read_u32(pos);
      if (header_len > size_ - pos - 4) fail("the record header (" + std::to_string(header_len) + " bytes) runs past the end of the file");
      std::vector<std::uint8_t> header = read_bytes(pos + 4, header_len);
      const auto fields = parse_fields(header.data(), header.size());
      const std::uint64_t data_at = pos + 4 + header_len;
      if (size_ - data_at < 4) fail("the file ends inside the record");
      const std::uint32_t data_len = read_u32(data_at);
      if (data_len > size_ - data_at - 4) fail("the record data (" + std::to_string(data_len) + " bytes) runs past the end of the file");
      const auto op = fields.find("op");
      if (op == fields.end() || op->second.size() != 1) fail("a record without its op field");
      const std::uint8_t code = static_cast<std::uint8_t>(op->second[0]);
      if (code == kOpBagHeader) bag_header(fields);
      else if (code == kOpChunk) chunk(fields, data_at + 4, data_len);
      else if (code == kOpIndexData) index_data(fields, data_at + 4, data_len);
      pos = data_at + 4 + data_len;
    }
    if (!saw_header_) fail("no bag header record");
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw Error(path_ + ": damaged rosbag: " + what + " (record at byte " + std::to_string(record_) + ")");
  }
  std::vector<std::uint8_t> read_bytes(std::uint64_t at, std::uint64_t n) {
    std::vector<std::uint8_t> b(n);
    in_.seekg(static_cast<std::streamoff>(at));
    in_.read(reinterpret_cast<char*>(b.data()), static_cast<std::streamsize>(n));
    if (static_cast<std::uint64_t>(in_.gcount()) != n) fail("the file cannot be read");
    return b;
  }
  std::uint32_t read_u32(std::uint64_t at) {
    if (size_ - at < 4) fail("the file ends inside a record length");
    return u32_at(read_bytes(at, 4).data());
  }
  std::map<std::string, std::string> parse_fields(const std::uint8_t* h, std::size_t n) const {
    std::map<std::string, std::string> f;
    std::size_t i = 0;
    while (i < n) {
      if (n - i < 4) fail("a header field length runs past its header");
      const std::uint32_t len = u32_at(h + i);
      i += 4;
      if (len > n - i) fail("a header field (" + std::to_string(len) + " bytes) runs past its header");
      const std::string field(reinterpret_cast<const char*>(h + i), len);
      const auto eq = field.find('=');
      if (eq == std::string::npos) fail("a header field without '='");
      f[field.substr(0, eq)] = field.substr(eq + 1);
      i += len;
    }
    return f;
  }
  const std::string& field(const std::map<std::string, std::string>& f, const char* name, std::size_t bytes) const {
    const auto it = f.find(name);
    if (it == f.end() || (bytes && it->second.size() != bytes))
      fail(std::string("a record without a valid '") + name + "' field");
    return it->second;
  }
  void bag_header(const std::map<std::string, std::string>& f) {
    saw_header_ = true;
    const std::uint64_t index_pos = u64_at(reinterpret_cast<const std::uint8_t*>(field(f, "index_pos", 8).data()));
    if (index_pos == 0) fail("the bag is not indexed (a recording that did not end cleanly: run `rosbag reindex`)");
    if (index_pos >= size_) fail("the index position " + std::to_string(index_pos) + " is past the end of the file (truncated)");
  }
  void chunk(const std::map<std::string, std::string>& f, std::uint64_t at, std::uint32_t len) {
    const std::string& compression = field(f, "compression", 0);
    chunk_size_ = u32_at(reinterpret_cast<const std::uint8_t*>(field(f, "size", 4).data()));
    chunk_plain_ = compression == "none";
    starts_.clear();
    if (!chunk_plain_) return;
    if (len != chunk_size_) fail("an uncompressed chunk whose size field disagrees with its data");
    const std::vector<std::uint8_t> data = read_bytes(at, len);
    std::size_t p = 0;
    while (p < data.size()) {
      if (data.size() - p < 4) fail("a record inside a chunk is cut");
      const std::uint32_t hl = u32_at(data.data() + p);
      if (hl > data.size() - p - 4 || data.size() - p - 4 - hl < 4) fail("a record header inside a chunk runs past the chunk");
      parse_fields(data.data() + p + 4, hl);
      const std::uint32_t dl = u32_at(data.data() + p + 4 + hl);
      if (dl > data.size() - p - 8 - hl) fail("a message inside a chunk runs past the chunk");
      starts_.push_back(static_cast<std::uint32_t>(p));
      p += 8 + static_cast<std::size_t>(hl) + dl;
    }
  }
  void index_data(const std::map<std::string, std::string>& f, std::uint64_t at, std::uint32_t len) {
    const std::uint32_t count = u32_at(reinterpret_cast<const std::uint8_t*>(field(f, "count", 4).data()));
    if (static_cast<std::uint64_t>(count) * 12 != len) fail("an index whose entry count disagrees with its data");
    const std::vector<std::uint8_t> data = read_bytes(at, len);
    for (std::uint32_t e = 0; e < count; ++e) {
      const std::uint32_t offset = u32_at(data.data() + 12 * e + 8);
      const bool ok = chunk_plain_ ? std::binary_search(starts_.begin(), starts_.end(), offset)
                                   : static_cast<std::uint64_t>(offset) + 8 <= chunk_size_;
      if (!ok) fail("an index entry points at byte " + std::to_string(offset) + ", not at a message of its chunk");
    }
  }

  std::string path_;
  std::ifstream in_;
  std::uint64_t size_ = 0, record_ = 0;
  bool saw_header_ = false, chunk_plain_ = true;
  std::uint32_t chunk_size_ = 0;
  std::vector<std::uint32_t> starts_;
};

}  // namespace

void check_bag_structure(const std::string& path) { Checker(path).run(); }

}  // namespace mppi::sysid::bag
