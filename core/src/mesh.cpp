#include "shapematch/mesh.hpp"

#include "shapematch/files.hpp"

#include "shapematch/errors.hpp"

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
#include <spdlog/fmt/fmt.h>
#include <spdlog/spdlog.h>

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <numeric>
#include <sstream>
#include <string_view>

namespace shapematch {
namespace {

namespace fs = std::filesystem;

// Beyond these counts int indices overflow: vertices directly, faces through the 3|F| = 2|E|
// directed edges and corners.
constexpr int64_t kMaxVertices = INT_MAX;
constexpr int64_t kMaxFaces = INT_MAX / 3;
// Beyond this a coordinate's fourth power (a squared area) overflows a double.
constexpr double kMaxCoordinate = 1e75;

[[noreturn]] void fail(const std::string& name, const std::string& problem) {
  throw InvalidInputError(name + ": " + problem);
}

std::string too_large(int64_t num_vertices, int64_t num_faces) {
  return fmt::format("too large: {} vertices and {} faces (at most {} and {} fit 32-bit indices)",
                     num_vertices, num_faces, kMaxVertices, kMaxFaces);
}

// Polygons as a file states them, before triangulation; indices are 0-based and unchecked.
struct RawMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<int64_t> indices;    // all polygons' vertex indices, concatenated
  std::vector<size_t> offsets{0};  // polygon p is indices[offsets[p], offsets[p + 1])
  // What the reader found odd but could parse (OFF: a plain vertex line with more than three
  // numbers): added to a validation error, which it may explain, else a warning.
  std::string oddity;

  size_t num_polygons() const { return offsets.size() - 1; }
  void end_polygon() { offsets.push_back(indices.size()); }
};

// ---- text formats -----------------------------------------------------------------------------

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> tokens;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    const size_t start = i;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
  return tokens;
}

// from_chars is locale-independent and accepts "nan"/"inf", which validation then reports.
bool parse(std::string_view s, double& x) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), x);
  return ec == std::errc() && end == s.data() + s.size();
}

bool parse(std::string_view s, int64_t& x) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), x);
  return ec == std::errc() && end == s.data() + s.size();
}

// Reads a text file line by line, dropping '#' comments and blank lines.
class LineReader {
public:
  explicit LineReader(const std::string& path) : path_(path), in_(open_for_reading(path)) {}
  // The next non-blank line as tokens (views into an internal buffer valid until the next call).
  bool next(std::vector<std::string_view>& tokens) {
    while (std::getline(in_, line_)) {
      ++line_number_;
      if (const size_t hash = line_.find('#'); hash != std::string::npos) line_.resize(hash);
      tokens = split(line_);
      if (!tokens.empty()) return true;
    }
    if (in_.bad()) throw IoError(path_ + ": read error");
    return false;
  }
  int64_t line_number() const { return line_number_; }

private:
  std::string path_;
  std::ifstream in_;
  std::string line_;
  int64_t line_number_ = 0;
};

RawMesh read_off(const std::string& path) {
  LineReader reader(path);
  std::vector<std::string_view> t;
  if (!reader.next(t)) fail(path, "empty file");
  // Header keyword [ST][C][N][4][n]OFF; the 4 and n variants are not 3D.
  const std::string_view key = t[0];
  if (key.size() < 3 || key.substr(key.size() - 3) != "OFF") fail(path, "missing OFF header");
  if (key.find_first_of("4n") != std::string_view::npos) fail(path, "only 3D OFF files are supported");
  // A plain OFF vertex is three numbers: more on its line is most often a face read as a vertex
  // because the header's count is too large, which then fails in the faces, and the error says so.
  // (Some writers put colours there all the same. COFF, NOFF, STOFF… add fields of their own.)
  // (Decided now: `key` views the reader's line, which the next line replaces.)
  const bool plain = key == "OFF";
  if (t.size() > 1 && t[1] == "BINARY") fail(path, "binary OFF is not supported");
  size_t first = 1;
  if (t.size() == 1) {
    if (!reader.next(t)) fail(path, "no faces");
    first = 0;
  }
  int64_t nv = 0, nf = 0;
  if (t.size() < first + 2 || !parse(t[first], nv) || !parse(t[first + 1], nf) || nv < 0 || nf < 0)
    fail(path, fmt::format("line {}: expected the vertex and face counts", reader.line_number()));
  if (nv > kMaxVertices || nf > kMaxFaces) fail(path, too_large(nv, nf));

  RawMesh raw;
  // Headers can lie: do not let one trigger a huge allocation.
  raw.vertices.reserve(std::min<int64_t>(nv, 1 << 20));
  const auto vertex_tokens = [](const std::vector<std::string_view>& tokens) {
    std::string s;
    for (std::string_view token : tokens) {
      if (!s.empty()) s += ' ';
      s.append(token.substr(0, 24));
    }
    return s;
  };
  for (int64_t i = 0; i < nv; ++i) {
    if (!reader.next(t)) fail(path, fmt::format("file ends after {} of {} vertices", i, nv));
    Eigen::Vector3d p;
    if (t.size() < 3 || !parse(t[0], p.x()) || !parse(t[1], p.y()) || !parse(t[2], p.z()))
      fail(path, fmt::format("line {}: vertex {} needs three numbers, got '{}'", reader.line_number(), i,
                             vertex_tokens(t)));
    if (plain && t.size() > 3 && raw.oddity.empty())  // (the first such line)
      raw.oddity = fmt::format("line {} gave vertex {} {} numbers: is the header's vertex count, {}, too large?",
                               reader.line_number(), i, t.size(), nv);
    raw.vertices.push_back(p);
  }
  const auto fail_faces = [&](const std::string& problem) {
    fail(path, raw.oddity.empty() ? problem : problem + " (" + raw.oddity + ")");
  };
  for (int64_t f = 0; f < nf; ++f) {
    if (!reader.next(t)) fail_faces(fmt::format("file ends after {} of {} faces", f, nf));
    int64_t n = 0;
    if (!parse(t[0], n) || n < 0 || static_cast<int64_t>(t.size()) < n + 1)
      fail_faces(fmt::format("line {}: malformed face {}", reader.line_number(), f));
    for (int64_t k = 1; k <= n; ++k) {
      int64_t index = 0;
      if (!parse(t[k], index)) fail_faces(fmt::format("line {}: malformed face {}", reader.line_number(), f));
      raw.indices.push_back(index);
    }
    raw.end_polygon();
  }
  if (reader.next(t))
    fail_faces(fmt::format("line {}: more data after the {} faces the header declares", reader.line_number(), nf));
  return raw;
}

