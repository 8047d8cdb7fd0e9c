#include "shapematch/errors.hpp"
#include "shapematch/mesh.hpp"
#include "shapematch/shapes.hpp"

#include "test_helpers.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <random>

using namespace shapematch;
namespace fs = std::filesystem;

namespace {

using test::TempDir;

// Loading `path` throws exactly InvalidInputError with "<path>: " and `problem` in its message.
void check_invalid(const std::string& path, const std::string& problem, const LoadOptions& options = {}) {
  CAPTURE(path);
  CAPTURE(problem);
  try {
    load_mesh(path, options);
    FAIL("no exception");
  } catch (const InvalidInputError& e) {
    const std::string what = e.what();
    CAPTURE(what);
    CHECK(what.rfind(path + ": ", 0) == 0);
    CHECK(what.find(problem) != std::string::npos);
    CHECK(what.find('\n') == std::string::npos);
  }
}

std::string off(const Mesh& m) {
  std::string s = "OFF\n" + std::to_string(m.num_vertices()) + " " + std::to_string(m.num_faces()) + " 0\n";
  for (const auto& p : m.vertices)
    s += std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z()) + "\n";
  for (const auto& f : m.faces)
    s += "3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) + "\n";
  return s;
}

const char* kTetraVertices = "1 1 1\n1 -1 -1\n-1 1 -1\n-1 -1 1\n";
const char* kTetraFaces = "3 0 1 2\n3 0 3 1\n3 0 2 3\n3 1 3 2\n";
const std::string kTetraHeader = std::string("OFF\n4 4 0\n") + kTetraVertices;

}  // namespace

TEST_CASE("mesh: edges are sorted and found by binary search") {
  const Mesh m = shapes::tetrahedron();
  REQUIRE(m.num_edges() == 6);
  CHECK(std::is_sorted(m.edges.begin(), m.edges.end()));
  for (int e = 0; e < m.num_edges(); ++e) {
    const auto [u, v] = m.edges[e];
    CHECK(u < v);
    CHECK(m.edge_index(u, v) == e);
    CHECK(m.edge_index(v, u) == e);
    CHECK(m.directed_edge_index(u, v) == 2 * e);
    CHECK(m.directed_edge_index(v, u) == 2 * e + 1);
    CHECK(m.directed_edge(2 * e + 1) == std::array<int, 2>{v, u});
  }
  const Mesh sphere = shapes::icosphere(2);
  CHECK(sphere.edge_index(0, 0) == -1);
  CHECK(sphere.num_edges() == 3 * sphere.num_faces() / 2);
  int missing = 0;
  for (int u = 0; u < 12; ++u)
    for (int v = 0; v < 12; ++v) missing += sphere.edge_index(u, v) < 0;
  CHECK(missing == 144);  // the original icosahedron vertices are no longer adjacent
}

TEST_CASE("mesh: edge lookup through each vertex's edges agrees with a search of all edges") {
  Mesh m = shapes::icosphere(2);
  REQUIRE(m.edge_begin.size() == size_t(m.num_vertices()) + 1);
  CHECK(m.edge_begin.back() == m.num_edges());
  std::vector<int> fast;
  for (int u = -1; u <= m.num_vertices(); ++u)
    for (int v = -1; v <= m.num_vertices(); ++v) fast.push_back(m.edge_index(u, v));
  CHECK(std::count_if(fast.begin(), fast.end(), [](int e) { return e >= 0; }) == 2 * m.num_edges());
  m.edge_begin.clear();  // `edges` filled by hand: the binary search
  size_t k = 0;
  for (int u = -1; u <= m.num_vertices(); ++u)
    for (int v = -1; v <= m.num_vertices(); ++v) CHECK(m.edge_index(u, v) == fast[k++]);
}

TEST_CASE("mesh: genus from the Euler characteristic") {
  CHECK(validate_mesh(shapes::tetrahedron()) == 0);
  CHECK(validate_mesh(shapes::icosphere(3)) == 0);
  CHECK(validate_mesh(shapes::torus(24, 12)) == 1);
  TempDir dir;
  save_mesh(shapes::torus(24, 12), dir / "torus.obj");
  MeshReport report;
  load_mesh(dir / "torus.obj", {}, &report);
  CHECK(report.genus == 1);
  CHECK(report.triangulated_faces == 0);
}

