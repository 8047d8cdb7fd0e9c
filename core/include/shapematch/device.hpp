#pragma once
// Vulkan compute devices, seen without any Vulkan type (those stay in core/src/vk/).
#include <cstdint>
#include <string>
#include <vector>

namespace shapematch {

struct DeviceInfo {
  int index = -1;                 // position in list_devices(), what --device takes
  std::string name;
  std::string type;               // "discrete", "integrated", "virtual", "cpu", "other"
  std::string driver;             // driver name/version string
  uint64_t device_local_bytes = 0;
  uint64_t max_storage_buffer_range = 0;
  uint32_t subgroup_size = 0;
};

// All Vulkan physical devices with a compute queue. Throws DeviceError when Vulkan itself is
// unavailable (no loader / no ICD); returns an empty list when there is no device.
std::vector<DeviceInfo> list_devices();

// The device --device N names, or with N < 0 the preferred one: discrete > integrated >
// virtual > cpu. Throws DeviceError if there is none or N is out of range.
DeviceInfo choose_device(int requested_index = -1);

}  // namespace shapematch