RawMesh read_obj(const std::string& path) {
  LineReader reader(path);
  RawMesh raw;
  std::vector<std::string_view> t;
  while (reader.next(t)) {
    if (t[0] == "v") {
      Eigen::Vector3d p;
      if (t.size() < 4 || !parse(t[1], p.x()) || !parse(t[2], p.y()) || !parse(t[3], p.z()))
        fail(path, fmt::format("line {}: vertex needs three numbers", reader.line_number()));
      raw.vertices.push_back(p);
      if (static_cast<int64_t>(raw.vertices.size()) > kMaxVertices)
        fail(path, too_large(raw.vertices.size(), raw.num_polygons()));
    } else if (t[0] == "f") {
      for (size_t k = 1; k < t.size(); ++k) {
        // "v", "v/vt", "v//vn" or "v/vt/vn"; 1-based, negative counts back from the last vertex.
        int64_t index = 0;
        if (!parse(t[k].substr(0, t[k].find('/')), index))
          fail(path, fmt::format("line {}: malformed face", reader.line_number()));
        if (index == 0) fail(path, fmt::format("line {}: face index 0 (OBJ counts vertices from 1)", reader.line_number()));
        if (index > 0) raw.indices.push_back(index - 1);
        else raw.indices.push_back(static_cast<int64_t>(raw.vertices.size()) + index);
      }
      raw.end_polygon();
      if (static_cast<int64_t>(raw.num_polygons()) > kMaxFaces)
        fail(path, too_large(raw.vertices.size(), raw.num_polygons()));
    }
  }
  return raw;
}

// ---- PLY and STL through OpenMesh -------------------------------------------------------------

// Records what OpenMesh's readers parse without building a mesh: OpenMesh's mesh kernel silently
// drops faces that would make it non-manifold, and validation must see the file as it is.
class RawImporter : public OpenMesh::IO::BaseImporter {
public:
  explicit RawImporter(RawMesh& raw) : raw_(raw) {}

  OpenMesh::VertexHandle add_vertex(const OpenMesh::Vec3f& p) override {
    return add_vertex(OpenMesh::Vec3d(p[0], p[1], p[2]));
  }
  OpenMesh::VertexHandle add_vertex(const OpenMesh::Vec3d& p) override {
    raw_.vertices.emplace_back(p[0], p[1], p[2]);
    return OpenMesh::VertexHandle(static_cast<int>(raw_.vertices.size()) - 1);
  }
  OpenMesh::VertexHandle add_vertex() override { return add_vertex(OpenMesh::Vec3d(0, 0, 0)); }
  void set_point(OpenMesh::VertexHandle v, const OpenMesh::Vec3f& p) override {
    if (v.is_valid() && static_cast<size_t>(v.idx()) < raw_.vertices.size())
      raw_.vertices[v.idx()] = Eigen::Vector3d(p[0], p[1], p[2]);
  }
  OpenMesh::FaceHandle add_face(const VHandles& vertices) override {
    for (const auto v : vertices) raw_.indices.push_back(v.idx());
    raw_.end_polygon();
    return OpenMesh::FaceHandle(static_cast<int>(raw_.num_polygons()) - 1);
  }
  size_t n_vertices() const override { return raw_.vertices.size(); }
  size_t n_faces() const override { return raw_.num_polygons(); }
  size_t n_edges() const override { return 0; }

