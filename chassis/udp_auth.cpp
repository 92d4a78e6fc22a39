#include "chassis/udp_auth.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "base/error.hpp"

namespace mppi::chassis::udp {
namespace {

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

bool space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

std::string octal_mode(mode_t mode) {
  char text[8];
  std::snprintf(text, sizeof text, "%04o", static_cast<unsigned>(mode & 07777));
  return text;
}

}  // namespace

Key Key::from_hex(std::string_view text, const std::string& where) {
  while (!text.empty() && space(text.front())) text.remove_prefix(1);
  while (!text.empty() && space(text.back())) text.remove_suffix(1);
  if (text.size() != 2 * kKeySize)
    throw Error(where + ": expected a key of 64 hex digits (32 bytes), got " + std::to_string(text.size()) +
                " characters (make one with: head -c 32 /dev/urandom | xxd -p -c 32)");
  Key k;
  for (std::size_t i = 0; i < kKeySize; ++i) {
    const int hi = hex_digit(text[2 * i]), lo = hex_digit(text[2 * i + 1]);
    if (hi < 0 || lo < 0) throw Error(where + ": not a hex digit at character " + std::to_string(2 * i + (hi < 0 ? 1 : 2)));
    k.bytes_[i] = static_cast<std::uint8_t>(hi * 16 + lo);
  }
  return k;
}

Key Key::load(const std::string& path) {
  // Open first, then check the open file: no window between the check and the read.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw Error("key file " + path + ": " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw Error("key file " + path + ": not a regular file");
  }
  if (st.st_mode & (S_IRWXG | S_IRWXO)) {
    ::close(fd);
    throw Error("key file " + path + " has mode " + octal_mode(st.st_mode) +
                "; it must not be readable or writable by group or others (chmod 600 " + path + ")");
  }
  char buffer[256];
  std::size_t n = 0;
  for (;;) {
    const ssize_t r = ::read(fd, buffer + n, sizeof buffer - n);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) break;
    n += static_cast<std::size_t>(r);
    if (n == sizeof buffer) break;
  }
  ::close(fd);
  Key k = from_hex(std::string_view(buffer, n), "key file " + path);
  OPENSSL_cleanse(buffer, sizeof buffer);
  return k;
}

std::array<std::uint8_t, kTagSize> hmac_sha256(std::span<const std::uint8_t> key, std::span<const std::uint8_t> data) {
  std::array<std::uint8_t, kTagSize> tag{};
  unsigned int length = 0;
  static const std::uint8_t kEmpty = 0;  // OpenSSL wants a non-null pointer, even for no bytes
  if (!HMAC(EVP_sha256(), key.empty() ? &kEmpty : key.data(), static_cast<int>(key.size()),
            data.empty() ? &kEmpty : data.data(), data.size(), tag.data(), &length) ||
      length != kTagSize)
    tag.fill(0);  // cannot happen with SHA-256; an all-zero tag then matches nothing honest
  return tag;
}

Datagram seal_datagram(std::span<const std::uint8_t> message, const Key* key) {
  Datagram d;
  const std::size_t n = std::min(message.size(), kMaxMessageSize);
  std::memcpy(d.bytes.data(), message.data(), n);
  d.size = n;
  if (key) {
    const auto tag = hmac_sha256(key->bytes(), std::span<const std::uint8_t>(d.bytes.data(), n));
    std::memcpy(d.bytes.data() + n, tag.data(), kTagSize);
    d.size += kTagSize;
  }
  return d;
}

Message decode_authenticated(std::span<const std::uint8_t> bytes, std::size_t datagram_size, const Key& key) {
  Message m;
  if (datagram_size > kMaxDatagramSize || bytes.size() < datagram_size) {
    m.reason = Reject::kOversized;
    return m;
  }
  // A message sent without a key: its header's length is the whole datagram's.
  if (datagram_size >= 8 && static_cast<std::size_t>(bytes[6] | (bytes[7] << 8)) == datagram_size) {
    m.reason = Reject::kUnauthenticated;
    return m;
  }
  if (datagram_size < kHeaderSize + 4 + kTagSize) {
    m.reason = Reject::kTruncated;
    return m;
  }
  const std::size_t message_size = datagram_size - kTagSize;
  const auto tag = hmac_sha256(key.bytes(), bytes.first(message_size));
  if (CRYPTO_memcmp(tag.data(), bytes.data() + message_size, kTagSize) != 0) {
    m.reason = Reject::kBadTag;
    return m;
  }
  return decode(bytes.first(message_size), message_size);
}

Message decode_datagram(std::span<const std::uint8_t> bytes, std::size_t datagram_size, const Key* key) {
  return key ? decode_authenticated(bytes, datagram_size, *key) : decode(bytes, datagram_size);
}

bool is_loopback_address(const std::string& address) {
  in_addr a{};
  if (inet_pton(AF_INET, address.c_str(), &a) != 1) return false;
  return (ntohl(a.s_addr) >> 24) == 127;
}

void require_key_off_loopback(const std::string& what, const std::string& address, const Key* key) {
  if (key || is_loopback_address(address)) return;
  throw Error(what + " at " + address + " is off loopback: it needs a key (--key FILE; docs/CHASSIS.md, "
              "\"Authentication\"), or anyone on that network could send datagrams that drive the car");
}

}  // namespace mppi::chassis::udp
