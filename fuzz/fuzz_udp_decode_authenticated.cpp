// The chassis UDP decoder with a key (chassis/udp_auth.cpp: the tag, then the message checks).
// Random bytes never carry a valid HMAC-SHA256 tag, so the first byte chooses what the target
// fixes before decoding: bit 0 the CRC-32 of the message part, bit 1 its tag under the target's
// key. With the tag fixed the fuzzer reaches the message checks behind it; without, it tries the
// tag check itself. The second byte: from 0xF0 on, the datagram was 1-16 bytes longer on the
// wire than what was received (a truncating receive buffer).
#include <cstring>
#include <vector>

#include "chassis/udp_auth.hpp"
#include "fuzz/fuzz_input.hpp"

namespace udp = mppi::chassis::udp;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const udp::Key key = udp::Key::from_hex("000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f");
  if (size < 2) return 0;
  const bool fix_crc = (data[0] & 1) != 0, fix_tag = (data[0] & 2) != 0;
  const std::size_t truncated_by = data[1] >= 0xF0 ? data[1] - 0xEFu : 0u;
  std::vector<std::uint8_t> bytes(data + 2, data + size);
  if (bytes.size() >= udp::kTagSize + 4) {
    const std::size_t message = bytes.size() - udp::kTagSize;
    if (fix_crc) {
      const std::uint32_t crc = udp::crc32(std::span(bytes.data(), message - 4));
      for (int i = 0; i < 4; ++i) bytes[message - 4 + i] = static_cast<std::uint8_t>(crc >> (8 * i));
    }
    if (fix_tag) {
      const auto tag = udp::hmac_sha256(key.bytes(), std::span(bytes.data(), message));
      std::memcpy(bytes.data() + message, tag.data(), udp::kTagSize);
    }
  }
  const udp::Message m = udp::decode_authenticated(bytes, bytes.size() + truncated_by, key);
  if (m.reason == udp::Reject::kNone) {
    // Accepted: the tag is right (never without one), and the sender is a NUL-terminated name.
    if (bytes.size() < udp::kTagSize || truncated_by) __builtin_trap();
    const std::size_t message = bytes.size() - udp::kTagSize;
    const auto tag = udp::hmac_sha256(key.bytes(), std::span(bytes.data(), message));
    if (std::memcmp(tag.data(), bytes.data() + message, udp::kTagSize) != 0) __builtin_trap();
    if (std::strlen(m.sender) == 0 || std::strlen(m.sender) >= sizeof m.sender) __builtin_trap();
  }
  return 0;
}
