// Tests of the Vulkan layer. They need a Vulkan device (CI points VK_ICD_FILENAMES at lavapipe)
// and fail without one, unless SHAPEMATCH_SKIP_VULKAN=1.
#include "shapematch/device.hpp"
#include "shapematch/errors.hpp"
#include "shapematch/sparse.hpp"
#include "vk/context.hpp"
#include "vk/spmv.hpp"

#include "test_helpers.hpp"

#include <doctest/doctest.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <numeric>
#include <random>
#include <string>

#include <sys/wait.h>
#include <unistd.h>

using namespace shapematch;

namespace {


// rows x cols with 0..max_per_row entries per row at random columns and signs.
SignedCsr random_csr(int64_t rows, int64_t cols, int max_per_row, std::mt19937& rng) {
  SignedCsr a;
  a.rows = rows;
  a.cols = cols;
  a.row_ptr.reserve(static_cast<size_t>(rows) + 1);
  a.row_ptr.push_back(0);
  std::uniform_int_distribution<int> count(0, max_per_row);
  std::uniform_int_distribution<uint32_t> col(0, static_cast<uint32_t>(cols - 1));
  std::bernoulli_distribution negative(0.5);
  for (int64_t r = 0; r < rows; ++r) {
    for (int k = count(rng); k > 0; --k)
      a.entry.push_back(col(rng) | (negative(rng) ? SignedCsr::kNegative : 0u));
    a.row_ptr.push_back(static_cast<uint32_t>(a.entry.size()));
  }
  return a;
}

std::vector<float> random_x(int64_t n, bool integers, std::mt19937& rng) {
  std::vector<float> x(static_cast<size_t>(n));
  std::uniform_int_distribution<int> i(-100, 100);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (float& v : x) v = integers ? static_cast<float>(i(rng)) : u(rng);
  return x;
}

// Integer x: sums are exact in float, so equality. Real x: a relative error 1e-5 of the sum of
// magnitudes (a relative error of y itself is meaningless where terms cancel).
void check_spmv(vk::SignedSpmv& gpu, const SignedCsr& a, bool integers, std::mt19937& rng) {
  const std::vector<float> x = random_x(a.cols, integers, rng);
  std::vector<float> expected(static_cast<size_t>(a.rows));
  spmv(a, x.data(), expected.data());
  const std::vector<float> y = gpu(a, x);
  REQUIRE(y.size() == expected.size());
  int64_t bad = 0;
  for (int64_t r = 0; r < a.rows; ++r) {
    double magnitude = 0;
    for (uint32_t k = a.row_ptr[r]; k < a.row_ptr[r + 1]; ++k) magnitude += std::abs(x[col_of(a.entry[k])]);
    const double error = std::abs(double(y[r]) - expected[r]);
    if (integers ? error != 0 : error > 1e-5 * magnitude) {
      if (bad++ < 5) CHECK_MESSAGE(false, "row " << r << ": gpu " << y[r] << ", cpu " << expected[r]);
    }
  }
  CHECK(bad == 0);
}

}  // namespace

TEST_CASE("Vulkan: list_devices and choose_device") {
  if (!test::vulkan_wanted()) return;
  const std::vector<DeviceInfo> devices = list_devices();
  for (size_t i = 0; i < devices.size(); ++i) {
    const DeviceInfo& d = devices[i];
    MESSAGE(d.index << ": " << d.name << " [" << d.type << "] " << d.driver << ", "
                    << (d.device_local_bytes >> 20) << " MiB, storage range "
                    << (d.max_storage_buffer_range >> 20) << " MiB, subgroup " << d.subgroup_size);
    CHECK(d.index == static_cast<int>(i));
    CHECK_FALSE(d.name.empty());
    CHECK_FALSE(d.driver.empty());
    CHECK(d.max_storage_buffer_range > 0);
    CHECK(d.subgroup_size > 0);
  }
  const DeviceInfo chosen = choose_device();
  CHECK(chosen.index >= 0);
  CHECK(choose_device(0).name == devices[0].name);
  CHECK_THROWS_AS(choose_device(static_cast<int>(devices.size())), DeviceError);

  const vk::Context context;
  CHECK(context.info().index == chosen.index);
  CHECK(context.limits().max_group_count[0] >= 65535u);
}

// Contexts come and go (one per LP solve) over one process-wide instance: NVIDIA's driver failed
// vkCreateInstance after some dozens of create/destroy cycles in one process.
TEST_CASE("Vulkan: contexts made one after another share the process's instance") {
  if (!test::vulkan_wanted()) return;
  const VkInstance instance = vk::shared_instance();
  REQUIRE(instance != VK_NULL_HANDLE);
  for (int k = 0; k < 3; ++k) {
    vk::Context context;
    CHECK(list_devices().size() >= 1);
    const std::vector<uint32_t> words{1, 2, 3, uint32_t(k)};
    const vk::Buffer buffer = context.upload(std::span<const uint32_t>(words));
    CHECK(context.download<uint32_t>(buffer, words.size()) == words);
  }
  CHECK(vk::shared_instance() == instance);

  // A child forked after Vulkan was initialised must refuse before any driver call (drivers do
  // not support it, and on NVIDIA the attempt broke the parent's next device), and the parent
  // must go on working.
  const pid_t pid = fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    int code = 2;  // 2: the parent's instance came back, 3: some other exception
    try {
      vk::shared_instance();
    } catch (const DeviceError&) {
      code = 0;
    } catch (...) {
      code = 3;
    }
    _exit(code);
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
  CHECK(vk::shared_instance() == instance);
  vk::Context after;
  const std::vector<uint32_t> words{4, 5, 6};
  CHECK(after.download<uint32_t>(after.upload(std::span<const uint32_t>(words)), words.size()) == words);
}