  // Everything else a reader may hand over (attributes, half-edge structure) is not needed.
  OpenMesh::HalfedgeHandle add_edge(OpenMesh::VertexHandle, OpenMesh::VertexHandle) override {
    return OpenMesh::HalfedgeHandle();
  }
  OpenMesh::FaceHandle add_face(OpenMesh::HalfedgeHandle) override { return OpenMesh::FaceHandle(); }
  void add_face_texcoords(OpenMesh::FaceHandle, OpenMesh::VertexHandle, const std::vector<OpenMesh::Vec2f>&) override {}
  void add_face_texcoords(OpenMesh::FaceHandle, OpenMesh::VertexHandle, const std::vector<OpenMesh::Vec3f>&) override {}
  void set_face_texindex(OpenMesh::FaceHandle, int) override {}
  void set_halfedge(OpenMesh::VertexHandle, OpenMesh::HalfedgeHandle) override {}
  void set_normal(OpenMesh::VertexHandle, const OpenMesh::Vec3f&) override {}
  void set_normal(OpenMesh::VertexHandle, const OpenMesh::Vec3d&) override {}
  void set_color(OpenMesh::VertexHandle, const OpenMesh::Vec3uc&) override {}
  void set_color(OpenMesh::VertexHandle, const OpenMesh::Vec4uc&) override {}
  void set_color(OpenMesh::VertexHandle, const OpenMesh::Vec3f&) override {}
  void set_color(OpenMesh::VertexHandle, const OpenMesh::Vec4f&) override {}
  void set_texcoord(OpenMesh::VertexHandle, const OpenMesh::Vec2f&) override {}
  void set_status(OpenMesh::VertexHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_next(OpenMesh::HalfedgeHandle, OpenMesh::HalfedgeHandle) override {}
  void set_face(OpenMesh::HalfedgeHandle, OpenMesh::FaceHandle) override {}
  void request_face_texcoords2D() override {}
  void set_texcoord(OpenMesh::HalfedgeHandle, const OpenMesh::Vec2f&) override {}
  void set_texcoord(OpenMesh::VertexHandle, const OpenMesh::Vec3f&) override {}
  void set_texcoord(OpenMesh::HalfedgeHandle, const OpenMesh::Vec3f&) override {}
  void set_status(OpenMesh::HalfedgeHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_color(OpenMesh::EdgeHandle, const OpenMesh::Vec3uc&) override {}
  void set_color(OpenMesh::EdgeHandle, const OpenMesh::Vec4uc&) override {}
  void set_color(OpenMesh::EdgeHandle, const OpenMesh::Vec3f&) override {}
  void set_color(OpenMesh::EdgeHandle, const OpenMesh::Vec4f&) override {}
  void set_status(OpenMesh::EdgeHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_normal(OpenMesh::FaceHandle, const OpenMesh::Vec3f&) override {}
  void set_normal(OpenMesh::FaceHandle, const OpenMesh::Vec3d&) override {}
  void set_color(OpenMesh::FaceHandle, const OpenMesh::Vec3uc&) override {}
  void set_color(OpenMesh::FaceHandle, const OpenMesh::Vec4uc&) override {}
  void set_color(OpenMesh::FaceHandle, const OpenMesh::Vec3f&) override {}
  void set_color(OpenMesh::FaceHandle, const OpenMesh::Vec4f&) override {}
  void set_status(OpenMesh::FaceHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void add_texture_information(int, std::string) override {}

private:
  RawMesh& raw_;
};

// The number of triangles an STL file declares: OpenMesh's reader merges coincident points and
// then skips triangles that became degenerate, which would otherwise go unnoticed.
int64_t stl_declared_triangles(const std::string& path) {
  std::ifstream in = open_for_reading(path, std::ios::binary);
  const std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (data.size() >= 84) {
    uint32_t n = 0;
    std::memcpy(&n, data.data() + 80, 4);  // binary STL is little-endian, like every host we run on
    if (data.size() == 84 + 50 * static_cast<uint64_t>(n)) return n;
  }
  int64_t count = 0;
  for (size_t at = data.find("endfacet"); at != std::string::npos; at = data.find("endfacet", at + 8)) ++count;
  return count;
}

// OpenMesh's readers say why they fail on its omerr stream (stderr by default): taken from there
// while one reads, so that the error stays one line and says what OpenMesh found. (The stream is
// global: one reader at a time.)
class OpenMeshMessages {
public:
  OpenMeshMessages() : lock_(mutex()) {
    ::omerr().disconnect(std::cerr);
    ::omerr().connect(text_);
  }
  ~OpenMeshMessages() {
    ::omerr().flush();
    ::omerr().disconnect(text_);
    ::omerr().connect(std::cerr);
  }
  OpenMeshMessages(const OpenMeshMessages&) = delete;
  OpenMeshMessages& operator=(const OpenMeshMessages&) = delete;
  // The first message, without OpenMesh's "[Reader] : " tag; empty if none.
  std::string first() {
    ::omerr().flush();
    std::string line = text_.str();
    line = line.substr(0, line.find('\n'));
    if (const size_t tag = line.find("] : "); line.rfind('[', 0) == 0 && tag != std::string::npos) line.erase(0, tag + 4);
    while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) line.pop_back();
    return line;
  }

private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  std::lock_guard<std::mutex> lock_;
  std::ostringstream text_;
};

RawMesh read_with_openmesh(const std::string& path, const std::string& extension) {
  RawMesh raw;
  RawImporter importer(raw);
  OpenMesh::IO::Options options;
  OpenMeshMessages messages;
  if (!OpenMesh::IO::IOManager().read(path, importer, options)) {
    const std::string why = messages.first();
    fail(path, "OpenMesh could not parse the file" + (why.empty() ? std::string() : " (" + why + ")"));
  }
  if (extension == ".stl") {
    const int64_t declared = stl_declared_triangles(path);
    const int64_t read = static_cast<int64_t>(raw.num_polygons());
    if (read < declared)
      fail(path, fmt::format("{} of {} triangles are degenerate (two corners coincide)", declared - read, declared));
  }
  return raw;
}

// Checks what is only visible before triangulation, then splits polygons into fans.
Mesh triangulate(const RawMesh& raw, const std::string& path, bool allow_polygons, int& triangulated) {
  const int64_t nv = static_cast<int64_t>(raw.vertices.size());
  if (raw.num_polygons() == 0) fail(path, "no faces");
  if (nv > kMaxVertices || static_cast<int64_t>(raw.num_polygons()) > kMaxFaces)
    fail(path, too_large(nv, raw.num_polygons()));
  Mesh mesh;
  mesh.name = path;
  mesh.vertices = raw.vertices;
  mesh.faces.reserve(raw.num_polygons());
  triangulated = 0;
  for (size_t p = 0; p < raw.num_polygons(); ++p) {
    const size_t begin = raw.offsets[p], n = raw.offsets[p + 1] - begin;
    for (size_t k = 0; k < n; ++k) {
      const int64_t v = raw.indices[begin + k];
      if (v < 0 || v >= nv)
        fail(path, fmt::format("face {} refers to vertex {}, out of range (the mesh has {} vertices)", p, v, nv));
    }
    if (n < 3) fail(path, fmt::format("face {} has only {} vertices", p, n));
    if (n > 3 && !allow_polygons) fail(path, fmt::format("face {} has {} vertices; only triangles are allowed", p, n));
    if (n > 3) ++triangulated;
    for (size_t k = 1; k + 1 < n; ++k)
      mesh.faces.push_back({static_cast<int>(raw.indices[begin]), static_cast<int>(raw.indices[begin + k]),
                            static_cast<int>(raw.indices[begin + k + 1])});
  }
  if (static_cast<int64_t>(mesh.faces.size()) > kMaxFaces) fail(path, too_large(nv, mesh.faces.size()));
  if (triangulated > 0)
    spdlog::warn("{}: split {} polygons into triangles (fans; non-convex polygons may fail validation)", path,
                 triangulated);
  return mesh;
}

std::string lower_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

// ---- validation -------------------------------------------------------------------------------

int find_root(std::vector<int>& parent, int v) {
  while (parent[v] != v) v = parent[v] = parent[parent[v]];
  return v;
}

// A face whose vertices are (numerically) collinear: sin of its largest angle below ~1e-12.
bool has_zero_area(const Mesh& mesh, const std::array<int, 3>& f) {
  const Eigen::Vector3d& a = mesh.vertices[f[0]];
  const Eigen::Vector3d& b = mesh.vertices[f[1]];
  const Eigen::Vector3d& c = mesh.vertices[f[2]];
  const double longest = std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
  return !((b - a).cross(c - a).norm() > 1e-12 * longest);
}

// Sorted by undirected edge so that the (up to) two half-edges of an edge are adjacent.
struct HalfEdge {
  int lo, hi, face;
  bool forward;  // traversed lo -> hi
};

// ---- OpenMesh conversion for decimation -------------------------------------------------------

struct DecimationTraits : public OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
  using Normal = OpenMesh::Vec3d;
  VertexAttributes(OpenMesh::Attributes::Status);
  EdgeAttributes(OpenMesh::Attributes::Status);
  FaceAttributes(OpenMesh::Attributes::Status | OpenMesh::Attributes::Normal);
};
using OmMesh = OpenMesh::TriMesh_ArrayKernelT<DecimationTraits>;

Eigen::Vector3d area_weighted_centroid(const Mesh& mesh, double& area) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  area = 0;
  for (const auto& f : mesh.faces) {
    const Eigen::Vector3d &a = mesh.vertices[f[0]], &b = mesh.vertices[f[1]], &c = mesh.vertices[f[2]];
    const double A = 0.5 * (b - a).cross(c - a).norm();
    area += A;
    sum += A * (a + b + c) / 3.0;
  }
  return sum / area;
}

// ---- writing ----------------------------------------------------------------------------------

void write_text(const Mesh& mesh, std::ostream& out, const std::string& ext,
                const std::vector<std::array<uint8_t, 3>>* colors) {
  // {} prints the shortest representation that reads back to the same double.
  if (ext == ".off") {
    out << fmt::format("OFF\n{} {} 0\n", mesh.num_vertices(), mesh.num_faces());
    for (const auto& p : mesh.vertices) out << fmt::format("{} {} {}\n", p.x(), p.y(), p.z());
    for (const auto& f : mesh.faces) out << fmt::format("3 {} {} {}\n", f[0], f[1], f[2]);
  } else if (ext == ".obj") {
    for (const auto& p : mesh.vertices) out << fmt::format("v {} {} {}\n", p.x(), p.y(), p.z());
    for (const auto& f : mesh.faces) out << fmt::format("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1);
  } else {  // .ply
    out << "ply\nformat ascii 1.0\ncomment written by shapematch\n";
    out << fmt::format("element vertex {}\n", mesh.num_vertices());
    out << "property double x\nproperty double y\nproperty double z\n";
    if (colors) out << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    out << fmt::format("element face {}\n", mesh.num_faces());
    out << "property list uchar int vertex_indices\nend_header\n";
    for (int i = 0; i < mesh.num_vertices(); ++i) {
      const auto& p = mesh.vertices[i];
      out << fmt::format("{} {} {}", p.x(), p.y(), p.z());
      if (colors) out << fmt::format(" {} {} {}", (*colors)[i][0], (*colors)[i][1], (*colors)[i][2]);
      out << '\n';
    }
    for (const auto& f : mesh.faces) out << fmt::format("3 {} {} {}\n", f[0], f[1], f[2]);
  }
}

void write_stl(const Mesh& mesh, std::ostream& out) {
  char header[80] = {};
  std::snprintf(header, sizeof header, "binary STL written by shapematch");
  out.write(header, sizeof header);
  const uint32_t n = static_cast<uint32_t>(mesh.faces.size());
  out.write(reinterpret_cast<const char*>(&n), 4);
  for (const auto& f : mesh.faces) {
    const Eigen::Vector3d &a = mesh.vertices[f[0]], &b = mesh.vertices[f[1]], &c = mesh.vertices[f[2]];
    float record[12];
    const Eigen::Vector3f normal = (b - a).cross(c - a).normalized().cast<float>();
    const Eigen::Vector3d* corners[3] = {&a, &b, &c};
    for (int k = 0; k < 3; ++k) record[k] = normal[k];
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) record[3 + 3 * i + k] = static_cast<float>((*corners[i])[k]);
    out.write(reinterpret_cast<const char*>(record), sizeof record);
    const uint16_t attribute = 0;
    out.write(reinterpret_cast<const char*>(&attribute), 2);
  }
}

void write_mesh(const Mesh& mesh, const std::string& path, const std::vector<std::array<uint8_t, 3>>* colors) {
  const std::string ext = lower_extension(path);
  if (ext != ".off" && ext != ".obj" && ext != ".ply" && ext != ".stl")
    fail(path, fmt::format("unknown extension '{}' (expected .off, .obj, .ply or .stl)", ext));
  if (colors && ext != ".ply") fail(path, "vertex colours can only be written to .ply");
  if (colors && colors->size() != mesh.vertices.size())
    fail(path, fmt::format("{} vertex colours for {} vertices", colors->size(), mesh.vertices.size()));

  write_file_atomic(path, [&](std::ostream& out) {
    if (ext == ".stl") write_stl(mesh, out);
    else write_text(mesh, out, ext, colors);
  });
}

// Closes every boundary loop with a fan around a new vertex at the loop's centroid. The loops
// come from the half-edges that have no opposite; a vertex where two of them start would make
// the fans non-manifold, so that is an error. Loops are closed in order of their smallest
// vertex, so equal connectivity (one animal's poses) gets equal new vertex indices.
int close_boundary_loops(Mesh& mesh) {
  std::map<std::pair<int, int>, int> directed;  // half-edge -> how often it occurs
  for (const auto& f : mesh.faces)
    for (int k = 0; k < 3; ++k) ++directed[{f[k], f[(k + 1) % 3]}];
  // A boundary half-edge u->v has no v->u; the fan must traverse v->u.
  std::map<int, int> next;  // v -> u for each boundary half-edge u->v
  for (const auto& [e, count] : directed) {
    if (count > 1 || directed.count({e.second, e.first})) continue;
    if (!next.emplace(e.second, e.first).second)
      fail(mesh.name, fmt::format("cannot close holes: boundary loops touch at vertex {}", e.second));
  }
  int loops = 0;
  while (!next.empty()) {
    std::vector<int> loop;
    int v = next.begin()->first;
    for (auto it = next.find(v); it != next.end(); it = next.find(v)) {
      loop.push_back(v);
      v = it->second;
      next.erase(it);
    }
    if (v != loop.front()) fail(mesh.name, fmt::format("cannot close holes: the boundary at vertex {} is not a loop", v));
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const int u : loop) centroid += mesh.vertices[u];
    const int c = mesh.num_vertices();
    mesh.vertices.push_back(centroid / static_cast<double>(loop.size()));
    for (size_t k = 0; k < loop.size(); ++k) mesh.faces.push_back({loop[k], loop[(k + 1) % loop.size()], c});
    ++loops;
  }
  return loops;
}

}  // namespace

