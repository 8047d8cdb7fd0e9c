// End-to-end tests of `shapematch bench`. bench lp: the CSV has its columns and one row per solver
// and size, the solvers agree, and the plot is made where Debian's Python has matplotlib. bench
// match: whole match runs per size or per pair of a pairs file, where a failed pair is a row.
#include "shapematch/coarse_to_fine.hpp"
#include "shapematch/mesh.hpp"
#include "shapematch/system.hpp"
#include "test_helpers.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <regex>
#include <string>
#include <sys/wait.h>
#include <vector>

namespace fs = std::filesystem;

namespace {

// Exit code; stderr goes to `err`, stdout to `out` when given.
int run_cli(const std::string& args, const fs::path& err, const fs::path& out = "/dev/null") {
  const std::string cmd = std::string(SHAPEMATCH_CLI) + " " + args + " >" + out.string() + " 2>" + err.string();
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string read_text(const fs::path& path) {
  std::ifstream f(path);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

// Replaces the value of `key` in a JSON file written one field per line (a run record).
void edit_json_field(const fs::path& file, const std::string& key, const std::string& value) {
  const std::string text = read_text(file);
  const std::string edited = std::regex_replace(text, std::regex("\"" + key + "\": [^,\n]+"), "\"" + key + "\": " + value);
  REQUIRE(edited != text);
  std::ofstream(file) << edited;
}

// Replaces every `from` in a file by `to` (a run record's paths or options).
void replace_in_file(const fs::path& file, const std::string& from, const std::string& to) {
  std::string text = read_text(file);
  size_t replaced = 0;
  for (size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()), ++replaced)
    text.replace(at, from.size(), to);
  REQUIRE(replaced > 0);
  std::ofstream(file) << text;
}

// One CSV record; quoted fields may hold commas (the device "cpu (Clp, 1 thread)").
std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char ch = line[i];
    if (quoted && ch == '"' && i + 1 < line.size() && line[i + 1] == '"') {
      fields.back() += '"';
      ++i;
    } else if (ch == '"') {
      quoted = !quoted;
    } else if (ch == ',' && !quoted) {
      fields.emplace_back();
    } else {
      fields.back() += ch;
    }
  }
  return fields;
}

struct Csv {
  std::vector<std::string> header;
  std::vector<std::map<std::string, std::string>> rows;
};

Csv read_csv(const fs::path& path) {
  std::ifstream f(path);
  REQUIRE(f.good());
  Csv csv;
  std::string line;
  std::getline(f, line);
  csv.header = split_csv(line);
  while (std::getline(f, line)) {
    const std::vector<std::string> fields = split_csv(line);
    REQUIRE(fields.size() == csv.header.size());
    std::map<std::string, std::string> row;
    for (size_t i = 0; i < fields.size(); ++i) row[csv.header[i]] = fields[i];
    csv.rows.push_back(row);
  }
  return csv;
}

// The plot exists where Debian's Python has matplotlib; otherwise the log says why not.
void check_plot(const fs::path& png, const fs::path& err) {
  if (std::system("/usr/bin/python3 -c 'import matplotlib' >/dev/null 2>&1") == 0)
    CHECK(fs::file_size(png) > 1000);
  else
    CHECK(read_text(err).find("matplotlib") != std::string::npos);
}

const std::string kAssets = SHAPEMATCH_ASSETS_DIR;

}  // namespace

TEST_CASE("cli: bench bandwidth runs on at most the CPUs it may use") {
  // --threads past the CPUs is capped (a warning; thousands of threads had been started as asked),
  // and the JSON says how many ran; a bandwidth is a positive number.
  const fs::path err = fs::temp_directory_path() / "shapematch_bandwidth_stderr.txt";
  const fs::path out = fs::temp_directory_path() / "shapematch_bandwidth_stdout.txt";
  REQUIRE(run_cli("bench bandwidth --threads 100000 --repeats 1", err, out) == 0);
  const std::string json = read_text(out);
  CHECK(shapematch::test::json_number(json, "threads") == shapematch::worker_threads());
  CHECK(shapematch::test::json_number(json, "gbps") > 0.0);
  CHECK(read_text(err).find("--threads 100000 is more than the") != std::string::npos);
  REQUIRE(run_cli("bench bandwidth --threads 1 --repeats 1", err, out) == 0);
  CHECK(shapematch::test::json_number(read_text(out), "threads") == 1);
  CHECK(read_text(err).find("more than the") == std::string::npos);
}

