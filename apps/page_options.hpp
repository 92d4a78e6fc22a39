#pragma once
// The operator page's --serve-* options, shared by mppi-sim and mppi-udp-drive: where the page
// listens and what it takes to listen off loopback (docs/SECURITY.md).
#include <string>

#include <CLI/CLI.hpp>

#include "ocs/page_access.hpp"

namespace mppi::apps {

inline void add_page_options(CLI::App& app, std::string& bind_address, ocs::PageAccess& access) {
  app.add_option("--serve-bind", bind_address,
                 "with --serve: address the page listens on (default 127.0.0.1; off loopback it needs "
                 "--serve-cert/--serve-key or --serve-insecure-remote)")
      ->type_name("ADDR");
  app.add_option("--serve-cert", access.tls_cert_file, "with --serve: serve HTTPS with this PEM certificate")
      ->type_name("FILE");
  app.add_option("--serve-key", access.tls_key_file, "with --serve-cert: the certificate's PEM private key")
      ->type_name("FILE");
  app.add_flag("--serve-insecure-remote", access.insecure_remote,
               "with --serve-bind off loopback: plain HTTP; anyone on the network path can read the token "
               "and drive the car");
  app.add_option("--serve-host", access.extra_hosts,
                 "with --serve: another name the page is reached by (NAME or NAME:PORT, repeatable)")
      ->type_name("NAME");
}

}  // namespace mppi::apps
