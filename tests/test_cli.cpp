// End-to-end tests of the `shapematch` executable: exit codes, one-line errors, JSON output.
#include "shapematch/coarse_to_fine.hpp"
#include "shapematch/rounding.hpp"
#include "shapematch/system.hpp"
#include "test_helpers.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;

namespace {

using Run = shapematch::test::CliRun;
using shapematch::test::json_number;
Run run(const std::string& args) { return shapematch::test::run_cli(args); }

std::string json_string(const std::string& json, const std::string& key) {
  const auto at = json.find("\"" + key + "\": \"");
  REQUIRE(at != std::string::npos);
  const auto begin = at + key.size() + 5;
  return json.substr(begin, json.find('"', begin) - begin);
}

fs::path write_temp(const std::string& name, const std::string& text) {
  const fs::path dir = fs::temp_directory_path() / "shapematch_cli";
  fs::create_directories(dir);
  const fs::path p = dir / name;
  std::ofstream(p) << text;
  return p;
}

std::string read_file(const fs::path& p) {
  std::ifstream in(p);
  REQUIRE_MESSAGE(in.good(), p.string());
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

const std::string kTetra = "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";

// How often `what` occurs in `text`.
size_t count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}
}  // namespace

TEST_CASE("cli: lp on the bundled pair is positive, on an identity pair zero") {
  const std::string a = std::string(SHAPEMATCH_ASSETS_DIR) + "/finger_straight.off";
  const std::string b = std::string(SHAPEMATCH_ASSETS_DIR) + "/finger_bent.off";
  Run r = run("lp --faces 40 --solver clp-dual");
  REQUIRE(r.code == 0);
  CHECK(json_string(r.out, "status") == "optimal");
  CHECK(json_number(r.out, "objective") > 1e-6);
  CHECK(json_number(r.out, "variables") > 0);
  CHECK(json_number(r.out, "peak_rss_mb") > 0);

  r = run("lp " + a + " " + a + " --faces 40 --solver clp-dual");
  REQUIRE(r.code == 0);
  CHECK(std::abs(json_number(r.out, "objective")) < 1e-9);

  const fs::path mps = fs::temp_directory_path() / "shapematch_cli_test.mps";
  r = run("lp " + a + " " + b + " --faces 20 --solver pdhg-cpu --export-mps " + mps.string());
  REQUIRE(r.code == 0);
  CHECK(json_string(r.out, "status") == "optimal");
  CHECK(json_number(r.out, "lower_bound") <= json_number(r.out, "objective") + 1e-12);
  CHECK(fs::file_size(mps) > 1000);
  fs::remove(mps);

  // The same LP written out and solved again from the file: the same optimum.
  const fs::path file = fs::temp_directory_path() / "shapematch_cli_test.smlp";
  r = run("lp " + a + " " + b + " --faces 20 --solver clp-dual --export-lp " + file.string());
  REQUIRE(r.code == 0);
  const double objective = json_number(r.out, "objective");
  Run again = run("lp --from " + file.string() + " --solver clp-dual");
  REQUIRE(again.code == 0);
  CHECK(json_number(again.out, "objective") == doctest::Approx(objective).epsilon(1e-9));
  CHECK(json_number(again.out, "variables") == json_number(r.out, "variables"));
  CHECK(json_string(again.out, "from") == file.string());
  again = run("lp " + a + " " + b + " --from " + file.string());
  CHECK(again.code == 1);
  CHECK(again.err.find("not both") != std::string::npos);
  fs::remove(file);
}

TEST_CASE("cli: match --branch-depth dives at the coarsest level and reports it") {
  shapematch::test::TempDir tmp;
  const std::string straight = std::string(SHAPEMATCH_ASSETS_DIR) + "/finger_straight.off";
  const std::string bent = std::string(SHAPEMATCH_ASSETS_DIR) + "/finger_bent.off";
  // At 60 faces without WKS this pair's LP is fractional, and its plain rounding ends 73 % above
  // its bound (1.369 against 0.791); the dive's first step rounds both sides (0.832 and 0.809), and
  // at the second (any split counts) both sides' LP bounds are above 0.809: not rounded.
  const std::string pair = "match " + straight + " " + bent + " --faces 60 --levels 1 --backend cpu --wks off ";
  const fs::path dive = tmp.path / "dive";
  Run r = run(pair + "--branch-depth 2 --branch-min-split 0.01 -o " + dive.string());
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(r.err.find("level 1: branch 1, vertex") != std::string::npos);
  CHECK(r.err.find("level 1: branch 2, vertex") != std::string::npos);
  CHECK(r.err.find("not rounded") != std::string::npos);
  const size_t at = r.err.find("a branch's Γ goes on: energy ");
  REQUIRE(at != std::string::npos);
  const std::string b = read_file(dive / "report.json");
  CHECK(b.find("\"branch_depth\": 2") != std::string::npos);
  const std::string lb = b.substr(b.find("\"levels\": ["));
  const double plain = std::stod(r.err.substr(r.err.find(" against ", at) + 9));
  MESSAGE("plain ", plain, ", dive ", json_number(b, "energy"), " (bound ", json_number(b, "lower_bound"), "), ",
          json_number(lb, "branch_roundings"), " sides");
  CHECK(json_number(b, "energy") < 0.9 * plain);
  CHECK(json_number(lb, "branch_roundings") == 2);
  CHECK(lb.find("\"branch_kept\": true") != std::string::npos);
  CHECK(json_number(lb, "branch_energy") == doctest::Approx(json_number(b, "energy")).epsilon(1e-9));
  CHECK(json_number(b, "lower_bound") < json_number(b, "energy"));
  CHECK(b.find("\"orientation_preserved\": true") != std::string::npos);
  r = run("match " + straight + " " + bent + " --faces 20 --levels 1 --backend cpu --branch-rings 2 -o " +
          (tmp.path / "alone").string());
  CHECK(r.err.find("without --branch-depth: no effect") != std::string::npos);
  r = run(pair + "--branch-depth -1 -o " + (tmp.path / "bad").string());
  CHECK(r.code != 0);
  CHECK_FALSE(fs::exists(tmp.path / "bad"));
}

TEST_CASE("cli: match --feasibility-first tests a refined level's first LPs at zero cost until one is feasible") {
  shapematch::test::TempDir tmp;
  const std::string straight = std::string(SHAPEMATCH_ASSETS_DIR) + "/finger_straight.off";
  const std::string bent = std::string(SHAPEMATCH_ASSETS_DIR) + "/finger_bent.off";
  // At ring 0 level 2's first LPs are widened on propagation's contradictions, then three are
  // solved: the first (tested at zero cost, feasible) and two re-solves after pricing widenings,
  // whose spaces contain its space (not tested). Level 1 is the full space (not tested).
  const std::string pair = "match " + straight + " " + bent +
                           " --faces 240 --levels 2 --ring 0 --coarse-ring 0 --backend cpu --threads 1 ";
  Run r = run("-v " + pair + "--feasibility-first 2000 -o " + (tmp.path / "tested").string());
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(count(r.err, "round 1's LP at zero cost: optimal") == 1);
  CHECK(count(r.err, "level 2 round  1:") >= 2);
  const std::string tested = read_file(tmp.path / "tested" / "report.json");
  CHECK(tested.find("\"feasibility_first\": 2000") != std::string::npos);
  // On a feasible LP the pre-test changes nothing but the time.
  r = run("-v " + pair + "--feasibility-first 0 -o " + (tmp.path / "plain").string());
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(count(r.err, "at zero cost") == 0);
  // The default: off (measured: narrower spaces, higher energies at 3 000 faces).
  CHECK(run(pair + "--help").out.find("--feasibility-first INT:NONNEGATIVE=0") != std::string::npos);
  const std::string plain = read_file(tmp.path / "plain" / "report.json");
  CHECK(plain.find("\"feasibility_first\": 0") != std::string::npos);
  CHECK(json_number(tested, "energy") == doctest::Approx(json_number(plain, "energy")).epsilon(1e-12));
  r = run(pair + "--feasibility-first -1 -o " + (tmp.path / "bad").string());
  CHECK(r.code != 0);
  CHECK_FALSE(fs::exists(tmp.path / "bad"));
}

