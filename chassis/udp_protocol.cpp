#include "chassis/udp_protocol.hpp"

#include <cstring>

#include "base/error.hpp"

namespace mppi::chassis::udp {
namespace {

// Little-endian writers/readers (the wire order, whatever the host's).
void put_u16(std::uint8_t* p, std::uint16_t v) {
  p[0] = static_cast<std::uint8_t>(v);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}
void put_u32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
void put_u64(std::uint8_t* p, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
void put_f32(std::uint8_t* p, float f) {
  std::uint32_t v;
  std::memcpy(&v, &f, 4);
  put_u32(p, v);
}
void put_f64(std::uint8_t* p, double f) {
  std::uint64_t v;
  std::memcpy(&v, &f, 8);
  put_u64(p, v);
}
std::uint16_t get_u16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}
std::uint32_t get_u32(const std::uint8_t* p) {
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(p[i]) << (8 * i);
  return v;
}
std::uint64_t get_u64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(p[i]) << (8 * i);
  return v;
}
float get_f32(const std::uint8_t* p) {
  const std::uint32_t v = get_u32(p);
  float f;
  std::memcpy(&f, &v, 4);
  return f;
}
double get_f64(const std::uint8_t* p) {
  const std::uint64_t v = get_u64(p);
  double f;
  std::memcpy(&f, &v, 8);
  return f;
}

bool printable(char c) { return c >= 0x21 && c <= 0x7e; }  // no spaces or control characters

void check_sender(std::string_view sender) {
  if (sender.empty() || sender.size() >= kSenderSize)
    throw Error("udp: sender name must have 1-15 characters, got '" + std::string(sender) + "'");
  for (char c : sender)
    if (!printable(c)) throw Error("udp: sender name must be printable ASCII without spaces");
}

void put_header(std::uint8_t* p, MessageType type, std::size_t size, std::string_view sender,
                std::uint64_t sequence) {
  check_sender(sender);
  std::memcpy(p, kMagic, 4);
  p[4] = kVersion;
  p[5] = static_cast<std::uint8_t>(type);
  put_u16(p + 6, static_cast<std::uint16_t>(size));
  put_u64(p + 8, sequence);
  std::memset(p + 16, 0, kSenderSize);
  std::memcpy(p + 16, sender.data(), sender.size());
}

template <std::size_t N>
void seal(std::array<std::uint8_t, N>& m) {
  put_u32(m.data() + N - 4, crc32(std::span<const std::uint8_t>(m.data(), N - 4)));
}

struct CrcTable {
  std::uint32_t t[256];
  constexpr CrcTable() : t{} {
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
  }
};
constexpr CrcTable kCrcTable;

}  // namespace

const char* to_string(Reject r) {
  switch (r) {
    case Reject::kNone: return "accepted";
    case Reject::kTruncated: return "truncated";
    case Reject::kOversized: return "oversized";
    case Reject::kBadMagic: return "bad magic";
    case Reject::kBadVersion: return "unsupported version";
    case Reject::kBadType: return "bad message type";
    case Reject::kLengthMismatch: return "length does not match the type";
    case Reject::kBadChecksum: return "bad checksum";
    case Reject::kBadSender: return "bad sender name";
    case Reject::kReservedNotZero: return "reserved bytes not zero";
    case Reject::kBadRunstopValue: return "runstop value not 0 or 1";
    case Reject::kReplayed: return "replayed or reordered (sequence not increasing)";
    case Reject::kUnknownSender: return "sender not in the priority list";
    case Reject::kInvalidCommand: return "invalid command values";
    case Reject::kTooManySenders: return "too many senders";
    case Reject::kRunstopRejected: return "runstop source rejected";
    case Reject::kBadParameterName: return "bad parameter name";
    case Reject::kUnauthenticated: return "unauthenticated (no tag)";
    case Reject::kBadTag: return "bad authentication tag";
  }
  return "unknown reason";
}

