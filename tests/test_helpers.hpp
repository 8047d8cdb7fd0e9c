#pragma once
// Small helpers shared by the tests.
#include "shapematch/mesh.hpp"

#include <Eigen/Geometry>
#include <random>

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

}  // namespace shapematch::test
