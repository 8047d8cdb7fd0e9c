#include "shapematch/render.hpp"

#include "shapematch/files.hpp"

#include "shapematch/errors.hpp"

#include <Eigen/Eigenvalues>
#include <spdlog/fmt/fmt.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

// The only translation unit that compiles stb_image_write. Static linkage keeps its symbols
// private, so nothing has to link libstb and nothing clashes with another copy.
#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#include <stb/stb_image_write.h>
#pragma GCC diagnostic pop

namespace shapematch {
namespace {

namespace fs = std::filesystem;
using Eigen::Vector3d;

Vector3d to_vector(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }

// Area-weighted vertex normals: smooth over curved parts, and the weighting keeps tiny
// triangles from tilting a vertex's normal.
std::vector<Vector3d> vertex_normals(const Mesh& mesh) {
  std::vector<Vector3d> normals(mesh.vertices.size(), Vector3d::Zero());
  for (const auto& f : mesh.faces) {
    const Vector3d n = (mesh.vertices[f[1]] - mesh.vertices[f[0]]).cross(mesh.vertices[f[2]] - mesh.vertices[f[0]]);
    for (int v : f) normals[v] += n;
  }
  for (auto& n : normals) n.normalize();  // Eigen leaves a zero vector unchanged
  return normals;
}

// Orthonormal camera frame: right, up, and towards the camera.
struct Camera {
  Vector3d right, up, back;
};

Camera make_camera(const RenderOptions& options) {
  Camera c;
  c.back = to_vector(options.view_direction);
  if (!(c.back.norm() > 0) || !c.back.allFinite())
    throw InvalidInputError("render: view_direction must be a finite, non-zero vector");
  c.back.normalize();
  Vector3d up = to_vector(options.up);
  // Looking straight along `up` leaves no "up" on screen; any perpendicular direction will do.
  if (!up.allFinite() || up.cross(c.back).norm() < 1e-6 * up.norm())
    up = std::abs(c.back.x()) < 0.9 ? Vector3d::UnitX() : Vector3d::UnitY();
  c.right = up.cross(c.back).normalized();
  c.up = c.back.cross(c.right);
  return c;
}

// The shaded colour buffer at supersampled resolution; depth grows towards the camera.
struct Canvas {
  int width, height;
  std::vector<float> color;  // 3 floats per sample, in [0, 255]
  std::vector<double> depth;