// ---- Mesh -------------------------------------------------------------------------------------

int Mesh::edge_index(int u, int v) const {
  const std::array<int, 2> key = u < v ? std::array<int, 2>{u, v} : std::array<int, 2>{v, u};
  if (key[0] >= 0 && size_t(key[0]) + 1 < edge_begin.size() && edge_begin.size() == vertices.size() + 1 &&
      edge_begin.back() == num_edges()) {
    for (int e = edge_begin[key[0]]; e < edge_begin[key[0] + 1]; ++e)
      if (edges[e][1] == key[1]) return e;
    return -1;
  }
  const auto it = std::lower_bound(edges.begin(), edges.end(), key);
  return it != edges.end() && *it == key ? static_cast<int>(it - edges.begin()) : -1;
}

void Mesh::build_edges() {
  edges.clear();
  edges.reserve(3 * faces.size());
  for (const auto& f : faces)
    for (int k = 0; k < 3; ++k) {
      const int u = f[k], v = f[(k + 1) % 3];
      edges.push_back(u < v ? std::array<int, 2>{u, v} : std::array<int, 2>{v, u});
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  edge_begin.assign(vertices.size() + 1, 0);
  for (const auto& e : edges)
    if (e[0] >= 0 && size_t(e[0]) < vertices.size()) ++edge_begin[e[0] + 1];
  for (size_t u = 0; u < vertices.size(); ++u) edge_begin[u + 1] += edge_begin[u];
  if (edge_begin.back() != num_edges()) edge_begin.clear();  // indices out of range: validation says so
}

int validate_mesh(const Mesh& mesh) {
  const std::string& name = mesh.name;
  const int64_t nv = static_cast<int64_t>(mesh.vertices.size());
  const int64_t nf = static_cast<int64_t>(mesh.faces.size());
  if (nf == 0) fail(name, "no faces");
  if (nv > kMaxVertices || nf > kMaxFaces) fail(name, too_large(nv, nf));

  for (int64_t i = 0; i < nv; ++i) {
    const Eigen::Vector3d& p = mesh.vertices[i];
    if (!p.allFinite())
      fail(name, fmt::format("vertex {} has a non-finite coordinate ({}, {}, {})", i, p.x(), p.y(), p.z()));
    // (Areas multiply four coordinates: past this they overflow, and every face looks degenerate.)
    if (p.cwiseAbs().maxCoeff() > kMaxCoordinate)
      fail(name, fmt::format("vertex {} has a coordinate beyond ±{:g} ({}, {}, {}): too large to compute areas with",
                             i, kMaxCoordinate, p.x(), p.y(), p.z()));
  }
  for (int64_t f = 0; f < nf; ++f) {
    const auto& t = mesh.faces[f];
    for (const int v : t)
      if (v < 0 || v >= nv)
        fail(name, fmt::format("face {} refers to vertex {}, out of range (the mesh has {} vertices)", f, v, nv));
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0])
      fail(name, fmt::format("face {} ({}, {}, {}) is degenerate: it repeats a vertex", f, t[0], t[1], t[2]));
    if (has_zero_area(mesh, t)) fail(name, fmt::format("face {} ({}, {}, {}) has zero area", f, t[0], t[1], t[2]));
  }

  // Edges: each must have exactly two faces, traversing it in opposite directions.
  std::vector<HalfEdge> half_edges;
  half_edges.reserve(3 * nf);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int u = mesh.faces[f][k], v = mesh.faces[f][(k + 1) % 3];
      half_edges.push_back({std::min(u, v), std::max(u, v), f, u < v});
    }
  std::sort(half_edges.begin(), half_edges.end(), [](const HalfEdge& a, const HalfEdge& b) {
    return std::tie(a.lo, a.hi, a.face) < std::tie(b.lo, b.hi, b.face);
  });
  int64_t num_edges = 0, boundary = 0, non_manifold = 0, misoriented = 0;
  const HalfEdge *first_boundary = nullptr, *first_non_manifold = nullptr, *first_misoriented = nullptr;
  int first_non_manifold_faces = 0;
  for (size_t i = 0; i < half_edges.size();) {
    size_t j = i + 1;
    while (j < half_edges.size() && half_edges[j].lo == half_edges[i].lo && half_edges[j].hi == half_edges[i].hi) ++j;
    ++num_edges;
    if (j - i == 1) {
      if (boundary++ == 0) first_boundary = &half_edges[i];
    } else if (j - i > 2) {
      if (non_manifold++ == 0) {
        first_non_manifold = &half_edges[i];
        first_non_manifold_faces = static_cast<int>(j - i);
      }
    } else if (half_edges[i].forward == half_edges[i + 1].forward) {
      if (misoriented++ == 0) first_misoriented = &half_edges[i];
    }
    i = j;
  }
  if (non_manifold > 0)
    fail(name, fmt::format("non-manifold: {} edges are shared by more than two faces, e.g. edge ({}, {}) by {}",
                           non_manifold, first_non_manifold->lo, first_non_manifold->hi, first_non_manifold_faces));
  if (boundary > 0)
    fail(name, fmt::format("not closed: {} boundary edges (edges with only one face), e.g. ({}, {})", boundary,
                           first_boundary->lo, first_boundary->hi));
  if (misoriented > 0) {
    const HalfEdge& h = *first_misoriented;
    const int u = h.forward ? h.lo : h.hi, v = h.forward ? h.hi : h.lo;
    fail(name, fmt::format("inconsistent orientation: {} edges are traversed twice in the same direction, "
                           "e.g. {} -> {} by faces {} and {}",
                           misoriented, u, v, h.face, (&h + 1)->face));
  }

  // Vertices: each must be used, and its faces must form one fan. Around a vertex v, each corner
  // (v, a, b) contributes the link edge a -> b; on a manifold the link edges form one cycle.
  std::vector<int> degree(nv + 1, 0);
  for (const auto& t : mesh.faces)
    for (const int v : t) ++degree[v + 1];
  for (int64_t v = 0; v < nv; ++v)
    if (degree[v + 1] == 0) {
      const auto unused = std::count(degree.begin() + 1, degree.end(), 0);
      fail(name, fmt::format("{} vertices are not used by any face, e.g. vertex {}", unused, v));
    }
  std::vector<int> offset(degree);
  std::partial_sum(offset.begin(), offset.end(), offset.begin());
  std::vector<std::array<int, 2>> link(3 * nf);
  {
    std::vector<int> fill(offset.begin(), offset.end() - 1);
    for (const auto& t : mesh.faces)
      for (int k = 0; k < 3; ++k) link[fill[t[k]]++] = {t[(k + 1) % 3], t[(k + 2) % 3]};
  }
  int64_t non_manifold_vertices = 0, first_vertex = -1;
  for (int64_t v = 0; v < nv; ++v) {
    const auto begin = link.begin() + offset[v], end = link.begin() + offset[v + 1];
    std::sort(begin, end);
    // Edge-manifoldness and consistent orientation make every link vertex a tail exactly once,
    // so the walk from the first link edge returns to its start; it must visit every link edge.
    const int start = (*begin)[0];
    int current = start;
    int64_t steps = 0;
    do {
      const auto it = std::lower_bound(begin, end, std::array<int, 2>{current, INT_MIN});
      if (it == end || (*it)[0] != current) break;
      current = (*it)[1];
      ++steps;
    } while (current != start && steps <= end - begin);
    if ((current != start || steps != end - begin) && non_manifold_vertices++ == 0) first_vertex = v;
  }
  if (non_manifold_vertices > 0)
    fail(name, fmt::format("non-manifold: {} vertices have faces that do not form a single fan, e.g. vertex {}",
                           non_manifold_vertices, first_vertex));

  std::vector<int> parent(nv);
  std::iota(parent.begin(), parent.end(), 0);
  for (const auto& t : mesh.faces) {
    parent[find_root(parent, t[1])] = find_root(parent, t[0]);
    parent[find_root(parent, t[2])] = find_root(parent, t[0]);
  }
  int64_t components = 0;
  for (int64_t v = 0; v < nv; ++v) components += find_root(parent, v) == v;
  if (components > 1) fail(name, fmt::format("{} connected components (exactly one is required)", components));

  const int64_t euler = nv - num_edges + nf;  // = 2 - 2 genus for a closed orientable surface
  return static_cast<int>((2 - euler) / 2);
}