TEST_CASE("cli: match --zero-cost-proof-rings widens around a level's widenings after its first proof at zero cost") {
  shapematch::test::TempDir tmp;
  const std::string bent = std::string(SHAPEMATCH_ASSETS_DIR) + "/finger_bent.off";
  const std::string straight = std::string(SHAPEMATCH_ASSETS_DIR) + "/finger_straight.off";
  // Measured: at ring 0 without a margin, level 2's first LP after propagation's widenings (9 517
  // variables) is infeasible, and the pre-test proves it in 192 iterations; the LPs after it are
  // feasible.
  const std::string pair = "match " + bent + " " + straight +
                           " --faces 200 --levels 3 --ring 0 --coarse-ring 0 --widen-margin 0 --backend cpu "
                           "--threads 1 --feasibility-first 4000 ";
  Run r = run("-v " + pair + "--zero-cost-proof-rings 0 -o " + (tmp.path / "none").string());
  REQUIRE_MESSAGE(r.code == 0, r.err);
  REQUIRE(count(r.err, "proved at zero cost") >= 1);
  CHECK(count(r.err, "after a proof at zero cost") == 0);
  const std::string none = read_file(tmp.path / "none" / "report.json");
  CHECK(count(none, "\"margin_widenings\": 0") == 3);
  CHECK(none.find("\"zero_cost_proof_rings\": 0") != std::string::npos);

  r = run("-v " + pair + "--zero-cost-proof-rings 2 -o " + (tmp.path / "margin").string());
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(count(r.err, "proved at zero cost") >= 1);
  CHECK(count(r.err, "level 2: widened around all earlier local widenings (2 rings) after a proof at zero cost") == 1);
  const std::string margin = read_file(tmp.path / "margin" / "report.json");
  CHECK(count(margin, "\"margin_widenings\": 1") == 1);  // level 2's
  CHECK(margin.find("\"zero_cost_proof_rings\": 2") != std::string::npos);
  CHECK(run(pair + "--help").out.find("--zero-cost-proof-rings INT:INT in [0 - 16]=2") != std::string::npos);
}

TEST_CASE("cli: match --truth restricts the coarsest level to the true map's neighbourhood, a diagnostic") {
  shapematch::test::TempDir tmp;
  const std::string straight = std::string(SHAPEMATCH_ASSETS_DIR) + "/dolphin_straight.off";
  const std::string swimming = std::string(SHAPEMATCH_ASSETS_DIR) + "/dolphin_swimming.off";
  const fs::path out = tmp.path / "truth";
  const std::string pair = "match " + straight + " " + swimming + " --faces 300 --levels 2 --backend cpu ";
  Run r = run(pair + "--truth identity --truth-rings 1 -o " + out.string());
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(r.err.find("within 1 rings of the true map") != std::string::npos);
  std::ifstream report(out / "report.json");
  const std::string text{std::istreambuf_iterator<char>(report), {}};
  CHECK(text.find("\"truth\": \"identity\"") != std::string::npos);
  // The coarsest level's space: a few per cent of its full space (the first level in the report).
  const std::string level1 = text.substr(text.find("\"levels\": ["));
  CHECK(json_number(level1, "variables") < json_number(level1, "full_variables") / 5);
  r = run("eval " + out.string() + " --gt identity");
  REQUIRE_MESSAGE(r.code == 0, r.err);
  const std::string levels = r.out.substr(r.out.find("\"levels\""));
  CHECK(json_number(levels, "mean_geodesic_error") < 0.15);

  // The true map from two columns: the same pairs as the identity.
  const fs::path map = tmp.path / "map.txt";
  {
    std::ofstream f(map);
    for (int v = 1; v <= 20; ++v) f << v << " " << v << "\n";
  }
  r = run(pair + "--truth-map " + map.string() + " --truth-rings 16 -o " + (tmp.path / "map").string());
  CHECK_MESSAGE(r.code == 0, r.err);
  r = run(pair + "--truth identity --checkpoint " + (tmp.path / "c.ckpt").string() + " -o " + (tmp.path / "c").string());
  CHECK(r.code != 0);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  CHECK(r.err.find("--checkpoint") != std::string::npos);
  CHECK_FALSE(fs::exists(tmp.path / "c"));
  CHECK(run(pair + "--truth-x " + map.string() + " -o " + (tmp.path / "x").string()).code != 0);
  std::ofstream(map, std::ios::app) << "3 x\n";
  r = run(pair + "--truth-map " + map.string() + " -o " + (tmp.path / "bad").string());
  CHECK(r.code != 0);
  CHECK(r.err.find(map.string()) != std::string::npos);
  CHECK_FALSE(fs::exists(tmp.path / "bad"));
}

TEST_CASE("cli: malformed inputs give one clear line and a non-zero exit") {
  const fs::path good = write_temp("good.off", kTetra);
  struct Case {
    std::string file, text, expect;
  };
  const std::vector<Case> cases = {
      {"nan.off", "OFF\n4 4 0\n0 0 0\nnan 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n", "finite"},
      {"open.off", "OFF\n4 3 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n", "boundary"},
      {"nonmanifold.off",
       "OFF\n5 5 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n0 0 -1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n3 0 1 4\n", "manifold"},
      {"empty.off", "", "empty"},
      {"index.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 9\n3 1 2 3\n", "range"},
      // OpenMesh's reader says why on its own stream: in the one line, not on a line before it.
      {"flat.ply", "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nend_header\n1\n2\n",
       "openmesh could not parse the file (only vertex dimension 3 is supported.)"},
  };
  for (const auto& c : cases) {
    CAPTURE(c.file);
    const fs::path bad = write_temp(c.file, c.text);
    const Run r = run("lp " + bad.string() + " " + good.string() + " --solver clp-dual");
    CHECK(r.code != 0);
    CHECK(r.out.empty());  // no half-written result
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK(r.err.find(bad.string()) != std::string::npos);
    std::string lower = r.err;
    for (auto& ch : lower) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    CHECK(lower.find(c.expect) != std::string::npos);
  }
  const Run missing = run("lp /nonexistent/x.off " + good.string());
  CHECK(missing.code != 0);
  CHECK(missing.err.find("/nonexistent/x.off") != std::string::npos);
  const Run not_lp = run("lp --from " + good.string());
  CHECK(not_lp.code == 1);
  CHECK(not_lp.out.empty());
  CHECK(std::count(not_lp.err.begin(), not_lp.err.end(), '\n') == 1);
  CHECK(not_lp.err.find(good.string() + ": not a shapematch LP file") != std::string::npos);
  const Run unknown = run("lp --solver magic");
  CHECK(unknown.code != 0);
}