std::uint32_t crc32(std::span<const std::uint8_t> bytes) {
  std::uint32_t c = 0xFFFFFFFFu;
  for (std::uint8_t b : bytes) c = kCrcTable.t[(c ^ b) & 0xFFu] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

std::array<std::uint8_t, kCommandSize> encode_command(std::string_view sender, std::uint64_t sequence,
                                                      const Command& c) {
  std::array<std::uint8_t, kCommandSize> m{};
  put_header(m.data(), MessageType::kCommand, kCommandSize, sender, sequence);
  put_f32(m.data() + 32, c.steering);
  put_f32(m.data() + 36, c.throttle);
  put_f32(m.data() + 40, c.front_brake);
  m[44] = c.actuators;
  seal(m);
  return m;
}

std::array<std::uint8_t, kRunstopSize> encode_runstop(std::string_view sender, std::uint64_t sequence,
                                                      bool motion_enabled) {
  std::array<std::uint8_t, kRunstopSize> m{};
  put_header(m.data(), MessageType::kRunstop, kRunstopSize, sender, sequence);
  m[32] = motion_enabled ? 1 : 0;
  seal(m);
  return m;
}

std::array<std::uint8_t, kStateSize> encode_state(std::string_view sender, std::uint64_t sequence,
                                                  const StateMessage& s) {
  std::array<std::uint8_t, kStateSize> m{};
  put_header(m.data(), MessageType::kState, kStateSize, sender, sequence);
  std::uint8_t* p = m.data() + 32;
  put_f64(p, s.time_s);
  for (int i = 0; i < 7; ++i) put_f32(p + 8 + 4 * i, s.state[static_cast<std::size_t>(i)]);
  for (int i = 0; i < 3; ++i) put_f32(p + 36 + 4 * i, s.applied[static_cast<std::size_t>(i)]);
  for (int i = 0; i < 3; ++i) put_u16(p + 48 + 2 * i, s.pulses_us[static_cast<std::size_t>(i)]);
  p[54] = static_cast<std::uint8_t>((s.motion_enabled ? 1 : 0) | (s.watchdog_tripped ? 2 : 0));
  seal(m);
  return m;
}

std::array<std::uint8_t, kParameterSize> encode_parameter(std::string_view sender, std::uint64_t sequence,
                                                          std::string_view name, double value) {
  if (name.empty() || name.size() >= kParameterNameSize)
    throw Error("udp: parameter name must have 1-31 characters, got '" + std::string(name) + "'");
  for (char c : name)
    if (!printable(c)) throw Error("udp: parameter name must be printable ASCII without spaces");
  std::array<std::uint8_t, kParameterSize> m{};
  put_header(m.data(), MessageType::kParameter, kParameterSize, sender, sequence);
  std::memcpy(m.data() + 32, name.data(), name.size());
  put_f64(m.data() + 32 + kParameterNameSize, value);
  seal(m);
  return m;
}

Message decode(std::span<const std::uint8_t> bytes, std::size_t datagram_size) {
  Message m;
  auto reject = [&](Reject r) {
    m.reason = r;
    return m;
  };
  if (datagram_size > kMaxMessageSize || bytes.size() < datagram_size) return reject(Reject::kOversized);
  if (datagram_size < kHeaderSize + 4) return reject(Reject::kTruncated);
  const std::uint8_t* p = bytes.data();
  if (std::memcmp(p, kMagic, 4) != 0) return reject(Reject::kBadMagic);
  if (p[4] != kVersion) return reject(Reject::kBadVersion);
  const std::size_t declared = get_u16(p + 6);
  if (datagram_size < declared) return reject(Reject::kTruncated);
  if (datagram_size > declared) return reject(Reject::kOversized);
  std::size_t expected = 0;
  switch (p[5]) {
    case 1: expected = kCommandSize; break;
    case 2: expected = kRunstopSize; break;
    case 3: expected = kStateSize; break;
    case 4: expected = kParameterSize; break;
    default: return reject(Reject::kBadType);
  }
  if (declared != expected) return reject(Reject::kLengthMismatch);
  if (get_u32(p + declared - 4) != crc32(std::span<const std::uint8_t>(p, declared - 4)))
    return reject(Reject::kBadChecksum);
  // Sender: 1-15 printable characters, then only NULs.
  std::size_t len = 0;
  while (len < kSenderSize && p[16 + len] != 0) ++len;
  if (len == 0 || len == kSenderSize) return reject(Reject::kBadSender);
  for (std::size_t i = 0; i < len; ++i)
    if (!printable(static_cast<char>(p[16 + i]))) return reject(Reject::kBadSender);
  for (std::size_t i = len; i < kSenderSize; ++i)
    if (p[16 + i] != 0) return reject(Reject::kBadSender);
  std::memcpy(m.sender, p + 16, len);
  m.type = static_cast<MessageType>(p[5]);
  m.sequence = get_u64(p + 8);
  const std::uint8_t* b = p + 32;
  if (m.type == MessageType::kCommand) {
    if (b[13] || b[14] || b[15]) return reject(Reject::kReservedNotZero);
    m.command = Command{get_f32(b), get_f32(b + 4), get_f32(b + 8), b[12]};
  } else if (m.type == MessageType::kRunstop) {
    if (b[1] || b[2] || b[3]) return reject(Reject::kReservedNotZero);
    if (b[0] > 1) return reject(Reject::kBadRunstopValue);
    m.motion_enabled = b[0] == 1;
  } else if (m.type == MessageType::kParameter) {
    std::size_t n = 0;
    while (n < kParameterNameSize && b[n] != 0) ++n;
    if (n == 0 || n == kParameterNameSize) return reject(Reject::kBadParameterName);
    for (std::size_t i = 0; i < n; ++i)
      if (!printable(static_cast<char>(b[i]))) return reject(Reject::kBadParameterName);
    for (std::size_t i = n; i < kParameterNameSize; ++i)
      if (b[i] != 0) return reject(Reject::kBadParameterName);
    std::memcpy(m.parameter_name, b, n);
    m.parameter_value = get_f64(b + kParameterNameSize);
  } else {
    if (b[55]) return reject(Reject::kReservedNotZero);
    m.state.time_s = get_f64(b);
    for (int i = 0; i < 7; ++i) m.state.state[static_cast<std::size_t>(i)] = get_f32(b + 8 + 4 * i);
    for (int i = 0; i < 3; ++i) m.state.applied[static_cast<std::size_t>(i)] = get_f32(b + 36 + 4 * i);
    for (int i = 0; i < 3; ++i) m.state.pulses_us[static_cast<std::size_t>(i)] = get_u16(b + 48 + 2 * i);
    if (b[54] & ~3u) return reject(Reject::kReservedNotZero);
    m.state.motion_enabled = b[54] & 1;
    m.state.watchdog_tripped = b[54] & 2;
  }
  return m;
}

}  // namespace mppi::chassis::udp