TEST_CASE("mesh: normalize_area gives unit area about the centroid") {
  Mesh m = shapes::icosphere(3, 5.0);
  for (auto& p : m.vertices) p += Eigen::Vector3d(3, -2, 7);
  normalize_area(m);
  CHECK(surface_area(m) == doctest::Approx(1.0).epsilon(1e-12));
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : m.vertices) centroid += p;
  CHECK((centroid / m.num_vertices()).norm() < 1e-12);
  normalize_area(m, 4.0);
  CHECK(surface_area(m) == doctest::Approx(4.0).epsilon(1e-12));
  CHECK(signed_volume(m) > 0);
}

TEST_CASE("mesh: round trip through OFF, OBJ, PLY and STL") {
  TempDir dir;
  const Mesh m = shapes::icosphere(2, 1.3);
  for (const std::string ext : {".off", ".obj", ".ply", ".PLY"}) {
    CAPTURE(ext);
    const std::string path = dir / ("sphere" + ext);
    save_mesh(m, path);
    const Mesh r = load_mesh(path, {.normalize_area = false});
    CHECK(r.name == path);
    REQUIRE(r.num_vertices() == m.num_vertices());
    CHECK(r.faces == m.faces);
    CHECK(r.edges == m.edges);
    // OFF and OBJ round-trip doubles exactly; OpenMesh reads PLY coordinates as floats.
    const double tolerance = ext == ".off" || ext == ".obj" ? 0.0 : 1e-6;
    for (int v = 0; v < m.num_vertices(); ++v) CHECK((r.vertices[v] - m.vertices[v]).norm() <= tolerance);
  }
  // STL has no shared vertices and single precision: the reader merges coincident corners.
  save_mesh(m, dir / "sphere.stl");
  const Mesh r = load_mesh(dir / "sphere.stl", {.normalize_area = false});
  REQUIRE(r.num_vertices() == m.num_vertices());
  REQUIRE(r.num_faces() == m.num_faces());
  for (int f = 0; f < m.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) CHECK((r.vertices[r.faces[f][k]] - m.vertices[m.faces[f][k]]).norm() < 1e-6);
  // Loading normalises by default.
  CHECK(surface_area(load_mesh(dir / "sphere.stl")) == doctest::Approx(1.0).epsilon(1e-12));
}

TEST_CASE("mesh: PLY with vertex colours") {
  TempDir dir;
  const Mesh m = shapes::octahedron();
  std::vector<std::array<uint8_t, 3>> colors(m.num_vertices(), {255, 0, 10});
  save_mesh(m, dir / "colored.ply", colors);
  const Mesh r = load_mesh(dir / "colored.ply", {.normalize_area = false});
  CHECK(r.faces == m.faces);
  CHECK(r.vertices == m.vertices);  // small integers are exact in single precision
  CHECK(dir.read("colored.ply").find("property uchar red") != std::string::npos);
  CHECK(dir.read("colored.ply").find("255 0 10\n") != std::string::npos);
  CHECK_THROWS_AS(save_mesh(m, dir / "colored.off", colors), InvalidInputError);
  colors.pop_back();
  CHECK_THROWS_AS(save_mesh(m, dir / "colored2.ply", colors), InvalidInputError);
  CHECK_THROWS_AS(save_mesh(m, dir / "mesh.xyz"), InvalidInputError);
  CHECK_THROWS_AS(save_mesh(m, dir / "no-such-dir/mesh.off"), IoError);
  CHECK(std::distance(fs::directory_iterator(dir.path), fs::directory_iterator()) == 1);  // no temporaries left
}

