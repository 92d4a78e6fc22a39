#pragma once
// The Vulkan entry points the backend uses, loaded at run time from the loader
// (libvulkan.so.1) with dlopen: a machine without a Vulkan loader still runs the library (the
// CPU backend) and gets a clear message instead of a failure to start. Internal to mppi_vulkan.
#define VK_NO_PROTOTYPES
#include <vulkan/vulkan.h>

#include <string>

namespace mppi::vulkan::detail {

#define MPPI_VK_INSTANCE_FUNCTIONS(X)         \
  X(vkDestroyInstance)                        \
  X(vkEnumeratePhysicalDevices)               \
  X(vkGetPhysicalDeviceProperties)            \
  X(vkGetPhysicalDeviceQueueFamilyProperties) \
  X(vkGetPhysicalDeviceMemoryProperties)      \
  X(vkCreateDevice)                           \
  X(vkGetDeviceProcAddr)

#define MPPI_VK_DEVICE_FUNCTIONS(X)   \
  X(vkDestroyDevice)                  \
  X(vkGetDeviceQueue)                 \
  X(vkCreateBuffer)                   \
  X(vkDestroyBuffer)                  \
  X(vkGetBufferMemoryRequirements)    \
  X(vkAllocateMemory)                 \
  X(vkFreeMemory)                     \
  X(vkBindBufferMemory)               \
  X(vkMapMemory)                      \
  X(vkUnmapMemory)                    \
  X(vkCreateShaderModule)             \
  X(vkDestroyShaderModule)            \
  X(vkCreateDescriptorSetLayout)      \
  X(vkDestroyDescriptorSetLayout)     \
  X(vkCreatePipelineLayout)           \
  X(vkDestroyPipelineLayout)          \
  X(vkCreateComputePipelines)         \
  X(vkDestroyPipeline)                \
  X(vkCreateDescriptorPool)           \
  X(vkDestroyDescriptorPool)          \
  X(vkAllocateDescriptorSets)         \
  X(vkUpdateDescriptorSets)           \
  X(vkCreateCommandPool)              \
  X(vkDestroyCommandPool)             \
  X(vkAllocateCommandBuffers)         \
  X(vkBeginCommandBuffer)             \
  X(vkEndCommandBuffer)               \
  X(vkCmdBindPipeline)                \
  X(vkCmdBindDescriptorSets)          \
  X(vkCmdDispatch)                    \
  X(vkCmdPipelineBarrier)             \
  X(vkCreateFence)                    \
  X(vkDestroyFence)                   \
  X(vkResetFences)                    \
  X(vkWaitForFences)                  \
  X(vkQueueSubmit)                    \
  X(vkDeviceWaitIdle)

#define MPPI_VK_DECLARE(name) PFN_##name name = nullptr;

struct Api {
  PFN_vkGetInstanceProcAddr vkGetInstanceProcAddr = nullptr;
  PFN_vkCreateInstance vkCreateInstance = nullptr;
  MPPI_VK_INSTANCE_FUNCTIONS(MPPI_VK_DECLARE)
  MPPI_VK_DEVICE_FUNCTIONS(MPPI_VK_DECLARE)
};

// The process-wide table: loader opened and global functions resolved once. Returns nullptr
// (and why) when there is no loader.
const Api* global_api(std::string* why);
// Resolve the instance-level and device-level functions into `api` (a copy per context).
bool load_instance_functions(Api& api, VkInstance instance, std::string* why);
bool load_device_functions(Api& api, VkDevice device, std::string* why);

const char* result_name(VkResult r);

}  // namespace mppi::vulkan::detail
