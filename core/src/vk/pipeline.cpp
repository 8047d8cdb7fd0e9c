#include "vk/pipeline.hpp"

#include <string>
#include <vector>

#include "shapematch/errors.hpp"
#include "vk/check.hpp"

namespace shapematch::vk {

ComputePipeline::ComputePipeline(const Context& context, std::span<const uint32_t> spirv,
                                 uint32_t buffer_count, uint32_t push_bytes)
    : device_(context.device()), buffer_count_(buffer_count), push_bytes_(push_bytes) {
  if (push_bytes % 4 != 0 || push_bytes > context.limits().max_push_constants_size)
    throw DeviceError("a push-constant block of " + std::to_string(push_bytes) +
                      " bytes is not a multiple of 4 or exceeds the device limit of " +
                      std::to_string(context.limits().max_push_constants_size));

  std::vector<VkDescriptorSetLayoutBinding> bindings(buffer_count);
  for (uint32_t i = 0; i < buffer_count; ++i) {
    bindings[i].binding = i;
    bindings[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    bindings[i].descriptorCount = 1;
    bindings[i].stageFlags = VK_SHADER_STAGE_COMPUTE_BIT;
  }
  VkDescriptorSetLayoutCreateInfo set_info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  set_info.bindingCount = buffer_count;
  set_info.pBindings = bindings.data();
  VkDescriptorSetLayout set_layout = VK_NULL_HANDLE;
  check(vkCreateDescriptorSetLayout(device_, &set_info, nullptr, &set_layout),
        "vkCreateDescriptorSetLayout");
  set_layout_ = DescriptorSetLayout(device_, set_layout);

  const VkPushConstantRange push{VK_SHADER_STAGE_COMPUTE_BIT, 0, push_bytes};
  VkPipelineLayoutCreateInfo layout_info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  layout_info.setLayoutCount = buffer_count > 0 ? 1 : 0;  // kernels on buffer addresses bind no set
  layout_info.pSetLayouts = &set_layout;
  layout_info.pushConstantRangeCount = push_bytes > 0 ? 1 : 0;
  layout_info.pPushConstantRanges = &push;
  VkPipelineLayout layout = VK_NULL_HANDLE;
  check(vkCreatePipelineLayout(device_, &layout_info, nullptr, &layout), "vkCreatePipelineLayout");
  layout_ = PipelineLayout(device_, layout);

  // The module is only needed while the pipeline is compiled.
  VkShaderModuleCreateInfo module_info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  module_info.codeSize = spirv.size_bytes();
  module_info.pCode = spirv.data();
  VkShaderModule module_handle = VK_NULL_HANDLE;
  check(vkCreateShaderModule(device_, &module_info, nullptr, &module_handle), "vkCreateShaderModule");
  const ShaderModule module(device_, module_handle);

  VkComputePipelineCreateInfo info{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
  info.stage.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
  info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  info.stage.module = module.get();
  info.stage.pName = "main";
  info.layout = layout;
  VkPipeline pipeline = VK_NULL_HANDLE;
  check(vkCreateComputePipelines(device_, VK_NULL_HANDLE, 1, &info, nullptr, &pipeline),
        "vkCreateComputePipelines");
  pipeline_ = Pipeline(device_, pipeline);
}

DescriptorSet ComputePipeline::bind(std::initializer_list<const Buffer*> buffers) const {
  if (buffers.size() != buffer_count_ || buffer_count_ == 0)
    throw DeviceError("a pipeline with " + std::to_string(buffer_count_) + " bindings was given " +
                      std::to_string(buffers.size()) + " buffers");
  DescriptorSet set;
  const VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, buffer_count_};
  VkDescriptorPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  pool_info.maxSets = 1;
  pool_info.poolSizeCount = 1;
  pool_info.pPoolSizes = &size;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  check(vkCreateDescriptorPool(device_, &pool_info, nullptr, &pool), "vkCreateDescriptorPool");
  set.pool_ = DescriptorPool(device_, pool);

  const VkDescriptorSetLayout set_layout = set_layout_.get();
  VkDescriptorSetAllocateInfo allocate{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  allocate.descriptorPool = pool;
  allocate.descriptorSetCount = 1;
  allocate.pSetLayouts = &set_layout;
  check(vkAllocateDescriptorSets(device_, &allocate, &set.set_), "vkAllocateDescriptorSets");

  std::vector<VkDescriptorBufferInfo> infos;
  std::vector<VkWriteDescriptorSet> writes;
  infos.reserve(buffers.size());  // writes point into infos
  for (const Buffer* buffer : buffers) {
    infos.push_back({buffer->handle(), 0, VK_WHOLE_SIZE});
    VkWriteDescriptorSet write{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    write.dstSet = set.set_;
    write.dstBinding = static_cast<uint32_t>(writes.size());
    write.descriptorCount = 1;
    write.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    write.pBufferInfo = &infos.back();
    writes.push_back(write);
  }
  vkUpdateDescriptorSets(device_, static_cast<uint32_t>(writes.size()), writes.data(), 0, nullptr);
  return set;
}

}  // namespace shapematch::vk
