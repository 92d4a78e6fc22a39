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
#include <iterator>
#include <string>

namespace {

// The "library_path" value of a Vulkan driver manifest (JSON), or "" when there is none.
std::string manifest_library_path(const std::filesystem::path& manifest) {
  std::ifstream in(manifest);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string key = "\"library_path\"";
  std::size_t at = text.find(key);
  if (at == std::string::npos) return "";
  at = text.find('"', text.find(':', at + key.size()));
  const std::size_t end = at == std::string::npos ? at : text.find('"', at + 1);
  if (end == std::string::npos) return "";
  return text.substr(at + 1, end - at - 1);
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
