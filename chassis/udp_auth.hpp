#pragma once
// Authentication of the chassis UDP link (docs/CHASSIS.md, "Authentication"). With a key, every
// datagram is a message of udp_protocol.hpp followed by a 32-byte tag:
//   datagram = message (header | body | CRC-32) | HMAC-SHA256(key, message)
// The tag covers every byte of the message, the CRC included; the header's length field still
// gives the message's length, without the tag. A receiver with a key checks the tag before it
// reads anything else, so a forged or altered datagram never reaches the message checks, the
// replay table or the arbiter. The key is 32 bytes, shared by the vehicle and every program
// that talks to it, read from a file holding them as 64 hex digits.
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "chassis/udp_protocol.hpp"

namespace mppi::chassis::udp {

inline constexpr std::size_t kKeySize = 32;
inline constexpr std::size_t kTagSize = 32;  // HMAC-SHA256
inline constexpr std::size_t kMaxDatagramSize = kMaxMessageSize + kTagSize;

class Key {
 public:
  // 64 hex digits (either case), optionally surrounded by whitespace; throws mppi::Error
  // naming `where` otherwise.
  static Key from_hex(std::string_view text, const std::string& where = "key");
  // Reads a key file. Refuses (mppi::Error naming the file) one that group or others may
  // read or write: the key lets whoever holds it drive the car.
  static Key load(const std::string& path);
  const std::array<std::uint8_t, kKeySize>& bytes() const { return bytes_; }

 private:
  std::array<std::uint8_t, kKeySize> bytes_{};
};

// HMAC-SHA256 (RFC 2104) of `data` under `key`, OpenSSL's.
std::array<std::uint8_t, kTagSize> hmac_sha256(std::span<const std::uint8_t> key, std::span<const std::uint8_t> data);

// One datagram as it goes on the wire: a message, with its tag when sent with a key.
struct Datagram {
  std::array<std::uint8_t, kMaxDatagramSize> bytes{};
  std::size_t size = 0;
  std::span<const std::uint8_t> span() const { return {bytes.data(), size}; }
};

// The datagram for `message` (an encoder's output): the message as it is without a key, the
// message and its tag with one. Never throws.
Datagram seal_datagram(std::span<const std::uint8_t> message, const Key* key);

// Checks and decodes one datagram received with a key: the tag first (kUnauthenticated for a
// message without one, kBadTag for a wrong one), then decode() on the message. `datagram_size`
// as for decode().
Message decode_authenticated(std::span<const std::uint8_t> bytes, std::size_t datagram_size, const Key& key);

// decode_authenticated() with a key, decode() without.
Message decode_datagram(std::span<const std::uint8_t> bytes, std::size_t datagram_size, const Key* key);

// True for an IPv4 loopback address (127.0.0.0/8), the only place the link may run without a key.
bool is_loopback_address(const std::string& address);

// Throws mppi::Error if an end of the link at `address` (bound there, or sending there) has no
// key off loopback; `what` names the end in the message.
void require_key_off_loopback(const std::string& what, const std::string& address, const Key* key);

}  // namespace mppi::chassis::udp
