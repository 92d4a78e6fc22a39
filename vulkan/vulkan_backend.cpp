// The Vulkan backend: device set-up, buffers, pipelines and the two recorded command buffers.
#include "vulkan/vulkan_backend.hpp"

#include <stdint.h>

#include <algorithm>
#include <cstddef>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "base/error.hpp"
#include "mppi/cpu_backend.hpp"
#include "vulkan/vulkan_api.hpp"

// SPIR-V made at build time by glslangValidator (vulkan/CMakeLists.txt), checked by spirv-val.
#include "costs/autorally_cost_gpu.hpp"
#include "reduce.spv.h"
#include "rollout_kernels.hpp"
#include "weighted_sum.spv.h"

namespace mppi::vulkan {

namespace {
constexpr int kRolloutGroup = 64;      // invocations per workgroup of the rollout shader
constexpr int kParamFloats = 4096;     // the parameter uniform buffer: vec4 params[1024]
constexpr int kCostFloats = kGpuCostFloats;  // its first floats are the cost (layout_cost.glsl)
constexpr int kNu = 2;                 // every GPU twin has (steer, throttle)
constexpr int kMaxStates = 16;

// std140 mirror of StepBlock in shaders/interface.glsl.
struct StepUbo {
  std::uint32_t sizes[4];  // K, T, padded, iteration
  std::uint32_t seed[4];   // seed low, seed high
  float scalars[4];        // dt, gamma, 1 / lambda
  float noise_std[4];
  float control_min[4];
  float control_max[4];
  float x0[kMaxStates];
  float noise_filter[4];   // carry, first gain, gain, white (1) or not (0)
  float actuator_delay[4];       // delay steps per channel; [3] = 1 when the chain is on
  float actuator_alpha[4];       // lag factor per channel
  float actuator_max_change[4];  // rate limit per control step (FLT_MAX: none)
  float actuator_start[4];       // rate outputs (0, 1), lag outputs (2, 3) at t = 0
  float actuator_pending[kNu * kMaxActuatorDelaySteps];  // channel c, step t at c * 32 + t
};
// The std140 offsets of StepBlock: uvec4/vec4 members at 16-byte steps, x0 as vec4[4].
static_assert(offsetof(StepUbo, seed) == 16 && offsetof(StepUbo, scalars) == 32 &&
              offsetof(StepUbo, noise_std) == 48 && offsetof(StepUbo, control_min) == 64 &&
              offsetof(StepUbo, control_max) == 80 && offsetof(StepUbo, x0) == 96 &&
              offsetof(StepUbo, noise_filter) == 96 + 4 * kMaxStates &&
              offsetof(StepUbo, actuator_delay) == 112 + 4 * kMaxStates &&
              offsetof(StepUbo, actuator_pending) == 176 + 4 * kMaxStates &&
              sizeof(StepUbo) == 176 + 4 * kMaxStates + 4 * kNu * kMaxActuatorDelaySteps,
              "StepUbo must mirror StepBlock (std140)");
static_assert(kNu * kMaxActuatorDelaySteps == 64, "StepBlock holds vec4 actuator_pending[16]");

// The actuator chain of one iteration into the step block (off when the plan has none).
void write_actuators(const ActuatorPlan& plan, StepUbo& s) {
  s.actuator_delay[3] = plan.enabled() ? 1.f : 0.f;
  if (!plan.enabled()) return;
  for (int c = 0; c < kNu; ++c) {
    const ActuatorStep& a = plan.steps[c];
    s.actuator_delay[c] = static_cast<float>(a.delay_steps);
    s.actuator_alpha[c] = a.lag_alpha;
    s.actuator_max_change[c] = std::min(a.max_change, std::numeric_limits<float>::max());
    s.actuator_start[c] = plan.start->rate_out[c];
    s.actuator_start[2 + c] = plan.start->lag_out[c];
    std::copy_n(plan.start->pending[c], kMaxActuatorDelaySteps, s.actuator_pending + c * kMaxActuatorDelaySteps);
  }
}

void check(VkResult r, const char* what) {
  if (r != VK_SUCCESS)
    throw Error(std::string("Vulkan backend: ") + what + " failed: " + detail::result_name(r));
}

// The cost's floats at the start of the parameter block, in the order of the table the GLSL
// offsets are generated from (costs/autorally_cost_gpu.hpp).
void pack_cost(const AutoRallyCost& cost, float* p) {
  for (const GpuCostField& field : gpu_cost_fields()) *p++ = field.value(cost);
}

const RolloutKernel* find_kernel(const std::string& id) {
  for (const RolloutKernel& k : kRolloutKernels)
    if (id == k.id) return &k;
  return nullptr;
}
}  // namespace

// ---- the backend ------------------------------------------------------------------------------

struct VulkanBackend::Impl {
  struct Buffer {
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    void* mapped = nullptr;
    VkDeviceSize bytes = 0;
    float* f() const { return static_cast<float*>(mapped); }
  };
  enum Binding { kStep, kNominal, kControls, kCosts, kMap, kParams, kCrash, kWeights, kStats, kNext, kBindings };

