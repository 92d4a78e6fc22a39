#pragma once
// The record structure of a rosbag (format 2.0) checked before librosbag reads it: librosbag
// trusts the lengths and index offsets inside a chunk and reads past its buffer when they are
// damaged. Checked: every record's header and data lie inside the file; header fields inside
// their header; the bag header's index position inside the file (0 = an unindexed bag, e.g. a
// `rosbag record` that was killed: `rosbag reindex` repairs it); inside an uncompressed chunk,
// every record inside the chunk and every index offset at the start of one of them; for a
// compressed chunk, every index offset inside its uncompressed size (a damaged compressed chunk
// fails to decompress in librosbag, which reports it).
#include <string>

namespace mppi::sysid::bag {

// Throws mppi::Error "<path>: damaged rosbag: <what> (record at byte N)".
void check_bag_structure(const std::string& path);

}  // namespace mppi::sysid::bag