Mesh make_mesh(std::vector<Eigen::Vector3d> vertices, std::vector<std::array<int, 3>> faces, std::string name) {
  Mesh mesh;
  mesh.name = std::move(name);
  mesh.vertices = std::move(vertices);
  mesh.faces = std::move(faces);
  validate_mesh(mesh);
  mesh.build_edges();
  return mesh;
}

Mesh load_mesh(const std::string& path, const LoadOptions& options, MeshReport* report) {
  std::error_code ec;
  const auto status = fs::status(path, ec);
  if (!fs::exists(status)) throw IoError(path + ": file not found");
  if (fs::is_directory(status)) throw IoError(path + ": is a directory, not a mesh file");
  const std::string ext = lower_extension(path);
  if (ext != ".off" && ext != ".obj" && ext != ".ply" && ext != ".stl")
    fail(path, fmt::format("unknown extension '{}' (expected .off, .obj, .ply or .stl)", ext));
  open_for_reading(path);  // (throws where it cannot be read)
  if (fs::file_size(path, ec) == 0 && !ec) fail(path, "empty file");

  const RawMesh raw = ext == ".off" ? read_off(path) : ext == ".obj" ? read_obj(path) : read_with_openmesh(path, ext);
  int triangulated = 0;
  int closed = 0, genus = 0;
  Mesh mesh;
  try {
    mesh = triangulate(raw, path, options.allow_polygons, triangulated);
    closed = options.close_holes ? close_boundary_loops(mesh) : 0;
    genus = validate_mesh(mesh);
  } catch (const InvalidInputError& e) {
    if (raw.oddity.empty()) throw;
    throw InvalidInputError(std::string(e.what()) + " (" + raw.oddity + ")");
  }
  if (!raw.oddity.empty()) spdlog::warn("{}: {}; the extra numbers are ignored", path, raw.oddity);
  if (closed > 0) spdlog::warn("{}: closed {} boundary loops with a vertex each", path, closed);
  mesh.build_edges();
  if (signed_volume(mesh) < 0) {
    spdlog::warn("{}: faces are clockwise seen from outside; reversing all of them", path);
    for (auto& f : mesh.faces) std::swap(f[1], f[2]);
  }
  if (options.normalize_area) normalize_area(mesh);
  if (report) {
    report->genus = genus;
    report->triangulated_faces = triangulated;
    report->closed_holes = closed;
  }
  return mesh;
}

