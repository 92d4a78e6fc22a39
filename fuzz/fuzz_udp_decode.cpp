// The chassis UDP datagram decoder (chassis/udp_protocol.cpp). Random bytes rarely carry a
// valid CRC-32, so for inputs whose first byte is odd the target writes the right CRC into the
// trailer first: the fuzzer then reaches the checks of the body, not only the checksum.
#include <cstring>
#include <vector>

#include "chassis/udp_protocol.hpp"
#include "fuzz/fuzz_input.hpp"

namespace udp = mppi::chassis::udp;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  const bool fix_crc = (data[0] & 1) != 0;
  // The second byte: from 0xF0 on, the datagram was 1-16 bytes longer on the wire than what
  // was received (a truncating receive buffer).
  const std::size_t truncated_by = data[1] >= 0xF0 ? data[1] - 0xEFu : 0u;
  std::vector<std::uint8_t> bytes(data + 2, data + size);
  if (fix_crc && bytes.size() >= 4) {
    const std::uint32_t crc = udp::crc32(std::span(bytes.data(), bytes.size() - 4));
    for (int i = 0; i < 4; ++i) bytes[bytes.size() - 4 + i] = static_cast<std::uint8_t>(crc >> (8 * i));
  }
  const udp::Message m = udp::decode(bytes, bytes.size() + truncated_by);
  // An accepted message has a NUL-terminated, non-empty sender.
  if (m.reason == udp::Reject::kNone && (std::strlen(m.sender) == 0 || std::strlen(m.sender) >= sizeof m.sender))
    __builtin_trap();
  return 0;
}