TEST_CASE("Vulkan: dispatch grid stays within the workgroup count limits") {
  const std::array<uint32_t, 3> max{10, 10, 10};
  CHECK(vk::dispatch_grid(0, 256, max) == std::array<uint32_t, 3>{0, 1, 1});
  CHECK(vk::dispatch_grid(1, 256, max) == std::array<uint32_t, 3>{1, 1, 1});
  CHECK(vk::dispatch_grid(2560, 256, max) == std::array<uint32_t, 3>{10, 1, 1});
  CHECK(vk::dispatch_grid(2561, 256, max) == std::array<uint32_t, 3>{10, 2, 1});
  CHECK(vk::dispatch_grid(25600, 256, max) == std::array<uint32_t, 3>{10, 10, 1});
  CHECK_THROWS_AS(vk::dispatch_grid(25601, 256, max), DeviceError);
}

TEST_CASE("Vulkan: buffers round-trip and refuse sizes beyond maxStorageBufferRange") {
  if (!test::vulkan_wanted()) return;
  for (auto transfers : {vk::Context::Transfers::automatic, vk::Context::Transfers::staged}) {
    CAPTURE(static_cast<int>(transfers));
    vk::Context context(-1, transfers);
    std::vector<uint32_t> data(1000);
    std::iota(data.begin(), data.end(), 7u);
    const vk::Buffer buffer = context.upload(std::span<const uint32_t>(data));
    CHECK(context.download<uint32_t>(buffer, data.size()) == data);
    CHECK((buffer.mapped() != nullptr) == context.unified());
    CHECK(context.storage_buffer(0).bytes() == 0);
    try {
      context.storage_buffer(context.limits().max_storage_buffer_range + 1);
      FAIL("no DeviceError");
    } catch (const DeviceError& e) {
      CHECK(std::string(e.what()).find("maxStorageBufferRange") != std::string::npos);
    }
  }
}

TEST_CASE("Vulkan: signed SpMV equals the CPU loop") {
  if (!test::vulkan_wanted()) return;
  vk::Context context;
  vk::SignedSpmv gpu(context);
  std::mt19937 rng(2024);
  for (int64_t rows : {1, 255, 256, 257, 100003}) {
    CAPTURE(rows);
    const int64_t cols = rows / 3 + 5;
    const SignedCsr a = random_csr(rows, cols, 12, rng);
    const SignedCsr at = transpose(a);
    for (bool integers : {true, false}) {
      CAPTURE(integers);
      check_spmv(gpu, a, integers, rng);
      check_spmv(gpu, at, integers, rng);
    }
  }
}

TEST_CASE("Vulkan: signed SpMV with empty rows, empty matrices and more rows than one grid row") {
  if (!test::vulkan_wanted()) return;
  vk::Context context;
  vk::SignedSpmv gpu(context);
  std::mt19937 rng(5);
  check_spmv(gpu, random_csr(0, 4, 3, rng), true, rng);
  check_spmv(gpu, random_csr(300, 1, 0, rng), true, rng);
  // Past 65535 workgroups of 256 the grid becomes 2D on lavapipe (NVIDIA stays 1D).
  const int64_t rows = int64_t{65535} * 256 + 1000;
  check_spmv(gpu, random_csr(rows, 1000, 1, rng), true, rng);
}

// Also with staging buffers, the path of discrete GPUs.
TEST_CASE("Vulkan: A x then Aᵀ y chained in one sequence, submitted twice") {
  if (!test::vulkan_wanted()) return;
  for (auto transfers : {vk::Context::Transfers::automatic, vk::Context::Transfers::staged}) {
    CAPTURE(static_cast<int>(transfers));
    vk::Context context(-1, transfers);
    vk::SignedSpmv gpu(context);
    std::mt19937 rng(9);
    const SignedCsr a = random_csr(5000, 3000, 6, rng);
    const SignedCsr at = transpose(a);
    const std::vector<float> x = random_x(a.cols, true, rng);

    const vk::Buffer a_ptr = context.upload(std::span<const uint32_t>(a.row_ptr));
    const vk::Buffer a_entry = context.upload(std::span<const uint32_t>(a.entry));
    const vk::Buffer at_ptr = context.upload(std::span<const uint32_t>(at.row_ptr));
    const vk::Buffer at_entry = context.upload(std::span<const uint32_t>(at.entry));
    vk::Buffer xb = context.upload(std::span<const float>(x));
    const vk::Buffer y = context.storage_buffer(a.rows * sizeof(float));
    const vk::Buffer z = context.storage_buffer(a.cols * sizeof(float));
    const vk::DescriptorSet forward = gpu.bind(a_ptr, a_entry, xb, y);
    const vk::DescriptorSet backward = gpu.bind(at_ptr, at_entry, y, z);
    vk::Sequence sequence(context);
    gpu.record(sequence, forward, static_cast<uint32_t>(a.rows));
    gpu.record(sequence, backward, static_cast<uint32_t>(at.rows));

    std::vector<float> ey(a.rows), ez(a.cols);
    spmv(a, x.data(), ey.data());
    spmv(at, ey.data(), ez.data());
    sequence.submit_and_wait();
    CHECK(context.download<float>(z, ez.size()) == ez);
    // Resubmission reads the new x.
    std::vector<float> x2(x.size(), 1.0f);
    context.upload(xb, x2.data(), x2.size() * sizeof(float));
    spmv(a, x2.data(), ey.data());
    spmv(at, ey.data(), ez.data());
    sequence.submit_and_wait();
    CHECK(context.download<float>(y, ey.size()) == ey);
    CHECK(context.download<float>(z, ez.size()) == ez);
  }
}