TEST_CASE("cli: bench lp writes one CSV row per solver and size, and the solvers agree") {
  const fs::path dir = fs::temp_directory_path() / "shapematch_bench_test";
  fs::remove_all(dir);
  const fs::path err = fs::temp_directory_path() / "shapematch_bench_stderr.txt";
  REQUIRE(run_cli("bench lp --faces 12,20 --solvers pdhg-cpu,clp-dual --out " + dir.string(), err) == 0);

  const auto [header, rows] = read_csv(dir / "bench_lp.csv");
  const std::vector<std::string> expected = {
      "faces_x", "faces_y", "variables", "constraints", "nonzeros", "solver", "device", "status", "iterations", "seconds",
      "setup_seconds", "seconds_per_iteration", "peak_rss_mb", "solver_rss_mb", "objective", "lower_bound", "rel_diff_best",
      "bytes_per_iteration", "achieved_gbps", "bandwidth_ratio"};
  REQUIRE(header == expected);
  REQUIRE(rows.size() == 4);

  std::map<std::string, double> objective_at;  // by variables, the first solver's objective
  for (const auto& row : rows) {
    CAPTURE(row.at("solver"));
    CAPTURE(row.at("variables"));
    CHECK(row.at("status") == "optimal");
    CHECK(std::stod(row.at("seconds")) > 0);
    CHECK(std::stod(row.at("peak_rss_mb")) > 0);
    CHECK(std::stod(row.at("rel_diff_best")) < 1e-3);
    CHECK(std::stod(row.at("lower_bound")) <= std::stod(row.at("objective")) * (1 + 1e-9) + 1e-12);
    const bool pdhg = row.at("solver") == "pdhg-cpu";
    // bytes per iteration ≥ 24 per nonzero (entry + gather, both kernels); Clp has none.
    CHECK(pdhg == !row.at("bytes_per_iteration").empty());
    if (pdhg) CHECK(std::stod(row.at("bytes_per_iteration")) >= 24.0 * std::stod(row.at("nonzeros")));
    // PDHG's set-up is part of its time and left out of the time per iteration; Clp has none.
    CHECK(pdhg == !row.at("setup_seconds").empty());
    if (pdhg) {
      const double setup = std::stod(row.at("setup_seconds")), seconds = std::stod(row.at("seconds"));
      CHECK(setup > 0);
      CHECK(setup < seconds);
      CHECK(std::stod(row.at("seconds_per_iteration")) ==
            doctest::Approx((seconds - setup) / std::stod(row.at("iterations"))).epsilon(1e-4));
    }
    auto [it, first] = objective_at.emplace(row.at("variables"), std::stod(row.at("objective")));
    if (!first) CHECK(std::abs(std::stod(row.at("objective")) - it->second) <= 1e-3 * std::abs(it->second));
  }
  CHECK(objective_at.size() == 2);  // two sizes
  check_plot(dir / "bench_lp.png", err);
  fs::remove_all(dir);
}

TEST_CASE("cli: bench match (scaling) writes one row per size with the child's own time and memory") {
  const fs::path dir = fs::temp_directory_path() / "shapematch_bench_match_test";
  fs::remove_all(dir);
  const fs::path err = fs::temp_directory_path() / "shapematch_bench_match_stderr.txt";
  const fs::path out = fs::temp_directory_path() / "shapematch_bench_match_stdout.txt";
  // Given out of order: the rows come ascending.
  REQUIRE(run_cli("bench match --faces 30,20 --out " + dir.string() + " -- --backend cpu", err, out) == 0);

  const auto [header, rows] = read_csv(dir / "bench_match.csv");
  const std::vector<std::string> expected = {"faces_requested", "faces_x", "faces_y", "levels", "variables", "rounds",
                                             "energy", "lower_bound", "gap", "max_level_gap", "seconds", "peak_rss_mb",
                                             "status"};
  REQUIRE(header == expected);
  REQUIRE(rows.size() == 2);
  for (size_t i = 0; i < rows.size(); ++i) {
    const auto& row = rows[i];
    CAPTURE(row.at("faces_requested"));
    CHECK(row.at("status") == "ok");
    CHECK(row.at("faces_requested") == (i == 0 ? "20" : "30"));
    // The bundled pair decimates to exactly the count asked for.
    CHECK(row.at("faces_x") == row.at("faces_requested"));
    CHECK(row.at("faces_y") == row.at("faces_requested"));
    CHECK(std::stoi(row.at("levels")) >= 1);
    // At most the full product space of two closed genus-0 meshes of n faces (V = n/2 + 2,
    // E = 3n/2): 3n² + 2Vn + 12En = 22n² + 4n.
    const long n = std::stol(row.at("faces_x"));
    CHECK(std::stol(row.at("variables")) > 0);
    CHECK(std::stol(row.at("variables")) <= 22 * n * n + 4 * n);
    CHECK(std::stoi(row.at("rounds")) >= 1);
    const double energy = std::stod(row.at("energy")), bound = std::stod(row.at("lower_bound"));
    CHECK(energy > 0);
    CHECK(bound <= energy * (1 + 1e-9));
    CHECK(std::stod(row.at("gap")) >= -1e-9);
    CHECK(std::stod(row.at("gap")) < 1);
    // The finest level is one of the levels.
    CHECK(std::stod(row.at("max_level_gap")) >= std::stod(row.at("gap")) - 1e-12);
    CHECK(std::stod(row.at("max_level_gap")) < 1);
    CHECK(std::stod(row.at("seconds")) > 0);
    CHECK(std::stod(row.at("seconds")) < 60);
    // A whole process with its meshes and LP: more than a few MiB, far less than a GiB.
    CHECK(std::stod(row.at("peak_rss_mb")) > 5);
    CHECK(std::stod(row.at("peak_rss_mb")) < 1024);
  }
  CHECK(fs::exists(dir / "runs" / "faces_20" / "report.json"));
  CHECK(read_text(out).find("| faces_requested |") != std::string::npos);
  check_plot(dir / "bench_match.png", err);
  fs::remove_all(dir);
}