TEST_CASE("mesh: OBJ with polygons, comments, texture indices and negative indices") {
  TempDir dir;
  // A unit cube of quads; the last face uses relative indices.
  const std::string cube =
      "# cube\nmtllib x.mtl\no cube\n"
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nvt 0 0\nvn 0 0 1\n"
      "f 1/1 4/1 3/1 2/1\nf 5//1 6//1 7//1 8//1\nf 1/1/1 2/1/1 6/1/1 5/1/1\n"
      "f 2 3 7 6\nf 3 4 8 7\nf -4 -1 -5 -8\n";
  const std::string path = dir.file("cube.obj", cube);
  MeshReport report;
  const Mesh m = load_mesh(path, {.normalize_area = false}, &report);
  CHECK(m.num_faces() == 12);
  CHECK(report.triangulated_faces == 6);
  CHECK(report.genus == 0);
  CHECK(surface_area(m) == doctest::Approx(6.0));
  CHECK(signed_volume(m) == doctest::Approx(1.0));
  check_invalid(path, "face 0 has 4 vertices; only triangles are allowed", {.allow_polygons = false});
}

TEST_CASE("mesh: close_holes fills each boundary loop with a fan, keeping the file's vertices") {
  TempDir dir;
  const Mesh sphere = shapes::icosphere(2);
  const int n = sphere.num_vertices();
  auto shared = [&](int f, int g) {
    int common = 0;
    for (const int u : sphere.faces[f])
      for (const int v : sphere.faces[g]) common += u == v;
    return common;
  };
  auto without = [&](std::vector<int> remove) {
    Mesh m = sphere;
    m.faces.clear();
    for (int f = 0; f < sphere.num_faces(); ++f)
      if (std::find(remove.begin(), remove.end(), f) == remove.end()) m.faces.push_back(sphere.faces[f]);
    return m;
  };
  // Hole A: face 0 and a face across one of its edges (a loop of four). Hole B: one face far away.
  // Touching: face 0 and a face that shares only one vertex with it.
  int across = -1, far = -1, corner = -1;
  for (int f = 1; f < sphere.num_faces(); ++f) {
    if (shared(0, f) == 2 && across < 0) across = f;
    if (shared(0, f) == 0 && far < 0 && sphere.vertices[sphere.faces[f][0]].dot(sphere.vertices[sphere.faces[0][0]]) < -0.5)
      far = f;
    if (shared(0, f) == 1 && corner < 0) corner = f;
  }
  REQUIRE(across > 0);
  REQUIRE(far > 0);
  REQUIRE(corner > 0);
  const std::string path = dir.file("open.off", off(without({0, across, far})));
  check_invalid(path, "not closed");

  MeshReport report;
  const Mesh closed = load_mesh(path, {.normalize_area = false, .close_holes = true}, &report);
  CHECK(report.closed_holes == 2);
  CHECK(report.genus == 0);
  REQUIRE(closed.num_vertices() == n + 2);
  for (int v = 0; v < n; ++v) CHECK((closed.vertices[v] - sphere.vertices[v]).norm() < 1e-5);
  // Hole B's new vertex is its triangle's centroid; fans of 4 and 3 faces replace the 3 removed.
  const auto& t = sphere.faces[far];
  const Eigen::Vector3d centroid = (sphere.vertices[t[0]] + sphere.vertices[t[1]] + sphere.vertices[t[2]]) / 3.0;
  CHECK(((closed.vertices[n] - centroid).norm() < 1e-5) != ((closed.vertices[n + 1] - centroid).norm() < 1e-5));
  CHECK(closed.num_faces() == sphere.num_faces() - 3 + 4 + 3);
  CHECK(signed_volume(closed) > 0);

  // Two holes that meet at a vertex cannot both get a manifold fan.
  check_invalid(dir.file("touching.off", off(without({0, corner}))), "cannot close holes: boundary loops touch",
                {.close_holes = true});
}

