// End-to-end test of `shapematch bench lp`: the CSV has its columns and one row per solver and
// size, the solvers agree, and the plot is made where Debian's Python has matplotlib.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <sys/wait.h>
#include <vector>

namespace fs = std::filesystem;

namespace {

// Exit code; stderr goes to `err`.
int run_cli(const std::string& args, const fs::path& err) {
  const std::string cmd = std::string(SHAPEMATCH_CLI) + " " + args + " >/dev/null 2>" + err.string();
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
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

}  // namespace

TEST_CASE("cli: bench lp writes one CSV row per solver and size, and the solvers agree") {
  const fs::path dir = fs::temp_directory_path() / "shapematch_bench_test";
  fs::remove_all(dir);
  const fs::path err = fs::temp_directory_path() / "shapematch_bench_stderr.txt";
  REQUIRE(run_cli("bench lp --faces 12,20 --solvers pdhg-cpu,clp-dual --out " + dir.string(), err) == 0);

  std::ifstream f(dir / "bench_lp.csv");
  REQUIRE(f.good());
  std::string line;
  std::getline(f, line);
  const std::vector<std::string> header = split_csv(line);
  const std::vector<std::string> expected = {
      "faces_x", "faces_y", "variables", "constraints", "nonzeros", "solver", "device", "status", "iterations", "seconds",
      "seconds_per_iteration", "peak_rss_mb", "solver_rss_mb", "objective", "lower_bound", "rel_diff_best",
      "bytes_per_iteration", "achieved_gbps", "bandwidth_ratio"};
  REQUIRE(header == expected);
  std::vector<std::map<std::string, std::string>> rows;
  while (std::getline(f, line)) {
    const std::vector<std::string> fields = split_csv(line);
    REQUIRE(fields.size() == header.size());
    std::map<std::string, std::string> row;
    for (size_t i = 0; i < header.size(); ++i) row[header[i]] = fields[i];
    rows.push_back(row);
  }
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
    auto [it, first] = objective_at.emplace(row.at("variables"), std::stod(row.at("objective")));
    if (!first) CHECK(std::abs(std::stod(row.at("objective")) - it->second) <= 1e-3 * std::abs(it->second));
  }
  CHECK(objective_at.size() == 2);  // two sizes

  std::ifstream log(err);
  const std::string errors(std::istreambuf_iterator<char>(log), {});
  if (std::system("/usr/bin/python3 -c 'import matplotlib' >/dev/null 2>&1") == 0)
    CHECK(fs::file_size(dir / "bench_lp.png") > 1000);
  else
    CHECK(errors.find("matplotlib") != std::string::npos);
  fs::remove_all(dir);
}