TEST_CASE("cli: match writes a verified, complete output directory, or nothing") {
  const fs::path out = fs::temp_directory_path() / "shapematch_cli_match";
  fs::remove_all(out);
  Run r = run("match --faces 30 --backend cpu -o " + out.string());
  REQUIRE(r.code == 0);
  std::ifstream f(out / "report.json");
  const std::string report((std::istreambuf_iterator<char>(f)), {});
  CHECK(report.find("\"verified\": true") != std::string::npos);
  CHECK(json_number(report, "energy") >= json_number(report, "lower_bound") - 1e-9);
  CHECK(json_number(report, "rounds") >= 1);
  // Every round's log says how far a release around a part reached, and of how many fixings.
  CHECK(json_number(report, "release_depth") >= 0.0);
  CHECK(json_number(report, "release_pool") >= 0.0);
  const double vx = json_number(report, "vertices");  // X's first
  auto count_lines = [](const fs::path& p) {
    std::ifstream in(p);
    return static_cast<double>(std::count(std::istreambuf_iterator<char>(in), {}, '\n'));
  };
  CHECK(count_lines(out / "map_x_to_y.txt") == vx);
  CHECK(count_lines(out / "map_x_to_y_points.txt") == vx);
  CHECK(count_lines(out / "map_y_to_x_points.txt") == count_lines(out / "map_y_to_x.txt"));
  CHECK(report.find("\"point_x_to_y\"") != std::string::npos);
  CHECK(count_lines(out / "graph_surface.txt") == json_number(report, "graph_surface_triangles"));
  std::ifstream png(out / "match.png", std::ios::binary);
  char sig[8] = {};
  png.read(sig, 8);
  CHECK(std::string(sig + 1, 3) == "PNG");
  CHECK(fs::file_size(out / "match.png") > 10000);
  CHECK(fs::exists(out / "x.ply"));
  CHECK(fs::exists(out / "y.ply"));
  CHECK(report.find("\"close_pockets\": false") != std::string::npos);  // off by default
  CHECK(json_number(report, "pockets_closed") == 0);
  CHECK(json_number(report, "untangle_rings") == 24);  // the defaults reach the report
  CHECK(json_number(report, "untangle_max_shift") == doctest::Approx(1e-3));
  CHECK(json_number(report, "release_after_trims") == shapematch::RoundingOptions{}.release_after_trims);
  CHECK(json_number(report, "max_rounds") == shapematch::RoundingOptions{}.max_rounds);
  CHECK(report.find("\"max_rounds_counts\": \"rounds without a new low\"") != std::string::npos);
  CHECK(json_number(report, "feasibility_skip_row") == shapematch::RoundingOptions{}.later_feasibility_skip_row);
  CHECK(report.find("\"time_limit\": null") != std::string::npos);  // none
  // The end game's zero-cost pre-test is on by default (seventy-sixth session), at its own tolerance.
  CHECK(json_number(report, "feasibility_later") == 8192);
  CHECK(json_number(report, "feasibility_tol") == doctest::Approx(1e-5));
  // One level of 30 faces: rounded with 0.5, and again with the default alternative 0.7.
  CHECK(json_number(report, "roundings") == 2);

  // --threads 1: one host thread (the report says so), the same Γ (PDHG's iterates are the same on
  // any thread count).
  CHECK(json_number(report, "threads") == shapematch::worker_threads());
  const fs::path single_thread = out.string() + "_t1";
  r = run("match --faces 30 --backend cpu --threads 1 -o " + single_thread.string());
  REQUIRE(r.code == 0);
  std::ifstream ft(single_thread / "report.json");
  const std::string one_thread((std::istreambuf_iterator<char>(ft)), {});
  CHECK(json_number(one_thread, "threads") == 1);
  CHECK(json_number(one_thread, "energy") == doctest::Approx(json_number(report, "energy")).epsilon(1e-9));
  fs::remove_all(single_thread);

  // --close-pockets reaches the rounding and the report (no pocket at 30 faces; the repair
  // itself is tested in test_rounding).
  const fs::path closed = out.string() + "_pockets";
  r = run("match --faces 30 --backend cpu --close-pockets --max-rounds 9 --feasibility-skip-row 0.05 "
          "--feasibility-skip-below 64 --max-ring 4 --suspicion-margins 3 --recurring-beyond 2 --proof-beyond 5 --suspicion-margin-around named --divergence-bound-factor 1.5 -o " +
          closed.string());
  REQUIRE(r.code == 0);
  std::ifstream fc(closed / "report.json");
  const std::string with((std::istreambuf_iterator<char>(fc)), {});
  CHECK(with.find("\"close_pockets\": true") != std::string::npos);
  // The rounding's and the widening's caps reach the report as given.
  CHECK(json_number(with, "max_rounds") == 9);
  CHECK(json_number(with, "feasibility_skip_row") == doctest::Approx(0.05));
  CHECK(json_number(with, "feasibility_skip_below") == 64);
  CHECK(json_number(with, "max_ring") == 4);
  CHECK(json_number(with, "suspicion_margins") == 3);
  CHECK(json_number(with, "recurring_beyond") == 2);
  CHECK(json_number(with, "proof_beyond") == 5);
  CHECK(json_string(with, "suspicion_margin_around") == "named");
  CHECK(json_number(with, "divergence_bound_factor") == 1.5);
  CHECK(json_number(with, "pockets_closed") >= 0);
  CHECK(with.find("\"verified\": true") != std::string::npos);
  fs::remove_all(closed);

  // --alt-thresholds none rounds once; a threshold outside (0, 1) is a usage error naming the option.
  const fs::path once = out.string() + "_once";
  r = run("match --faces 30 --backend cpu --alt-thresholds none -o " + once.string());
  REQUIRE(r.code == 0);
  std::ifstream fo(once / "report.json");
  const std::string single((std::istreambuf_iterator<char>(fo)), {});
  CHECK(json_number(single, "roundings") == 1);
  fs::remove_all(once);
  r = run("match --faces 30 --backend cpu --alt-thresholds 0.7,1.5 -o " + once.string());
  CHECK(r.code != 0);
  CHECK(r.err.find("--alt-thresholds") != std::string::npos);
  CHECK_FALSE(fs::exists(once));

  // --backend cpu-f32 reaches the solver (the report names it) and lands on the fp64 run's Γ, or
  // one of the same energy within the LP tolerance.
  const fs::path f32 = out.string() + "_f32";
  r = run("match --faces 30 --backend cpu-f32 -o " + f32.string());
  REQUIRE(r.code == 0);
  std::ifstream ff(f32 / "report.json");
  const std::string narrow((std::istreambuf_iterator<char>(ff)), {});
  CHECK(narrow.find("\"pdhg-cpu-f32\"") != std::string::npos);
  CHECK(narrow.find("\"verified\": true") != std::string::npos);
  CHECK(std::abs(json_number(narrow, "energy") - json_number(report, "energy")) <=
        1e-3 * std::abs(json_number(report, "energy")));
  fs::remove_all(f32);

  // A failing run leaves the previous output untouched and no temporary directory behind.
  const fs::path bad = write_temp("open2.off", "OFF\n4 3 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n");
  r = run("match " + bad.string() + " " + bad.string() + " -o " + out.string());
  CHECK(r.code != 0);
  CHECK(fs::exists(out / "report.json"));
  for (const auto& entry : fs::directory_iterator(out.parent_path()))
    CHECK(entry.path().filename().string().rfind("shapematch_cli_match.tmp", 0) != 0);
  fs::remove_all(out);
}

// The error is one line in the documented form, stderr's last (after the log, if any), exit 1,
// nothing on stdout.
void check_usage_error(const Run& r, const std::string& expect) {
  CAPTURE(r.err);
  CHECK(r.code == 1);
  CHECK(r.out.empty());
  REQUIRE(!r.err.empty());
  CHECK(r.err.back() == '\n');
  const size_t last = r.err.rfind('\n', r.err.size() - 2);
  const std::string line = r.err.substr(last == std::string::npos ? 0 : last + 1);
  CHECK(line.rfind("shapematch: error: ", 0) == 0);
  CHECK(line.find(expect) != std::string::npos);
  CHECK(r.err.find("shapematch: error: ") == (last == std::string::npos ? 0 : last + 1));  // (only there)
}