TEST_CASE("cli: bench match kills a run at the time limit and skips the larger sizes") {
  const fs::path dir = fs::temp_directory_path() / "shapematch_bench_match_timeout_test";
  fs::remove_all(dir);
  const fs::path err = dir.string() + "_stderr.txt";
  // A 1000-face match takes far longer than this limit on any machine.
  REQUIRE(run_cli("bench match --faces 1000,full --time-limit 0.2 --out " + dir.string() + " -- --backend cpu", err) == 0);
  const auto [header, rows] = read_csv(dir / "bench_match.csv");
  REQUIRE(rows.size() == 2);
  CHECK(rows[0].at("status") == "timed out");
  CHECK(std::stod(rows[0].at("seconds")) >= 0.2);
  CHECK(std::stod(rows[0].at("seconds")) < 5);
  CHECK(rows[0].at("energy").empty());
  CHECK(rows[1].at("faces_requested") == "full");
  CHECK(rows[1].at("status").rfind("skipped", 0) == 0);
  fs::remove_all(dir);
}

TEST_CASE("cli: bench match --pairs matches and evaluates each pair and adds a row of medians") {
  const fs::path dir = fs::temp_directory_path() / "shapematch_bench_pairs_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path err = dir.string() + "_stderr.txt";
  // Relative to the pairs file, which lives elsewhere than the meshes.
  const fs::path assets = fs::relative(kAssets, dir);
  const std::string x = (assets / "finger_straight.off").string(), y = (assets / "finger_bent.off").string();
  // The second line scores the identity as .vts files, with a reversed order as the "symmetric" truth.
  const int n = shapematch::load_mesh((fs::path(kAssets) / "finger_straight.off").string()).num_vertices();
  std::ofstream same(dir / "same.vts"), reversed(dir / "reversed.vts");
  for (int v = 1; v <= n; ++v) {
    same << v << "\n";
    reversed << n + 1 - v << "\n";
  }
  same.close();
  reversed.close();
  std::ofstream(dir / "pairs.txt") << "# the bundled pair shares its connectivity: identity is the truth\n"
                                   << x << " " << y << "\n\n"
                                   << x << " " << y << " same.vts same.vts reversed.vts\n";
  REQUIRE(run_cli("bench match --pairs " + (dir / "pairs.txt").string() + " --faces 20 --out " + (dir / "out").string() +
                      " -- --backend cpu",
                  err) == 0);

  const auto [header, rows] = read_csv(dir / "out" / "bench_pairs.csv");
  const std::vector<std::string> expected = {"pair", "faces_x", "faces_y", "seconds", "total_seconds", "peak_rss_mb", "energy",
                                             "lower_bound", "gap", "max_level_gap", "rounds", "mean_geodesic_error",
                                             "median_geodesic_error", "symmetric_mean_geodesic_error",
                                             "mirrored_error_share", "orientation_flips", "point_mean_geodesic_error",
                                             "point_orientation_flips", "resumed_after_level", "status"};
  REQUIRE(header == expected);
  REQUIRE(rows.size() == 3);
  std::vector<double> seconds;
  for (size_t i = 0; i < 2; ++i) {
    const auto& row = rows[i];
    CAPTURE(i);
    CHECK(row.at("pair") == (i == 0 ? "finger_straight-finger_bent" : "finger_straight-finger_bent.2"));  // (as its run)
    CHECK(row.at("status") == "ok");
    CHECK(row.at("faces_x") == "20");
    CHECK(std::stod(row.at("lower_bound")) <= std::stod(row.at("energy")) * (1 + 1e-9));
    CHECK(std::stoi(row.at("rounds")) >= 1);
    // Normalised by √area: a wrong map errs by a fraction of the shape's size, never by more than
    // its diameter.
    const double mean = std::stod(row.at("mean_geodesic_error")), median = std::stod(row.at("median_geodesic_error"));
    CHECK(mean >= 0);
    CHECK(mean < 3);
    CHECK(median >= 0);
    CHECK(std::stoi(row.at("orientation_flips")) >= 0);
    // The point map never inverts more faces than the vertex map it starts from.
    CHECK(std::stoi(row.at("point_orientation_flips")) <= std::stoi(row.at("orientation_flips")));
    CHECK(std::stod(row.at("point_mean_geodesic_error")) < 3);
    // Only the second line names a symmetric truth, a different one, so its error differs.
    CHECK(row.at("symmetric_mean_geodesic_error").empty() == (i == 0));
    if (i == 1) CHECK(std::stod(row.at("symmetric_mean_geodesic_error")) != doctest::Approx(mean));
    // The share of the error in mirrored parts: only with the symmetric truth, a fraction.
    CHECK(row.at("mirrored_error_share").empty() == (i == 0));
    if (i == 1) CHECK(std::stod(row.at("mirrored_error_share")) >= 0);
    if (i == 1) CHECK(std::stod(row.at("mirrored_error_share")) <= 1 + 1e-9);
    seconds.push_back(std::stod(row.at("seconds")));
    CHECK(row.at("total_seconds") == row.at("seconds"));  // (no checkpoint before it)
  }
  const auto& median = rows[2];
  CHECK(median.at("pair") == "median");
  CHECK(median.at("status") == "2 of 2 ok");
  CHECK(std::stod(median.at("seconds")) == doctest::Approx((seconds[0] + seconds[1]) / 2).epsilon(1e-4));
  CHECK(std::stod(median.at("mean_geodesic_error")) == doctest::Approx(std::stod(rows[0].at("mean_geodesic_error"))));
  CHECK(!median.at("gap").empty());
  CHECK(!median.at("max_level_gap").empty());
  CHECK(median.at("energy").empty());

  // The same pair twice: two runs, the second one counted.
  CHECK(fs::is_directory(dir / "out" / "runs" / "finger_straight-finger_bent"));
  CHECK(fs::is_directory(dir / "out" / "runs" / "finger_straight-finger_bent.2"));
  const std::string md = read_text(dir / "out" / "bench_pairs.md");
  CHECK(md.rfind("| pair ", 0) == 0);
  CHECK(md.find("| **median** ") != std::string::npos);
  CHECK(md.find("2 of 2 ok") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("cli: bench match --pairs records a pair that fails as a row and goes on") {
  const fs::path dir = fs::temp_directory_path() / "shapematch_bench_pairs_fail_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path err = dir.string() + "_stderr.txt";
  const std::string x = kAssets + "/finger_straight.off", y = kAssets + "/finger_bent.off";
  std::ofstream(dir / "pairs.txt") << "missing.off " << y << "\n"
                                   << x << " " << y << " no_such_x.vts no_such_y.vts\n"
                                   << x << " " << y << " identity\n";
  REQUIRE(run_cli("bench match --pairs " + (dir / "pairs.txt").string() + " --faces 12 --out " + (dir / "out").string() +
                      " -- --backend cpu",
                  err) == 0);
  const auto [header, rows] = read_csv(dir / "out" / "bench_pairs.csv");
  REQUIRE(rows.size() == 4);
  CHECK(rows[0].at("pair") == "missing-finger_bent");
  // The child's one-line error, naming the file.
  CHECK(rows[0].at("status").rfind("failed: ", 0) == 0);
  CHECK(rows[0].at("status").find("missing.off") != std::string::npos);
  CHECK(rows[0].at("energy").empty());
  // Its ground truth is missing: the row fails before the match (no run, no energy).
  CHECK(rows[1].at("status").rfind("failed: ", 0) == 0);
  CHECK(rows[1].at("status").find("no_such_x.vts: ground truth not found") != std::string::npos);
  CHECK(rows[1].at("energy").empty());
  CHECK_FALSE(fs::exists(dir / "out" / "runs" / "finger_straight-finger_bent" / "report.json"));
  // The same pair again: its row is named as its run, X-Y.2.
  CHECK(rows[1].at("pair") == "finger_straight-finger_bent");
  CHECK(rows[2].at("pair") == "finger_straight-finger_bent.2");
  CHECK(rows[2].at("status") == "ok");
  CHECK(fs::exists(dir / "out" / "runs" / "finger_straight-finger_bent.2" / "report.json"));
  CHECK(rows[3].at("status") == "1 of 3 ok");
  fs::remove_all(dir);
}

TEST_CASE("cli: bench match --pairs --jobs runs pairs side by side: the rows of one at a time, in the file's order") {
  const fs::path dir = fs::temp_directory_path() / "shapematch_bench_pairs_jobs_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path err = dir.string() + "_stderr.txt";
  const std::string x = kAssets + "/finger_straight.off", y = kAssets + "/finger_bent.off";
  // The failing pair is first, so that it ends first and a table in the order of ending would show.
  std::ofstream(dir / "pairs.txt") << "missing.off " << y << "\n"
                                   << x << " " << y << " identity\n"
                                   << y << " " << x << " identity\n";
  std::map<int, Csv> tables;
  for (int jobs : {1, 3}) {
    const fs::path out = dir / ("out" + std::to_string(jobs));
    REQUIRE(run_cli("bench match --pairs " + (dir / "pairs.txt").string() + " --jobs " + std::to_string(jobs) +
                        " --faces 20 --out " + out.string() + " -- --backend cpu",
                    err) == 0);
    tables[jobs] = read_csv(out / "bench_pairs.csv");
    // Each of the three runs at once gets its share of the CPUs (at least one thread).
    const std::string report = read_text(out / "runs" / "finger_straight-finger_bent" / "report.json");
    const int cpus = shapematch::worker_threads();
    CHECK(shapematch::test::json_number(report, "threads") == (jobs == 1 ? cpus : std::max(1, cpus / 3)));
  }
  const auto& one = tables[1].rows;
  const auto& three = tables[3].rows;
  REQUIRE(one.size() == 4);
  REQUIRE(three.size() == 4);
  for (size_t i = 0; i < 4; ++i) {
    CAPTURE(i);
    CHECK(three[i].at("pair") == one[i].at("pair"));
    CHECK(three[i].at("status") == one[i].at("status"));
    CHECK(three[i].at("energy") == one[i].at("energy"));  // the thread count changes no Γ
    CHECK(three[i].at("mean_geodesic_error") == one[i].at("mean_geodesic_error"));
  }
  CHECK(one[0].at("status").rfind("failed: ", 0) == 0);
  CHECK(one[1].at("status") == "ok");
  CHECK(one[2].at("pair") == "finger_bent-finger_straight");
  CHECK(one[3].at("status") == "2 of 3 ok");
  // --jobs is for lists of pairs.
  CHECK(run_cli("bench match --jobs 2 --faces 20 --out " + (dir / "scaling").string(), err) != 0);
  fs::remove_all(dir);
}

TEST_CASE("cli: bench match --pairs --resume reuses the rows of finished runs of the same command") {
  const fs::path dir = fs::temp_directory_path() / "shapematch_bench_resume_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path err = dir.string() + "_stderr.txt";
  const std::string x = kAssets + "/finger_straight.off", y = kAssets + "/finger_bent.off";
  std::ofstream(dir / "pairs.txt") << x << " " << y << " identity\n";
  const std::string bench = "bench match --pairs " + (dir / "pairs.txt").string() + " --out " + (dir / "out").string();
  const fs::path record = dir / "out" / "runs" / "finger_straight-finger_bent.run.json";
  // A recorded number that no run measures shows whether the row was reused or measured again.
  auto edit_record = [&](const std::string& key, const std::string& value) { edit_json_field(record, key, value); };
  auto row = [&] {
    const auto [header, rows] = read_csv(dir / "out" / "bench_pairs.csv");
    REQUIRE(rows.size() == 2);
    return rows[0];
  };

  // Nothing recorded yet: the pair runs, and its record is written.
  REQUIRE(run_cli(bench + " --faces 20 --resume -- --backend cpu", err) == 0);
  REQUIRE(fs::exists(record));
  const auto first = row();
  REQUIRE(first.at("status") == "ok");
  edit_record("seconds", "12345");

  SUBCASE("the same command: the recorded row, errors and all") {
    REQUIRE(run_cli(bench + " --faces 20 --resume -- --backend cpu", err) == 0);
    const auto again = row();
    CHECK(std::stod(again.at("seconds")) == 12345);
    CHECK(again.at("status") == "ok");
    CHECK(again.at("energy") == first.at("energy"));
    CHECK(again.at("mean_geodesic_error") == first.at("mean_geodesic_error"));
    CHECK(again.at("point_orientation_flips") == first.at("point_orientation_flips"));
    CHECK(read_text(err).find("resumed") != std::string::npos);
  }
  SUBCASE("another --threads: the recorded row (the count changes no Γ)") {
    REQUIRE(run_cli(bench + " --faces 20 --resume -- --backend cpu --threads 2", err) == 0);
    CHECK(std::stod(row().at("seconds")) == 12345);
  }
  SUBCASE("the same meshes and ground truth in another folder: the recorded row") {
    replace_in_file(record, kAssets + "/", "/elsewhere/assets/");
    REQUIRE(run_cli(bench + " --faces 20 --resume -- --backend cpu", err) == 0);
    CHECK(std::stod(row().at("seconds")) == 12345);
  }
  SUBCASE("another backend: measured again (its row is not this one's)") {
    replace_in_file(record, "\"cpu\"", "\"vulkan\"");
    REQUIRE(run_cli(bench + " --faces 20 --resume -- --backend cpu", err) == 0);
    CHECK(std::stod(row().at("seconds")) < 12345);
    CHECK(read_text(err).find("ran elsewhere (--backend vulkan); running it again") != std::string::npos);
  }
  SUBCASE("a list that grew: the pair keeps its row wherever its line went") {
    std::ofstream(dir / "pairs.txt") << y << " " << x << " identity\n" << x << " " << y << " identity\n";
    REQUIRE(run_cli(bench + " --faces 20 --resume -- --backend cpu", err) == 0);
    const auto [header, rows] = read_csv(dir / "out" / "bench_pairs.csv");
    REQUIRE(rows.size() == 3);
    CHECK(rows[0].at("pair") == "finger_bent-finger_straight");
    CHECK(std::stod(rows[0].at("seconds")) < 12345);
    CHECK(rows[1].at("pair") == "finger_straight-finger_bent");
    CHECK(std::stod(rows[1].at("seconds")) == 12345);
  }
  SUBCASE("other options or no --resume: measured again") {
    REQUIRE(run_cli(bench + " --faces 16 --resume -- --backend cpu", err) == 0);
    CHECK(std::stod(row().at("seconds")) < 12345);
    CHECK(row().at("faces_x") == "16");
    edit_record("seconds", "12345");
    REQUIRE(run_cli(bench + " --faces 16 -- --backend cpu", err) == 0);
    CHECK(std::stod(row().at("seconds")) < 12345);
  }
  SUBCASE("a run that timed out: kept under the same limit, tried again under a longer one") {
    edit_record("status", "\"timed out\"");
    REQUIRE(run_cli(bench + " --faces 20 --resume -- --backend cpu", err) == 0);
    CHECK(row().at("status") == "timed out");
    CHECK(row().at("energy").empty());
    REQUIRE(run_cli(bench + " --faces 20 --resume --time-limit 900 -- --backend cpu", err) == 0);
    CHECK(row().at("status") == "ok");
    CHECK(row().at("energy") == first.at("energy"));
  }
  fs::remove_all(dir);
}

TEST_CASE("cli: bench match --pairs --resume goes on from where a run that timed out left its checkpoint") {
  const fs::path dir = fs::temp_directory_path() / "shapematch_bench_checkpoint_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path err = dir.string() + "_stderr.txt";
  const std::string x = kAssets + "/dolphin_straight.off", y = kAssets + "/dolphin_swimming.off";
  std::ofstream(dir / "pairs.txt") << x << " " << y << " identity\n";
  const std::string options = " --backend cpu --levels 3";
  const std::string bench =
      "bench match --pairs " + (dir / "pairs.txt").string() + " --out " + (dir / "out").string() + " --faces 200 --resume --" + options;
  const fs::path runs = dir / "out" / "runs";
  const fs::path record = runs / "dolphin_straight-dolphin_swimming.run.json";
  const fs::path checkpoint = runs / "dolphin_straight-dolphin_swimming.ckpt";
  const fs::path log = runs / "dolphin_straight-dolphin_swimming.match.log";
  auto edit_record = [&](const std::string& key, const std::string& value) { edit_json_field(record, key, value); };
  auto row = [&] { return read_csv(dir / "out" / "bench_pairs.csv").rows.at(0); };

  REQUIRE(run_cli(bench, err) == 0);
  const auto first = row();
  REQUIRE(first.at("status") == "ok");
  CHECK_FALSE(fs::exists(checkpoint));  // a finished run keeps none
  CHECK(read_text(record).find("\"checkpoint_levels_before\": 0") != std::string::npos);
  CHECK(first.at("resumed_after_level") == "0");

  // The harness stopped during a run ("started"), its checkpoint unreadable: the pair runs afresh.
  // (Killed while saving it, too: the temporary file it left goes.)
  edit_record("status", "\"started\"");
  std::ofstream(checkpoint) << "not a checkpoint";
  const fs::path left = checkpoint.string() + ".tmp-12345";
  std::ofstream(left) << "half a checkpoint";
  REQUIRE(run_cli(bench, err) == 0);
  CHECK_FALSE(fs::exists(left));
  CHECK(read_text(err).find("not a shapematch checkpoint") != std::string::npos);
  CHECK(row().at("status") == "ok");
  CHECK(row().at("resumed_after_level") == "0");
  CHECK(row().at("total_seconds") == row().at("seconds"));  // afresh: the stopped run's time is not in it
  CHECK(row().at("energy") == first.at("energy"));
  CHECK_FALSE(fs::exists(checkpoint));

  // As if the run had been stopped in its finest level: the record says timed out, the checkpoint
  // holds the coarse level (written by the same match, as the killed run would have).
  REQUIRE(run_cli("match " + x + " " + y + " --faces 200" + options + " --checkpoint " + checkpoint.string() + " -o " +
                      (dir / "direct").string(),
                  err) == 0);
  REQUIRE(fs::exists(checkpoint));
  fs::copy_file(checkpoint, dir / "saved.ckpt");
  edit_record("status", "\"timed out\"");
  edit_record("total_seconds", "1000");  // (as if the run that timed out had taken that long)
  REQUIRE(run_cli(bench, err) == 0);  // the same limit, but the checkpoint got further: it goes on
  CHECK(std::stod(row().at("total_seconds")) ==
        doctest::Approx(1000 + std::stod(row().at("seconds"))).epsilon(1e-4));
  CHECK(read_text(err).find("going on from it") != std::string::npos);
  CHECK(read_text(log).find("going on from a checkpoint after level 2 of 3") != std::string::npos);
  CHECK(row().at("status") == "ok");
  CHECK(row().at("resumed_after_level") == "2");
  CHECK(row().at("energy") == first.at("energy"));
  CHECK_FALSE(fs::exists(checkpoint));

  // One interrupted (its match stopped by SIGINT or SIGTERM, which saves as it goes): run again
  // from its checkpoint, whatever the checkpoint's progress.
  fs::copy_file(dir / "saved.ckpt", checkpoint);
  edit_record("status", "\"interrupted\"");
  REQUIRE(run_cli(bench, err) == 0);
  CHECK(read_text(err).find("interrupted; running it again, from its checkpoint") != std::string::npos);
  CHECK(read_text(log).find("going on from a checkpoint after level 2 of 3") != std::string::npos);
  CHECK(row().at("status") == "ok");
  CHECK(row().at("resumed_after_level") == "2");
  CHECK_FALSE(fs::exists(checkpoint));

  // One that timed out without getting past the checkpoint it started from keeps its row.
  fs::copy_file(dir / "saved.ckpt", checkpoint);
  CHECK(read_text(record).find("\"checkpoint_levels_before\": 2") != std::string::npos);  // it started from it
  edit_record("status", "\"timed out\"");
  REQUIRE(run_cli(bench, err) == 0);
  CHECK(row().at("status") == "timed out");
  CHECK(fs::exists(checkpoint));
  // Nor a level further, but a widening further into the finest level: it goes on, from the
  // attempt that widening started (one more extra ring on one face, as if it had been written).
  int had = 0;
  {
    shapematch::LevelCheckpoint c = shapematch::load_checkpoint(checkpoint.string());
    if (c.attempt.empty()) {  // (this pair's finest level widens at ring 1: the match left one)
      c.attempt.ring = 1;
      c.attempt.extra.assign(std::stoi(first.at("faces_x")), 0);
      c.attempt.report.level = 2;
    }
    had = c.attempt.report.local_widenings + c.attempt.report.widenings;
    c.attempt.extra[0] += 1;
    c.attempt.local += 1;
    c.attempt.report.local_widenings += 1;
    shapematch::save_checkpoint(checkpoint.string(), c);
    // (Below: the same attempt a round of its rounding further, as of an LP of another size.)
    c.attempt.rounding = {.columns = 1, .rows = 1, .rounds = 1};
    shapematch::save_checkpoint((dir / "rounded.ckpt").string(), c);
  }
  CHECK(read_text(record).find("\"checkpoint_widenings_before\": " + std::to_string(had)) != std::string::npos);
  REQUIRE(run_cli(bench, err) == 0);
  CHECK(read_text(err).find("from 2 levels (and " + std::to_string(had) + " widenings of the next, 0 rounds of its "
                            "rounding) to 2 (and " + std::to_string(had + 1) + ", 0)") != std::string::npos);
  CHECK(read_text(log).find("level 3's widenings " + std::to_string(had + 1)) != std::string::npos);
  CHECK(row().at("status") == "ok");
  CHECK(row().at("resumed_after_level") == "2");
  CHECK_FALSE(fs::exists(checkpoint));
  // Nor a widening further, but a round of that attempt's rounding: it goes on (here rounding
  // afresh: the LP it was of had another size).
  edit_record("status", "\"timed out\"");
  fs::copy_file(dir / "rounded.ckpt", checkpoint);
  REQUIRE(run_cli(bench, err) == 0);
  CHECK(read_text(err).find("to 2 (and " + std::to_string(had + 1) + ", 1); going on from it") != std::string::npos);
  CHECK(read_text(log).find("the checkpointed rounding was of an LP of 1 × 1") != std::string::npos);
  CHECK(row().at("status") == "ok");
  CHECK_FALSE(fs::exists(checkpoint));
  // Asked with other options: it runs afresh, the checkpoint of the old ones set aside (whole).
  fs::copy_file(dir / "saved.ckpt", checkpoint);
  edit_record("status", "\"timed out\"");
  REQUIRE(run_cli(bench + " --ring 1", err) == 0);
  const fs::path aside = checkpoint.string() + ".other-options";
  CHECK(read_text(err).find("had other options; running it again (its checkpoint kept as " + aside.string() + ")") !=
        std::string::npos);
  CHECK(row().at("resumed_after_level") == "0");
  CHECK(read_text(aside) == read_text(dir / "saved.ckpt"));
  fs::remove(aside);
  REQUIRE(run_cli(bench, err) == 0);  // (the record back at this test's options)
  // Stopped on another backend, in another folder (a GPU machine's queue): its checkpoint goes on
  // here, whatever the limit.
  fs::copy_file(dir / "saved.ckpt", checkpoint);
  edit_record("status", "\"timed out\"");
  edit_record("time_limit", "99999");
  edit_record("total_seconds", "500");
  replace_in_file(record, "\"cpu\"", "\"vulkan\"");
  replace_in_file(record, kAssets + "/", "/root/q/data/");
  auto went_on = [&] {  // (the log goes on with the run: count)
    const std::string text = read_text(log), line = "going on from a checkpoint after level 2 of 3";
    int n = 0;
    for (size_t at = text.find(line); at != std::string::npos; at = text.find(line, at + 1)) ++n;
    return n;
  };
  const int went_on_before = went_on();
  REQUIRE(run_cli(bench, err) == 0);
  CHECK(read_text(err).find("ran elsewhere (--backend vulkan); running it again, from its checkpoint") !=
        std::string::npos);
  CHECK(went_on() == went_on_before + 1);
  CHECK(std::stod(row().at("total_seconds")) == doctest::Approx(500 + std::stod(row().at("seconds"))).epsilon(1e-4));
  CHECK(row().at("status") == "ok");
  CHECK(row().at("resumed_after_level") == "2");
  CHECK(row().at("energy") == first.at("energy"));
  CHECK_FALSE(fs::exists(checkpoint));
  // Stopped with the harness (its record says started): it goes on, its total unknown.
  fs::copy_file(dir / "saved.ckpt", checkpoint);
  edit_record("status", "\"started\"");
  REQUIRE(run_cli(bench, err) == 0);
  CHECK(went_on() == went_on_before + 2);
  CHECK(row().at("status") == "ok");
  CHECK(row().at("total_seconds").empty());
  // Without --resume (other options, say) a checkpoint left there goes: nothing on record made it.
  REQUIRE(run_cli("bench match --pairs " + (dir / "pairs.txt").string() + " --out " + (dir / "out").string() +
                      " --faces 200 --" + options + " --ring 1",
                  err) == 0);
  CHECK(row().at("status") == "ok");
  CHECK(read_text(log).find("going on from a checkpoint") == std::string::npos);
  CHECK_FALSE(fs::exists(checkpoint));
  fs::remove_all(dir);
}

TEST_CASE("cli: bench match --pairs rejects a malformed pairs file before running anything") {
  const fs::path dir = fs::temp_directory_path() / "shapematch_bench_pairs_bad_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path err = dir.string() + "_stderr.txt";
  std::ofstream(dir / "pairs.txt") << "a.off b.off\n# comment\nonly_one.off\n";
  CHECK(run_cli("bench match --pairs " + (dir / "pairs.txt").string() + " --out " + (dir / "out").string(), err) == 1);
  const std::string message = read_text(err);
  CHECK(std::count(message.begin(), message.end(), '\n') == 1);
  CHECK(message.rfind("shapematch: error: ", 0) == 0);
  CHECK(message.find("pairs.txt:3:") != std::string::npos);
  CHECK(!fs::exists(dir / "out"));
  fs::remove_all(dir);
}
