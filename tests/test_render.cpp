#include "shapematch/errors.hpp"
#include "shapematch/render.hpp"
#include "shapematch/shapes.hpp"

#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <numeric>
#include <random>

using namespace shapematch;
namespace fs = std::filesystem;

namespace {

bool is_background(const Color& c, const Color& background) { return c == background; }
int brightness(const Color& c) { return c[0] + c[1] + c[2]; }

std::vector<Color> uniform(const Mesh& m, Color c) { return std::vector<Color>(m.vertices.size(), c); }

}  // namespace

TEST_CASE("render: an icosphere appears in the middle of each half, the corners stay background") {
  const Mesh sphere = shapes::icosphere(2);
  RenderOptions options;
  options.width = 200;
  options.height = 100;
  const Image image = render_side_by_side(sphere, uniform(sphere, {200, 80, 80}), sphere,
                                          uniform(sphere, {80, 80, 200}), options);
  REQUIRE(image.width == 200);
  REQUIRE(image.height == 100);
  REQUIRE(image.rgb.size() == 200u * 100u * 3u);
  CHECK_FALSE(is_background(image.pixel(50, 50), options.background));
  CHECK_FALSE(is_background(image.pixel(150, 50), options.background));
  // Each half shows its own mesh's colour: red left, blue right.
  CHECK(image.pixel(50, 50)[0] > image.pixel(50, 50)[2]);
  CHECK(image.pixel(150, 50)[2] > image.pixel(150, 50)[0]);
  for (auto [x, y] : {std::pair{0, 0}, {199, 0}, {0, 99}, {199, 99}, {100, 0}, {100, 99}})
    CHECK(is_background(image.pixel(x, y), options.background));
}

TEST_CASE("render: the sphere is brighter on the lit side (above left) than on the far side") {
  const Mesh sphere = shapes::icosphere(3);
  RenderOptions options;
  options.width = 200;
  options.height = 100;
  options.background = {0, 0, 0};
  const auto white = uniform(sphere, {255, 255, 255});
  const Image image = render_side_by_side(sphere, white, sphere, white, options);
  // The sphere of the left half is centred at (50, 50) with radius 44 pixels.
  const Color lit = image.pixel(50 - 15, 50 - 20), dark = image.pixel(50 + 25, 50 + 25);
  CHECK(brightness(lit) > brightness(dark) + 150);
  CHECK(brightness(dark) > 0);  // ambient light: the shadowed side is not black
}

TEST_CASE("render: edges are drawn darker when asked") {
  const Mesh sphere = shapes::icosphere(1);
  RenderOptions options;
  options.width = 200;
  options.height = 100;
  const auto white = uniform(sphere, {255, 255, 255});
  const Image plain = render_side_by_side(sphere, white, sphere, white, options);
  options.draw_edges = true;
  const Image edged = render_side_by_side(sphere, white, sphere, white, options);
  long sum_plain = 0, sum_edged = 0;
  for (std::size_t i = 0; i < plain.rgb.size(); ++i) {
    sum_plain += plain.rgb[i];
    sum_edged += edged.rgb[i];
  }
  CHECK(sum_edged < sum_plain);
}

TEST_CASE("render: a colour count that does not match the mesh is rejected") {
  const Mesh sphere = shapes::icosphere(1);
  CHECK_THROWS_AS(render_side_by_side(sphere, uniform(sphere, {1, 2, 3}), sphere, {}, {}), InvalidInputError);
}

TEST_CASE("render: transfer_colors with the identity map reproduces the colours") {
  const Mesh finger = shapes::bent_finger(30.0, 8, 6);
  const auto colors = smooth_colors(finger);
  std::vector<int> identity(finger.vertices.size());
  std::iota(identity.begin(), identity.end(), 0);
  CHECK(transfer_colors(colors, identity) == colors);
  CHECK(transfer_colors(colors, {2, 0})[0] == colors[2]);
  CHECK_THROWS_AS(transfer_colors(colors, {static_cast<int>(colors.size())}), InvalidInputError);
  CHECK_THROWS_AS(transfer_colors(colors, {-1}), InvalidInputError);
}

TEST_CASE("render: smooth_colors tells the two ends of the bent finger apart and varies smoothly") {
  const Mesh finger = shapes::bent_finger(70.0);
  const auto colors = smooth_colors(finger);
  REQUIRE(colors.size() == finger.vertices.size());
  // bent_finger puts the base pole first and the tip pole last.
  const Color base = colors.front(), tip = colors.back();
  int difference = 0;
  for (int k = 0; k < 3; ++k) difference += std::abs(int(base[k]) - int(tip[k]));
  CHECK(difference > 150);
  // Neighbours get similar colours: no edge jumps by more than a fraction of the range.
  int largest_jump = 0;
  for (const auto& e : finger.edges)
    for (int k = 0; k < 3; ++k)
      largest_jump = std::max(largest_jump, std::abs(int(colors[e[0]][k]) - int(colors[e[1]][k])));
  CHECK(largest_jump < 60);
}

TEST_CASE("render: write_png writes a PNG file and names the path when it cannot") {
  std::random_device rd;
  const fs::path dir = fs::temp_directory_path() / ("shapematch-render-" + std::to_string(rd()));
  fs::create_directories(dir);
  const Mesh sphere = shapes::icosphere(1);
  RenderOptions options;
  options.width = 40;
  options.height = 20;
  const auto colors = smooth_colors(sphere);
  const Image image = render_side_by_side(sphere, colors, sphere, colors, options);
  const std::string path = (dir / "out.png").string();
  write_png(image, path);
  std::ifstream in(path, std::ios::binary);
  std::string head(8, '\0');
  in.read(head.data(), 8);
  CHECK(head == std::string("\x89PNG\r\n\x1a\n", 8));
  CHECK(std::distance(fs::directory_iterator(dir), fs::directory_iterator()) == 1);  // no temporary left

  const std::string bad = (dir / "missing" / "out.png").string();
  try {
    write_png(image, bad);
    FAIL("expected IoError");
  } catch (const IoError& e) {
    CHECK(std::string(e.what()).find(bad) != std::string::npos);
  }
  fs::remove_all(dir);
}