TEST_CASE("cli: match replaces only an earlier output, and sweeps what a stopped run left") {
  const fs::path base = fs::temp_directory_path() / "shapematch_cli_out";
  fs::remove_all(base);
  fs::create_directories(base);
  const std::string tetra = write_temp("out_tetra.off", kTetra).string();
  const std::string pair = "match " + tetra + " " + tetra + " --backend cpu ";

  // A directory of the user's own, a file, an empty name, the root: refused before any work,
  // and left as they were.
  const fs::path mine = base / "mine";
  fs::create_directories(mine);
  { std::ofstream(mine / "thesis.tex") << "x"; }
  check_usage_error(run(pair + "-o " + mine.string()), mine.string() + ": exists and is not a match output");
  CHECK(fs::exists(mine / "thesis.tex"));
  const fs::path file = base / "file";
  { std::ofstream(file) << "y"; }
  check_usage_error(run(pair + "-o " + file.string()), file.string() + ": exists and is not a directory");
  CHECK(fs::is_regular_file(file));
  check_usage_error(run(pair + "-o ''"), "--out: empty path");
  check_usage_error(run(pair + "-o /"), "the root cannot be an output directory");

  // An empty directory, then the output it became: replaced.
  const fs::path out = base / "out";
  fs::create_directories(out);
  REQUIRE(run(pair + "-o " + out.string()).code == 0);
  REQUIRE(fs::exists(out / "report.json"));
  { std::ofstream(out / "note.txt") << "z"; }
  REQUIRE(run(pair + "-o " + out.string() + "/").code == 0);
  CHECK(fs::exists(out / "report.json"));
  CHECK_FALSE(fs::exists(out / "note.txt"));  // (the whole directory is the run's)

  // What a run stopped while writing leaves (its process gone, its marker inside): its temporary
  // directory is removed; the output it was replacing goes back in place if nothing took its
  // place. Folders of the same names without the markers are the user's: left alone.
  const pid_t child = fork();
  if (child == 0) _exit(0);
  REQUIRE(child > 0);
  waitpid(child, nullptr, 0);  // a process id that is no one's now
  const std::string gone = std::to_string(child);
  fs::create_directories(base / ("out.tmp-" + gone));
  { std::ofstream(base / ("out.tmp-" + gone) / ".shapematch-writing") << gone << "\n"; }
  { std::ofstream(out / ".shapematch-replaced") << gone << "\n"; }
  fs::rename(out, base / ("out.old-" + gone));
  for (const char* user : {"out.tmp-notapid", "out.old-2023", "out.tmp-2024"}) {
    fs::create_directories(base / user);
    std::ofstream(base / user / "mine.txt") << "keep";
  }
  REQUIRE(run(pair + "-o " + (base / "other").string()).code == 0);  // (another output's run sweeps none of them)
  CHECK(fs::exists(base / ("out.tmp-" + gone)));
  CHECK(fs::exists(base / ("out.old-" + gone)));
  { std::ofstream(base / ("c.ckpt.tmp-" + gone)) << "half"; }  // a checkpoint being saved when its run was killed
  const Run again = run(pair + "--checkpoint " + (base / "c.ckpt").string() + " -o " + out.string());
  REQUIRE(again.code == 0);
  CHECK_FALSE(fs::exists(base / ("c.ckpt.tmp-" + gone)));
  CHECK(again.err.find("c.ckpt.tmp-" + gone + ": removed, left by a run killed while saving its checkpoint") != std::string::npos);
  fs::remove(base / "c.ckpt");
  CHECK(again.err.find("put back as " + out.string()) != std::string::npos);
  CHECK(again.err.find("out.tmp-" + gone + ": removed") != std::string::npos);
  CHECK(fs::exists(out / "report.json"));
  CHECK_FALSE(fs::exists(out / ".shapematch-replaced"));
  CHECK_FALSE(fs::exists(out / ".shapematch-writing"));
  std::vector<std::string> siblings;  // of the output, left beside it
  for (const auto& entry : fs::directory_iterator(base)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("out.", 0) == 0) siblings.push_back(name);
  }
  std::sort(siblings.begin(), siblings.end());
  CHECK(siblings == std::vector<std::string>{"out.old-2023", "out.tmp-2024", "out.tmp-notapid"});
  for (const char* user : {"out.tmp-notapid", "out.old-2023", "out.tmp-2024"}) CHECK(fs::exists(base / user / "mine.txt"));

  // A folder of the user's with a report.json of its own is not a match output.
  const fs::path report_only = base / "report_only";
  fs::create_directories(report_only);
  { std::ofstream(report_only / "report.json") << "{\"title\": \"my report\"}\n"; }
  check_usage_error(run(pair + "-o " + report_only.string()), report_only.string() + ": exists and is not a match output");
  CHECK(fs::exists(report_only / "report.json"));
  // A symbolic link, the current directory: refused too.
  fs::create_directory_symlink(out, base / "link");
  check_usage_error(run(pair + "-o " + (base / "link").string()), "is a symbolic link");
  const fs::path here = base / "here";
  fs::create_directories(here);
  const std::string in_here = "cd " + here.string() + " && " + SHAPEMATCH_CLI + " " + pair;
  check_usage_error(shapematch::test::run_command(in_here + "-o ."), here.string() + ": is the current directory or holds it");
  check_usage_error(shapematch::test::run_command(in_here + "-o .."), base.string() + ": is the current directory or holds it");
  CHECK(fs::is_empty(here));

  // -o DIR made by the user while the run wrote its output: the run is stopped (SIGSTOP) while
  // its temporary output exists, DIR made with a file of the user's, and the run let go on. Its
  // output is kept beside as DIR.new-PID, named in the error; DIR is left as the user made it.
  // (Where the run got past its last look at DIR before it was stopped: tried again.)
  const fs::path raced = base / "raced";
  const fs::path script = base / "race.sh";
  {
    std::ofstream sh(script);
    sh << "cd " << base.string() << "\n"
       << "for i in $(seq 20); do\n"
       << "  rm -rf raced raced.*\n"
       << "  " << SHAPEMATCH_CLI << " " << pair << "-o raced >/dev/null 2>race.err & p=$!\n"
       << "  trap 'kill -CONT $p 2>/dev/null' EXIT\n"
       << "  while [ ! -e raced.tmp-$p/.shapematch-writing ] && kill -0 $p 2>/dev/null; do :; done\n"
       << "  kill -STOP $p 2>/dev/null || { wait $p; continue; }\n"
       // (Its marker still there once stopped: it has not yet looked at DIR for the last time.)
       << "  if [ -e raced.tmp-$p/.shapematch-writing ] && mkdir raced 2>/dev/null; then echo mine > raced/mine.txt; "
          "kill -CONT $p; wait $p; echo \"$? $p\"; exit 0; fi\n"
       << "  kill -CONT $p 2>/dev/null; wait $p\n"
       << "done\n"
       << "echo missed\n";
  }
  const Run race = shapematch::test::run_command("bash " + script.string());
  std::istringstream said(race.out);
  int race_code = -1;
  std::string race_pid;
  said >> race_code >> race_pid;
  REQUIRE_MESSAGE(!race_pid.empty(), race.out);  // (caught while writing within 20 tries)
  const std::string race_err = read_file(base / "race.err");
  CHECK(race_code == 1);
  const fs::path kept = base / ("raced.new-" + race_pid);
  CHECK(race_err.find(raced.string() + ": exists and is not a match output") != std::string::npos);
  CHECK(race_err.find("it changed while this run worked; its output is in " + kept.string()) != std::string::npos);
  CHECK(read_file(raced / "mine.txt") == "mine\n");
  CHECK_FALSE(fs::exists(raced / "report.json"));
  CHECK(fs::exists(kept / "report.json"));
  CHECK(fs::exists(kept / "map_x_to_y.txt"));
  CHECK_FALSE(fs::exists(kept / ".shapematch-writing"));
  CHECK_FALSE(fs::exists(base / ("raced.tmp-" + race_pid)));
  // A later run leaves both alone: DIR is the user's, DIR.new-PID no leftover to sweep.
  check_usage_error(run(pair + "-o " + raced.string()), raced.string() + ": exists and is not a match output");
  CHECK(fs::exists(kept / "report.json"));
  fs::remove_all(base);
}

TEST_CASE("cli: an installed shapematch finds its meshes and scripts in its own share folder") {
  // `cmake --install` into a prefix of its own: the installed binary's default pair is the
  // installed copy of the bundled meshes (not the source tree's), and eval's plot script runs
  // from there where Debian's matplotlib is.
  shapematch::test::TempDir tmp;
  const fs::path prefix = tmp.path / "prefix";
  const Run installed = shapematch::test::run_command("cmake --install " + std::string(SHAPEMATCH_BUILD_DIR) +
                                                       " --prefix " + prefix.string() + " >/dev/null");
  REQUIRE_MESSAGE(installed.code == 0, installed.err);
  const fs::path share = prefix / "share" / "shapematch";
  for (const fs::path& file : {prefix / "bin" / "shapematch", share / "assets" / "dolphin_straight.off",
                               share / "assets" / "finger_bent.off", share / "tools" / "plot_pck.py",
                               share / "tools" / "plot_bench_match.py"})
    CHECK_MESSAGE(fs::is_regular_file(file), file.string());
  const std::string bin = (prefix / "bin" / "shapematch").string();
  const fs::path out = tmp.path / "out";
  const Run matched = shapematch::test::run_command("cd " + tmp.path.string() + " && " + bin +
                                                    " match --faces 60 --levels 1 --backend cpu -o " + out.string());
  REQUIRE_MESSAGE(matched.code == 0, matched.err);
  CHECK(matched.err.find((share / "assets" / "dolphin_straight.off").string()) != std::string::npos);
  CHECK(matched.err.find(SHAPEMATCH_ASSETS_DIR) == std::string::npos);
  const fs::path png = tmp.path / "pck.png";
  const Run scored = shapematch::test::run_command(bin + " eval " + out.string() + " --gt identity --threads 1 --pck-png " +
                                                   png.string() + " >/dev/null");
  REQUIRE_MESSAGE(scored.code == 0, scored.err);
  if (std::system("/usr/bin/python3 -c 'import matplotlib' >/dev/null 2>&1") == 0)
    CHECK(fs::file_size(png) > 5000);
}

