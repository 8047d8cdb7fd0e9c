#pragma once
// Move-only owners of Vulkan handles (the RAII of Kompute without shared_ptr). Descriptor sets
// and command buffers need no owner of their own: they are freed with their pool.
#include <vulkan/vulkan.h>

#include <utility>

namespace shapematch::vk {

// A handle destroyed by Destroy(handle, allocator): VkInstance, VkDevice.
template <class T, auto Destroy>
class RootHandle {
public:
  RootHandle() = default;
  explicit RootHandle(T handle) : handle_(handle) {}
  RootHandle(RootHandle&& other) noexcept : handle_(std::exchange(other.handle_, nullptr)) {}
  RootHandle& operator=(RootHandle&& other) noexcept {
    if (this != &other) {
      reset();
      handle_ = std::exchange(other.handle_, nullptr);
    }
    return *this;
  }
  ~RootHandle() { reset(); }

  T get() const { return handle_; }
  // Gives the handle up without destroying it.
  T release() { return std::exchange(handle_, nullptr); }

private:
  void reset() {
    if (handle_) Destroy(handle_, nullptr);
    handle_ = nullptr;
  }
  T handle_ = nullptr;
};

// A handle destroyed by Destroy(device, handle, allocator): everything created from a VkDevice.
template <class T, auto Destroy>
class DeviceHandle {
public:
  DeviceHandle() = default;
  DeviceHandle(VkDevice device, T handle) : device_(device), handle_(handle) {}
  DeviceHandle(DeviceHandle&& other) noexcept
      : device_(other.device_), handle_(std::exchange(other.handle_, VK_NULL_HANDLE)) {}
  DeviceHandle& operator=(DeviceHandle&& other) noexcept {
    if (this != &other) {
      reset();
      device_ = other.device_;
      handle_ = std::exchange(other.handle_, VK_NULL_HANDLE);
    }
    return *this;
  }
  ~DeviceHandle() { reset(); }

  T get() const { return handle_; }

private:
  void reset() {
    if (handle_ != VK_NULL_HANDLE) Destroy(device_, handle_, nullptr);
    handle_ = VK_NULL_HANDLE;
  }
  VkDevice device_ = VK_NULL_HANDLE;
  T handle_ = VK_NULL_HANDLE;
};

using Instance = RootHandle<VkInstance, vkDestroyInstance>;
using Device = RootHandle<VkDevice, vkDestroyDevice>;
using BufferHandle = DeviceHandle<VkBuffer, vkDestroyBuffer>;
using Memory = DeviceHandle<VkDeviceMemory, vkFreeMemory>;
using ShaderModule = DeviceHandle<VkShaderModule, vkDestroyShaderModule>;
using DescriptorSetLayout = DeviceHandle<VkDescriptorSetLayout, vkDestroyDescriptorSetLayout>;
using DescriptorPool = DeviceHandle<VkDescriptorPool, vkDestroyDescriptorPool>;
using PipelineLayout = DeviceHandle<VkPipelineLayout, vkDestroyPipelineLayout>;
using Pipeline = DeviceHandle<VkPipeline, vkDestroyPipeline>;
using CommandPool = DeviceHandle<VkCommandPool, vkDestroyCommandPool>;
using Fence = DeviceHandle<VkFence, vkDestroyFence>;

}  // namespace shapematch::vk
