// Who may use the operator page: the token (right, wrong, missing), the page's own Host and
// Origin, the rules applied by a running server to every request (a 403 naming the reason,
// counted), and no plain HTTP off loopback unless asked for.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <string>

#include "ocs/live_observer.hpp"
#include "ocs/page_access.hpp"
#include "ocs/server.hpp"
#include "error_of.hpp"

// last: <httplib.h> pulls in <resolv.h>, whose `_res` macro breaks Eigen headers included after it
#include <httplib.h>

using mppi::ocs::AccessRules;
using mppi::ocs::refusal;

namespace {
const std::string kToken(64, 'a');
AccessRules rules() { return {kToken, mppi::ocs::page_hosts("127.0.0.1", 8080, false, {}), false}; }
const std::optional<std::string> kNone;
}  // namespace

TEST_CASE("tokens: random, 64 hex digits, compared in full", "[ocs][access]") {
  const std::string a = mppi::ocs::make_token(), b = mppi::ocs::make_token();
  CHECK(a.size() == 64);
  CHECK(a.find_first_not_of("0123456789abcdef") == std::string::npos);
  CHECK(a != b);
  CHECK(mppi::ocs::same_secret(a, a));
  CHECK_FALSE(mppi::ocs::same_secret(a, b));
  std::string last = a;
  last.back() = last.back() == '0' ? '1' : '0';
  CHECK_FALSE(mppi::ocs::same_secret(a, last));
  CHECK_FALSE(mppi::ocs::same_secret(a, a.substr(0, 63)));
  CHECK_FALSE(mppi::ocs::same_secret(a, ""));
}

TEST_CASE("a state-changing request needs the right token and reading needs none", "[ocs][access]") {
  const AccessRules r = rules();
  const std::string host = "127.0.0.1:8080";
  CHECK(refusal(r, host, kNone, kToken, true).empty());                        // right
  CHECK(refusal(r, host, kNone, kNone, true).find("no X-MPPI-Token") == 0);      // missing
  CHECK(refusal(r, host, kNone, std::string(64, 'b'), true).find("wrong X-MPPI-Token") == 0);
  CHECK(refusal(r, host, kNone, std::string(), true).find("wrong") == 0);       // empty
  CHECK(refusal(r, host, kNone, kToken + "a", true).find("wrong") == 0);        // longer
  CHECK(refusal(r, host, kNone, kNone, false).empty());                          // a GET
  AccessRules other = r;
  other.token = std::string(64, 'c');
  CHECK_FALSE(refusal(other, host, kNone, kToken, true).empty());
}

TEST_CASE("only the page's own Host and Origin are let in", "[ocs][access]") {
  const AccessRules r = rules();
  for (const char* host : {"127.0.0.1:8080", "localhost:8080", "LOCALHOST:8080", "[::1]:8080"}) {
    INFO(host);
    CHECK(refusal(r, host, kNone, kToken, true).empty());
    CHECK(refusal(r, host, std::string("http://") + host, kToken, true).empty());
  }
  // DNS rebinding: the browser names the attacker's host; another port is another origin.
  CHECK(refusal(r, "evil.example:8080", kNone, kNone, false).find("Host 'evil.example:8080' is not this page's") == 0);
  CHECK_FALSE(refusal(r, "127.0.0.1:8081", kNone, kToken, true).empty());
  CHECK_FALSE(refusal(r, "127.0.0.1", kNone, kToken, true).empty());
  CHECK_FALSE(refusal(r, "", kNone, kToken, true).empty());
  // Another site's page, even with the token: refused by its Origin.
  for (const char* origin : {"http://evil.example", "http://127.0.0.1:8081", "https://127.0.0.1:8080", "null",
                             "http://127.0.0.1:8080.evil.example", "file://"}) {
    INFO(origin);
    CHECK(refusal(r, "127.0.0.1:8080", std::string(origin), kToken, true).find("Origin") == 0);
    CHECK(refusal(r, "127.0.0.1:8080", std::string(origin), kNone, false).find("Origin") == 0);
  }
  // Over TLS the page's origin is https://; more names with --serve-host; off loopback the address.
  AccessRules tls = r;
  tls.tls = true;
  CHECK(refusal(tls, "127.0.0.1:8080", std::string("https://127.0.0.1:8080"), kToken, true).empty());
  CHECK_FALSE(refusal(tls, "127.0.0.1:8080", std::string("http://127.0.0.1:8080"), kToken, true).empty());
  const auto hosts = mppi::ocs::page_hosts("192.0.2.7", 443, true, {"car.lan", "car:9000"});
  CHECK(hosts == std::vector<std::string>{"192.0.2.7:443", "192.0.2.7", "car.lan:443", "car.lan", "car:9000"});
  CHECK(mppi::ocs::is_loopback_bind("127.0.0.1"));
  CHECK(mppi::ocs::is_loopback_bind("::1"));
  CHECK_FALSE(mppi::ocs::is_loopback_bind("0.0.0.0"));
  CHECK_FALSE(mppi::ocs::is_loopback_bind("192.0.2.7"));
}