TEST_CASE("cli: usage errors are one documented line with exit 1") {
  const std::string tetra = write_temp("usage_tetra.off", kTetra).string();
  const fs::path never = fs::temp_directory_path() / "shapematch_cli_usage_never";  // (no run gets to write it)
  fs::remove_all(never);
  const std::string pair = "match " + tetra + " " + tetra + " --backend cpu -o " + never.string() + " ";
  const std::vector<std::pair<std::string, std::string>> refused = {  // (arguments, the error says)
      {"", "A subcommand is required"},
      {"match --no-such-option", "--no-such-option"},
      {pair + "--tol -1", "--tol: must be positive, not -1"},
      {pair + "--tol 0", "--tol: must be positive, not 0"},
      {pair + "--faces -5", "--faces: must not be negative, not -5"},
      {pair + "--bending nan", "--bending: must be a finite number, not nan"},
      {pair + "--lame 1,inf", "--lame: must be a finite number, not inf"},
      {pair + "--time-limit -inf", "--time-limit: must be positive"},
      {"lp --max-iter -3", "--max-iter: must be positive, not -3"},
      {"lp --time-limit 0", "--time-limit: must be positive, not 0"},
  };
  for (const auto& [args, expect] : refused) {
    CAPTURE(args);
    check_usage_error(run(args), expect);
  }
  // A device asked for by index that is not there: an error, not a quiet fall back to the CPU.
  const Run device = run("match " + tetra + " " + tetra + " --backend auto --device 99 -o " + never.string());
  check_usage_error(device, "");
  CHECK(device.err.find("info X: ") == std::string::npos);  // (before any mesh is loaded)
  CHECK((device.err.find("device 99 does not exist") != std::string::npos ||
         device.err.find("Vulkan") != std::string::npos));  // (or no Vulkan at all on this machine)
  // … and with a backend that uses no device, a warning that it is not used.
  const fs::path unused = fs::temp_directory_path() / "shapematch_cli_usage_unused_device";
  fs::remove_all(unused);
  const Run cpu = run("match " + tetra + " " + tetra + " --backend cpu --device 3 -o " + unused.string());
  CHECK(cpu.code == 0);
  CHECK(cpu.err.find("--device 3 is for the Vulkan backend; --backend cpu does not use it") != std::string::npos);
  CHECK(cpu.err.find("one level") == std::string::npos);  // (the default --levels 0 is one level there anyway: no warning)
  fs::remove_all(unused);
  // The Vulkan driver before the meshes: a missing one is an error before any loading.
  const Run no_driver = shapematch::test::run_command("VK_ICD_FILENAMES=/nonexistent.json " + std::string(SHAPEMATCH_CLI) +
                                                      " match " + tetra + " " + tetra + " --backend vulkan -o " +
                                                      never.string());
  check_usage_error(no_driver, "Vulkan");
  CHECK(no_driver.err.find("info X: ") == std::string::npos);
  // bench's output folder where a file is: one line, before any run.
  check_usage_error(run("bench lp --out " + tetra), tetra + ": cannot make this output folder");
  // Both shapes at or below the coarsest size: one level, not the same level three times.
  const fs::path small = fs::temp_directory_path() / "shapematch_cli_usage_small";
  fs::remove_all(small);
  const Run one = run("match --faces 30 --levels 3 --backend cpu -o " + small.string());
  CHECK(one.code == 0);
  CHECK(one.err.find("both shapes have at most --coarsest-faces 100 faces (30 and 30): one level") != std::string::npos);
  CHECK(one.err.find("level 1/1:") != std::string::npos);
  fs::remove_all(small);
  CHECK(run("match --help").code == 0);
  CHECK(run("--version").code == 0);
  // +∞ is a limit that means none.
  const Run unlimited = run("lp " + tetra + " " + tetra + " --solver clp-dual --time-limit inf");
  CHECK(unlimited.code == 0);
  // A limit below the solver's set-up: an error naming the option, not rounds of nothing.
  const fs::path limited = fs::temp_directory_path() / "shapematch_cli_time_limited";
  fs::remove_all(limited);
  const Run tiny = run("match --faces 30 --backend cpu --time-limit 1e-9 -o " + limited.string());
  check_usage_error(tiny, "reached its time limit (1e-09 s) before its first iteration; allow more time per LP (--time-limit)");
  CHECK_FALSE(fs::exists(limited));

  // Paths that are directories where a file is wanted: one line naming them, not a crash.
  const fs::path folder = fs::temp_directory_path() / "shapematch_cli_folder";
  fs::create_directories(folder);
  check_usage_error(run("checkpoint " + folder.string()), folder.string() + ": is a directory, not a file");
  check_usage_error(run("lp --from " + folder.string()), folder.string() + ": is a directory, not a file");
  check_usage_error(run(pair + "--checkpoint " + folder.string()), folder.string() + ": is a directory, not a file");

  // bench match checks the options for its runs before the first one.
  const fs::path pairs = write_temp("usage_pairs.txt", tetra + " " + tetra + " identity\n");
  const fs::path bench = fs::temp_directory_path() / "shapematch_cli_bench_usage";
  fs::remove_all(bench);
  const std::string b = "bench match --pairs " + pairs.string() + " --faces 30 --out " + bench.string() + " -- ";
  const std::vector<std::pair<std::string, std::string>> refused_by_bench = {  // (arguments, the error says)
      {b + "-o elsewhere", "bench match: -o after `--` is set by the benchmark for each run"},
      {b + "--faces 10", "bench match: --faces after `--` is set by the benchmark"},
      {b + "--checkpoint=c", "bench match: --checkpoint after `--`"},
      {b + "--help", "bench match: --help after `--`: the options there are those of `shapematch match --help`"},
      {b + "--backend cpu -- x y", "bench match: a second `--` among the match options"},
      {b + "--bogus", "bench match: the match options after `--`: The following argument was not expected: --bogus"},
      {b + "--lame nan,1", "the match options after `--`: --lame: must be a finite number, not nan"},
  };
  for (const auto& [args, expect] : refused_by_bench) {
    CAPTURE(args);
    check_usage_error(run(args), expect);
  }
  CHECK_FALSE(fs::exists(bench));
  CHECK_FALSE(fs::exists(never));
}

// Every coarser level's map is written in input vertices and scored by eval: a shape matched
// with itself through two levels is the identity at both (exactly 0 only if the level's
// vertices are translated to input vertices correctly), and a corrupted level file is one line.
TEST_CASE("cli: match writes each coarser level's map and eval scores it") {
  shapematch::test::TempDir tmp;
  const std::string dolphin = std::string(SHAPEMATCH_ASSETS_DIR) + "/dolphin_straight.off";
  const fs::path out = tmp.path / "self";
  Run r = run("match " + dolphin + " " + dolphin + " --faces 300 --levels 2 --backend cpu -o " + out.string());
  REQUIRE_MESSAGE(r.code == 0, r.err);
  REQUIRE(fs::exists(out / "levels" / "level_1.txt"));
  CHECK_FALSE(fs::exists(out / "levels" / "level_2.txt"));  // the finest is map_x_to_y.txt
  std::ifstream lf(out / "levels" / "level_1.txt");
  int lines = 0, x = -1, y = -1;
  for (std::string line; std::getline(lf, line); ++lines) {
    std::istringstream(line) >> x >> y;
    CHECK(x == y);
  }
  CHECK(lines > 40);   // about 52 vertices at 100 faces
  CHECK(lines < 100);
  r = run("eval " + out.string() + " --gt identity");
  REQUIRE_MESSAGE(r.code == 0, r.err);
  const size_t at = r.out.find("\"levels\"");
  REQUIRE(at != std::string::npos);
  const std::string levels = r.out.substr(at);
  CHECK(json_number(levels, "level") == 1);
  CHECK(json_number(levels, "points") == lines);
  CHECK(json_number(levels, "mean_geodesic_error") == 0.0);

  // Two poses: the coarse level's error is measured on its own points, not the finest's.
  const std::string swimming = std::string(SHAPEMATCH_ASSETS_DIR) + "/dolphin_swimming.off";
  const fs::path pair = tmp.path / "pair";
  r = run("match " + dolphin + " " + swimming + " --faces 300 --levels 2 --backend cpu -o " + pair.string());
  REQUIRE_MESSAGE(r.code == 0, r.err);
  r = run("eval " + pair.string() + " --gt identity");
  REQUIRE_MESSAGE(r.code == 0, r.err);
  const std::string pl = r.out.substr(r.out.find("\"levels\""));
  CHECK(json_number(pl, "points") == lines);
  CHECK(json_number(pl, "mean_geodesic_error") > 0.0);
  CHECK(json_number(pl, "mean_geodesic_error") < 0.3);  // not a swapped match

  std::ofstream(out / "levels" / "level_1.txt", std::ios::app) << "3 7 9\n";
  r = run("eval " + out.string() + " --gt identity");
  CHECK(r.code != 0);
  CHECK(r.err.find("level_1.txt: line") != std::string::npos);
}