  detail::Api api;
  VkInstance instance = VK_NULL_HANDLE;
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  VkQueue queue = VK_NULL_HANDLE;
  VkPhysicalDeviceMemoryProperties memory_props{};
  Buffer buffers[kBindings];
  VkDescriptorSetLayout set_layout = VK_NULL_HANDLE;
  VkPipelineLayout pipeline_layout = VK_NULL_HANDLE;
  VkPipeline rollout_generate = VK_NULL_HANDLE, rollout_given = VK_NULL_HANDLE;
  VkPipeline reduce = VK_NULL_HANDLE, weighted_sum = VK_NULL_HANDLE;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  VkDescriptorSet set = VK_NULL_HANDLE;
  VkCommandPool command_pool = VK_NULL_HANDLE;
  VkCommandBuffer cmd_iterate = VK_NULL_HANDLE, cmd_rollout = VK_NULL_HANDLE;
  VkFence fence = VK_NULL_HANDLE;
  RolloutShape shape;
  int num_states = 0;
  std::optional<AutoRallyCost> cost;  // the cost the parameter block holds (changes at run time)
  float dt_s = 0.f;

  ~Impl() { destroy(); }

  void destroy() {
    if (!device) {
      if (instance) api.vkDestroyInstance(instance, nullptr);
      instance = VK_NULL_HANDLE;
      return;
    }
    api.vkDeviceWaitIdle(device);
    if (fence) api.vkDestroyFence(device, fence, nullptr);
    if (command_pool) api.vkDestroyCommandPool(device, command_pool, nullptr);
    if (pool) api.vkDestroyDescriptorPool(device, pool, nullptr);
    for (VkPipeline p : {rollout_generate, rollout_given, reduce, weighted_sum})
      if (p) api.vkDestroyPipeline(device, p, nullptr);
    if (pipeline_layout) api.vkDestroyPipelineLayout(device, pipeline_layout, nullptr);
    if (set_layout) api.vkDestroyDescriptorSetLayout(device, set_layout, nullptr);
    for (Buffer& b : buffers) {
      if (b.buffer) api.vkDestroyBuffer(device, b.buffer, nullptr);
      if (b.memory) api.vkFreeMemory(device, b.memory, nullptr);  // unmaps too
    }
    api.vkDestroyDevice(device, nullptr);
    api.vkDestroyInstance(instance, nullptr);
    device = VK_NULL_HANDLE;
    instance = VK_NULL_HANDLE;
  }

