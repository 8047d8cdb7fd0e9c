#include "shapematch/shapes.hpp"

#include "shapematch/errors.hpp"

#include <spdlog/fmt/fmt.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>

namespace shapematch::shapes {

Mesh tetrahedron() {
  return make_mesh({{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}},
                   {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}}, "tetrahedron");
}

Mesh octahedron() {
  return make_mesh({{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}},
                   {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}},
                   "octahedron");
}

Mesh icosphere(int subdivisions, double radius) {
  if (subdivisions < 0 || subdivisions > 10 || !(radius > 0))
    throw InvalidInputError(fmt::format("icosphere: need 0 <= subdivisions <= 10 and radius > 0, got {} and {}",
                                        subdivisions, radius));
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> vertices = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                           {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> faces = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                           {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                           {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                           {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& p : vertices) p.normalize();
  for (int level = 0; level < subdivisions; ++level) {
    // Each edge gets one midpoint, shared by its two faces.
    std::map<std::pair<int, int>, int> midpoint;
    auto split = [&](int u, int v) {
      const auto [it, inserted] = midpoint.try_emplace({std::min(u, v), std::max(u, v)}, 0);
      if (inserted) {
        it->second = static_cast<int>(vertices.size());
        vertices.push_back((vertices[u] + vertices[v]).normalized());
      }
      return it->second;
    };
    std::vector<std::array<int, 3>> finer;
    finer.reserve(4 * faces.size());
    for (const auto& [a, b, c] : faces) {
      const int ab = split(a, b), bc = split(b, c), ca = split(c, a);
      finer.insert(finer.end(), {{a, ab, ca}, {ab, b, bc}, {ca, bc, c}, {ab, bc, ca}});
    }
    faces = std::move(finer);
  }
  for (auto& p : vertices) p *= radius;
  return make_mesh(std::move(vertices), std::move(faces), fmt::format("icosphere({}, {})", subdivisions, radius));
}

Mesh torus(int n_major, int n_minor, double major_radius, double minor_radius) {
  if (n_major < 3 || n_minor < 3 || !(minor_radius > 0) || !(major_radius > minor_radius))
    throw InvalidInputError(fmt::format("torus: need n_major, n_minor >= 3 and major_radius > minor_radius > 0, "
                                        "got {}, {}, {}, {}",
                                        n_major, n_minor, major_radius, minor_radius));
  std::vector<Eigen::Vector3d> vertices;
  vertices.reserve(n_major * n_minor);
  for (int i = 0; i < n_major; ++i) {
    const double u = 2.0 * M_PI * i / n_major;
    for (int j = 0; j < n_minor; ++j) {
      const double v = 2.0 * M_PI * j / n_minor;
      const double rho = major_radius + minor_radius * std::cos(v);
      vertices.emplace_back(rho * std::cos(u), rho * std::sin(u), minor_radius * std::sin(v));
    }
  }
  // d/du x d/dv points outwards, so (i, j), (i+1, j), (i+1, j+1), (i, j+1) is counter-clockwise.
  std::vector<std::array<int, 3>> faces;
  faces.reserve(2 * n_major * n_minor);
  auto index = [&](int i, int j) { return (i % n_major) * n_minor + (j % n_minor); };
  for (int i = 0; i < n_major; ++i)
    for (int j = 0; j < n_minor; ++j) {
      const int a = index(i, j), b = index(i + 1, j), c = index(i + 1, j + 1), d = index(i, j + 1);
      faces.push_back({a, b, c});
      faces.push_back({a, c, d});
    }
  return make_mesh(std::move(vertices), std::move(faces), fmt::format("torus({}, {})", n_major, n_minor));
}

namespace {

// Faces of a closed tube: a pole vertex 0, `rings` rings of `segments` vertices, a pole last.
// theta grows counter-clockwise around the axis and rings grow along it: (a, b, c), (a, c, d)
// face out.
std::vector<std::array<int, 3>> tube_faces(int rings, int segments) {
  const int top = rings * segments + 1;
  auto ring = [&](int i, int j) { return 1 + i * segments + j % segments; };
  std::vector<std::array<int, 3>> faces;
  faces.reserve(2 * rings * segments);
  for (int j = 0; j < segments; ++j) {
    faces.push_back({0, ring(0, j + 1), ring(0, j)});
    for (int i = 0; i + 1 < rings; ++i) {
      const int a = ring(i, j), b = ring(i, j + 1), c = ring(i + 1, j + 1), d = ring(i + 1, j);
      faces.push_back({a, b, c});
      faces.push_back({a, c, d});
    }
    faces.push_back({top, ring(rings - 1, j), ring(rings - 1, j + 1)});
  }
  return faces;
}

// Ring i of `rings` on a capsule (hemispherical caps of `radius`, a cylinder between): its
// position s along the axis and distance r from it. Rings are equally spaced in arc length
// along the meridian, so caps and cylinder get triangles of the same size.
std::pair<double, double> capsule_ring(int i, int rings, double radius, double cylinder) {
  const double cap = M_PI * radius / 2.0, profile = 2.0 * cap + cylinder, length = cylinder + 2 * radius;
  const double t = profile * (i + 1) / (rings + 1);
  if (t < cap) return {radius * (1 - std::cos(t / radius)), radius * std::sin(t / radius)};
  if (t <= cap + cylinder) return {radius + (t - cap), radius};
  return {length - radius * (1 - std::cos((profile - t) / radius)), radius * std::sin((profile - t) / radius)};
}

// The vertices of a capsule's tube (tube_faces' order): point(s, r, theta) at both poles and at
// every ring, s along the axis, r from it, theta around it.
template <class Point>
std::vector<Eigen::Vector3d> capsule_vertices(const Point& point, int rings, int segments, double radius,
                                              double cylinder) {
  std::vector<Eigen::Vector3d> vertices;
  vertices.reserve(rings * segments + 2);
  vertices.push_back(point(0, 0, 0));
  for (int i = 0; i < rings; ++i) {
    const auto [s, r] = capsule_ring(i, rings, radius, cylinder);
    for (int j = 0; j < segments; ++j) vertices.push_back(point(s, r, 2 * M_PI * j / segments));
  }
  vertices.push_back(point(cylinder + 2 * radius, 0, 0));
  return vertices;
}

}  // namespace

Mesh bent_finger(double bend_degrees, int rings, int segments) {
  if (rings < 2 || segments < 3 || !std::isfinite(bend_degrees))
    throw InvalidInputError(fmt::format("bent_finger: need rings >= 2, segments >= 3 and a finite angle, "
                                        "got {}, {}, {}",
                                        rings, segments, bend_degrees));
  // A capsule along +z from s = 0 (base) to s = length (tip), bent towards -y (the palm).
  constexpr double radius = 0.5, cylinder = 3.0, length = cylinder + 2 * radius;
  constexpr double joint = length / 2, joint_width = 1.5;
  const double bend = bend_degrees * M_PI / 180.0;
  const double joint_begin = joint - joint_width / 2, joint_end = joint + joint_width / 2;

  // Tangent angle of the axis: 0 before the joint, `bend` after it, a C2 smootherstep between.
  auto angle = [&](double s) {
    const double u = std::clamp((s - joint_begin) / joint_width, 0.0, 1.0);
    return bend * u * u * u * (u * (6 * u - 15) + 10);
  };
  auto tangent = [&](double s) { return Eigen::Vector3d(0, -std::sin(angle(s)), std::cos(angle(s))); };
  // The axis c(s) = integral of the tangent: straight outside the joint, Simpson's rule inside.
  auto axis = [&](double s) {
    if (s <= joint_begin) return Eigen::Vector3d(0, 0, s);
    const double end = std::min(s, joint_end);
    constexpr int n = 256;
    const double h = (end - joint_begin) / n;
    Eigen::Vector3d sum = tangent(joint_begin) + tangent(end);
    for (int k = 1; k < n; ++k) sum += (k % 2 ? 4.0 : 2.0) * tangent(joint_begin + k * h);
    Eigen::Vector3d c = Eigen::Vector3d(0, 0, joint_begin) + sum * (h / 3.0);
    if (s > joint_end) c += (s - joint_end) * tangent(joint_end);
    return c;
  };
  // A point at distance r from the axis in direction theta (0 = +x, pi/2 = +y, the back), in the
  // cross-section plane, which turns with the axis so that the bend keeps it perpendicular.
  auto point = [&](double s, double r, double theta) {
    const double taper = 1.0 - 0.2 * s / length;  // the tip is thinner than the base
    const double around = std::remainder(theta - M_PI / 2, 2 * M_PI);
    const double knuckle = 1.0 + 0.25 * std::exp(-(s - joint) * (s - joint) / (2 * 0.3 * 0.3)) *
                                     std::exp(-around * around / (2 * 0.6 * 0.6));
    const double d = r * taper * knuckle;
    const Eigen::Vector3d back(0, std::cos(angle(s)), std::sin(angle(s)));  // +y turned like the axis
    return Eigen::Vector3d(axis(s) + d * std::cos(theta) * Eigen::Vector3d::UnitX() + d * std::sin(theta) * back);
  };

  std::vector<Eigen::Vector3d> vertices = capsule_vertices(point, rings, segments, radius, cylinder);

  return make_mesh(std::move(vertices), tube_faces(rings, segments), fmt::format("bent_finger({})", bend_degrees));
}

Mesh dolphin(double head_bend_degrees, double tail_bend_degrees, int rings, int segments) {
  if (rings < 2 || segments < 3 || !std::isfinite(head_bend_degrees) || !std::isfinite(tail_bend_degrees))
    throw InvalidInputError(fmt::format("dolphin: need rings >= 2, segments >= 3 and finite angles, got {}, {}, {}, {}",
                                        rings, segments, head_bend_degrees, tail_bend_degrees));
  // A capsule along +z from s = 0 (tail) to s = 4 (head), reshaped: the thickness profile
  // breaks the end-to-end symmetry, the dorsal fin on +y and the flat tail (flukes in x) break
  // every rotation about the spine. Only the mirror x -> -x remains, which reverses orientation,
  // so a matching that keeps orientation has exactly one right answer.
  constexpr double radius = 0.5, cylinder = 3.0;
  constexpr double tail_joint = 1.3, head_joint = 2.9, joint_width = 1.0;
  const double tail_bend = tail_bend_degrees * M_PI / 180.0, head_bend = head_bend_degrees * M_PI / 180.0;

  auto smootherstep = [](double u) {
    u = std::clamp(u, 0.0, 1.0);
    return u * u * u * (u * (6 * u - 15) + 10);
  };
  // The spine turns up and down (in the y-z plane, as a dolphin swims) at two joints.
  auto angle = [&](double s) {
    return tail_bend * smootherstep((s - tail_joint) / joint_width + 0.5) +
           head_bend * smootherstep((s - head_joint) / joint_width + 0.5);
  };
  auto tangent = [&](double s) { return Eigen::Vector3d(0, std::sin(angle(s)), std::cos(angle(s))); };
  auto axis = [&](double s) {  // Simpson's rule for the integral of the tangent from the tail
    constexpr int n = 256;
    const double h = s / n;
    Eigen::Vector3d sum = tangent(0) + tangent(s);
    for (int k = 1; k < n; ++k) sum += (k % 2 ? 4.0 : 2.0) * tangent(k * h);
    return Eigen::Vector3d(sum * (h / 3.0));
  };
  auto point = [&](double s, double r, double theta) {
    // Thickest behind the head, thin at the tail; the tail is flattened into horizontal flukes.
    const double body = 0.35 + 0.95 * std::exp(-(s - 2.8) * (s - 2.8) / (1.4 * 1.4));
    const double tail = std::exp(-s * s / (0.7 * 0.7));
    const double width = 0.75 * (1.0 + 1.5 * tail), height = 1.0 - 0.6 * tail;
    const double around = std::remainder(theta - M_PI / 2, 2 * M_PI);  // 0 on the back (+y)
    const double fin = 1.0 + 0.7 * std::exp(-(s - 2.0) * (s - 2.0) / (0.6 * 0.6)) *
                                 std::exp(-around * around / (2 * 0.25 * 0.25));
    const double d = r * body;
    const double a = angle(s);
    const Eigen::Vector3d up(0, std::cos(a), -std::sin(a));  // +y turned with the spine
    return Eigen::Vector3d(axis(s) + d * width * std::cos(theta) * Eigen::Vector3d::UnitX() +
                           d * height * fin * std::sin(theta) * up);
  };

  std::vector<Eigen::Vector3d> vertices = capsule_vertices(point, rings, segments, radius, cylinder);
  // Turn the spine from +z to (1, 0, -1): the renderer's default camera, from (1, 0.5, 1), then
  // sees the dolphin from its side and a little above.
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.75 * M_PI, Eigen::Vector3d::UnitY()).toRotationMatrix();
  for (auto& p : vertices) p = turn * p;
  return make_mesh(std::move(vertices), tube_faces(rings, segments),
                   fmt::format("dolphin({}, {})", head_bend_degrees, tail_bend_degrees));
}

void write_bundled_assets(const std::string& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw IoError(dir + ": cannot create directory (" + ec.message() + ")");
  // 30 rings x 20 segments: 1200 faces, nearly equilateral triangles on the cylinder.
  save_mesh(bent_finger(10.0, 30, 20), (fs::path(dir) / "finger_straight.off").string());
  save_mesh(bent_finger(70.0, 30, 20), (fs::path(dir) / "finger_bent.off").string());
  save_mesh(dolphin(0.0, 5.0, 30, 20), (fs::path(dir) / "dolphin_straight.off").string());
  save_mesh(dolphin(-40.0, 45.0, 30, 20), (fs::path(dir) / "dolphin_swimming.off").string());
}

}  // namespace shapematch::shapes