TEST_CASE("cli: match --checkpoint goes on after the levels a stopped run finished") {
  shapematch::test::TempDir tmp;
  const std::string dolphin = std::string(SHAPEMATCH_ASSETS_DIR) + "/dolphin_straight.off";
  const std::string swimming = std::string(SHAPEMATCH_ASSETS_DIR) + "/dolphin_swimming.off";
  const std::string ckpt = (tmp.path / "pair.ckpt").string();
  const std::string args = " --faces 200 --levels 3 --backend cpu --rounding-checkpoint-seconds 2.5 --stuck-restarts 1"
                           " --checkpoint " + ckpt + " -o ";
  Run r = run("match " + dolphin + " " + swimming + args + (tmp.path / "a").string());
  REQUIRE_MESSAGE(r.code == 0, r.err);
  REQUIRE(fs::exists(ckpt));  // after level 2 of 3
  const std::string first = read_file(tmp.path / "a" / "report.json");
  CHECK(json_number(first, "resumed_after_level") == 0);
  CHECK(json_number(first, "rounding_checkpoint_seconds") == 2.5);  // echoed with the options
  CHECK(json_number(first, "suspicion_rings") == 2);                // the default
  CHECK(json_number(first, "suspicion_margins") == 1);              // the default
  CHECK(json_number(first, "recurring_beyond") == 3);               // the default
  CHECK(json_number(first, "proof_beyond") == 3);                   // the default
  CHECK(json_string(first, "suspicion_margin_around") == "widened");  // the default
  CHECK(json_number(first, "divergence_bound_factor") == 2);          // the default
  CHECK(json_number(first, "lp_checkpoint_seconds") == 600);          // the default
  CHECK(json_number(first, "max_suspected_widenings") == 1);        // the default
  CHECK(first.find("\"stuck_restarts\": 1") != std::string::npos);
  CHECK(first.find("\"stuck_restarts\": 0") != std::string::npos);  // per level
  r = run("match " + dolphin + " " + swimming + " --stuck-restarts -1 -o " + (tmp.path / "d").string());
  CHECK(r.code != 0);
  CHECK_FALSE(fs::exists(tmp.path / "d"));
  r = run("match " + dolphin + " " + swimming + " --suspicion-rings 17 -o " + (tmp.path / "d").string());
  CHECK(r.code != 0);
  CHECK(r.err.find("--suspicion-rings") != std::string::npos);
  CHECK_FALSE(fs::exists(tmp.path / "d"));
  r = run("match " + dolphin + " " + swimming + " --recurring-beyond 0 -o " + (tmp.path / "d").string());
  CHECK(r.code != 0);
  CHECK(r.err.find("--recurring-beyond") != std::string::npos);
  CHECK_FALSE(fs::exists(tmp.path / "d"));
  r = run("match " + dolphin + " " + swimming + " --lp-checkpoint-seconds -1 -o " + (tmp.path / "d").string());
  CHECK(r.code != 0);
  CHECK(r.err.find("--lp-checkpoint-seconds") != std::string::npos);
  CHECK_FALSE(fs::exists(tmp.path / "d"));
  r = run("match " + dolphin + " " + swimming + " --divergence-bound-factor -1 -o " + (tmp.path / "d").string());
  CHECK(r.code != 0);
  CHECK(r.err.find("--divergence-bound-factor") != std::string::npos);
  CHECK_FALSE(fs::exists(tmp.path / "d"));
  r = run("match " + dolphin + " " + swimming + " --suspicion-margin-around all -o " + (tmp.path / "d").string());
  CHECK(r.code != 0);
  CHECK(r.err.find("--suspicion-margin-around") != std::string::npos);
  CHECK_FALSE(fs::exists(tmp.path / "d"));
  // What it holds, without the meshes: two levels done, the second's energy as in the report.
  r = run("checkpoint " + ckpt);
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(json_number(r.out, "levels_done") == 2);
  REQUIRE(r.out.find("\"level\": 1,") != std::string::npos);
  REQUIRE(first.find("\"level\": 1,") != std::string::npos);
  CHECK(json_number(r.out.substr(r.out.find("\"level\": 1,")), "energy") ==
        json_number(first.substr(first.find("\"level\": 1,")), "energy"));
  // (and the second start's numbers there, null where it did not run, as written)
  auto value = [](const std::string& json, const std::string& key) {
    const size_t level = json.find("\"level\": 1,");
    const size_t at = level == std::string::npos ? level : json.find("\"" + key + "\": ", level);
    return at == std::string::npos ? std::string("missing") : json.substr(at, json.find_first_of(",\n", at) - at);
  };
  CHECK(value(r.out, "second_start_energy") == value(first, "second_start_energy"));
  CHECK(value(r.out, "second_start_kept") == value(first, "second_start_kept"));
  CHECK(value(r.out, "second_start_kept") != "missing");
  CHECK(r.out.find("\"branch_kept\": false") != std::string::npos);
  // Going on from it solves only the finest level again, to the same Γ.
  r = run("match " + dolphin + " " + swimming + args + (tmp.path / "b").string());
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(r.err.find("going on from a checkpoint after level 2 of 3") != std::string::npos);
  const std::string second = read_file(tmp.path / "b" / "report.json");
  CHECK(json_number(second, "resumed_after_level") == 2);
  CHECK(json_number(second, "energy") == json_number(first, "energy"));
  CHECK(read_file(tmp.path / "b" / "map_x_to_y.txt") == read_file(tmp.path / "a" / "map_x_to_y.txt"));
  // Only level 1 of it: the run solves level 2 again, from level 1's Γ as in the first run, so
  // every level ends as there.
  const std::string one = (tmp.path / "one.ckpt").string();
  r = run("checkpoint " + ckpt + " --keep-levels 1 --out " + one);
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(json_number(r.out, "levels_done") == 1);
  CHECK(r.out.find(one) != std::string::npos);  // what it shows is the new file
  r = run("match " + dolphin + " " + swimming + args.substr(0, args.find(" --checkpoint ")) + " --checkpoint " + one +
          " -o " + (tmp.path / "e").string());
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(r.err.find("going on from a checkpoint after level 1 of 3") != std::string::npos);
  CHECK(json_number(read_file(tmp.path / "e" / "report.json"), "energy") == json_number(first, "energy"));
  CHECK(read_file(tmp.path / "e" / "map_x_to_y.txt") == read_file(tmp.path / "a" / "map_x_to_y.txt"));
  // More levels than it holds, or none: one line naming the file, nothing written.
  for (const char* keep : {"3", "0"}) {
    r = run("checkpoint " + ckpt + " --keep-levels " + keep + " --out " + (tmp.path / "bad.ckpt").string());
    CHECK(r.code != 0);
    CHECK(r.err.find(ckpt + ": --keep-levels " + keep + " is not between 1 and the 2 levels") != std::string::npos);
    CHECK_FALSE(fs::exists(tmp.path / "bad.ckpt"));
  }
  r = run("checkpoint " + ckpt + " --keep-levels 1");  // where to?
  CHECK(r.code != 0);
  // Another pair: one line naming the file, nothing written.
  r = run("match " + swimming + " " + dolphin + args + (tmp.path / "c").string());
  CHECK(r.code != 0);
  CHECK(r.err.find(ckpt + ": the checkpoint was written for other meshes") != std::string::npos);
  CHECK_FALSE(fs::exists(tmp.path / "c"));
  // Not a checkpoint: one line naming the file.
  r = run("checkpoint " + dolphin);
  CHECK(r.code == 1);
  CHECK(r.err.find(dolphin + ": not a shapematch checkpoint") != std::string::npos);
  // A byte changed on disk: refused as damaged (its checksum), by match and checkpoint alike,
  // before any work; the file is kept.
  std::string bytes = read_file(ckpt);
  bytes[bytes.size() / 2] = char(bytes[bytes.size() / 2] ^ 1);
  std::ofstream(ckpt, std::ios::binary) << bytes;
  for (const std::string& cmd : {"checkpoint " + ckpt, "match " + dolphin + " " + swimming + args + (tmp.path / "damaged").string()}) {
    r = run(cmd);
    CHECK(r.code == 1);
    CHECK(r.err.find(ckpt + ": the checkpoint is damaged (its checksum does not match") != std::string::npos);
  }
  CHECK_FALSE(fs::exists(tmp.path / "damaged"));
  CHECK(read_file(ckpt) == bytes);
}

