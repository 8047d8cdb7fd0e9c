#include "vk/sequence.hpp"

#include <cstdint>
#include <string>

#include "shapematch/errors.hpp"
#include "vk/check.hpp"

namespace shapematch::vk {

namespace {
constexpr VkPipelineStageFlags kDeviceStages =
    VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT;
constexpr VkAccessFlags kDeviceAccess = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT |
                                        VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
}  // namespace

Sequence::Sequence(const Context& context) : device_(context.device()), queue_(context.queue()) {
  VkCommandPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pool_info.queueFamilyIndex = context.queue_family();
  VkCommandPool pool = VK_NULL_HANDLE;
  check(vkCreateCommandPool(device_, &pool_info, nullptr, &pool), "vkCreateCommandPool");
  pool_ = CommandPool(device_, pool);

  VkCommandBufferAllocateInfo allocate{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  allocate.commandPool = pool;
  allocate.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  allocate.commandBufferCount = 1;
  check(vkAllocateCommandBuffers(device_, &allocate, &commands_), "vkAllocateCommandBuffers");

  VkFenceCreateInfo fence_info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  VkFence fence = VK_NULL_HANDLE;
  check(vkCreateFence(device_, &fence_info, nullptr, &fence), "vkCreateFence");
  fence_ = Fence(device_, fence);

  const VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  check(vkBeginCommandBuffer(commands_, &begin), "vkBeginCommandBuffer");
  // Orders this buffer after whatever ran on the queue before, including an earlier
  // submission of itself.
  barrier(kDeviceStages, kDeviceAccess);
}

void Sequence::barrier(VkPipelineStageFlags dst_stages, VkAccessFlags dst_access) {
  VkMemoryBarrier memory{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  memory.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
  memory.dstAccessMask = dst_access;
  vkCmdPipelineBarrier(commands_, kDeviceStages, dst_stages, 0, 1, &memory, 0, nullptr, 0, nullptr);
}

void Sequence::dispatch(const ComputePipeline& pipeline, const DescriptorSet& set,
                        std::span<const std::byte> push, const std::array<uint32_t, 3>& groups) {
  record(pipeline, &set, push, groups);
}

void Sequence::dispatch(const ComputePipeline& pipeline, std::span<const std::byte> push,
                        const std::array<uint32_t, 3>& groups) {
  record(pipeline, nullptr, push, groups);
}

void Sequence::record(const ComputePipeline& pipeline, const DescriptorSet* set,
                      std::span<const std::byte> push, const std::array<uint32_t, 3>& groups) {
  if (!recording_) throw DeviceError("Sequence::dispatch after the sequence was submitted");
  if (push.size() != pipeline.push_bytes())
    throw DeviceError("push constants of " + std::to_string(push.size()) + " bytes for a pipeline " +
                      "declaring " + std::to_string(pipeline.push_bytes()));
  vkCmdBindPipeline(commands_, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline.handle());
  if (set) {
    const VkDescriptorSet handle = set->handle();
    vkCmdBindDescriptorSets(commands_, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline.layout(), 0, 1,
                            &handle, 0, nullptr);
  }
  if (!push.empty())
    vkCmdPushConstants(commands_, pipeline.layout(), VK_SHADER_STAGE_COMPUTE_BIT, 0,
                       static_cast<uint32_t>(push.size()), push.data());
  vkCmdDispatch(commands_, groups[0], groups[1], groups[2]);
  barrier(kDeviceStages, kDeviceAccess);
}

void Sequence::copy(const Buffer& src, const Buffer& dst, uint64_t bytes) {
  if (!recording_) throw DeviceError("Sequence::copy after the sequence was submitted");
  const VkBufferCopy region{0, 0, bytes};
  vkCmdCopyBuffer(commands_, src.handle(), dst.handle(), 1, &region);
  barrier(kDeviceStages, kDeviceAccess);
}

void Sequence::submit_and_wait() {
  if (recording_) {
    barrier(VK_PIPELINE_STAGE_HOST_BIT, VK_ACCESS_HOST_READ_BIT);
    check(vkEndCommandBuffer(commands_), "vkEndCommandBuffer");
    recording_ = false;
  }
  const VkFence fence = fence_.get();
  check(vkResetFences(device_, 1, &fence), "vkResetFences");
  VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &commands_;
  check(vkQueueSubmit(queue_, 1, &submit, fence), "vkQueueSubmit");
  check(vkWaitForFences(device_, 1, &fence, VK_TRUE, UINT64_MAX), "vkWaitForFences");
}

}  // namespace shapematch::vk
