#include "vk/context.hpp"

#include <algorithm>
#include <cstring>
#include <mutex>
#include <string>

#include <unistd.h>

#include "shapematch/errors.hpp"
#include "vk/check.hpp"
#include "vk/sequence.hpp"

namespace shapematch::vk {

namespace {

std::string type_name(VkPhysicalDeviceType type) {
  switch (type) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual";
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return "cpu";
    default: return "other";
  }
}

std::string mib(uint64_t bytes) { return std::to_string(bytes >> 20) + " MiB"; }

uint64_t largest_device_local_heap(const VkPhysicalDeviceMemoryProperties& memory) {
  uint64_t largest = 0;
  for (uint32_t i = 0; i < memory.memoryHeapCount; ++i)
    if (memory.memoryHeaps[i].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT)
      largest = std::max<uint64_t>(largest, memory.memoryHeaps[i].size);
  return largest;
}

// DeviceInfo plus the limits only the Vulkan layer needs.
void describe(VkPhysicalDevice physical, int index, DeviceInfo& info, Limits& limits) {
  VkPhysicalDeviceProperties basic;
  vkGetPhysicalDeviceProperties(physical, &basic);
  // Driver properties and buffer addresses are core only from 1.2 (instance and device).
  uint32_t instance_version = VK_API_VERSION_1_0;
  check(vkEnumerateInstanceVersion(&instance_version), "vkEnumerateInstanceVersion");
  VkPhysicalDeviceDriverProperties driver{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
  VkPhysicalDeviceMaintenance3Properties maintenance3{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MAINTENANCE_3_PROPERTIES};
  VkPhysicalDeviceSubgroupProperties subgroup{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES, &maintenance3};
  const bool has_vulkan_1_2 =
      instance_version >= VK_API_VERSION_1_2 && basic.apiVersion >= VK_API_VERSION_1_2;
  if (has_vulkan_1_2) maintenance3.pNext = &driver;
  VkPhysicalDeviceProperties2 props{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, &subgroup};
  vkGetPhysicalDeviceProperties2(physical, &props);
  VkPhysicalDeviceBufferDeviceAddressFeatures address{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_BUFFER_DEVICE_ADDRESS_FEATURES};
  VkPhysicalDeviceFeatures2 features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, has_vulkan_1_2 ? &address : nullptr};
  vkGetPhysicalDeviceFeatures2(physical, &features);
  VkPhysicalDeviceMemoryProperties memory;
  vkGetPhysicalDeviceMemoryProperties(physical, &memory);

  const VkPhysicalDeviceLimits& l = props.properties.limits;
  limits.max_storage_buffer_range = l.maxStorageBufferRange;
  std::copy(std::begin(l.maxComputeWorkGroupCount), std::end(l.maxComputeWorkGroupCount),
            limits.max_group_count.begin());
  limits.max_push_constants_size = l.maxPushConstantsSize;
  limits.subgroup_size = subgroup.subgroupSize;
  limits.device_local_bytes = largest_device_local_heap(memory);
  limits.max_memory_allocation_size = maintenance3.maxMemoryAllocationSize;
  limits.buffer_device_address = address.bufferDeviceAddress && features.features.shaderInt64;
  limits.shader_float64 = features.features.shaderFloat64;
  limits.subgroup_arithmetic = (subgroup.supportedStages & VK_SHADER_STAGE_COMPUTE_BIT) &&
                               (subgroup.supportedOperations & VK_SUBGROUP_FEATURE_ARITHMETIC_BIT);

  info.index = index;
  info.name = props.properties.deviceName;
  info.type = type_name(props.properties.deviceType);
  info.driver = has_vulkan_1_2
                    ? std::string(driver.driverName) + " " + driver.driverInfo
                    : "driver version " + std::to_string(props.properties.driverVersion);
  info.device_local_bytes = limits.device_local_bytes;
  info.max_storage_buffer_range = limits.max_storage_buffer_range;
  info.subgroup_size = limits.subgroup_size;
}

Instance create_instance() {
  uint32_t loader_version = VK_API_VERSION_1_0;
  check(vkEnumerateInstanceVersion(&loader_version), "vkEnumerateInstanceVersion");
  if (loader_version < VK_API_VERSION_1_1)
    throw DeviceError("the Vulkan loader supports only Vulkan 1.0; shapematch needs 1.1");
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "shapematch";
  app.apiVersion = std::min<uint32_t>(loader_version, VK_API_VERSION_1_2);
  VkInstanceCreateInfo create{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  create.pApplicationInfo = &app;
  VkInstance instance = VK_NULL_HANDLE;
  const VkResult result = vkCreateInstance(&create, nullptr, &instance);
  if (result == VK_ERROR_INCOMPATIBLE_DRIVER)
    throw DeviceError("vkCreateInstance failed: no Vulkan driver found (VK_ERROR_INCOMPATIBLE_DRIVER); "
                      "install one or point VK_ICD_FILENAMES at an ICD such as lavapipe");
  check(result, "vkCreateInstance");
  return Instance(instance);
}

}  // namespace

VkInstance shared_instance() {
  static std::mutex mutex;
  // Never destroyed: on NVIDIA's driver (H100, 580.159) vkDestroyInstance from a static
  // destructor at exit crashed every process that had used Vulkan (segfault after its output
  // was written), since the driver's own state is torn down first. The OS reclaims it.
  static VkInstance instance = VK_NULL_HANDLE;
  static pid_t owner = 0;
  const std::lock_guard<std::mutex> lock(mutex);
  if (instance != VK_NULL_HANDLE && owner != getpid()) {
    // A forked child shares the parent's driver state (mappings, files) but not its threads.
    // Drivers do not support Vulkan there: on NVIDIA a child that made its own instance got an
    // error and left the parent's next vkCreateDevice failing with VK_ERROR_DEVICE_LOST. So the
    // child refuses before any driver call; fork before the first Vulkan call instead.
    throw DeviceError("Vulkan cannot be used in a process forked after Vulkan was initialised; "
                      "fork before the first Vulkan call");
  }
  if (instance == VK_NULL_HANDLE) {
    instance = create_instance().release();  // a failure throws and is tried again at the next call
    owner = getpid();
  }
  return instance;
}

std::vector<PhysicalDevice> compute_devices(VkInstance instance) {
  uint32_t count = 0;
  check(vkEnumeratePhysicalDevices(instance, &count, nullptr), "vkEnumeratePhysicalDevices");
  std::vector<VkPhysicalDevice> handles(count);
  check(vkEnumeratePhysicalDevices(instance, &count, handles.data()), "vkEnumeratePhysicalDevices");

  std::vector<PhysicalDevice> devices;
  for (VkPhysicalDevice handle : handles) {
    uint32_t family_count = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(handle, &family_count, nullptr);
    std::vector<VkQueueFamilyProperties> families(family_count);
    vkGetPhysicalDeviceQueueFamilyProperties(handle, &family_count, families.data());
    const auto compute = std::find_if(families.begin(), families.end(), [](const auto& f) {
      return (f.queueFlags & VK_QUEUE_COMPUTE_BIT) && f.queueCount > 0;
    });
    if (compute == families.end()) continue;
    PhysicalDevice device;
    device.handle = handle;
    device.queue_family = static_cast<uint32_t>(compute - families.begin());
    describe(handle, static_cast<int>(devices.size()), device.info, device.limits);
    devices.push_back(std::move(device));
  }
  return devices;
}

size_t pick_device(const std::vector<DeviceInfo>& devices, int requested_index) {
  if (devices.empty()) throw DeviceError("no Vulkan device with a compute queue was found");
  if (requested_index >= 0) {
    if (static_cast<size_t>(requested_index) >= devices.size())
      throw DeviceError("device " + std::to_string(requested_index) + " does not exist; there are " +
                        std::to_string(devices.size()) + " (see `shapematch devices`)");
    return static_cast<size_t>(requested_index);
  }
  for (const char* type : {"discrete", "integrated", "virtual", "cpu"}) {
    const auto it = std::find_if(devices.begin(), devices.end(),
                                 [&](const DeviceInfo& d) { return d.type == type; });
    if (it != devices.end()) return static_cast<size_t>(it - devices.begin());
  }
  return 0;
}

std::array<uint32_t, 3> dispatch_grid(uint64_t threads, uint32_t local_size,
                                      const std::array<uint32_t, 3>& max_groups) {
  const uint64_t groups = (threads + local_size - 1) / local_size;
  if (groups <= max_groups[0]) return {static_cast<uint32_t>(groups), 1, 1};
  const uint64_t rows = (groups + max_groups[0] - 1) / max_groups[0];
  if (rows > max_groups[1])
    throw DeviceError("a dispatch of " + std::to_string(threads) +
                      " invocations exceeds the device's workgroup count limits");
  return {max_groups[0], static_cast<uint32_t>(rows), 1};
}

Context::Context(int requested_index, Transfers transfers) {
  const std::vector<PhysicalDevice> devices = compute_devices(shared_instance());
  std::vector<DeviceInfo> infos;
  for (const PhysicalDevice& d : devices) infos.push_back(d.info);
  const PhysicalDevice& chosen = devices[pick_device(infos, requested_index)];
  physical_ = chosen.handle;
  queue_family_ = chosen.queue_family;
  info_ = chosen.info;
  limits_ = chosen.limits;
  vkGetPhysicalDeviceMemoryProperties(physical_, &memory_);

  const float priority = 1.0f;
  VkDeviceQueueCreateInfo queue{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  queue.queueFamilyIndex = queue_family_;
  queue.queueCount = 1;
  queue.pQueuePriorities = &priority;
  VkPhysicalDeviceBufferDeviceAddressFeatures address{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_BUFFER_DEVICE_ADDRESS_FEATURES};
  address.bufferDeviceAddress = VK_TRUE;
  VkPhysicalDeviceFeatures2 features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &address};
  features.features.shaderInt64 = limits_.buffer_device_address;
  features.features.shaderFloat64 = limits_.shader_float64;
  if (!limits_.buffer_device_address) features.pNext = nullptr;
  VkDeviceCreateInfo create{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  create.pNext = &features;
  create.queueCreateInfoCount = 1;
  create.pQueueCreateInfos = &queue;
  VkDevice device = VK_NULL_HANDLE;
  check(vkCreateDevice(physical_, &create, nullptr, &device), "vkCreateDevice");
  device_ = Device(device);
  vkGetDeviceQueue(device, queue_family_, 0, &queue_);

  // CPU and integrated devices compute in host memory: staging copies would only cost time.
  // A discrete GPU's host-visible VRAM (BAR/ReBAR) is not used: host reads of it are uncached.
  const bool shares_host_memory = info_.type == "cpu" || info_.type == "integrated";
  const VkMemoryPropertyFlags all = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT |
                                    VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT |
                                    VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  unified_ = transfers == Transfers::automatic && shares_host_memory &&
             std::any_of(memory_.memoryTypes, memory_.memoryTypes + memory_.memoryTypeCount,
                         [&](const VkMemoryType& t) { return (t.propertyFlags & all) == all; });
}

Buffer Context::storage_buffer(uint64_t bytes) {
  if (bytes > limits_.max_storage_buffer_range)
    throw DeviceError("a storage buffer of " + std::to_string(bytes) + " bytes exceeds the " +
                      "maxStorageBufferRange of " + std::to_string(limits_.max_storage_buffer_range) +
                      " bytes on " + info_.name + "; the array must be split");
  return device_buffer(bytes, 0);
}

Buffer Context::addressed_buffer(uint64_t bytes) {
  if (!limits_.buffer_device_address)
    throw DeviceError(info_.name + " lacks the Vulkan 1.2 features bufferDeviceAddress and "
                      "shaderInt64 that addressed buffers need");
  if (bytes > limits_.max_memory_allocation_size)
    throw DeviceError("a buffer of " + std::to_string(bytes) + " bytes (" + mib(bytes) +
                      ") exceeds the maxMemoryAllocationSize of " + mib(limits_.max_memory_allocation_size) +
                      " on " + info_.name);
  return device_buffer(bytes, VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT);
}

Buffer Context::device_buffer(uint64_t bytes, VkBufferUsageFlags extra_usage) {
  const VkBufferUsageFlags usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT |
                                   VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
                                   VK_BUFFER_USAGE_TRANSFER_DST_BIT | extra_usage;
  if (unified_)
    return make_buffer(bytes, usage,
                       VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
                       VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, true);
  return make_buffer(bytes, usage, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0, false);
}

Buffer Context::make_buffer(uint64_t bytes, VkBufferUsageFlags usage,
                            VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred,
                            bool map) {
  VkDevice device = device_.get();
  Buffer buffer;
  buffer.bytes_ = bytes;
  VkBufferCreateInfo create{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  create.size = std::max<uint64_t>(bytes, 4);  // Vulkan forbids empty buffers
  create.usage = usage;
  create.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  VkBuffer handle = VK_NULL_HANDLE;
  check(vkCreateBuffer(device, &create, nullptr, &handle), "vkCreateBuffer");
  buffer.buffer_ = BufferHandle(device, handle);

  VkMemoryRequirements needs;
  vkGetBufferMemoryRequirements(device, handle, &needs);
  // The first allowed type with every preferred flag, else the first with the required ones.
  uint32_t type = memory_.memoryTypeCount;
  for (VkMemoryPropertyFlags flags : {required | preferred, required}) {
    for (uint32_t i = 0; i < memory_.memoryTypeCount && type == memory_.memoryTypeCount; ++i)
      if ((needs.memoryTypeBits & (1u << i)) &&
          (memory_.memoryTypes[i].propertyFlags & flags) == flags)
        type = i;
  }
  if (type == memory_.memoryTypeCount)
    throw DeviceError(info_.name + " has no memory type with the properties a buffer needs");

  const bool addressed = usage & VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT;
  VkMemoryAllocateFlagsInfo flags{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
  flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
  VkMemoryAllocateInfo allocate{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, addressed ? &flags : nullptr};
  allocate.allocationSize = needs.size;
  allocate.memoryTypeIndex = type;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  const VkResult result = vkAllocateMemory(device, &allocate, nullptr, &memory);
  if (result == VK_ERROR_OUT_OF_DEVICE_MEMORY || result == VK_ERROR_OUT_OF_HOST_MEMORY)
    throw DeviceError("vkAllocateMemory failed (" + std::string(result_name(result)) +
                      "): out of memory allocating " + std::to_string(needs.size) + " bytes (" +
                      mib(needs.size) + ") on " + info_.name + ", whose largest device-local heap is " +
                      mib(limits_.device_local_bytes));
  check(result, "vkAllocateMemory");
  buffer.memory_ = Memory(device, memory);
  check(vkBindBufferMemory(device, handle, memory, 0), "vkBindBufferMemory");
  if (map)
    check(vkMapMemory(device, memory, 0, VK_WHOLE_SIZE, 0, &buffer.mapped_), "vkMapMemory");
  if (addressed) {
    VkBufferDeviceAddressInfo info{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
    info.buffer = handle;
    buffer.address_ = vkGetBufferDeviceAddress(device, &info);
  }
  return buffer;
}

void Context::upload(Buffer& dst, const void* src, uint64_t bytes) {
  if (bytes == 0) return;
  if (dst.mapped_) {  // coherent memory: the next queue submission sees host writes
    std::memcpy(dst.mapped_, src, bytes);
    return;
  }
  Buffer staging = make_buffer(bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                               VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT, 0, true);
  std::memcpy(staging.mapped_, src, bytes);
  Sequence copy(*this);
  copy.copy(staging, dst, bytes);
  copy.submit_and_wait();
}

void Context::download(const Buffer& src, void* dst, uint64_t bytes) {
  if (bytes == 0) return;
  if (src.mapped_) {  // every Sequence ends with a barrier that makes device writes host-visible
    std::memcpy(dst, src.mapped_, bytes);
    return;
  }
  // Cached memory where available: the host reads uncached memory slowly.
  Buffer staging = make_buffer(bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                               VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
                               VK_MEMORY_PROPERTY_HOST_CACHED_BIT, true);
  Sequence copy(*this);
  copy.copy(src, staging, bytes);
  copy.submit_and_wait();
  std::memcpy(dst, staging.mapped_, bytes);
}

}  // namespace shapematch::vk
