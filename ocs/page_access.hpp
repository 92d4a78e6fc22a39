#pragma once
// Who may change what through the operator page (docs/SECURITY.md). A browser sends any site's
// form POST to a local port, and a page served by a rebound DNS name reaches it with that name
// as Host: so every request must name this page's own host (Host, and Origin when the browser
// sends one), and a request that changes state (any method but GET and HEAD) must carry the
// per-launch secret token, which the page reads from its own URL (?token=...) and sends back
// in the X-MPPI-Token header. Another site's page never learns the token, and cannot send a
// custom header to this port without a CORS preflight, which the Origin check refuses.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace mppi::ocs {

inline constexpr const char* kTokenHeader = "X-MPPI-Token";

// How the page is served and reached; the programs' --serve-* options.
struct PageAccess {
  std::string tls_cert_file, tls_key_file;  // both: HTTPS (PEM files)
  bool insecure_remote = false;             // allow plain HTTP off loopback (anyone on the path sees the token)
  std::vector<std::string> extra_hosts;     // more names the page is reached by ("name" or "name:port")
  std::string token;                        // the secret; empty: a fresh random one at start
};

// 32 bytes from /dev/urandom as 64 hex digits; throws mppi::Error if it cannot be read.
std::string make_token();

// a == b in time that does not depend on where they differ (their lengths are not secret).
bool same_secret(std::string_view a, std::string_view b);

// True for an address that only this machine can reach: 127.0.0.0/8, ::1, "localhost".
bool is_loopback_bind(const std::string& address);

// The Host header values the page answers to: host:port for 127.0.0.1, localhost and [::1] when
// bound to loopback, the bound address otherwise (with this machine's host name when bound to
// every address), and each extra host (":port" added when it has none). The bare names too
// when port is the scheme's default.
std::vector<std::string> page_hosts(const std::string& bind_address, int port, bool tls,
                                    const std::vector<std::string>& extra_hosts);

// The rules one request is checked against.
struct AccessRules {
  std::string token;
  std::vector<std::string> hosts;  // page_hosts()
  bool tls = false;                // the page's own origin is https://host
};

// Why a request is refused ("" = allowed). host: the Host header (empty if none); origin and
// token: the Origin and X-MPPI-Token headers, if sent; changes_state: not a GET or HEAD.
std::string refusal(const AccessRules& rules, std::string_view host, const std::optional<std::string>& origin,
                    const std::optional<std::string>& token, bool changes_state);

}  // namespace mppi::ocs
