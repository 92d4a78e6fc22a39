#include "ocs/page_access.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>

#include "base/error.hpp"

namespace mppi::ocs {
namespace {

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

bool has_port(const std::string& host) {
  const auto colon = host.rfind(':');
  return colon != std::string::npos && (host.front() != '[' || host.find(']') < colon);
}

// Quoted for a log line or an error: at most 80 characters, control characters as '?'.
std::string quoted(std::string_view s) {
  std::string out = "'";
  for (std::size_t i = 0; i < s.size() && i < 80; ++i) out += std::isprint(static_cast<unsigned char>(s[i])) ? s[i] : '?';
  return out + (s.size() > 80 ? "...'" : "'");
}

}  // namespace

std::string make_token() {
  unsigned char bytes[32];
  const int fd = ::open("/dev/urandom", O_RDONLY | O_CLOEXEC);
  std::size_t got = 0;
  while (fd >= 0 && got < sizeof bytes) {
    const ssize_t n = ::read(fd, bytes + got, sizeof bytes - got);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    got += static_cast<std::size_t>(n);
  }
  if (fd >= 0) ::close(fd);
  if (got != sizeof bytes) throw Error("ocs: cannot read 32 random bytes from /dev/urandom for the page's token");
  static const char* digits = "0123456789abcdef";
  std::string token;
  for (unsigned char b : bytes) token += digits[b >> 4], token += digits[b & 15];
  return token;
}

bool same_secret(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  volatile unsigned char diff = 0;  // volatile: no early exit compiled in
  for (std::size_t i = 0; i < a.size(); ++i) diff = diff | static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

bool is_loopback_bind(const std::string& address) {
  if (address == "localhost" || address == "::1") return true;
  in_addr a{};
  return inet_pton(AF_INET, address.c_str(), &a) == 1 && (ntohl(a.s_addr) >> 24) == 127;
}

std::vector<std::string> page_hosts(const std::string& bind_address, int port, bool tls,
                                    const std::vector<std::string>& extra_hosts) {
  std::vector<std::string> names;
  if (is_loopback_bind(bind_address)) {
    names = {"127.0.0.1", "localhost", "[::1]"};
    if (bind_address != "127.0.0.1" && bind_address != "localhost" && bind_address != "::1") names.push_back(bind_address);
  } else if (bind_address == "0.0.0.0" || bind_address == "::" || bind_address.empty()) {
    char name[256] = {};
    if (::gethostname(name, sizeof name - 1) == 0 && name[0]) names.push_back(name);
  } else {
    const bool ipv6 = bind_address.find(':') != std::string::npos;  // in brackets, as in a URL
    names.push_back(ipv6 ? std::string("[").append(bind_address).append("]") : bind_address);
  }
  const std::string suffix = std::string(":").append(std::to_string(port));
  const bool default_port = port == (tls ? 443 : 80);
  std::vector<std::string> hosts;
  auto add = [&](const std::string& h) {
    if (std::find(hosts.begin(), hosts.end(), lower(h)) == hosts.end()) hosts.push_back(lower(h));
  };
  for (const std::string& n : names) {
    add(n + suffix);
    if (default_port) add(n);
  }
  for (const std::string& h : extra_hosts) {
    if (h.empty()) continue;
    if (has_port(h)) {
      add(h);
    } else {
      add(h + suffix);
      if (default_port) add(h);
    }
  }
  return hosts;
}

std::string refusal(const AccessRules& rules, std::string_view host, const std::optional<std::string>& origin,
                    const std::optional<std::string>& token, bool changes_state) {
  const auto known = [&](std::string_view h) {
    return std::find(rules.hosts.begin(), rules.hosts.end(), lower(h)) != rules.hosts.end();
  };
  const std::string own = (rules.tls ? "https://" : "http://") + (rules.hosts.empty() ? "" : rules.hosts.front());
  if (!known(host))
    return "Host " + quoted(host) + " is not this page's (" + own.substr(own.find("//") + 2) +
           "): a request through another name (DNS rebinding?) is refused";
  if (origin) {
    const std::string scheme = rules.tls ? "https://" : "http://";
    const std::string o = lower(*origin);
    if (o.rfind(scheme, 0) != 0 || !known(std::string_view(o).substr(scheme.size())))
      return "Origin " + quoted(*origin) + " is not this page's (" + own + "): another site's page may not use it";
  }
  if (!changes_state) return "";
  if (!token)
    return std::string("no ") + kTokenHeader +
           " header: open the page at the URL printed when the server started (it carries ?token=...)";
  if (!same_secret(*token, rules.token))
    return std::string("wrong ") + kTokenHeader + ": open the page at the URL printed when the server started";
  return "";
}

}  // namespace mppi::ocs