TEST_CASE("mesh: a mesh that is consistently inside out is flipped") {
  TempDir dir;
  const std::string path = dir.file("inside_out.off", kTetraHeader + "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  const Mesh m = load_mesh(path, {.normalize_area = false});
  CHECK(signed_volume(m) > 0);
}

TEST_CASE("mesh: malformed inputs are rejected with a one-line message") {
  TempDir dir;
  const std::string tetra = kTetraHeader + kTetraFaces;
  REQUIRE_NOTHROW(load_mesh(dir.file("ok.off", tetra)));

  SUBCASE("missing file and unknown extension") {
    CHECK_THROWS_AS(load_mesh(dir / "missing.off"), IoError);
    try {
      load_mesh(dir / "missing.off");
    } catch (const IoError& e) {
      CHECK(std::string(e.what()) == dir / "missing.off" + ": file not found");
    }
    check_invalid(dir.file("mesh.xyz", tetra), "unknown extension '.xyz'");
  }
  SUBCASE("empty file and no faces") {
    check_invalid(dir.file("empty.off", ""), "empty file");
    check_invalid(dir.file("empty.obj", ""), "empty file");
    check_invalid(dir.file("comments.off", "# nothing\n\n"), "empty file");
    check_invalid(dir.file("nofaces.off", std::string("OFF\n4 0 0\n") + kTetraVertices), "no faces");
    check_invalid(dir.file("nofaces.obj", "v 0 0 0\nv 1 0 0\n"), "no faces");
  }
  SUBCASE("NaN and infinite coordinates") {
    check_invalid(dir.file("nan.off", std::string("OFF\n4 4 0\n1 1 1\n1 -1 -1\nnan 1 -1\n-1 -1 1\n") + kTetraFaces),
                  "vertex 2 has a non-finite coordinate");
    check_invalid(dir.file("inf.obj", "v 1 1 1\nv 1 -1 -1\nv -1 1 -1\nv -1 -1 inf\n"
                                      "f 1 2 3\nf 1 4 2\nf 1 3 4\nf 2 4 3\n"),
                  "vertex 3 has a non-finite coordinate");
  }
  SUBCASE("index out of range") {
    check_invalid(dir.file("range.off", kTetraHeader + "3 0 1 2\n3 0 3 1\n3 0 2 7\n3 1 3 2\n"),
                  "face 2 refers to vertex 7, out of range");
    check_invalid(dir.file("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n"),
                  "line 4: face index 0 (OBJ counts vertices from 1)");
    check_invalid(dir.file("range2.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"), "face 0 refers to vertex 3");
  }
  SUBCASE("malformed text") {
    check_invalid(dir.file("header.off", "OFF\nfour 4 0\n"), "expected the vertex and face counts");
    check_invalid(dir.file("short.off", std::string("OFF\n4 4 0\n") + kTetraVertices + "3 0 1 2\n"),
                  "file ends after 1 of 4 faces");
    check_invalid(dir.file("word.off", std::string("OFF\n4 4 0\n1 1 one\n") + kTetraFaces),
                  "line 3: vertex 0 needs three numbers, got '1 1 one'");
    // Out of a double's range: named, not taken for a missing number.
    check_invalid(dir.file("e400.off", std::string("OFF\n4 4 0\n1 1 1e400\n") + kTetraFaces), "got '1 1 1e400'");
    check_invalid(dir.file("notoff.off", "PLY\n"), "missing OFF header");
  }
  SUBCASE("counts that do not match the file") {
    // One vertex too many declared: the first face line is read as a fifth vertex, and the
    // faces then end in the wrong place; the error names the line that tells why.
    check_invalid(dir.file("more.off", std::string("OFF\n5 3 0\n") + kTetraVertices + kTetraFaces),
                  "not closed: 3 boundary edges (edges with only one face), e.g. (0, 1) (line 7 gave vertex 4 4 "
                  "numbers: is the header's vertex count, 5, too large?)");
    check_invalid(dir.file("more2.off", std::string("OFF\n5 2 0\n") + kTetraVertices + kTetraFaces),
                  "line 10: more data after the 2 faces the header declares (line 7 gave vertex 4 4 numbers");
    check_invalid(dir.file("more4.off", std::string("OFF\n5 4 0\n") + kTetraVertices + kTetraFaces),
                  "file ends after 3 of 4 faces (line 7 gave vertex 4 4 numbers");
    // One face too few declared: the last face would be dropped (and the mesh reported open).
    check_invalid(dir.file("fewer.off", std::string("OFF\n4 3 0\n") + kTetraVertices + kTetraFaces),
                  "line 10: more data after the 3 faces the header declares");
    // Extra numbers on plain vertex lines where the counts hold (colours some writers add): read,
    // the rest ignored (with a warning).
    const Mesh coloured = load_mesh(dir.file("plaincolour.off", std::string("OFF\n4 4 0\n1 1 1 255 0 0\n1 -1 -1\n"
                                                                              "-1 1 -1\n-1 -1 1\n") +
                                                                  kTetraFaces),
                                     LoadOptions{.normalize_area = false});
    CHECK(coloured.vertices[0] == Eigen::Vector3d(1, 1, 1));
    // A COFF vertex carries its colour: extra numbers are its fields there, not a miscount.
    REQUIRE_NOTHROW(load_mesh(dir.file("colour.off", std::string("COFF\n4 4 0\n") +
                                                         "1 1 1 255 0 0 255\n1 -1 -1 0 255 0 255\n"
                                                         "-1 1 -1 0 0 255 255\n-1 -1 1 9 9 9 255\n" +
                                                         kTetraFaces)));
    // Face colours after the indices, comments and blank lines after the faces are fine.
    REQUIRE_NOTHROW(load_mesh(dir.file("facecolour.off", kTetraHeader + "3 0 1 2 1 0 0\n3 0 3 1\n3 0 2 3\n"
                                                                        "3 1 3 2\n\n# end\n")));
  }
  SUBCASE("huge coordinates whose areas would overflow") {
    check_invalid(dir.file("far.off", std::string("OFF\n4 4 0\n1e200 1 1\n1 -1 -1\n-1 1 -1\n-1 -1 1\n") + kTetraFaces),
                  "vertex 0 has a coordinate beyond ±1e+75");
    // Large but computable: accepted (areas are normalised after loading).
    REQUIRE_NOTHROW(load_mesh(dir.file("large.off", std::string("OFF\n4 4 0\n1e70 1e70 1e70\n1e70 -1e70 -1e70\n"
                                                                    "-1e70 1e70 -1e70\n-1e70 -1e70 1e70\n") +
                                                        kTetraFaces)));
  }
  SUBCASE("a directory named as a mesh") {
    fs::create_directories(dir / "folder.off");
    CHECK_THROWS_WITH_AS(load_mesh(dir / "folder.off"), doctest::Contains("is a directory"), IoError);
  }
  SUBCASE("huge counts that would overflow int indices") {
    check_invalid(dir.file("huge.off", "OFF\n3000000000 1 0\n"), "too large");
    check_invalid(dir.file("huge2.off", "OFF\n3 900000000 0\n"), "too large");
  }
  SUBCASE("degenerate and zero-area faces") {
    check_invalid(dir.file("repeat.off", kTetraHeader + "3 0 1 1\n3 0 3 1\n3 0 2 3\n3 1 3 2\n"),
                  "face 0 (0, 1, 1) is degenerate: it repeats a vertex");
    // An octahedron whose +x vertex moved onto the segment between +y and +z.
    check_invalid(dir.file("flat.off",
                           "OFF\n6 8 0\n0 0.5 0.5\n-1 0 0\n0 1 0\n0 -1 0\n0 0 1\n0 0 -1\n"
                           "3 0 2 4\n3 2 1 4\n3 1 3 4\n3 3 0 4\n3 2 0 5\n3 1 2 5\n3 3 1 5\n3 0 3 5\n"),
                  "face 0 (0, 2, 4) has zero area");
  }
  SUBCASE("open mesh") {
    Mesh sphere = shapes::icosphere(1);
    sphere.faces.pop_back();
    check_invalid(dir.file("open.off", off(sphere)), "not closed: 3 boundary edges");
  }
  SUBCASE("non-manifold edge: three faces on one edge") {
    const std::string fin = std::string("OFF\n5 5 0\n") + kTetraVertices + "0 0 5\n" + kTetraFaces + "3 0 1 4\n";
    check_invalid(dir.file("fin.off", fin),
                  "non-manifold: 1 edges are shared by more than two faces, e.g. edge (0, 1) by 3");
    // OpenMesh's own mesh kernel would drop the extra face; the PLY path must still see it.
    const std::string ply = std::string("ply\nformat ascii 1.0\nelement vertex 5\n") +
                            "property float x\nproperty float y\nproperty float z\nelement face 5\n" +
                            "property list uchar int vertex_indices\nend_header\n" +
                            kTetraVertices + "0 0 5\n" + kTetraFaces + "3 0 1 4\n";
    check_invalid(dir.file("fin.ply", ply), "non-manifold: 1 edges");
  }
  SUBCASE("non-manifold vertex: two tetrahedra touching at a vertex") {
    check_invalid(dir.file("bowtie.off",
                           std::string("OFF\n7 8 0\n") + kTetraVertices + "3 3 3\n1 3 5\n3 1 5\n" + kTetraFaces +
                               "3 3 4 5\n3 3 6 4\n3 3 5 6\n3 4 6 5\n"),
                  "non-manifold: 1 vertices have faces that do not form a single fan, e.g. vertex 3");
  }
  SUBCASE("flipped face") {
    check_invalid(dir.file("flipped.off", kTetraHeader + "3 0 2 1\n3 0 3 1\n3 0 2 3\n3 1 3 2\n"),
                  "inconsistent orientation: 3 edges are traversed twice in the same direction");
  }
  SUBCASE("two components") {
    Mesh two = shapes::tetrahedron();
    for (const auto& f : shapes::tetrahedron().faces) two.faces.push_back({f[0] + 4, f[1] + 4, f[2] + 4});
    for (const auto& p : shapes::tetrahedron().vertices) two.vertices.push_back(p + Eigen::Vector3d(5, 0, 0));
    check_invalid(dir.file("two.off", off(two)), "2 connected components");
  }
  SUBCASE("unused vertex") {
    check_invalid(dir.file("unused.off", std::string("OFF\n5 4 0\n") + kTetraVertices + "9 9 9\n" + kTetraFaces),
                  "1 vertices are not used by any face, e.g. vertex 4");
  }
  SUBCASE("STL triangles that collapse when corners are merged") {
    std::string stl = "solid t\n";
    const Mesh t = shapes::tetrahedron();
    auto facet = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
      stl += "facet normal 0 0 0\nouter loop\n";
      for (const auto* p : {&a, &b, &c})
        stl += "vertex " + std::to_string(p->x()) + " " + std::to_string(p->y()) + " " + std::to_string(p->z()) + "\n";
      stl += "endloop\nendfacet\n";
    };
    for (const auto& f : t.faces) facet(t.vertices[f[0]], t.vertices[f[1]], t.vertices[f[2]]);
    facet(t.vertices[0], t.vertices[0], t.vertices[1]);
    stl += "endsolid t\n";
    check_invalid(dir.file("degenerate.stl", stl), "1 of 5 triangles are degenerate");
  }
  SUBCASE("make_mesh validates too") {
    CHECK_THROWS_WITH_AS(make_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}, "triangle"),
                         "triangle: not closed: 3 boundary edges (edges with only one face), e.g. (0, 1)",
                         InvalidInputError);
    CHECK_THROWS_WITH_AS(make_mesh({}, {}, "nothing"), "nothing: no faces", InvalidInputError);
  }
}

