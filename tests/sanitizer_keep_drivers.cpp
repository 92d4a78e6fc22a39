// Under AddressSanitizer only: keeps the Vulkan drivers loaded until the process ends.
//
// The Vulkan loader unloads a driver (dlclose) when its instance is destroyed. LeakSanitizer
// checks at exit, when the driver's one-time allocations can no longer be traced to a module:
// it reports them under "<unknown module>", which no suppression can name. Opened once more here
// with RTLD_NODELETE, each installed driver stays mapped, its allocations keep their module name,
// and tests/lsan.supp can name the third-party modules whose allocations live until exit.
#if defined(__SANITIZE_ADDRESS__)
#define MPPI_TESTS_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define MPPI_TESTS_UNDER_ASAN 1
#endif
#endif

#ifdef MPPI_TESTS_UNDER_ASAN
#include <dlfcn.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

namespace {

// ICD.library_path of a Vulkan driver manifest, or "" when the file has none.
std::string manifest_library_path(const std::filesystem::path& manifest) {
  std::ifstream in(manifest);
  const auto json = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (!json.is_object() || !json.contains("ICD") || !json["ICD"].is_object()) return "";
  const auto& icd = json["ICD"];
  return icd.contains("library_path") && icd["library_path"].is_string() ? icd["library_path"].get<std::string>()
                                                                         : std::string();
}

struct KeepVulkanDriversLoaded {
  KeepVulkanDriversLoaded() {
    for (const char* dir : {"/usr/share/vulkan/icd.d", "/etc/vulkan/icd.d"}) {
      std::error_code ec;
      for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
        if (entry.path().extension() != ".json") continue;
        const std::string library = manifest_library_path(entry.path());
        if (!library.empty()) dlopen(library.c_str(), RTLD_NOW | RTLD_NODELETE);
      }
    }
  }
} keep_vulkan_drivers_loaded;

}  // namespace
#endif
