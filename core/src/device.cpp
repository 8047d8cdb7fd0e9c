#include "shapematch/device.hpp"

#include "vk/context.hpp"

namespace shapematch {

std::vector<DeviceInfo> list_devices() {
  std::vector<DeviceInfo> infos;
  for (const vk::PhysicalDevice& device : vk::compute_devices(vk::shared_instance()))
    infos.push_back(device.info);
  return infos;
}

DeviceInfo choose_device(int requested_index) {
  const std::vector<DeviceInfo> devices = list_devices();
  return devices[vk::pick_device(devices, requested_index)];
}

}  // namespace shapematch