  Canvas(int w, int h, const Color& background)
      : width(w), height(h), color(3 * static_cast<std::size_t>(w) * h),
        depth(static_cast<std::size_t>(w) * h, -std::numeric_limits<double>::infinity()) {
    for (std::size_t i = 0; i < depth.size(); ++i)
      for (int k = 0; k < 3; ++k) color[3 * i + k] = background[k];
  }
};

// Where one mesh lands on the canvas: screen x = offset_x + scale * (p . right - center_right), etc.
struct Placement {
  double offset_x, offset_y, scale, center_right, center_up;
};

// The extent of a mesh on the screen plane: (min right, max right, min up, max up).
std::array<double, 4> screen_bounds(const Mesh& mesh, const Camera& cam) {
  std::array<double, 4> b{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                          std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  for (const auto& p : mesh.vertices) {
    const double r = p.dot(cam.right), u = p.dot(cam.up);
    b[0] = std::min(b[0], r);
    b[1] = std::max(b[1], r);
    b[2] = std::min(b[2], u);
    b[3] = std::max(b[3], u);
  }
  return b;
}

// The light comes from above-left of the camera, fixed to the view so that every view direction
// is lit the same way; the ambient term keeps the faces turned away readable, not black.
constexpr double kAmbient = 0.45;
const Vector3d kLightInCamera = Vector3d(-0.45, 0.6, 0.65).normalized();  // (right, up, back)

// Z-buffered rasterisation of one mesh. Colours and normals are interpolated per sample
// (orthographic projection, so screen-space barycentrics are the true ones).
void rasterize(Canvas& canvas, const Mesh& mesh, const std::vector<Color>& colors, const Camera& cam,
               const Placement& place, bool draw_edges, double edge_width) {
  const int n = mesh.num_vertices();
  std::vector<double> sx(n), sy(n), sz(n);
  for (int v = 0; v < n; ++v) {
    const Vector3d& p = mesh.vertices[v];
    sx[v] = place.offset_x + place.scale * (p.dot(cam.right) - place.center_right);
    sy[v] = place.offset_y - place.scale * (p.dot(cam.up) - place.center_up);  // rows grow downwards
    sz[v] = p.dot(cam.back);
  }
  const std::vector<Vector3d> normals = vertex_normals(mesh);
  const Vector3d light = kLightInCamera.x() * cam.right + kLightInCamera.y() * cam.up + kLightInCamera.z() * cam.back;

  for (const auto& f : mesh.faces) {
    const double ax = sx[f[0]], ay = sy[f[0]], bx = sx[f[1]], by = sy[f[1]], cx = sx[f[2]], cy = sy[f[2]];
    // Twice the signed screen area; its sign says which side of the triangle faces the camera.
    const double area = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
    if (std::abs(area) < 1e-12) continue;  // seen edge-on: covers no sample
    // The face normal decides the side so that a triangle seen from behind (an open or
    // self-intersecting input) is lit on the side we see instead of going dark.
    const Vector3d face_normal = (mesh.vertices[f[1]] - mesh.vertices[f[0]]).cross(mesh.vertices[f[2]] - mesh.vertices[f[0]]);
    const double side = face_normal.dot(cam.back) < 0 ? -1.0 : 1.0;
    // Distance in samples from a point to the edge opposite vertex i is w_i * |area| / |edge_i|.
    const std::array<double, 3> edge_length{std::hypot(cx - bx, cy - by), std::hypot(ax - cx, ay - cy),
                                            std::hypot(bx - ax, by - ay)};

    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({ax, bx, cx}))));
    const int x1 = std::min(canvas.width - 1, static_cast<int>(std::ceil(std::max({ax, bx, cx}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({ay, by, cy}))));
    const int y1 = std::min(canvas.height - 1, static_cast<int>(std::ceil(std::max({ay, by, cy}))));
    for (int y = y0; y <= y1; ++y) {
      const double py = y + 0.5;
      for (int x = x0; x <= x1; ++x) {
        const double px = x + 0.5;
        const double w0 = ((cx - bx) * (py - by) - (cy - by) * (px - bx)) / area;
        const double w1 = ((ax - cx) * (py - cy) - (ay - cy) * (px - cx)) / area;
        const double w2 = 1.0 - w0 - w1;
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        const double z = w0 * sz[f[0]] + w1 * sz[f[1]] + w2 * sz[f[2]];
        const std::size_t s = static_cast<std::size_t>(y) * canvas.width + x;
        if (z <= canvas.depth[s]) continue;
        canvas.depth[s] = z;

        Vector3d normal = w0 * normals[f[0]] + w1 * normals[f[1]] + w2 * normals[f[2]];
        normal = side * normal.normalized();
        double shade = kAmbient + (1.0 - kAmbient) * std::max(0.0, normal.dot(light));
        if (draw_edges) {
          const double d = std::min({w0 * std::abs(area) / edge_length[0], w1 * std::abs(area) / edge_length[1],
                                     w2 * std::abs(area) / edge_length[2]});
          if (d < edge_width) shade *= 0.45;
        }
        for (int k = 0; k < 3; ++k) {
          const double c = w0 * colors[f[0]][k] + w1 * colors[f[1]][k] + w2 * colors[f[2]][k];
          canvas.color[3 * s + k] = static_cast<float>(std::min(255.0, c * shade));
        }
      }
    }
  }
}

void check_colors(const Mesh& mesh, const std::vector<Color>& colors, const char* which) {
  if (colors.size() != mesh.vertices.size())
    throw InvalidInputError(fmt::format("render: {} colours for the {} vertices of {} ({})", colors.size(),
                                        mesh.vertices.size(), which, mesh.name));
}

}  // namespace

std::vector<Color> smooth_colors(const Mesh& x) {
  const std::size_t n = x.vertices.size();
  if (n == 0) return {};
  Vector3d mean = Vector3d::Zero();
  for (const auto& p : x.vertices) mean += p;
  mean /= static_cast<double>(n);
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const auto& p : x.vertices) covariance += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  // Eigen sorts eigenvalues increasingly; red goes to the largest spread.
  const Eigen::Matrix3d axes = eigen.eigenvectors().rowwise().reverse();

  std::vector<Vector3d> coords(n);
  Vector3d lo = Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t v = 0; v < n; ++v) {
    coords[v] = axes.transpose() * (x.vertices[v] - mean);
    lo = lo.cwiseMin(coords[v]);
    hi = hi.cwiseMax(coords[v]);
  }
  std::vector<Color> colors(n);
  for (std::size_t v = 0; v < n; ++v) {
    for (int k = 0; k < 3; ++k) {
      const double range = hi[k] - lo[k];
      const double t = range > 0 ? (coords[v][k] - lo[k]) / range : 0.5;
      // A floor keeps every channel off zero so no part turns black once it is shaded.
      colors[v][k] = static_cast<uint8_t>(std::lround(255.0 * (0.2 + 0.8 * t)));
    }
  }
  return colors;
}

