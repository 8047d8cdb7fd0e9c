// Small subcommands: `devices` and `generate-assets`.
#include "commands.hpp"
#include "shapematch/device.hpp"
#include "shapematch/shapes.hpp"

#include <spdlog/spdlog.h>

#include <iostream>

namespace shapematch::app {

Action add_devices_command(CLI::App& app) {
  return [] {
    const auto devices = list_devices();
    if (devices.empty()) {
      std::cout << "no Vulkan compute device found\n";
      return 1;
    }
    const DeviceInfo preferred = choose_device(-1);
    for (const auto& d : devices) {
      std::cout << (d.index == preferred.index ? "* " : "  ") << d.index << ": " << d.name << " (" << d.type
                << ", " << d.device_local_bytes / (1024 * 1024) << " MiB, max storage buffer "
                << d.max_storage_buffer_range / (1024 * 1024) << " MiB, subgroup " << d.subgroup_size << ", "
                << d.driver << ")\n";
    }
    return 0;
  };
}

Action add_generate_assets_command(CLI::App& app) {
  auto dir = std::make_shared<std::string>(SHAPEMATCH_ASSETS_DIR);
  app.add_option("--out", *dir, "output directory")->capture_default_str();
  return [dir] {
    shapes::write_bundled_assets(*dir);
    spdlog::info("wrote the bundled meshes to {}", *dir);
    return 0;
  };
}

}  // namespace shapematch::app
