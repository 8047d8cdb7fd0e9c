#pragma once
// Small helpers shared by the tests.
#include "shapematch/mesh.hpp"

#include "shapematch/device.hpp"
#include "shapematch/errors.hpp"

#include <Eigen/Geometry>
#include <doctest/doctest.h>
#include <cstdlib>
#include <random>
#include <string>

namespace shapematch::test {

// The same connectivity with every vertex mapped by f.
template <class F>
Mesh deformed(const Mesh& m, F&& f, const std::string& name = "deformed") {
  std::vector<Eigen::Vector3d> v;
  for (const auto& p : m.vertices) v.push_back(f(p));
  return make_mesh(v, m.faces, name);
}

inline Eigen::Matrix3d random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> n;
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  return q.toRotationMatrix();
}

// False (the test returns) only when skipping was asked for; no device otherwise fails.
inline bool vulkan_wanted() {
  const char* skip = std::getenv("SHAPEMATCH_SKIP_VULKAN");
  if (skip && std::string(skip) == "1") {
    MESSAGE("SHAPEMATCH_SKIP_VULKAN=1: Vulkan test skipped");
    return false;
  }
  std::string problem;
  try {
    if (list_devices().empty()) problem = "no Vulkan device with a compute queue";
  } catch (const DeviceError& e) {
    problem = e.what();
  }
  if (!problem.empty())
    FAIL("Vulkan unavailable (" << problem << "). Set VK_ICD_FILENAMES="
         "/usr/share/vulkan/icd.d/lvp_icd.x86_64.json for lavapipe, or "
         "SHAPEMATCH_SKIP_VULKAN=1 to skip the Vulkan tests.");
  return true;
}

}  // namespace shapematch::test
