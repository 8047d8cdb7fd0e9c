#pragma once
// One command buffer of dispatches and copies, submitted to the Context's queue and waited for
// with a fence. It can be submitted again after the first submit_and_wait(), e.g. to run K
// pre-recorded solver iterations per submission.
#include <vulkan/vulkan.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "vk/context.hpp"
#include "vk/handles.hpp"
#include "vk/pipeline.hpp"

namespace shapematch::vk {

class Sequence {
public:
  explicit Sequence(const Context& context);

  // Every command is followed by a global memory barrier, so each one sees the writes of all
  // before it: the kernels here form chains, and a forgotten barrier is a silent wrong answer.
  void dispatch(const ComputePipeline& pipeline, const DescriptorSet& set,
                std::span<const std::byte> push, const std::array<uint32_t, 3>& groups);
  template <class Push>
  void dispatch(const ComputePipeline& pipeline, const DescriptorSet& set, const Push& push,
                const std::array<uint32_t, 3>& groups) {
    dispatch(pipeline, set, std::as_bytes(std::span(&push, 1)), groups);
  }
  // For a pipeline without buffer bindings (buffer addresses in the push constants).
  void dispatch(const ComputePipeline& pipeline, std::span<const std::byte> push,
                const std::array<uint32_t, 3>& groups);
  template <class Push>
  void dispatch(const ComputePipeline& pipeline, const Push& push, const std::array<uint32_t, 3>& groups) {
    dispatch(pipeline, std::as_bytes(std::span(&push, 1)), groups);
  }
  void copy(const Buffer& src, const Buffer& dst, uint64_t bytes);

  // Ends recording on the first call; afterwards the buffers' contents are visible to the host.
  void submit_and_wait();

private:
  void record(const ComputePipeline& pipeline, const DescriptorSet* set,
              std::span<const std::byte> push, const std::array<uint32_t, 3>& groups);
  void barrier(VkPipelineStageFlags dst_stages, VkAccessFlags dst_access);

  VkDevice device_;
  VkQueue queue_;
  CommandPool pool_;
  VkCommandBuffer commands_ = VK_NULL_HANDLE;  // freed with pool_
  Fence fence_;
  bool recording_ = true;
};

}  // namespace shapematch::vk