TEST_CASE("cli: SIGTERM (as SIGINT) stops a match with a checkpoint where it can go on from") {
  // The run is sent SIGTERM as soon as it logs level 2's start: it leaves off in level 2's first
  // LP (at its first residual check, after saving its whole state there), says so naming the
  // checkpoint, dies by the signal (status 143), writes no output; the same command then goes on
  // from that checkpoint, exactly: the uninterrupted run's Γ, byte for byte. (SIGINT is handled
  // alike, but a script's background job inherits it ignored, and then it stays ignored.)
  shapematch::test::TempDir tmp;
  const std::string dolphin = std::string(SHAPEMATCH_ASSETS_DIR) + "/dolphin_straight.off";
  const std::string swimming = std::string(SHAPEMATCH_ASSETS_DIR) + "/dolphin_swimming.off";
  const std::string ckpt = (tmp.path / "c.ckpt").string();
  const fs::path out = tmp.path / "out";
  const std::string args = "match " + dolphin + " " + swimming + " --faces 300 --levels 2 --backend cpu --threads 1";
  const Run whole = run(args + " -o " + (tmp.path / "whole").string());
  REQUIRE_MESSAGE(whole.code == 0, whole.err);
  const std::string command =
      std::string(SHAPEMATCH_CLI) + " " + args + " --checkpoint " + ckpt + " -o " + out.string();
  const fs::path script = tmp.path / "stop.sh";
  const std::string err_file = (tmp.path / "err.txt").string();
  std::ofstream(script) << command << " >/dev/null 2>" << err_file << " & p=$!\n"
                        << "while ! grep -q 'level 2/2' " << err_file << " && kill -0 $p 2>/dev/null; do sleep 0.01; done\n"
                        << "kill -TERM $p 2>/dev/null\nwait $p\necho $?\n";
  const Run stopped = shapematch::test::run_command("bash " + script.string());
  const std::string err = read_file(tmp.path / "err.txt");
  CHECK_MESSAGE(stopped.out == "143\n", err);
  CHECK(err.find("shapematch: stopping where the run can be saved") != std::string::npos);
  CHECK(err.find("shapematch: stopped by SIGTERM (") != std::string::npos);
  CHECK(err.find(ckpt + " holds where the run got; the same command goes on from it") != std::string::npos);
  CHECK_FALSE(fs::exists(out));
  const shapematch::LevelCheckpoint left = shapematch::load_checkpoint(ckpt);
  CHECK(left.done() == 1);
  REQUIRE_FALSE(left.attempt.empty());  // (saved inside level 2, not only after level 1)
  const bool in_lp = !left.attempt.solving.empty();  // (where the stop came in the LP: its whole state)
  if (in_lp) CHECK(left.attempt.solving_state != nullptr);
  const Run again = run(command.substr(std::string(SHAPEMATCH_CLI).size() + 1));
  REQUIRE_MESSAGE(again.code == 0, again.err);
  CHECK(again.err.find("going on from a checkpoint after level 1 of 2") != std::string::npos);
  CHECK(json_number(read_file(out / "report.json"), "resumed_after_level") == 1);
  CHECK(read_file(out / "report.json").find("\"verified\": true") != std::string::npos);
  if (in_lp) {
    CHECK(again.err.find("goes on from the checkpointed state (exactly") != std::string::npos);
    CHECK(read_file(out / "graph_surface.txt") == read_file(tmp.path / "whole" / "graph_surface.txt"));
    for (const char* key : {"energy", "lower_bound"})  // (its LP's bound too, which the iterate alone moved)
      CHECK(json_number(read_file(out / "report.json"), key) ==
            json_number(read_file(tmp.path / "whole" / "report.json"), key));
  } else {
    MESSAGE("the stop came after level 2's first LP (a slow machine): its exactness not checked here");
  }
}

TEST_CASE("cli: checkpoint shows both chains of a run stopped inside lookahead") {
  shapematch::test::TempDir tmp;
  const std::string ckpt = (tmp.path / "two.ckpt").string();
  // Level 1 done before the split, then levels 2 and 3 on each chain (the command needs no meshes).
  shapematch::LevelCheckpoint c;
  auto level = [](int l, double energy) {
    shapematch::LevelReport r;
    r.level = l;
    r.energy = energy;
    r.gamma.resize(3);
    return r;
  };
  c.levels = {level(0, 1.5)};
  c.chains = {{{level(1, 2.25), level(2, 3.5)}, {}, true}, {{level(1, 2.5), level(2, 3.25)}, {}, false}};
  shapematch::save_checkpoint(ckpt, c);
  const Run r = run("checkpoint " + ckpt);
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(json_number(r.out, "levels_done") == 3);
  const size_t lookahead = r.out.find("\"lookahead\"");
  REQUIRE(lookahead != std::string::npos);
  const std::string chains = r.out.substr(lookahead);
  CHECK(chains.find("\"leading\": true") < chains.find("\"leading\": false"));
  for (const char* energy : {"2.25", "3.5", "2.5", "3.25"})
    CHECK(chains.find(std::string("\"energy\": ") + energy) != std::string::npos);
  CHECK(r.out.substr(0, lookahead).find("\"energy\": 2.25") == std::string::npos);  // not among `levels`
  CHECK(r.out.find("\"attempt\": null") != std::string::npos);
  // Inside level 4: the first chain has done it, the second is at it (its attempt, in its rounding).
  shapematch::LevelCheckpoint inside = c;
  inside.chains[0].pending.push_back(level(3, 4.75));
  shapematch::LevelAttempt& a = inside.chains[1].attempt;
  a.ring = 2;
  a.report.level = 3;
  a.extra = {0, 1, 1};
  a.rounding.rounds = 3;
  a.rounding.columns = 10;
  a.rounding.rows = 4;
  a.rounding.ones = {1, 7};
  a.rounding.cap_scale = 4.0;
  a.priced_from = shapematch::CarriedIterate::from_parts(
      {.keys = {1, 2}, .values = {0.5, 0.25}, .row_edge = {3}, .y = {0.1, 0.2}, .closedness_rows = 1, .scale = 1.0});
  a.cold_iterations = 64;
  const std::string inside_file = (tmp.path / "inside.ckpt").string();
  shapematch::save_checkpoint(inside_file, inside);
  const Run at = run("checkpoint " + inside_file);
  REQUIRE_MESSAGE(at.code == 0, at.err);
  CHECK(json_number(at.out, "levels_done") == 3);
  const size_t second = at.out.find("\"leading\": false");
  REQUIRE(second != std::string::npos);
  CHECK(at.out.find("\"energy\": 4.75") < second);  // the first chain's level 4
  CHECK(at.out.find("\"faces_with_extra_rings\": 2", second) != std::string::npos);  // under the second chain
  const size_t top = at.out.rfind("\"attempt\"");  // the level in progress, after `lookahead`
  CHECK(json_number(at.out.substr(top), "level") == 3);
  CHECK(json_number(at.out.substr(top), "fixings_to_one") == 2);
  CHECK(json_number(at.out.substr(top), "cap_scale") == 4);
  CHECK(at.out.find("\"warm_resolve\": true", top) != std::string::npos);  // a pricing's iterate kept with it
  CHECK(at.out.find("\"solving_iterations\": null", top) != std::string::npos);  // no LP under way kept
  CHECK(at.out.find("\"solving_exact\": null", top) != std::string::npos);
  CHECK(r.out.find("\"warm_resolve\"") == std::string::npos);               // (no attempt there)
  {  // An LP under way kept with its whole state (version 19): "solving_exact" says so.
    shapematch::LevelCheckpoint solving = inside;
    shapematch::LevelAttempt& s = solving.chains[1].attempt;
    s.rounding = {};
    s.solving = s.priced_from;
    s.priced_from = {};
    s.solving_iterations = 128;
    auto state = std::make_shared<shapematch::SolverState>();
    state->solver = "pdhg-cpu";
    state->x = state->x0 = {0.5, 0.0};
    state->y = state->y0 = {0.25};
    state->step = 1.0;
    state->primal_weight = 2.0;
    state->iterations = 128;
    s.solving_state = state;
    const std::string file = (tmp.path / "exact.ckpt").string();
    shapematch::save_checkpoint(file, solving);
    const Run e = run("checkpoint " + file);
    REQUIRE_MESSAGE(e.code == 0, e.err);
    const size_t t = e.out.rfind("\"attempt\"");
    CHECK(json_number(e.out.substr(t), "solving_iterations") == 128);
    CHECK(e.out.find("\"solving_exact\": true", t) != std::string::npos);
    CHECK(e.out.find("\"solving_last_window\": null", t) != std::string::npos);  // (not watched yet)
    // Watched: its last window (the bound 0.5 above an objective of 3: 0.5 / (1 + 3)).
    s.solving_watch.windows = 3;
    s.solving_watch.primal = 4e-3;
    s.solving_watch.gap = 2e-3;
    s.solving_watch.bound = 3.5;
    s.solving_watch.excess[0] = 0.25;
    s.solving_watch.excess[1] = 0.5;
    shapematch::save_checkpoint(file, solving);
    const Run w = run("checkpoint " + file);
    REQUIRE_MESSAGE(w.code == 0, w.err);
    const size_t lw = w.out.find("\"solving_last_window\": {", w.out.rfind("\"attempt\""));
    REQUIRE(lw != std::string::npos);
    CHECK(json_number(w.out.substr(lw), "windows") == 3);
    CHECK(json_number(w.out.substr(lw), "primal_residual") == doctest::Approx(4e-3));
    CHECK(json_number(w.out.substr(lw), "gap") == doctest::Approx(2e-3));
    CHECK(json_number(w.out.substr(lw), "bound_above_objective") == doctest::Approx(0.125));
  }
  // Its first level alone: neither chain goes with it.
  const Run kept = run("checkpoint " + ckpt + " --keep-levels 1 --out " + ckpt);
  REQUIRE_MESSAGE(kept.code == 0, kept.err);
  CHECK(json_number(kept.out, "levels_done") == 1);
  CHECK(kept.out.find("\"energy\": 2.25") == std::string::npos);
  CHECK(shapematch::load_checkpoint(ckpt).chains.empty());
}

