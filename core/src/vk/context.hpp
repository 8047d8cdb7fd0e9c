#pragma once
// The Vulkan instance, one device with one compute queue, and the storage buffers made on it.
// Everything made from a Context (buffers, pipelines, sequences) keeps raw handles of it and
// must be destroyed before it.
#include <vulkan/vulkan.h>

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "shapematch/device.hpp"
#include "vk/handles.hpp"

namespace shapematch::vk {

// What the Vulkan layer needs to know about a device beyond DeviceInfo.
struct Limits {
  uint64_t max_storage_buffer_range = 0;  // bytes one storage-buffer binding may span
  std::array<uint32_t, 3> max_group_count{};
  uint32_t max_push_constants_size = 0;
  uint32_t subgroup_size = 0;
  uint64_t device_local_bytes = 0;  // largest device-local heap
  uint64_t max_memory_allocation_size = 0;  // bytes one allocation (so one buffer) may span
  // Buffer device addresses and 64-bit integers in shaders (Vulkan 1.2 features), what
  // addressed buffers need; enabled on the device when present, as is shader_float64.
  bool buffer_device_address = false;
  bool shader_float64 = false;
  bool subgroup_arithmetic = false;  // subgroupAdd etc. in compute shaders
};

// Instance creation and device enumeration, shared by Context and shapematch::list_devices()
// so that both see the same indices.
struct PhysicalDevice {
  VkPhysicalDevice handle = VK_NULL_HANDLE;
  uint32_t queue_family = 0;  // first family with compute
  DeviceInfo info;
  Limits limits;
};
// The process's one VkInstance, created at the first call and kept until exit. NVIDIA's driver
// went wrong after repeated create/destroy cycles in one process: seen on an H100 (driver
// 580.159), vkCreateInstance failed with VK_ERROR_INCOMPATIBLE_DRIVER after some dozens of
// LP solves, each of which had made and destroyed its own instance; others report subgroup
// builtins corrupted after ~11 cycles. Devices are still made per Context. It is never destroyed
// (destroying it at exit crashed on NVIDIA). A process forked after the first call gets a
// DeviceError here: bench lp forks its solver children before any Vulkan call.
VkInstance shared_instance();
std::vector<PhysicalDevice> compute_devices(VkInstance instance);
// Index into devices: requested_index if valid, else (for < 0) discrete > integrated >
// virtual > cpu > other, first of its kind. Throws DeviceError when nothing fits.
size_t pick_device(const std::vector<DeviceInfo>& devices, int requested_index);

// Workgroup counts covering `threads` invocations of local_size each within max_groups per
// dimension. Beyond max_groups[0] workgroups the grid becomes 2D, so a shader computes its index
// as gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * local_size and
// returns when it is past the end.
std::array<uint32_t, 3> dispatch_grid(uint64_t threads, uint32_t local_size,
                                      const std::array<uint32_t, 3>& max_groups);

// A storage buffer on the device. On unified (CPU/integrated) devices it stays mapped and
// transfers are memcpy; otherwise they go through a staging buffer.
class Buffer {
public:
  uint64_t bytes() const { return bytes_; }
  VkBuffer handle() const { return buffer_.get(); }
  void* mapped() const { return mapped_; }
  // The device address shaders reach it by (GL_EXT_buffer_reference); 0 unless addressed.
  uint64_t address() const { return address_; }

private:
  friend class Context;
  Memory memory_;         // declared first so that it is freed after the buffer bound to it
  BufferHandle buffer_;
  uint64_t bytes_ = 0;
  void* mapped_ = nullptr;
  uint64_t address_ = 0;
};

class Context {
public:
  // How storage buffers are filled and read. `staged` forces the discrete-GPU path (a staging
  // buffer and a copy on the queue) on any device, so that lavapipe tests cover it.
  enum class Transfers { automatic, staged };

  // requested_index as for shapematch::choose_device().
  explicit Context(int requested_index = -1, Transfers transfers = Transfers::automatic);
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  const DeviceInfo& info() const { return info_; }
  const Limits& limits() const { return limits_; }
  bool unified() const { return unified_; }
  VkDevice device() const { return device_.get(); }
  VkQueue queue() const { return queue_; }
  uint32_t queue_family() const { return queue_family_; }

  // A storage buffer of `bytes` (contents undefined). Throws DeviceError when bytes exceeds
  // maxStorageBufferRange or the device is out of memory.
  Buffer storage_buffer(uint64_t bytes);
  // A storage buffer that shaders reach through its address() instead of a descriptor, so that
  // maxStorageBufferRange does not apply: it may span up to maxMemoryAllocationSize. Throws
  // DeviceError beyond that, when out of memory, or when the device lacks buffer addresses.
  Buffer addressed_buffer(uint64_t bytes);
  // Host <-> device copies of the first `bytes` of a buffer; they wait for completion.
  void upload(Buffer& dst, const void* src, uint64_t bytes);
  void download(const Buffer& src, void* dst, uint64_t bytes);

  template <class T>
  Buffer upload(std::span<const T> data) {
    Buffer buffer = storage_buffer(data.size_bytes());
    upload(buffer, data.data(), data.size_bytes());
    return buffer;
  }
  template <class T>
  Buffer upload_addressed(std::span<const T> data) {
    Buffer buffer = addressed_buffer(data.size_bytes());
    upload(buffer, data.data(), data.size_bytes());
    return buffer;
  }
  template <class T>
  std::vector<T> download(const Buffer& src, size_t count) {
    std::vector<T> out(count);
    download(src, out.data(), count * sizeof(T));
    return out;
  }

  std::array<uint32_t, 3> grid(uint64_t threads, uint32_t local_size) const {
    return dispatch_grid(threads, local_size, limits_.max_group_count);
  }

private:
  // Maps the memory when `map` (it must then be host-visible); takes the device address when
  // usage has VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT.
  Buffer make_buffer(uint64_t bytes, VkBufferUsageFlags usage, VkMemoryPropertyFlags required,
                     VkMemoryPropertyFlags preferred, bool map);
  Buffer device_buffer(uint64_t bytes, VkBufferUsageFlags extra_usage);

  Device device_;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  uint32_t queue_family_ = 0;
  DeviceInfo info_;
  Limits limits_;
  VkPhysicalDeviceMemoryProperties memory_{};
  bool unified_ = false;
};

}  // namespace shapematch::vk
