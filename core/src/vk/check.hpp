#pragma once
// Turning VkResult into shapematch::DeviceError: every Vulkan call goes through check().
#include <vulkan/vulkan.h>

namespace shapematch::vk {

// "VK_ERROR_OUT_OF_DEVICE_MEMORY" etc.; the number for codes this build does not name.
const char* result_name(VkResult result);

// Throws DeviceError("<call> failed: <result>").
[[noreturn]] void fail(const char* call, VkResult result);

inline void check(VkResult result, const char* call) {
  if (result != VK_SUCCESS) fail(call, result);
}

}  // namespace shapematch::vk