TEST_CASE("cli: checkpoint --keep-levels drops the attempt of the level in progress") {
  shapematch::test::TempDir tmp;
  const std::string ckpt = (tmp.path / "attempt.ckpt").string();
  shapematch::LevelCheckpoint c;
  for (int l = 0; l < 2; ++l) {
    shapematch::LevelReport r;
    r.level = l;
    r.gamma.resize(3);
    c.levels.push_back(r);
  }
  c.widened = {0, 1, 0};
  c.attempt.ring = 1;
  c.attempt.extra = {0, 2, 0, 1};
  c.attempt.report.level = 2;
  shapematch::save_checkpoint(ckpt, c);
  Run r = run("checkpoint " + ckpt);
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(r.out.find("\"faces_with_extra_rings\": 2") != std::string::npos);
  CHECK(r.out.find("\"most_extra_rings\": 2") != std::string::npos);
  CHECK(r.out.find("\"proof_region\": null") != std::string::npos);
  {  // (a local proof's region to check again: its faces and rings)
    shapematch::LevelCheckpoint p = c;
    p.attempt.proof_faces = {1, 3};
    p.attempt.proof_rings = 1;
    p.attempt.report.proof_rechecks = 4;
    p.attempt.proof_rows = 12;
    p.attempt.proof_cols = 34;
    const std::string region = (tmp.path / "region.ckpt").string();
    shapematch::save_checkpoint(region, p);
    const Run q = run("checkpoint " + region);
    REQUIRE_MESSAGE(q.code == 0, q.err);
    CHECK(q.out.find("\"faces\": 2") != std::string::npos);
    CHECK(q.out.find("\"rings\": 1") != std::string::npos);
    CHECK(q.out.find("\"proof_rechecks\": 4") != std::string::npos);
    CHECK(q.out.find("\"rechecked_rows\": 12") != std::string::npos);
    CHECK(q.out.find("\"rechecked_columns\": 34") != std::string::npos);
  }
  const std::string two = (tmp.path / "two.ckpt").string(), one = (tmp.path / "one.ckpt").string();
  r = run("checkpoint " + ckpt + " --keep-levels 2 --out " + two);
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(r.out.find("\"attempt\": null") != std::string::npos);
  const shapematch::LevelCheckpoint kept = shapematch::load_checkpoint(two);
  CHECK(kept.levels.size() == 2);
  CHECK(kept.attempt.empty());
  CHECK(kept.widened == c.widened);  // the last level's, still the one the next refines
  r = run("checkpoint " + ckpt + " --keep-levels 1 --out " + one);
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(shapematch::load_checkpoint(one).widened.empty());  // level 2's, not level 1's
  CHECK(shapematch::load_checkpoint(ckpt).attempt.ring == 1);  // the file itself unchanged
}

// tools/pdhg_work.sh reads what PDHG logs at debug level: on a written log its sums are checked
// by hand, on a real `-v match` log it must find the solves (else the log's format moved).
TEST_CASE("cli: tools/pdhg_work.sh sums PDHG's solves in a -v log") {
  shapematch::test::TempDir tmp;
  const fs::path script = fs::path(SHAPEMATCH_ASSETS_DIR).parent_path() / "tools" / "pdhg_work.sh";
  auto work = [&](const fs::path& log) {
    const Run script_run = shapematch::test::run_command("bash " + script.string() + " " + log.string());
    CHECK(script_run.code == 0);
    const std::string& out = script_run.out;
    // The last line is the log's row: | log | solves | iterations | column-iterations | seconds |
    std::string row = out.substr(out.rfind("| " + log.string()));
    std::vector<std::string> cells;
    for (size_t at = row.find('|'), next; (next = row.find('|', at + 1)) != std::string::npos; at = next)
      cells.push_back(row.substr(at + 1, next - at - 1));
    REQUIRE(cells.size() == 5);
    return std::array<double, 4>{std::atof(cells[1].c_str()), std::atof(cells[2].c_str()),
                                 std::atof(cells[3].c_str()), std::atof(cells[4].c_str())};
  };
  const fs::path written = tmp.path / "written.log";
  std::ofstream(written) << "[00:00:01.000] info level 1/2: 100 × 100 faces\n"
                            "[00:00:01.100] debug pdhg-cpu: 40000 x 1000000, ‖Ã‖ ≈ 0.9, step 1.1, primal weight 1, on cpu\n"
                            "[00:00:09.000] debug pdhg-cpu: optimal after 2000 iterations and 5 restarts (7.500 s)\n"
                            "[00:00:09.100] info level 1 round  1: 1000000 variables, LP optimal in 2000 it\n"
                            "[00:00:09.200] debug pdhg-vulkan: 90000 x 3000000, ‖Ã‖ ≈ 0.9, step 1.1, primal weight 1, on gpu\n"
                            "[00:00:12.000] debug pdhg-vulkan: infeasible after 500 iterations and 1 restarts (2.500 s)\n";
  const auto w = work(written);
  CHECK(w[0] == 2);
  CHECK(w[1] == 2500);
  CHECK(w[2] == doctest::Approx(3.5));  // 1e6 × 2000 + 3e6 × 500, in 10⁹
  CHECK(w[3] == 10);

  const fs::path out = tmp.path / "m";
  const Run r = run("-v match --faces 30 --backend cpu --threads 1 -o " + out.string());
  REQUIRE_MESSAGE(r.code == 0, r.err);
  const fs::path real = tmp.path / "match.log";
  std::ofstream(real) << r.err;
  const auto v = work(real);
  CHECK(v[0] >= 1);
  CHECK(v[1] >= 64 * v[0]);  // PDHG checks every 64 iterations
  CHECK(v[2] > 0);
}

// The README's main command, checked for what its picture should show: the bundled dolphins
// (identity ground truth) matched head to head and fin to fin. Measured: mean geodesic error
// 0.089 at 100 faces, no inverted face; a twisted or end-swapped match scores above 0.25.
TEST_CASE("cli: the bundled pair matches sensibly" * doctest::test_suite("slow")) {
  shapematch::test::TempDir tmp;
  const fs::path out = tmp.path / "out";
  Run r = run("match --backend cpu -o " + out.string());
  REQUIRE_MESSAGE(r.code == 0, r.err);
  std::ifstream f(out / "report.json");
  const std::string report((std::istreambuf_iterator<char>(f)), {});
  CHECK(report.find("\"verified\": true") != std::string::npos);
  CHECK(report.find("dolphin_straight.off") != std::string::npos);
  // Theorem 1 on a solved pair with independent triangulations (decimated separately).
  CHECK(report.find("\"orientation_preserved\": true") != std::string::npos);
  CHECK(report.find("\"continuous\": true") != std::string::npos);
  r = run("eval " + out.string() + " --gt identity");
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(json_number(r.out, "mean_geodesic_error") < 0.15);
  CHECK(json_number(r.out, "orientation_flips") == 0);
  // The point map: scored the same way, no worse for orientation, and close in error.
  const size_t at = r.out.find("\"point_map\"");
  REQUIRE(at != std::string::npos);
  const std::string points = r.out.substr(at);
  CHECK(json_number(points, "orientation_flips") == 0);
  CHECK(json_number(points, "mean_geodesic_error") < 0.15);
  // And the other direction's point map, as match reported it.
  CHECK(json_number(points, "y_to_x_orientation_flips") == 0);
  const size_t back = report.find("\"point_y_to_x\"");
  REQUIRE(back != std::string::npos);
  CHECK(json_number(report.substr(back), "inverted") == json_number(points, "y_to_x_orientation_flips"));
}
