// Loading the Vulkan loader at run time, listing the devices and picking one.
#include <dlfcn.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <mutex>
#include <string>
#include <vector>

#include "vulkan/vulkan_api.hpp"
#include "vulkan/vulkan_backend.hpp"

namespace mppi::vulkan {
namespace detail {

const char* result_name(VkResult r) {
  switch (r) {
    case VK_SUCCESS: return "VK_SUCCESS";
    case VK_ERROR_OUT_OF_HOST_MEMORY: return "VK_ERROR_OUT_OF_HOST_MEMORY";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY: return "VK_ERROR_OUT_OF_DEVICE_MEMORY";
    case VK_ERROR_INITIALIZATION_FAILED: return "VK_ERROR_INITIALIZATION_FAILED";
    case VK_ERROR_DEVICE_LOST: return "VK_ERROR_DEVICE_LOST";
    case VK_ERROR_INCOMPATIBLE_DRIVER: return "VK_ERROR_INCOMPATIBLE_DRIVER (no Vulkan driver/ICD)";
    case VK_ERROR_LAYER_NOT_PRESENT: return "VK_ERROR_LAYER_NOT_PRESENT";
    case VK_ERROR_EXTENSION_NOT_PRESENT: return "VK_ERROR_EXTENSION_NOT_PRESENT";
    case VK_ERROR_FEATURE_NOT_PRESENT: return "VK_ERROR_FEATURE_NOT_PRESENT";
    case VK_TIMEOUT: return "VK_TIMEOUT";
    default: return "VkResult error";
  }
}

const Api* global_api(std::string* why) {
  static Api api;
  static std::string error;
  static std::once_flag once;
  std::call_once(once, [] {
    void* lib = dlopen("libvulkan.so.1", RTLD_NOW | RTLD_LOCAL);
    if (!lib) lib = dlopen("libvulkan.so", RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
      error = "no Vulkan loader (libvulkan.so.1 not found; Debian: apt install libvulkan1 mesa-vulkan-drivers)";
      return;
    }
    api.vkGetInstanceProcAddr =
        reinterpret_cast<PFN_vkGetInstanceProcAddr>(dlsym(lib, "vkGetInstanceProcAddr"));
    if (!api.vkGetInstanceProcAddr) {
      error = "the Vulkan loader has no vkGetInstanceProcAddr";
      return;
    }
    api.vkCreateInstance = reinterpret_cast<PFN_vkCreateInstance>(
        api.vkGetInstanceProcAddr(nullptr, "vkCreateInstance"));
    if (!api.vkCreateInstance) error = "the Vulkan loader has no vkCreateInstance";
  });
  if (!error.empty()) {
    if (why) *why = error;
    return nullptr;
  }
  return &api;
}

#define MPPI_VK_LOAD_INSTANCE(name)                                                      \
  api.name = reinterpret_cast<PFN_##name>(api.vkGetInstanceProcAddr(instance, #name));   \
  if (!api.name) {                                                                       \
    if (why) *why = "Vulkan: missing " #name;                                            \
    return false;                                                                        \
  }
#define MPPI_VK_LOAD_DEVICE(name)                                                        \
  api.name = reinterpret_cast<PFN_##name>(api.vkGetDeviceProcAddr(device, #name));       \
  if (!api.name) {                                                                       \
    if (why) *why = "Vulkan: missing " #name;                                            \
    return false;                                                                        \
  }

bool load_instance_functions(Api& api, VkInstance instance, std::string* why) {
  MPPI_VK_INSTANCE_FUNCTIONS(MPPI_VK_LOAD_INSTANCE)
  return true;
}
bool load_device_functions(Api& api, VkDevice device, std::string* why) {
  MPPI_VK_DEVICE_FUNCTIONS(MPPI_VK_LOAD_DEVICE)
  return true;
}

}  // namespace detail

namespace {
const char* type_name(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete-gpu";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated-gpu";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual-gpu";
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return "cpu";
    default: return "other";
  }
}
int type_rank(const DeviceInfo& d) {  // lower is preferred
  if (d.type == "discrete-gpu") return 0;
  if (d.type == "integrated-gpu") return 1;
  if (d.type == "virtual-gpu") return 2;
  if (d.type == "other") return 3;
  return 4;  // cpu
}
std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}
}  // namespace

Probe probe() {
  Probe result;
  std::string why;
  const detail::Api* global = detail::global_api(&why);
  if (!global) {
    result.error = why;
    return result;
  }
  detail::Api api = *global;
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "mppi";
  app.apiVersion = VK_API_VERSION_1_1;
  VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  info.pApplicationInfo = &app;
  VkInstance instance = VK_NULL_HANDLE;
  const VkResult r = api.vkCreateInstance(&info, nullptr, &instance);
  if (r != VK_SUCCESS) {
    result.error = std::string("vkCreateInstance failed: ") + detail::result_name(r);
    return result;
  }
  if (!detail::load_instance_functions(api, instance, &why)) {
    result.error = why;
    return result;
  }
  std::uint32_t count = 0;
  api.vkEnumeratePhysicalDevices(instance, &count, nullptr);
  std::vector<VkPhysicalDevice> devices(count);
  if (count) api.vkEnumeratePhysicalDevices(instance, &count, devices.data());
  for (std::uint32_t i = 0; i < count; ++i) {
    VkPhysicalDeviceProperties p;
    api.vkGetPhysicalDeviceProperties(devices[i], &p);
    DeviceInfo d;
    d.index = static_cast<int>(i);
    d.name = p.deviceName;
    d.type = type_name(p.deviceType);
    d.is_cpu = p.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU;
    d.api_version = p.apiVersion;
    result.devices.push_back(d);
  }
  api.vkDestroyInstance(instance, nullptr);
  result.available = !result.devices.empty();
  if (!result.available) result.error = "the Vulkan loader found no device";
  return result;
}

int pick_device(const Probe& probe, bool allow_cpu, std::string* why) {
  auto fail = [&](const std::string& msg) {
    if (why) *why = msg;
    return -1;
  };
  if (!probe.available) return fail(probe.error.empty() ? "no Vulkan device" : probe.error);
  if (const char* env = std::getenv("MPPI_VULKAN_DEVICE"); env && *env) {
    const std::string want = env;
    char* end = nullptr;
    const long index = std::strtol(env, &end, 10);
    if (end && *end == '\0') {
      if (index < 0 || index >= static_cast<long>(probe.devices.size()))
        return fail("MPPI_VULKAN_DEVICE=" + want + ": no such device (found " +
                    std::to_string(probe.devices.size()) + ")");
      return static_cast<int>(index);
    }
    for (const DeviceInfo& d : probe.devices)
      if (lower(d.name).find(lower(want)) != std::string::npos) return d.index;
    return fail("MPPI_VULKAN_DEVICE=" + want + " matches no device name");
  }
  int best = -1;
  for (const DeviceInfo& d : probe.devices) {
    if (d.api_version < VK_API_VERSION_1_1) continue;
    if (d.is_cpu && !allow_cpu) continue;
    if (best < 0 || type_rank(d) < type_rank(probe.devices[best])) best = d.index;
  }
  if (best >= 0) return best;
  std::string found;
  for (const DeviceInfo& d : probe.devices)
    found += (found.empty() ? "" : ", ") + d.name + " (" + d.type + ")";
  return fail(allow_cpu ? "no Vulkan 1.1 device (found: " + found + ")"
                        : "no GPU Vulkan device (found only: " + found +
                              "; a CPU Vulkan device is used only with --backend vulkan)");
}

}  // namespace mppi::vulkan