  void create_device(int device_index, std::string* name, bool* is_cpu) {
    std::string why;
    const detail::Api* global = detail::global_api(&why);
    if (!global) throw Error("Vulkan backend: " + why);
    api = *global;
    VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.pApplicationName = "mppi";
    app.apiVersion = VK_API_VERSION_1_1;
    VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    info.pApplicationInfo = &app;
    check(api.vkCreateInstance(&info, nullptr, &instance), "vkCreateInstance");
    if (!detail::load_instance_functions(api, instance, &why)) throw Error("Vulkan backend: " + why);
    std::uint32_t count = 0;
    api.vkEnumeratePhysicalDevices(instance, &count, nullptr);
    std::vector<VkPhysicalDevice> devices(count);
    if (count) api.vkEnumeratePhysicalDevices(instance, &count, devices.data());
    if (device_index < 0 || device_index >= static_cast<int>(count))
      throw Error("Vulkan backend: no device " + std::to_string(device_index));
    physical = devices[device_index];
    VkPhysicalDeviceProperties props;
    api.vkGetPhysicalDeviceProperties(physical, &props);
    *name = props.deviceName;
    *is_cpu = props.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU;
    if (props.limits.maxUniformBufferRange < kParamFloats * sizeof(float))
      throw Error("Vulkan backend: the device's uniform buffers are smaller than 16 KiB");
    api.vkGetPhysicalDeviceMemoryProperties(physical, &memory_props);

    std::uint32_t families = 0;
    api.vkGetPhysicalDeviceQueueFamilyProperties(physical, &families, nullptr);
    std::vector<VkQueueFamilyProperties> family_props(families);
    api.vkGetPhysicalDeviceQueueFamilyProperties(physical, &families, family_props.data());
    std::uint32_t family = families;
    for (std::uint32_t i = 0; i < families && family == families; ++i)
      if (family_props[i].queueFlags & VK_QUEUE_COMPUTE_BIT) family = i;
    if (family == families) throw Error("Vulkan backend: device " + *name + " has no compute queue");
    const float priority = 1.f;
    VkDeviceQueueCreateInfo queue_info{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    queue_info.queueFamilyIndex = family;
    queue_info.queueCount = 1;
    queue_info.pQueuePriorities = &priority;
    VkDeviceCreateInfo device_info{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    device_info.queueCreateInfoCount = 1;
    device_info.pQueueCreateInfos = &queue_info;
    check(api.vkCreateDevice(physical, &device_info, nullptr, &device), "vkCreateDevice");
    if (!detail::load_device_functions(api, device, &why)) throw Error("Vulkan backend: " + why);
    api.vkGetDeviceQueue(device, family, 0, &queue);

    VkCommandPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pool_info.queueFamilyIndex = family;
    check(api.vkCreateCommandPool(device, &pool_info, nullptr, &command_pool), "vkCreateCommandPool");
    VkFenceCreateInfo fence_info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    check(api.vkCreateFence(device, &fence_info, nullptr, &fence), "vkCreateFence");
  }

  // Host-visible, coherent memory (device-local as well where the device offers it: then the
  // GPU reads and writes it at full speed and the host maps it directly).
  // host_reads: the host reads this buffer after every iteration (costs, weights, the plan): it
  // goes to host-cached memory where the device has it. A host read of device-local memory
  // through the PCIe BAR is uncached, one bus round trip per read: on an H200 reading the K
  // costs and weights back that way took ~0.5 ms at K = 2048.
  void create_buffer(Buffer& b, VkDeviceSize bytes, VkBufferUsageFlags usage, bool host_reads = false) {
    b.bytes = std::max<VkDeviceSize>(bytes, 16);
    VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    info.size = b.bytes;
    info.usage = usage;
    info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    check(api.vkCreateBuffer(device, &info, nullptr, &b.buffer), "vkCreateBuffer");
    VkMemoryRequirements req;
    api.vkGetBufferMemoryRequirements(device, b.buffer, &req);
    const VkMemoryPropertyFlags need = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    std::uint32_t type = memory_props.memoryTypeCount;
    const VkMemoryPropertyFlags first =
        host_reads ? need | VK_MEMORY_PROPERTY_HOST_CACHED_BIT : need | VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
    for (VkMemoryPropertyFlags want : {first, need | VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, need}) {
      for (std::uint32_t i = 0; i < memory_props.memoryTypeCount && type == memory_props.memoryTypeCount; ++i)
        if ((req.memoryTypeBits & (1u << i)) &&
            (memory_props.memoryTypes[i].propertyFlags & want) == want)
          type = i;
      if (type != memory_props.memoryTypeCount) break;
    }
    if (type == memory_props.memoryTypeCount) throw Error("Vulkan backend: no host-visible coherent memory");
    VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    alloc.allocationSize = req.size;
    alloc.memoryTypeIndex = type;
    VkResult r = api.vkAllocateMemory(device, &alloc, nullptr, &b.memory);
    if (r != VK_SUCCESS && (memory_props.memoryTypes[type].propertyFlags & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT)) {
      // the device-local host-visible heap can be small (256 MiB BAR): fall back to system memory
      for (std::uint32_t i = 0; i < memory_props.memoryTypeCount; ++i)
        if ((req.memoryTypeBits & (1u << i)) && (memory_props.memoryTypes[i].propertyFlags & need) == need &&
            !(memory_props.memoryTypes[i].propertyFlags & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT)) {
          alloc.memoryTypeIndex = i;
          r = api.vkAllocateMemory(device, &alloc, nullptr, &b.memory);
          break;
        }
    }
    check(r, "vkAllocateMemory");
    check(api.vkBindBufferMemory(device, b.buffer, b.memory, 0), "vkBindBufferMemory");
    check(api.vkMapMemory(device, b.memory, 0, VK_WHOLE_SIZE, 0, &b.mapped), "vkMapMemory");
    std::memset(b.mapped, 0, b.bytes);
  }

  VkPipeline make_pipeline(const std::uint32_t* code, std::size_t bytes, const VkSpecializationInfo* spec) {
    VkShaderModuleCreateInfo module_info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    module_info.codeSize = bytes;
    module_info.pCode = code;
    VkShaderModule module = VK_NULL_HANDLE;
    check(api.vkCreateShaderModule(device, &module_info, nullptr, &module), "vkCreateShaderModule");
    VkComputePipelineCreateInfo info{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    info.stage.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
    info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    info.stage.module = module;
    info.stage.pName = "main";
    info.stage.pSpecializationInfo = spec;
    info.layout = pipeline_layout;
    VkPipeline pipeline = VK_NULL_HANDLE;
    const VkResult r = api.vkCreateComputePipelines(device, VK_NULL_HANDLE, 1, &info, nullptr, &pipeline);
    api.vkDestroyShaderModule(device, module, nullptr);
    check(r, "vkCreateComputePipelines");
    return pipeline;
  }

  // weights_in_shared: the model reads its parameters from workgroup memory (a GPU's constant
  // cache is too small for the network's ~6 KB: read from the uniform buffer, every multiply-add
  // waited for its weight); a CPU driver reads the uniform buffer faster.
  void create_pipelines(const TwinModel& model, bool weights_in_shared) {
    VkDescriptorSetLayoutBinding bindings[kBindings];
    for (int i = 0; i < kBindings; ++i) {
      bindings[i] = {};
      bindings[i].binding = static_cast<std::uint32_t>(i);
      bindings[i].descriptorType = (i == kStep || i == kParams) ? VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER
                                                                : VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
      bindings[i].descriptorCount = 1;
      bindings[i].stageFlags = VK_SHADER_STAGE_COMPUTE_BIT;
    }
    VkDescriptorSetLayoutCreateInfo layout_info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    layout_info.bindingCount = kBindings;
    layout_info.pBindings = bindings;
    check(api.vkCreateDescriptorSetLayout(device, &layout_info, nullptr, &set_layout), "vkCreateDescriptorSetLayout");
    VkPipelineLayoutCreateInfo pl_info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    pl_info.setLayoutCount = 1;
    pl_info.pSetLayouts = &set_layout;
    check(api.vkCreatePipelineLayout(device, &pl_info, nullptr, &pipeline_layout), "vkCreatePipelineLayout");

    const RolloutKernel* kernel = find_kernel(model.kernel);
    if (!kernel) throw Error("Vulkan backend: no rollout shader for the model kernel '" + model.kernel + "'");
    const std::uint32_t* code = kernel->code;
    const std::size_t bytes = kernel->bytes;
    struct Spec {
      std::uint32_t group;
      VkBool32 generate;
      std::int32_t constant_a, constant_b;
      VkBool32 weights_in_shared;
    };
    const VkSpecializationMapEntry entries[] = {{0, offsetof(Spec, group), 4},
                                                {1, offsetof(Spec, generate), 4},
                                                {2, offsetof(Spec, constant_a), 4},
                                                {3, offsetof(Spec, constant_b), 4},
                                                {4, offsetof(Spec, weights_in_shared), 4}};
    Spec values{kRolloutGroup, VK_TRUE, std::max(model.constant_a, 1), std::max(model.constant_b, 1),
                weights_in_shared ? VK_TRUE : VK_FALSE};
    VkSpecializationInfo spec{5, entries, sizeof(Spec), &values};
    rollout_generate = make_pipeline(code, bytes, &spec);
    values.generate = VK_FALSE;
    rollout_given = make_pipeline(code, bytes, &spec);
    reduce = make_pipeline(reduce_spv, sizeof reduce_spv, nullptr);
    weighted_sum = make_pipeline(weighted_sum_spv, sizeof weighted_sum_spv, nullptr);

    VkDescriptorPoolSize sizes[] = {{VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 2},
                                    {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, kBindings - 2}};
    VkDescriptorPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    pool_info.maxSets = 1;
    pool_info.poolSizeCount = 2;
    pool_info.pPoolSizes = sizes;
    check(api.vkCreateDescriptorPool(device, &pool_info, nullptr, &pool), "vkCreateDescriptorPool");
    VkDescriptorSetAllocateInfo set_info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    set_info.descriptorPool = pool;
    set_info.descriptorSetCount = 1;
    set_info.pSetLayouts = &set_layout;
    check(api.vkAllocateDescriptorSets(device, &set_info, &set), "vkAllocateDescriptorSets");
    VkDescriptorBufferInfo infos[kBindings];
    VkWriteDescriptorSet writes[kBindings];
    for (int i = 0; i < kBindings; ++i) {
      infos[i] = {buffers[i].buffer, 0, VK_WHOLE_SIZE};
      writes[i] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
      writes[i].dstSet = set;
      writes[i].dstBinding = static_cast<std::uint32_t>(i);
      writes[i].descriptorCount = 1;
      writes[i].descriptorType = bindings[i].descriptorType;
      writes[i].pBufferInfo = &infos[i];
    }
    api.vkUpdateDescriptorSets(device, kBindings, writes, 0, nullptr);
  }

  void barrier(VkCommandBuffer cmd, VkPipelineStageFlags dst_stage, VkAccessFlags dst_access) {
    VkMemoryBarrier b{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    b.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
    b.dstAccessMask = dst_access;
    api.vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, dst_stage, 0, 1, &b, 0, nullptr, 0, nullptr);
  }

  void record() {
    VkCommandBufferAllocateInfo info{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    info.commandPool = command_pool;
    info.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    info.commandBufferCount = 2;
    VkCommandBuffer cmds[2];
    check(api.vkAllocateCommandBuffers(device, &info, cmds), "vkAllocateCommandBuffers");
    cmd_iterate = cmds[0];
    cmd_rollout = cmds[1];
    const auto groups = static_cast<std::uint32_t>((shape.num_samples + kRolloutGroup - 1) / kRolloutGroup);
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    // iterate: sample + roll out, weights, weighted sum
    check(api.vkBeginCommandBuffer(cmd_iterate, &begin), "vkBeginCommandBuffer");
    api.vkCmdBindDescriptorSets(cmd_iterate, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_layout, 0, 1, &set, 0, nullptr);
    api.vkCmdBindPipeline(cmd_iterate, VK_PIPELINE_BIND_POINT_COMPUTE, rollout_generate);
    api.vkCmdDispatch(cmd_iterate, groups, 1, 1);
    barrier(cmd_iterate, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
    api.vkCmdBindPipeline(cmd_iterate, VK_PIPELINE_BIND_POINT_COMPUTE, reduce);
    api.vkCmdDispatch(cmd_iterate, 1, 1, 1);
    barrier(cmd_iterate, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
    api.vkCmdBindPipeline(cmd_iterate, VK_PIPELINE_BIND_POINT_COMPUTE, weighted_sum);
    api.vkCmdDispatch(cmd_iterate, static_cast<std::uint32_t>(shape.horizon * kNu), 1, 1);
    barrier(cmd_iterate, VK_PIPELINE_STAGE_HOST_BIT, VK_ACCESS_HOST_READ_BIT);
    check(api.vkEndCommandBuffer(cmd_iterate), "vkEndCommandBuffer");
    // rollout: the given controls only
    check(api.vkBeginCommandBuffer(cmd_rollout, &begin), "vkBeginCommandBuffer");
    api.vkCmdBindDescriptorSets(cmd_rollout, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_layout, 0, 1, &set, 0, nullptr);
    api.vkCmdBindPipeline(cmd_rollout, VK_PIPELINE_BIND_POINT_COMPUTE, rollout_given);
    api.vkCmdDispatch(cmd_rollout, groups, 1, 1);
    barrier(cmd_rollout, VK_PIPELINE_STAGE_HOST_BIT, VK_ACCESS_HOST_READ_BIT);
    check(api.vkEndCommandBuffer(cmd_rollout), "vkEndCommandBuffer");
  }

  void submit(VkCommandBuffer cmd) {
    VkSubmitInfo info{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    info.commandBufferCount = 1;
    info.pCommandBuffers = &cmd;
    check(api.vkQueueSubmit(queue, 1, &info, fence), "vkQueueSubmit");
    check(api.vkWaitForFences(device, 1, &fence, VK_TRUE, UINT64_MAX), "vkWaitForFences");
    check(api.vkResetFences(device, 1, &fence), "vkResetFences");
  }

  StepUbo& step_ubo() const { return *static_cast<StepUbo*>(buffers[kStep].mapped); }

  void write_step(std::span<const float> x0, std::uint32_t iteration) {
    StepUbo& s = step_ubo();
    s.sizes[0] = static_cast<std::uint32_t>(shape.num_samples);
    s.sizes[1] = static_cast<std::uint32_t>(shape.horizon);
    s.sizes[2] = static_cast<std::uint32_t>(shape.padded_samples);
    s.sizes[3] = iteration;
    s.scalars[0] = dt_s;
    std::copy_n(x0.begin(), std::min<std::size_t>(x0.size(), kMaxStates), s.x0);
  }
};

VulkanBackend::VulkanBackend(const TwinModel& model, const AutoRallyCost& cost, int num_samples,
                             int horizon, float dt_s, int device_index)
    : impl_(std::make_unique<Impl>()) {
  if (num_samples < 1 || horizon < 1) throw Error("VulkanBackend: need num_samples, horizon >= 1");
  if (model.num_states > kMaxStates) throw Error("VulkanBackend: model has too many states");
  Impl& m = *impl_;
  shape_ = {num_samples, padded_sample_count(num_samples), horizon, model.num_states, kNu};
  m.shape = shape_;
  m.num_states = model.num_states;
  m.dt_s = dt_s;
  m.create_device(device_index, &device_name_, &device_is_cpu_);

  const auto f = sizeof(float);
  const VkBufferUsageFlags storage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  const std::size_t plan = static_cast<std::size_t>(horizon) * kNu;
  const std::size_t padded = static_cast<std::size_t>(shape_.padded_samples);
  const CostMap& map = cost.map();
  m.create_buffer(m.buffers[Impl::kStep], sizeof(StepUbo), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT);
  m.create_buffer(m.buffers[Impl::kNominal], plan * f, storage);
  m.create_buffer(m.buffers[Impl::kControls], plan * padded * f, storage);
  m.create_buffer(m.buffers[Impl::kCosts], padded * f, storage, /*host_reads=*/true);
  m.create_buffer(m.buffers[Impl::kMap], map.values().size() * f, storage);
  m.create_buffer(m.buffers[Impl::kParams], kParamFloats * f, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT);
  m.create_buffer(m.buffers[Impl::kCrash], static_cast<std::size_t>(horizon) * f, storage);
  m.create_buffer(m.buffers[Impl::kWeights], padded * f, storage, /*host_reads=*/true);
  m.create_buffer(m.buffers[Impl::kStats], 8 * f, storage, /*host_reads=*/true);
  m.create_buffer(m.buffers[Impl::kNext], plan * f, storage, /*host_reads=*/true);

  // Constant data: cost + model parameters, the cost map, the crash cost per step (computed
  // here with the CPU's own std::pow so both sides use the same numbers).
  if (static_cast<int>(model.params.size()) + kCostFloats > kParamFloats)
    throw Error("Vulkan backend: the model's " + std::to_string(model.params.size()) +
                " parameter floats do not fit the 16 KiB uniform buffer");
  m.cost.emplace(cost);
  float* params = m.buffers[Impl::kParams].f();
  pack_cost(cost, params);
  std::copy(model.params.begin(), model.params.end(), params + kCostFloats);
  std::copy(map.values().begin(), map.values().end(), m.buffers[Impl::kMap].f());
  for (int t = 0; t < horizon; ++t) m.buffers[Impl::kCrash].f()[t] = cost.crash_cost_at(t);

  // MPPI_VULKAN_WEIGHTS_IN_SHARED=0/1 overrides the choice by device type (tests run the GPU's
  // path on lavapipe with it).
  const char* shared_env = std::getenv("MPPI_VULKAN_WEIGHTS_IN_SHARED");
  const bool weights_in_shared = shared_env && *shared_env ? std::string(shared_env) != "0" : !device_is_cpu_;
  m.create_pipelines(model, weights_in_shared);
  m.record();

  // Warm-up: run both command buffers once (lavapipe compiles a shader at its first dispatch).
  StepUbo& s = m.step_ubo();
  const std::vector<float> x0(static_cast<std::size_t>(model.num_states), 0.f);
  m.write_step(x0, 0);
  for (int c = 0; c < kNu; ++c) {
    s.noise_std[c] = 0.1f;
    s.control_min[c] = -1.f;
    s.control_max[c] = 1.f;
  }
  s.scalars[2] = 1.f;
  s.noise_filter[3] = 1.f;
  write_actuators(ActuatorPlan{}, s);
  m.submit(m.cmd_iterate);
  m.submit(m.cmd_rollout);
}

VulkanBackend::~VulkanBackend() = default;

void VulkanBackend::rollout(std::span<const float> x0, std::span<const float> controls,
                            std::span<float> costs) {
  Impl& m = *impl_;
  m.write_step(x0, 0);
  write_actuators(ActuatorPlan{}, m.step_ubo());  // rollout() steps the model on the controls given
  const std::size_t n = std::min<std::size_t>(controls.size(), m.buffers[Impl::kControls].bytes / sizeof(float));
  std::copy_n(controls.begin(), n, m.buffers[Impl::kControls].f());
  m.submit(m.cmd_rollout);
  std::copy_n(m.buffers[Impl::kCosts].f(), std::min<std::size_t>(costs.size(), shape_.num_samples), costs.begin());
}

void VulkanBackend::iterate(const IterationInput& in, IterationOutput& out) {
  Impl& m = *impl_;
  m.write_step(in.x0, in.iteration);
  StepUbo& s = m.step_ubo();
  s.seed[0] = static_cast<std::uint32_t>(in.seed);
  s.seed[1] = static_cast<std::uint32_t>(in.seed >> 32);
  s.scalars[1] = in.gamma;
  s.scalars[2] = 1.f / in.lambda;
  s.noise_filter[0] = in.noise_filter.carry;
  s.noise_filter[1] = in.noise_filter.first_gain;
  s.noise_filter[2] = in.noise_filter.gain;
  s.noise_filter[3] = in.noise_filter.white() ? 1.f : 0.f;
  write_actuators(in.actuators, s);
  for (int c = 0; c < kNu; ++c) {
    s.noise_std[c] = in.noise_std[c];
    s.control_min[c] = in.control_min[c];
    s.control_max[c] = in.control_max[c];
  }
  std::copy(in.nominal.begin(), in.nominal.end(), m.buffers[Impl::kNominal].f());
  m.submit(m.cmd_iterate);
  const float* stats = m.buffers[Impl::kStats].f();
  out.min_cost = stats[0];
  out.sum_sq_weights = stats[2];
  out.valid_samples = static_cast<int>(stats[3]);
  out.mean_cost = out.valid_samples > 0 ? stats[4] / stats[3] : 0.f;
  const auto k = static_cast<std::size_t>(shape_.num_samples);
  std::copy_n(m.buffers[Impl::kNext].f(), std::min(out.next.size(), static_cast<std::size_t>(shape_.horizon) * kNu), out.next.begin());
  std::copy_n(m.buffers[Impl::kCosts].f(), std::min(out.costs.size(), k), out.costs.begin());
  std::copy_n(m.buffers[Impl::kWeights].f(), std::min(out.weights.size(), k), out.weights.begin());
}

bool VulkanBackend::set_cost_param(std::string_view key, double value, std::string* why) {
  Impl& m = *impl_;
  if (!m.cost->set_param(key, value, why)) return false;
  // Between submits the device reads nothing: rewrite the cost's floats and the crash costs.
  pack_cost(*m.cost, m.buffers[Impl::kParams].f());
  for (int t = 0; t < shape_.horizon; ++t) m.buffers[Impl::kCrash].f()[t] = m.cost->crash_cost_at(t);
  return true;
}

bool VulkanBackend::set_cost_map(std::shared_ptr<const CostMap> map, std::string* why) {
  Impl& m = *impl_;
  if (map && map->values().size() * sizeof(float) != m.buffers[Impl::kMap].bytes) {
    if (why) *why = "vulkan backend: a new cost map must have the size of the old one (its buffer is fixed)";
    return false;
  }
  if (!m.cost->set_map(map, why)) return false;
  std::copy(map->values().begin(), map->values().end(), m.buffers[Impl::kMap].f());
  pack_cost(*m.cost, m.buffers[Impl::kParams].f());  // the map's bounds and resolution
  return true;
}

std::span<const float> VulkanBackend::sampled_controls() const {
  const Impl::Buffer& b = impl_->buffers[Impl::kControls];
  return {b.f(), static_cast<std::size_t>(shape_.horizon) * kNu * shape_.padded_samples};
}

}  // namespace mppi::vulkan
