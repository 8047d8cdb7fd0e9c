// Real meshes from ../shared/datasets (never copied into the repository). Skips cleanly when the
// folder is absent, as on a machine without the evaluation data.
#include "shapematch/errors.hpp"
#include "shapematch/matching.hpp"

#include <doctest/doctest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

using namespace shapematch;
namespace fs = std::filesystem;

namespace {

bool have(const fs::path& p) {
  if (fs::exists(p)) return true;
  MESSAGE("dataset file absent, skipped: " << p.string());
  return false;
}

const fs::path kData = SHAPEMATCH_DATASETS_DIR;

}  // namespace

TEST_CASE("datasets: real meshes load, validate and decimate; open ones are rejected by name") {
  const fs::path faust = kData / "faust_r_bcicp/off/tr_reg_016.off";
  const fs::path cat = kData / "tosca_r_bcicp/isometric/off/cat0.off";
  const fs::path horse = kData / "deformation_transfer/horse-poses/1.obj";
  for (const fs::path& p : {faust, cat}) {
    if (!have(p)) continue;
    MeshReport report;
    const Mesh m = load_mesh(p.string(), {}, &report);
    CHECK(report.genus == 0);
    CHECK(surface_area(m) == doctest::Approx(1.0));
    const Mesh small = decimate(m, 40);
    CHECK(small.num_faces() <= 44);
    CHECK(validate_mesh(small) == 0);
  }
  if (have(horse)) {
    try {
      load_mesh(horse.string());
      FAIL("the horse has a hoof slit (19 boundary edges) and must be rejected");
    } catch (const InvalidInputError& e) {
      CHECK(std::string(e.what()).find(horse.string()) != std::string::npos);
      CHECK(std::string(e.what()).find("boundary") != std::string::npos);
    }
  }
}

TEST_CASE("datasets: the LP of a decimated FAUST_r pair is built and bounded") {
  const fs::path a = kData / "faust_r_bcicp/off/tr_reg_016.off", b = kData / "faust_r_bcicp/off/tr_reg_020.off";
  if (!have(a) || !have(b)) return;
  const Mesh x = decimate(load_mesh(a.string()), 20), y = decimate(load_mesh(b.string()), 20);
  const Geometry gx = compute_geometry(x), gy = compute_geometry(y);
  const MatchingLp m = build_matching_lp(x, gx, y, gy);
  CHECK(m.lp.cols() == ProductSpace::full_size(x, y));
  const LpResult exact = solve_lp(m.lp, "clp-dual");
  REQUIRE(exact.status == LpStatus::Optimal);
  const LpResult r = solve_lp(m.lp, "pdhg-cpu");
  REQUIRE(r.status == LpStatus::Optimal);
  CHECK(r.lower_bound <= exact.objective * (1 + 1e-9));
  CHECK(std::abs(r.objective - exact.objective) <= 1e-3 * exact.objective);
}

// The pairs files behind docs/results.md's tables (`bench match --pairs`) are made from the data
// sets' own test-pair lists by tools/make_pairs.sh; every file they name must exist.
TEST_CASE("datasets: tools/make_pairs.sh writes pairs files that name existing files") {
  if (!have(kData)) return;
  const fs::path script = fs::path(SHAPEMATCH_ASSETS_DIR).parent_path() / "tools" / "make_pairs.sh";
  const fs::path out = fs::temp_directory_path() / "shapematch_make_pairs_test";
  fs::remove_all(out);
  const std::string cmd = "bash " + script.string() + " " + kData.string() + " " + out.string() + " >/dev/null";
  REQUIRE(std::system(cmd.c_str()) == 0);
  int lines = 0;
  for (const char* name : {"faust_r_test.txt", "tosca_r_test.txt", "deformation_transfer.txt"}) {
    std::ifstream in(out / name);
    REQUIRE(in.good());
    std::string line;
    while (std::getline(in, line)) {
      ++lines;
      std::istringstream words(line);
      std::vector<std::string> w{std::istream_iterator<std::string>(words), {}};
      CAPTURE(line);
      CHECK((w.size() == 3 || w.size() == 5));
      for (const std::string& word : w)
        if (word != "identity") CHECK(fs::exists(word));
    }
  }
  CHECK(lines == 15 + 21 + 4);
  fs::remove_all(out);
}
