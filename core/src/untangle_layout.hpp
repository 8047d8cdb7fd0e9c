#pragma once
// Unfolding a planar layout of a triangulated disc with its rim held (point_map.cpp's discs).
#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <vector>

namespace shapematch::detail {

struct UntangleLayoutOptions {
  int max_rounds = 40;          // ε steps
  int max_steps = 300;          // quasi-Newton steps per ε
  double area_weight = 1.0 / 16;  // of the area term beside the conformal one
  int64_t max_work = 200'000'000;  // triangle evaluations in all (a bound on time)
};

struct UntangleLayoutResult {
  int inverted_before = 0;  // triangles with area <= 0 in the layout given
  int inverted_after = 0;
  int rounds = 0;
  int64_t work = 0;
};

// Moves the free vertices of `layout` so that no triangle of `triangles` (counterclockwise when
// right) has area <= 0, its other vertices held: a minimiser of a conformal plus area energy
// whose barrier χ(det, ε) = (det + sqrt(ε² + det²)) / 2 is relaxed, so that it is finite at
// inverted triangles, and ε is shrunk until none is left (after Garanzha et al., "Foldover-free
// maps in 50 lines of code", SIGGRAPH 2021). Tutte's embedding is sure not to fold only where the
// rim is convex; this unfolds what a simple rim allows. `rest` gives each vertex's 3D position,
// the triangles' shapes to keep. `layout` becomes the best layout seen, the one given included
// (fewest inverted, then the largest worst det).
UntangleLayoutResult untangle_layout(const std::vector<std::array<int, 3>>& triangles,
                                     const std::vector<Eigen::Vector3d>& rest, const std::vector<char>& free,
                                     std::vector<Eigen::Vector2d>& layout, const UntangleLayoutOptions& options = {});

}  // namespace shapematch::detail