std::vector<Color> transfer_colors(const std::vector<Color>& colors_x, const std::vector<int>& map_y_to_x) {
  std::vector<Color> colors_y(map_y_to_x.size());
  for (std::size_t j = 0; j < map_y_to_x.size(); ++j) {
    const int i = map_y_to_x[j];
    if (i < 0 || static_cast<std::size_t>(i) >= colors_x.size())
      throw InvalidInputError(fmt::format("transfer_colors: vertex {} of Y maps to {}, not a vertex of X (which has {})",
                                          j, i, colors_x.size()));
    colors_y[j] = colors_x[i];
  }
  return colors_y;
}

Image render_side_by_side(const Mesh& x, const std::vector<Color>& colors_x, const Mesh& y,
                          const std::vector<Color>& colors_y, const RenderOptions& options) {
  if (options.width < 2 || options.height < 1 || options.supersampling < 1 || options.supersampling > 8)
    throw InvalidInputError(fmt::format("render: need width >= 2, height >= 1 and supersampling in [1, 8], got {}x{}, {}",
                                        options.width, options.height, options.supersampling));
  check_colors(x, colors_x, "X");
  check_colors(y, colors_y, "Y");
  const Camera cam = make_camera(options);
  const int ss = options.supersampling;
  Canvas canvas(options.width * ss, options.height * ss, options.background);

  // One scale for both meshes: the largest at which each fits its half with a margin.
  const double half_width = 0.5 * canvas.width, margin = 0.06;
  const std::array<const Mesh*, 2> meshes{&x, &y};
  std::array<std::array<double, 4>, 2> bounds;
  double scale = std::numeric_limits<double>::infinity();
  for (int m = 0; m < 2; ++m) {
    bounds[m] = screen_bounds(*meshes[m], cam);
    const double w = bounds[m][1] - bounds[m][0], h = bounds[m][3] - bounds[m][2];
    if (w > 0) scale = std::min(scale, (1 - 2 * margin) * half_width / w);
    if (h > 0) scale = std::min(scale, (1 - 2 * margin) * canvas.height / h);
  }
  if (!std::isfinite(scale)) scale = 1.0;  // nothing with extent to draw: any scale works

  const std::array<const std::vector<Color>*, 2> colors{&colors_x, &colors_y};
  for (int m = 0; m < 2; ++m) {
    if (meshes[m]->vertices.empty()) continue;
    const Placement place{(m + 0.5) * half_width, 0.5 * canvas.height, scale, 0.5 * (bounds[m][0] + bounds[m][1]),
                          0.5 * (bounds[m][2] + bounds[m][3])};
    rasterize(canvas, *meshes[m], *colors[m], cam, place, options.draw_edges, 0.6 * ss);
  }

  // Box-filter the samples down to pixels.
  Image image{options.width, options.height, std::vector<uint8_t>(3 * static_cast<std::size_t>(options.width) * options.height)};
  for (int py = 0; py < image.height; ++py)
    for (int px = 0; px < image.width; ++px)
      for (int k = 0; k < 3; ++k) {
        double sum = 0;
        for (int dy = 0; dy < ss; ++dy)
          for (int dx = 0; dx < ss; ++dx)
            sum += canvas.color[3 * (static_cast<std::size_t>(py * ss + dy) * canvas.width + px * ss + dx) + k];
        image.rgb[3 * (static_cast<std::size_t>(py) * image.width + px) + k] =
            static_cast<uint8_t>(std::lround(sum / (ss * ss)));
      }
  return image;
}

void write_png(const Image& image, const std::string& path) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgb.size() != 3 * static_cast<std::size_t>(image.width) * image.height)
    throw InvalidInputError(fmt::format("{}: cannot write a {}x{} image with {} bytes as PNG", path, image.width,
                                        image.height, image.rgb.size()));
  // Encode in memory first, so that every failure of the file system is caught by the stream.
  std::string png;
  auto append = [](void* context, void* data, int size) {
    static_cast<std::string*>(context)->append(static_cast<const char*>(data), size);
  };
  if (!stbi_write_png_to_func(append, &png, image.width, image.height, 3, image.rgb.data(), 3 * image.width))
    throw IoError(path + ": PNG encoding failed");

  write_file_atomic(path, [&](std::ostream& out) { out.write(png.data(), static_cast<std::streamsize>(png.size())); });
}

}  // namespace shapematch
