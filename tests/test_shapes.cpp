#include "shapematch/errors.hpp"
#include "shapematch/shapes.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <random>

using namespace shapematch;
namespace fs = std::filesystem;

namespace {

// Every face of a convex shape around the origin must face away from it (CCW from outside).
void check_outward_convex(const Mesh& m) {
  CAPTURE(m.name);
  for (const auto& f : m.faces) {
    const Eigen::Vector3d &a = m.vertices[f[0]], &b = m.vertices[f[1]], &c = m.vertices[f[2]];
    CHECK((b - a).cross(c - a).dot(a + b + c) > 0);
  }
}

Eigen::Vector3d ring_centre(const Mesh& m, int ring, int segments) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int j = 0; j < segments; ++j) c += m.vertices[1 + ring * segments + j];
  return c / segments;
}

}  // namespace

TEST_CASE("shapes: platonic solids and icospheres are closed, outward and genus 0") {
  const Mesh tet = shapes::tetrahedron(), oct = shapes::octahedron();
  CHECK(tet.num_faces() == 4);
  CHECK(oct.num_faces() == 8);
  check_outward_convex(tet);
  check_outward_convex(oct);
  CHECK(validate_mesh(tet) == 0);
  CHECK(validate_mesh(oct) == 0);
  for (int s = 0; s <= 3; ++s) {
    const Mesh m = shapes::icosphere(s, 2.5);
    CHECK(m.num_faces() == 20 * (1 << (2 * s)));
    CHECK(m.num_vertices() == 10 * (1 << (2 * s)) + 2);
    CHECK(validate_mesh(m) == 0);
    check_outward_convex(m);
    for (const auto& p : m.vertices) CHECK(p.norm() == doctest::Approx(2.5));
  }
  CHECK(signed_volume(shapes::icosphere(4)) == doctest::Approx(4.0 / 3.0 * M_PI).epsilon(0.01));
  CHECK_THROWS_AS(shapes::icosphere(-1), InvalidInputError);
}

TEST_CASE("shapes: torus has genus 1 and the right volume") {
  const Mesh m = shapes::torus(64, 32, 1.0, 0.3);
  CHECK(m.num_faces() == 2 * 64 * 32);
  CHECK(validate_mesh(m) == 1);
  CHECK(signed_volume(m) == doctest::Approx(2 * M_PI * M_PI * 1.0 * 0.3 * 0.3).epsilon(0.01));
  CHECK_THROWS_AS(shapes::torus(2, 8), InvalidInputError);
}

TEST_CASE("shapes: the bent finger keeps its connectivity and bends by the given angle") {
  const int rings = 30, segments = 20;
  const Mesh straight = shapes::bent_finger(10, rings, segments);
  const Mesh bent = shapes::bent_finger(70, rings, segments);
  CHECK(straight.faces == bent.faces);
  CHECK(straight.num_faces() == 2 * rings * segments);
  CHECK(validate_mesh(straight) == 0);
  CHECK(validate_mesh(bent) == 0);
  CHECK(signed_volume(straight) > 0);
  CHECK(signed_volume(bent) > 0);
  // Bending is nearly isometric: areas and volumes change little.
  CHECK(surface_area(bent) == doctest::Approx(surface_area(straight)).epsilon(0.02));
  CHECK(signed_volume(bent) == doctest::Approx(signed_volume(straight)).epsilon(0.02));

  // Rings 2-5 lie before the joint, rings 22-24 after it: their axis turns by the bend.
  for (const double degrees : {0.0, 10.0, 70.0, 90.0}) {
    const Mesh m = shapes::bent_finger(degrees, rings, segments);
    const Eigen::Vector3d base = ring_centre(m, 5, segments) - ring_centre(m, 2, segments);
    const Eigen::Vector3d tip = ring_centre(m, 24, segments) - ring_centre(m, 22, segments);
    const double angle = std::acos(base.normalized().dot(tip.normalized())) * 180 / M_PI;
    CAPTURE(degrees);
    CHECK(angle == doctest::Approx(degrees).epsilon(0.01).scale(10.0));
    CHECK(tip.y() <= 1e-3);  // towards the palm (-y), away from the knuckle
  }

  // No symmetry: the knuckle makes +y differ from -y, the taper the base from the tip.
  const Mesh flat = shapes::bent_finger(0, rings, segments);
  double ymax = 0, ymin = 0;
  for (const auto& p : flat.vertices) {
    ymax = std::max(ymax, p.y());
    ymin = std::min(ymin, p.y());
  }
  CHECK(ymax > -ymin + 0.05);
  const double base_radius = (flat.vertices[1 + 5 * segments] - ring_centre(flat, 5, segments)).norm();
  const double tip_radius = (flat.vertices[1 + 24 * segments] - ring_centre(flat, 24, segments)).norm();
  CHECK(base_radius > tip_radius + 0.05);
  CHECK_THROWS_AS(shapes::bent_finger(10, 1, 20), InvalidInputError);
}

