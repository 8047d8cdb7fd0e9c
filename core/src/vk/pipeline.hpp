#pragma once
// A compute pipeline whose shader reads N storage buffers (set 0, bindings 0..N-1) and one
// push-constant block, and the descriptor sets that bind buffers to it. With N = 0 the shader
// reaches its buffers through device addresses in the push constants and binds no set.
#include <vulkan/vulkan.h>

#include <cstdint>
#include <initializer_list>
#include <span>

#include "vk/context.hpp"
#include "vk/handles.hpp"

namespace shapematch::vk {

// One set of buffers for one pipeline, with a pool of its own so that sets come and go
// independently; the same pipeline can run on several sets in one Sequence (A x and Aᵀ y).
class DescriptorSet {
public:
  VkDescriptorSet handle() const { return set_; }

private:
  friend class ComputePipeline;
  DescriptorPool pool_;
  VkDescriptorSet set_ = VK_NULL_HANDLE;  // freed with pool_
};

class ComputePipeline {
public:
  // spirv: the words from a generated <name>_spv.hpp; push_bytes may be 0.
  ComputePipeline(const Context& context, std::span<const uint32_t> spirv, uint32_t buffer_count,
                  uint32_t push_bytes);

  // buffers[i] goes to binding i, whole buffer.
  DescriptorSet bind(std::initializer_list<const Buffer*> buffers) const;

  VkPipeline handle() const { return pipeline_.get(); }
  VkPipelineLayout layout() const { return layout_.get(); }
  uint32_t push_bytes() const { return push_bytes_; }

private:
  VkDevice device_;
  uint32_t buffer_count_;
  uint32_t push_bytes_;
  DescriptorSetLayout set_layout_;
  PipelineLayout layout_;
  Pipeline pipeline_;
};

}  // namespace shapematch::vk