TEST_CASE("the server refuses other sites and requests without the token with 403, and counts them",
          "[ocs][access]") {
  mppi::ocs::LiveObserver live;
  mppi::ocs::ServerSettings s;
  s.port = 0;
  mppi::ocs::OcsServer server(s, &live, "", "");
  server.start();
  const std::string url = server.page_url();
  const std::string prefix = "http://127.0.0.1:" + std::to_string(server.port()) + "/?token=";
  REQUIRE(url.rfind(prefix, 0) == 0);
  const std::string token = url.substr(prefix.size());
  CHECK(token.size() == 64);
  const std::string own = "http://127.0.0.1:" + std::to_string(server.port());
  httplib::Client client("127.0.0.1", server.port());
  auto post = [&](const httplib::Headers& headers) {
    return client.Post("/api/control", headers, "runstop=1&target_speed=3", "application/x-www-form-urlencoded");
  };
  // Reading stays open; the page cannot be framed and leaks no Referer.
  CHECK(client.Get("/api/info")->status == 200);
  auto index = client.Get("/");
  CHECK(index->status == 200);
  CHECK(index->get_header_value("Referrer-Policy") == "no-referrer");
  CHECK(index->get_header_value("X-Frame-Options") == "DENY");
  // Refused, and nothing changed.
  auto missing = post({});
  CHECK(missing->status == 403);
  CHECK(nlohmann::json::parse(missing->body)["error"].get<std::string>().find("no X-MPPI-Token") == 0);
  CHECK(post({{"X-MPPI-Token", std::string(64, '0')}})->status == 403);
  CHECK(post({{"Origin", "http://evil.example"}})->status == 403);
  auto evil = post({{"Origin", "http://evil.example"}, {"X-MPPI-Token", token}});
  CHECK(evil->status == 403);
  CHECK(nlohmann::json::parse(evil->body)["error"].get<std::string>().find("Origin 'http://evil.example'") == 0);
  CHECK(client.Get("/api/info", {{"Host", "evil.example:" + std::to_string(server.port())}})->status == 403);
  auto info = nlohmann::json::parse(client.Get("/api/info")->body);
  CHECK(info["motion_enabled"] == true);
  CHECK(info["target_speed_mps"].is_null());
  CHECK(info["refused_requests"] == 5);
  CHECK(server.refused_requests() == 5);
  const auto none = live.poll_requests(0.0);
  CHECK_FALSE(none.motion_enabled.has_value());
  CHECK_FALSE(none.target_speed_mps.has_value());
  // The page itself: its origin and its token.
  auto ok = post({{"Origin", own}, {"X-MPPI-Token", token}});
  CHECK(ok->status == 200);
  info = nlohmann::json::parse(client.Get("/api/info")->body);
  CHECK(info["motion_enabled"] == false);
  CHECK(info["target_speed_mps"] == 3.0);
  const auto r = live.poll_requests(0.0);
  CHECK(r.motion_enabled == false);
  CHECK(r.target_speed_mps == 3.0);
  server.stop();
}

TEST_CASE("no plain HTTP off loopback unless asked for, and TLS needs a usable certificate", "[ocs][access]") {
  mppi::ocs::ServerSettings s;
  s.port = 0;
  s.bind_address = "0.0.0.0";
  const std::string why = mppi::test::error_of([&] { mppi::ocs::OcsServer server(s, nullptr, "", "{}"); });
  CHECK(why.find("refusing to serve the operator page on 0.0.0.0 (off loopback) over plain HTTP") !=
        std::string::npos);
  CHECK(why.find("--serve-insecure-remote") != std::string::npos);
  s.access.tls_cert_file = "/nonexistent/cert.pem";
  CHECK(mppi::test::error_of([&] { mppi::ocs::OcsServer server(s, nullptr, "", "{}"); })
            .find("TLS needs both a certificate and a key file") != std::string::npos);
  s.access.tls_key_file = "/nonexistent/key.pem";
  CHECK(mppi::test::error_of([&] { mppi::ocs::OcsServer server(s, nullptr, "", "{}"); })
            .find("cannot use the TLS certificate /nonexistent/cert.pem") != std::string::npos);
  s.access = {};
  s.access.insecure_remote = true;
  mppi::ocs::OcsServer remote(s, nullptr, "", "{}");  // asked for: it starts
  remote.start();
  CHECK(remote.port() > 0);
  remote.stop();
}
