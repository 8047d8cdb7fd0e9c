#pragma once
// Colouring a correspondence and looking at it: vertex colours that vary smoothly over X, the
// same colours carried to Y through a vertex map, and a headless software renderer that draws
// X and Y side by side in those colours and writes a PNG.
#include "shapematch/mesh.hpp"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace shapematch {

using Color = std::array<uint8_t, 3>;

// An 8-bit RGB image, row-major, top row first, 3 bytes per pixel.
struct Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;

  Color pixel(int x, int y) const {
    const std::size_t i = 3 * (static_cast<std::size_t>(y) * width + x);
    return {rgb[i], rgb[i + 1], rgb[i + 2]};
  }
};

// One colour per vertex of x that varies smoothly and spreads over the colour cube: the vertex
// coordinates along x's principal axes (largest spread first), each normalised to [0, 1], become
// red, green and blue. Distant parts of the shape get clearly different colours, and the third
// axis separates left from right, so a flipped (orientation-reversing) match would show.
std::vector<Color> smooth_colors(const Mesh& x);

// Colours for Y: vertex j of Y gets the colour of its matched vertex map_y_to_x[j] of X.
// Throws InvalidInputError if an entry is not a vertex of X.
std::vector<Color> transfer_colors(const std::vector<Color>& colors_x, const std::vector<int>& map_y_to_x);

struct RenderOptions {
  int width = 1600, height = 800;
  // Towards the camera, in mesh coordinates (orthographic projection). The default looks from
  // front-right and a little above for a y-up shape: a 3/4 view that shows depth.
  std::array<double, 3> view_direction{1.0, 0.5, 1.0};
  // The direction that points up on screen (projected perpendicular to view_direction).
  std::array<double, 3> up{0.0, 1.0, 0.0};
  Color background{255, 255, 255};
  bool draw_edges = false;  // darken the triangle edges (wireframe over the shading)
  int supersampling = 2;    // samples per pixel along each axis, averaged: smooth silhouettes
};

// Draws x in the left half and y in the right half of one image, both seen from the same
// direction and at the same scale (so relative sizes are honest), each centred in its half and
// together as large as the halves allow. Z-buffered triangles, per-vertex colours and normals
// interpolated per pixel, Lambert shading from a light above-left of the camera plus ambient.
// Throws InvalidInputError on a colour count that does not match a mesh or on bad options.
Image render_side_by_side(const Mesh& x, const std::vector<Color>& colors_x, const Mesh& y,
                          const std::vector<Color>& colors_y, const RenderOptions& options = {});

// Writes the image as PNG through a temporary file renamed into place. Throws IoError naming
// the path if it cannot be written.
void write_png(const Image& image, const std::string& path);

}  // namespace shapematch
