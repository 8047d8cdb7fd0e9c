#pragma once
// Small helpers shared by the tests.
#include "shapematch/mesh.hpp"

#include "shapematch/device.hpp"
#include "shapematch/errors.hpp"
#include "shapematch/lp.hpp"
#include "shapematch/shapes.hpp"

#include <Eigen/Geometry>
#include <doctest/doctest.h>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sys/wait.h>
#include <optional>
#include <random>
#include <string>

namespace shapematch::test {

// Builds an LP from dense rows with entries in {-1, 0, 1}.
inline LpProblem dense_lp(const std::vector<std::vector<int>>& rows, std::vector<double> b, std::vector<double> c) {
  LpProblem p;
  p.a.rows = static_cast<int64_t>(rows.size());
  p.a.cols = static_cast<int64_t>(c.size());
  p.a.row_ptr.push_back(0);
  for (const auto& r : rows) {
    for (size_t j = 0; j < r.size(); ++j)
      if (r[j] != 0) p.a.entry.push_back(static_cast<uint32_t>(j) | (r[j] < 0 ? SignedCsr::kNegative : 0u));
    p.a.row_ptr.push_back(static_cast<uint32_t>(p.a.entry.size()));
  }
  p.at = transpose(p.a);
  p.b = std::move(b);
  p.c = std::move(c);
  return p;
}

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

// A fresh directory under the system temp dir, removed with everything in it at scope exit.
struct TempDir {
  std::filesystem::path path;
  TempDir() {
    std::random_device rd;
    path = std::filesystem::temp_directory_path() / ("shapematch-test-" + std::to_string(rd()) + std::to_string(rd()));
    std::filesystem::create_directories(path);
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string file(const std::string& name, const std::string& content) const {
    const std::string p = (path / name).string();
    std::ofstream(p, std::ios::binary) << content;
    return p;
  }
  std::string read(const std::string& name) const {
    std::ifstream in(path / name, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }
  std::string operator/(const std::string& name) const { return (path / name).string(); }
};

struct CliRun {
  int code = -1;
  std::string out;  // stdout
  std::string err;  // stderr
};

// Runs a shell command; stderr goes through a file in `dir` (a fresh temporary directory when
// empty, so that tests running in parallel never share it).
inline CliRun run_command(const std::string& command, const std::filesystem::path& dir = {}) {
  std::optional<TempDir> own;
  if (dir.empty()) own.emplace();
  const std::filesystem::path err = (dir.empty() ? own->path : dir) / "stderr.txt";
  const std::string cmd = command + " 2>" + err.string();
  CliRun r;
  FILE* p = popen(cmd.c_str(), "r");
  REQUIRE(p != nullptr);
  std::array<char, 4096> buf{};
  size_t k;
  while ((k = fread(buf.data(), 1, buf.size(), p)) > 0) r.out.append(buf.data(), k);
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream f(err);
  r.err.assign(std::istreambuf_iterator<char>(f), {});
  return r;
}

// Runs the built `shapematch` with `args` (run_command).
inline CliRun run_cli(const std::string& args, const std::filesystem::path& dir = {}) {
  return run_command(std::string(SHAPEMATCH_CLI) + " " + args, dir);
}

// The number after "key": in a JSON text (the CLI's flat outputs).
inline double json_number(const std::string& json, const std::string& key) {
  const auto at = json.find("\"" + key + "\": ");
  REQUIRE_MESSAGE(at != std::string::npos, key << " missing in " << json);
  return std::stod(json.substr(at + key.size() + 4));
}

// icosphere(3) with every vertex's radius scaled by a random factor in [1 − jitter, 1 + jitter]:
// curved and irregular, with obtuse triangles.
inline Mesh bumpy_sphere(double jitter) {
  Mesh m = shapes::icosphere(3);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> scale(1.0 - jitter, 1.0 + jitter);
  std::vector<Eigen::Vector3d> v;
  for (const auto& p : m.vertices) v.push_back(p * scale(rng));
  return make_mesh(v, m.faces, "bumpy");
}

// An ellipsoid with jittered vertices: no symmetries, so a self-match has one zero-energy answer.
inline Mesh lumpy_sphere(int subdivisions, unsigned seed, double jitter = 0.1) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-jitter, jitter);
  return deformed(shapes::icosphere(subdivisions), [&](const Eigen::Vector3d& p) {
    return Eigen::Vector3d(1.3 * p.x() + u(rng), p.y() + u(rng), 0.8 * p.z() + u(rng));
  });
}

}  // namespace shapematch::test