double surface_area(const Mesh& mesh) {
  double area = 0;
  for (const auto& f : mesh.faces)
    area += 0.5 * (mesh.vertices[f[1]] - mesh.vertices[f[0]]).cross(mesh.vertices[f[2]] - mesh.vertices[f[0]]).norm();
  return area;
}

double signed_volume(const Mesh& mesh) {
  double volume = 0;
  for (const auto& f : mesh.faces)
    volume += mesh.vertices[f[0]].dot(mesh.vertices[f[1]].cross(mesh.vertices[f[2]]));
  return volume / 6.0;
}

void normalize_area(Mesh& mesh, double target_area) {
  double area = 0;
  const Eigen::Vector3d centroid = area_weighted_centroid(mesh, area);
  if (!(area > 0) || !std::isfinite(area)) fail(mesh.name, fmt::format("cannot normalise a surface area of {}", area));
  if (!(target_area > 0)) fail(mesh.name, fmt::format("target area must be positive, got {}", target_area));
  const double scale = std::sqrt(target_area / area);
  for (auto& p : mesh.vertices) p = (p - centroid) * scale;
}

Mesh decimate(const Mesh& mesh, int target_faces, std::vector<int>* kept_vertices) {
  if (target_faces < 1) fail(mesh.name, fmt::format("decimation target must be positive, got {}", target_faces));
  if (mesh.num_faces() <= target_faces) {
    if (kept_vertices) {
      kept_vertices->resize(mesh.vertices.size());
      std::iota(kept_vertices->begin(), kept_vertices->end(), 0);
    }
    return mesh;
  }

  OmMesh om;
  om.reserve(mesh.vertices.size(), 3 * mesh.faces.size() / 2, mesh.faces.size());
  OpenMesh::VPropHandleT<int> input_index;
  om.add_property(input_index);
  for (const auto& p : mesh.vertices) {
    const auto v = om.add_vertex(OmMesh::Point(p.x(), p.y(), p.z()));
    om.property(input_index, v) = v.idx();
  }
  for (const auto& f : mesh.faces) {
    const OpenMesh::VertexHandle a(f[0]), b(f[1]), c(f[2]);
    if (!om.add_face(a, b, c).is_valid()) fail(mesh.name, "cannot be decimated: not a valid manifold mesh");
  }
  om.update_face_normals();

  OpenMesh::Decimater::DecimaterT<OmMesh> decimater(om);
  OpenMesh::Decimater::ModQuadricT<OmMesh>::Handle quadric;
  OpenMesh::Decimater::ModNormalFlippingT<OmMesh>::Handle normal_flipping;
  decimater.add(quadric);
  decimater.add(normal_flipping);
  decimater.module(quadric).unset_max_err();  // stop on the face count, not on an error bound
  // Refuse collapses that turn a face by more than this: avoids fold-overs and slivers.
  decimater.module(normal_flipping).set_max_normal_deviation(60.0);
  decimater.initialize();
  decimater.decimate_to_faces(0, target_faces);
  // Garbage collection moves handles around, so each vertex carries its input index through it.
  om.garbage_collection();
  std::vector<int> kept;
  kept.reserve(om.n_vertices());
  for (const auto v : om.vertices()) kept.push_back(om.property(input_index, v));

  std::vector<Eigen::Vector3d> vertices;
  vertices.reserve(om.n_vertices());
  for (const auto v : om.vertices()) vertices.emplace_back(om.point(v)[0], om.point(v)[1], om.point(v)[2]);
  std::vector<std::array<int, 3>> faces;
  faces.reserve(om.n_faces());
  for (const auto f : om.faces()) {
    std::array<int, 3> t{};
    int k = 0;
    for (const auto v : om.fv_range(f)) t[k++] = v.idx();
    faces.push_back(t);
  }
  Mesh result;
  try {
    result = make_mesh(std::move(vertices), std::move(faces), mesh.name);
  } catch (const InvalidInputError& e) {
    // The input was valid, so this is a failure of decimation, not of the input.
    throw Error(fmt::format("decimation to {} faces produced an invalid mesh: {}", target_faces, e.what()));
  }

  // Keep the input's area and centroid, so that normalised meshes stay normalised.
  double area_in = 0, area_out = 0;
  const Eigen::Vector3d centroid_in = area_weighted_centroid(mesh, area_in);
  const Eigen::Vector3d centroid_out = area_weighted_centroid(result, area_out);
  const double scale = std::sqrt(area_in / area_out);
  for (auto& p : result.vertices) p = centroid_in + (p - centroid_out) * scale;
  if (kept_vertices) *kept_vertices = std::move(kept);
  return result;
}

void save_mesh(const Mesh& mesh, const std::string& path) { write_mesh(mesh, path, nullptr); }

void save_mesh(const Mesh& mesh, const std::string& path, const std::vector<std::array<uint8_t, 3>>& vertex_colors) {
  write_mesh(mesh, path, &vertex_colors);
}

}  // namespace shapematch
