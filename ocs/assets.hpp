#pragma once
// The page's files, compiled into the library at build time (ocs/web and the npm packages of
// ocs/web/package-lock.json; see ocs/CMakeLists.txt): nothing is fetched at run time.
#include <span>
#include <string_view>

namespace mppi::ocs {

struct Asset {
  std::string_view path;          // URL path, e.g. "/app.js"
  std::string_view content_type;
  std::string_view body;
};

std::span<const Asset> assets();

}  // namespace mppi::ocs