TEST_CASE("shapes: the dolphin keeps its connectivity, bends by the given angles and has no symmetry") {
  const int rings = 30, segments = 20;
  const Mesh straight = shapes::dolphin(0, 0, rings, segments);
  const Mesh swimming = shapes::dolphin(-40, 45, rings, segments);
  CHECK(straight.faces == swimming.faces);
  CHECK(straight.num_faces() == 2 * rings * segments);
  CHECK(validate_mesh(straight) == 0);
  CHECK(validate_mesh(swimming) == 0);
  CHECK(signed_volume(straight) > 0);
  CHECK(signed_volume(swimming) > 0);
  CHECK(surface_area(swimming) == doctest::Approx(surface_area(straight)).epsilon(0.03));
  CHECK(signed_volume(swimming) == doctest::Approx(signed_volume(straight)).epsilon(0.03));

  // The spine runs along (1, 0, -1) and turns in the vertical plane through it: rings 2-5 lie
  // before the tail joint, 14-17 between the joints, 25-27 after the head joint. A ring's two
  // side vertices (theta = 0 and pi) straddle the spine; the fin shifts its centroid.
  auto spine = [&](const Mesh& m, int ring) {
    return Eigen::Vector3d(
        (m.vertices[1 + ring * segments] + m.vertices[1 + ring * segments + segments / 2]) / 2);
  };
  auto direction = [&](const Mesh& m, int from, int to) {
    return Eigen::Vector3d(spine(m, to) - spine(m, from)).normalized();
  };
  auto degrees_up = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {  // signed, + turns up
    return std::atan2(b.y(), b.cwiseProduct(Eigen::Vector3d(1, 0, 1)).norm()) * 180 / M_PI -
           std::atan2(a.y(), a.cwiseProduct(Eigen::Vector3d(1, 0, 1)).norm()) * 180 / M_PI;
  };
  for (const auto& [head, tail] : {std::pair{0.0, 0.0}, {-40.0, 45.0}, {30.0, -20.0}}) {
    const Mesh m = shapes::dolphin(head, tail, rings, segments);
    const Eigen::Vector3d t = direction(m, 2, 5), b = direction(m, 14, 17), h = direction(m, 25, 27);
    CAPTURE(head);
    CAPTURE(tail);
    CHECK(degrees_up(t, b) == doctest::Approx(tail).scale(10.0).epsilon(0.02));
    CHECK(degrees_up(b, h) == doctest::Approx(head).scale(10.0).epsilon(0.02));
    CHECK(t.x() == doctest::Approx(-t.z()).epsilon(1e-6));  // the spine stays in the plane x = -z
  }
  const Eigen::Vector3d along = direction(straight, 2, 27);
  CHECK(along.isApprox(Eigen::Vector3d(1, 0, -1).normalized(), 1e-6));

  // The fin makes up differ from down; the body thickness makes the head differ from the tail;
  // the flukes are wider than high (the body the other way), so no rotation about the spine fits.
  double ymax = 0, ymin = 0;
  for (const auto& p : straight.vertices) {
    ymax = std::max(ymax, p.y());
    ymin = std::min(ymin, p.y());
  }
  CHECK(ymax > -ymin + 0.1);
  auto extent = [&](int ring, const Eigen::Vector3d& axis) {
    double lo = 1e9, hi = -1e9;
    for (int j = 0; j < segments; ++j) {
      const double v = straight.vertices[1 + ring * segments + j].dot(axis);
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
    return hi - lo;
  };
  const Eigen::Vector3d side = Eigen::Vector3d(1, 0, 1).normalized(), up = Eigen::Vector3d::UnitY();
  CHECK(extent(24, up) > 2 * extent(4, up));
  CHECK(extent(4, side) > 1.5 * extent(4, up));
  CHECK(extent(20, up) > 1.2 * extent(20, side));
  CHECK_THROWS_AS(shapes::dolphin(10, std::nan(""), rings, segments), InvalidInputError);
}

TEST_CASE("shapes: bundled assets are what the generator writes") {
  const fs::path committed = SHAPEMATCH_ASSETS_DIR;
  std::random_device rd;
  const fs::path fresh = fs::temp_directory_path() / ("shapematch-assets-" + std::to_string(rd()));
  shapes::write_bundled_assets(fresh.string());
  for (const std::string name :
       {"dolphin_straight.off", "dolphin_swimming.off", "finger_straight.off", "finger_bent.off"}) {
    CAPTURE(name);
    const Mesh a = load_mesh((committed / name).string(), {.normalize_area = false});
    const Mesh b = load_mesh((fresh / name).string(), {.normalize_area = false});
    CHECK(a.faces == b.faces);
    REQUIRE(a.num_vertices() == b.num_vertices());
    double worst = 0;
    for (int v = 0; v < a.num_vertices(); ++v) worst = std::max(worst, (a.vertices[v] - b.vertices[v]).norm());
    CHECK(worst < 1e-9);
    MeshReport report;
    const Mesh m = load_mesh((committed / name).string(), {}, &report);
    CHECK(report.genus == 0);
    CHECK(m.num_faces() >= 1000);
    CHECK(m.num_faces() <= 1500);
    CHECK(surface_area(m) == doctest::Approx(1.0));
  }
  CHECK(load_mesh((committed / "finger_straight.off").string()).faces ==
        load_mesh((committed / "finger_bent.off").string()).faces);
  CHECK(load_mesh((committed / "dolphin_straight.off").string()).faces ==
        load_mesh((committed / "dolphin_swimming.off").string()).faces);
  fs::remove_all(fresh);
}