TEST_CASE("mesh: decimation keeps a valid closed mesh near the target") {
  Mesh sphere = shapes::icosphere(4);
  normalize_area(sphere);
  const Mesh coarse = decimate(sphere, 200);
  CHECK(coarse.num_faces() <= 200);
  CHECK(coarse.num_faces() >= 190);
  CHECK(validate_mesh(coarse) == 0);
  CHECK(coarse.name == sphere.name);
  CHECK(coarse.num_edges() == 3 * coarse.num_faces() / 2);
  CHECK(surface_area(coarse) == doctest::Approx(1.0).epsilon(1e-12));
  CHECK(signed_volume(coarse) > 0);
  // Still a sphere: every vertex at nearly the same distance from the centre.
  double rmin = 1e9, rmax = 0;
  for (const auto& p : coarse.vertices) {
    rmin = std::min(rmin, p.norm());
    rmax = std::max(rmax, p.norm());
  }
  CHECK(rmax / rmin < 1.05);

  const Mesh finger = decimate(shapes::bent_finger(70, 30, 20), 300);
  CHECK(finger.num_faces() <= 300);
  CHECK(validate_mesh(finger) == 0);

  const Mesh small = decimate(shapes::octahedron(), 100);
  CHECK(small.faces == shapes::octahedron().faces);
  CHECK(small.vertices == shapes::octahedron().vertices);
  CHECK_THROWS_AS(decimate(sphere, 0), InvalidInputError);
}
