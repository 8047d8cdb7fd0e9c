// `shapematch bench lp`: the paper's Fig. 4 (LP solve time against problem size, one line per
// solver) with Clp in place of CPLEX; `shapematch bench bandwidth`: the streaming memory
// bandwidth that bounds one PDHG iteration.
#include "commands.hpp"
#include "shapematch/errors.hpp"
#include "shapematch/json.hpp"
#include "shapematch/matching.hpp"
#include "shapematch/pdhg.hpp"
#include "shapematch/system.hpp"

#include <spdlog/fmt/fmt.h>
#include <spdlog/spdlog.h>

#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <barrier>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <set>
#include <sstream>
#include <thread>

namespace shapematch::app {
namespace {

namespace fs = std::filesystem;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// ---------------------------------------------------------------------------------------------
// Bandwidth

struct BandwidthOptions {
  int threads = 0;              // 0 = all hardware threads, as the native PDHG backend uses
  int64_t elements = 1 << 24;   // per array: 3 × 128 MiB, far beyond any last-level cache
  int repeats = 10;             // best of, so that a neighbour's burst on a shared machine does not count
};

// STREAM triad a = b + s·c on all threads, each on the slice it touched first (so its pages are
// local). Bytes are counted STREAM's way, 24 per element without write-allocate, the same
// convention as pdhg_bytes_per_iteration.
double measure_bandwidth_gbps(const BandwidthOptions& options) {
  const int threads = options.threads > 0 ? options.threads : std::max(1, int(std::thread::hardware_concurrency()));
  const int64_t n = options.elements;
  std::unique_ptr<double[]> a(new double[n]), b(new double[n]), c(new double[n]);
  std::barrier sync(threads + 1);
  std::vector<std::jthread> workers;
  for (int t = 0; t < threads; ++t)
    workers.emplace_back([&, t] {
      double* __restrict pa = a.get();
      const double* __restrict pb = b.get();
      const double* __restrict pc = c.get();
      const int64_t begin = n * t / threads, end = n * (t + 1) / threads;
      for (int64_t i = begin; i < end; ++i) {
        pa[i] = 0.0;
        b[i] = 1.0;
        c[i] = 2.0;
      }
      for (int r = 0; r < options.repeats; ++r) {
        sync.arrive_and_wait();
        for (int64_t i = begin; i < end; ++i) pa[i] = pb[i] + 3.0 * pc[i];
        sync.arrive_and_wait();
      }
    });
  double best = kInf;
  for (int r = 0; r < options.repeats; ++r) {
    sync.arrive_and_wait();
    Stopwatch clock;
    sync.arrive_and_wait();
    best = std::min(best, clock.seconds());
  }
  workers.clear();
  if (a[n - 1] != 7.0) throw SolverError("bandwidth: the triad computed a wrong value");
  return 24.0 * double(n) / best / 1e9;
}

// ---------------------------------------------------------------------------------------------
// One solve in a child process, so that its peak memory is its own and a solver that ignores
// its time limit can be killed.

struct SolveRecord {
  std::string status;  // to_string(LpStatus), "killed" (watchdog) or "error"
  std::string device;  // the error message when status is "error"
  int64_t iterations = 0;
  double seconds = kNaN, objective = kNaN, lower_bound = kNaN;
  double peak_rss_mb = kNaN;    // peak RSS of the process during the solve, the LP it was given included
  double solver_rss_mb = kNaN;  // what the solve added on top of the RSS it started with
};

bool timed_out(const std::string& status) { return status == "time_limit" || status == "killed"; }

// "VmHWM:" or "VmRSS:" of /proc/self/status in MiB.
double proc_status_mb(const std::string& key) {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind(key, 0) == 0) return std::strtod(line.c_str() + key.size(), nullptr) / 1024.0;
  return kNaN;
}

std::string one_line(std::string text) {
  std::replace(text.begin(), text.end(), '\n', ' ');
  return text;
}

std::string serialize(const SolveRecord& r) {
  return fmt::format("{}\n{}\n{} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g}\n", r.status, one_line(r.device), r.iterations,
                     r.seconds, r.objective, r.lower_bound, r.peak_rss_mb, r.solver_rss_mb);
}

SolveRecord deserialize(const std::string& text) {
  std::istringstream in(text);
  SolveRecord r;
  std::getline(in, r.status);
  std::getline(in, r.device);
  std::string numbers;
  std::getline(in, numbers);
  // strtod, unlike operator>>, reads back "nan" and "inf".
  const char* p = numbers.c_str();
  char* end = nullptr;
  r.iterations = std::strtoll(p, &end, 10);
  for (double* v : {&r.seconds, &r.objective, &r.lower_bound, &r.peak_rss_mb, &r.solver_rss_mb}) {
    p = end;
    *v = std::strtod(p, &end);
  }
  return r;
}

SolveRecord solve_measured(const LpProblem& lp, const std::string& solver, const SolverParams& params) {
  // Writing 5 to clear_refs resets the peak RSS to the current RSS (Linux ≥ 4.0); a child's
  // peak would otherwise start from the parent's, which built every mesh and LP so far.
  std::ofstream reset("/proc/self/clear_refs");
  reset << "5";
  reset.close();
  const bool peak_is_ours = !reset.fail();
  const double start_mb = proc_status_mb("VmRSS:");
  const LpResult r = solve_lp(lp, solver, params);
  SolveRecord out;
  out.status = to_string(r.status);
  out.device = r.device;
  out.iterations = r.iterations;
  out.seconds = r.seconds;
  out.objective = r.objective;
  out.lower_bound = r.lower_bound;
  if (peak_is_ours) {
    out.peak_rss_mb = proc_status_mb("VmHWM:");
    out.solver_rss_mb = out.peak_rss_mb - start_mb;
  }
  return out;
}

std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char ch : s) q += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
  return q + "'";
}

// Runs the solve in a forked child and reads its record through a pipe; after `watchdog`
// seconds without an answer the child is killed.
SolveRecord solve_isolated(const LpProblem& lp, const std::string& solver, const SolverParams& params, double watchdog) {
  int fds[2];
  if (pipe(fds) != 0) throw SolverError(std::string("bench: pipe: ") + std::strerror(errno));
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  Stopwatch clock;
  const pid_t pid = fork();
  if (pid < 0) throw SolverError(std::string("bench: fork: ") + std::strerror(errno));
  if (pid == 0) {
    close(fds[0]);
    std::string text;
    try {
      text = serialize(solve_measured(lp, solver, params));
    } catch (const std::exception& e) {
      SolveRecord failed;
      failed.status = "error";
      failed.device = e.what();
      text = serialize(failed);
    }
    for (size_t done = 0; done < text.size();) {
      const ssize_t k = write(fds[1], text.data() + done, text.size() - done);
      if (k <= 0) break;
      done += size_t(k);
    }
    _exit(0);  // no destructors or atexit handlers of the parent's state
  }
  close(fds[1]);
  std::string text;
  bool killed = false;
  while (true) {
    const double left = watchdog - clock.seconds();
    if (left <= 0) {
      kill(pid, SIGKILL);
      killed = true;
      break;
    }
    pollfd p{fds[0], POLLIN, 0};
    const int timeout_ms = std::isfinite(left) ? int(std::min(left * 1000.0 + 1.0, 1e9)) : -1;
    const int ready = poll(&p, 1, timeout_ms);
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) continue;  // timed out: the next turn kills
    char buf[4096];
    const ssize_t k = read(fds[0], buf, sizeof buf);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) break;
    text.append(buf, size_t(k));
  }
  close(fds[0]);
  int wstatus = 0;
  while (waitpid(pid, &wstatus, 0) < 0 && errno == EINTR) {
  }
  SolveRecord r;
  if (killed) {
    r.status = "killed";
    r.seconds = clock.seconds();
  } else if (text.empty()) {
    r.status = "error";
    r.device = WIFSIGNALED(wstatus) ? fmt::format("the solver process died of signal {} (out of memory?)", WTERMSIG(wstatus))
                                    : "the solver process exited without a result";
  } else {
    r = deserialize(text);
  }
  return r;
}

// ---------------------------------------------------------------------------------------------
// bench lp

struct BenchLpArgs {
  std::vector<std::string> pair;  // X Y; default: the bundled pair
  std::vector<int> faces{25, 50, 100, 200, 400};
  std::vector<std::string> solvers{"pdhg-cpu", "pdhg-vulkan", "clp-dual", "clp-barrier"};
  double tolerance = 1e-4;
  double clp_time_limit = 300.0;
  double pdhg_time_limit = kInf;
  std::string out = "bench";
  int repeat = 1;
  bool bandwidth = false;
};

struct BenchRow {
  int faces_x = 0, faces_y = 0;
  int64_t variables = 0, constraints = 0, nonzeros = 0;
  std::string solver;
  SolveRecord run;
  double rel_diff_best = kNaN;
  double bytes_per_iteration = kNaN;  // PDHG only: Clp's iterations are not comparable units of work
};

std::string csv_text(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char ch : s) q += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return q + "\"";
}

// Empty for "not applicable / not measured", so that spreadsheets and the plot skip the cell.
std::string csv_number(double v, int digits = 6) {
  return std::isfinite(v) ? fmt::format("{:.{}g}", v, digits) : std::string();
}

std::string csv_table(const std::vector<BenchRow>& rows, double bandwidth_gbps) {
  std::string text =
      "faces_x,faces_y,variables,constraints,nonzeros,solver,device,status,iterations,seconds,"
      "seconds_per_iteration,peak_rss_mb,solver_rss_mb,objective,lower_bound,rel_diff_best,"
      "bytes_per_iteration,achieved_gbps,bandwidth_ratio\n";
  for (const BenchRow& r : rows) {
    const double per_iteration = r.run.iterations > 0 ? r.run.seconds / double(r.run.iterations) : kNaN;
    const double bound = r.bytes_per_iteration / (bandwidth_gbps * 1e9);  // seconds, NaN unless both known
    text += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", r.faces_x, r.faces_y, r.variables,
                        r.constraints, r.nonzeros, csv_text(r.solver), csv_text(r.run.device), csv_text(r.run.status),
                        r.run.iterations, csv_number(r.run.seconds), csv_number(per_iteration),
                        csv_number(r.run.peak_rss_mb, 5), csv_number(r.run.solver_rss_mb, 5),
                        csv_number(r.run.objective, 12), csv_number(r.run.lower_bound, 12),
                        csv_number(r.rel_diff_best, 3), csv_number(r.bytes_per_iteration, 15),
                        csv_number(r.bytes_per_iteration / per_iteration / 1e9, 4), csv_number(per_iteration / bound, 4));
  }
  return text;
}

// Relative difference of each optimal run's objective to the lowest one at this size (the rows
// of one size); the objective of a run that stopped early says nothing about the solver.
void fill_rel_diff(std::vector<BenchRow>::iterator begin, std::vector<BenchRow>::iterator end) {
  double best = kInf;
  for (auto it = begin; it != end; ++it)
    if (it->run.status == "optimal" && std::isfinite(it->run.objective)) best = std::min(best, it->run.objective);
  if (!std::isfinite(best)) return;
  for (auto it = begin; it != end; ++it)
    if (it->run.status == "optimal" && std::isfinite(it->run.objective))
      it->rel_diff_best = std::abs(it->run.objective - best) / std::max(std::abs(best), 1e-300);
}

// The fastest of `repeat` runs (timings on a shared machine only err upwards), with the largest
// peak memory; a run that hit its time limit ends the repeats.
SolveRecord solve_repeated(const LpProblem& lp, const std::string& solver, const SolverParams& params, int repeat) {
  const double watchdog = params.time_limit + std::max(30.0, 0.25 * params.time_limit);
  SolveRecord best;
  double peak = kNaN, added = kNaN;
  for (int i = 0; i < repeat; ++i) {
    const SolveRecord r = solve_isolated(lp, solver, params, watchdog);
    peak = std::fmax(peak, r.peak_rss_mb);  // fmax skips a NaN (not measured)
    added = std::fmax(added, r.solver_rss_mb);
    if (i == 0 || r.seconds < best.seconds) best = r;
    if (timed_out(r.status) || r.status == "error") {
      best = r;
      break;
    }
  }
  best.peak_rss_mb = peak;
  best.solver_rss_mb = added;
  return best;
}

// tools/plot_bench.py with Debian's Python, which has matplotlib; a missing matplotlib is a
// warning, not a failed benchmark. Returns the PNG path, or "" when there is none.
std::string plot(const std::string& csv_path, const std::string& png_path) {
  const fs::path script = fs::path(SHAPEMATCH_ASSETS_DIR).parent_path() / "tools" / "plot_bench.py";
  const std::string python = "/usr/bin/python3";
  if (std::system((python + " -c 'import matplotlib' >/dev/null 2>&1").c_str()) != 0) {
    spdlog::warn("{} cannot import matplotlib (apt install python3-matplotlib); no plot, the CSV is {}", python,
                 csv_path);
    return "";
  }
  const std::string cmd = python + " " + shell_quote(script.string()) + " " + shell_quote(csv_path) + " " +
                          shell_quote(png_path) + " >&2";
  if (std::system(cmd.c_str()) != 0) {
    spdlog::warn("plotting failed ({}); the CSV is {}", cmd, csv_path);
    return "";
  }
  return png_path;
}

int run_bench_lp(BenchLpArgs args) {
  if (args.pair.empty()) args.pair = {default_mesh_x(), default_mesh_y()};
  std::sort(args.faces.begin(), args.faces.end());  // "timed out, skip larger sizes" needs ascending sizes
  fs::create_directories(args.out);
  const std::string csv_path = (fs::path(args.out) / "bench_lp.csv").string();
  const std::string png_path = (fs::path(args.out) / "bench_lp.png").string();

  double bandwidth_gbps = kNaN;
  if (args.bandwidth) {
    bandwidth_gbps = measure_bandwidth_gbps({});
    spdlog::info("streaming bandwidth (triad, all threads): {:.2f} GB/s", bandwidth_gbps);
  }

  LoadOptions load;
  const Mesh x_full = load_mesh(args.pair[0], load);
  const Mesh y_full = load_mesh(args.pair[1], load);
  std::vector<BenchRow> rows;
  std::set<std::string> gave_up;
  for (const int faces : args.faces) {
    const Mesh x = decimate(x_full, faces), y = decimate(y_full, faces);
    const MatchingLp m = build_matching_lp(x, compute_geometry(x), y, compute_geometry(y));
    spdlog::info("{} faces: X {} faces, Y {} faces, LP {} variables, {} constraints, {} nonzeros", faces, x.num_faces(),
                 y.num_faces(), m.lp.cols(), m.lp.rows(), m.lp.nonzeros());
    const size_t first = rows.size();
    for (const std::string& solver : args.solvers) {
      if (gave_up.count(solver)) {
        spdlog::info("  {}: skipped (timed out at a smaller size)", solver);
        continue;
      }
      const bool pdhg = solver.rfind("pdhg", 0) == 0;
      SolverParams params;
      params.tolerance = args.tolerance;
      params.time_limit = pdhg ? args.pdhg_time_limit : args.clp_time_limit;
      BenchRow row;
      row.faces_x = x.num_faces();
      row.faces_y = y.num_faces();
      row.variables = m.lp.cols();
      row.constraints = m.lp.rows();
      row.nonzeros = m.lp.nonzeros();
      row.solver = solver;
      row.run = solve_repeated(m.lp, solver, params, args.repeat);
      if (pdhg) row.bytes_per_iteration = pdhg_bytes_per_iteration(m.lp);
      if (row.run.status == "error")
        spdlog::warn("  {}: failed: {}", solver, row.run.device);
      else
        spdlog::info("  {}: {} after {} iterations, {:.3f} s, objective {:.9g}, peak {:.0f} MiB", solver, row.run.status,
                     row.run.iterations, row.run.seconds, row.run.objective, row.run.peak_rss_mb);
      if (timed_out(row.run.status)) gave_up.insert(solver);
      rows.push_back(std::move(row));
    }
    fill_rel_diff(rows.begin() + std::ptrdiff_t(first), rows.end());
    // Rewritten after every size, so that a long benchmark that is stopped keeps what it measured.
    write_file_atomic(csv_path, csv_table(rows, bandwidth_gbps));
  }
  if (rows.empty()) write_file_atomic(csv_path, csv_table(rows, bandwidth_gbps));

  Json out = Json::object();
  out.set("csv", csv_path).set("plot", plot(csv_path, png_path));
  out.set("bandwidth_gbps", bandwidth_gbps);
  std::cout << out.dump() << std::endl;
  return 0;
}

}  // namespace

Action add_bench_command(CLI::App& app) {
  app.require_subcommand(1);
  CLI::App* lp = app.add_subcommand("lp", "time every LP solver on the matching LP at growing sizes (CSV + plot)");
  auto args = std::make_shared<BenchLpArgs>();
  lp->add_option("--pair", args->pair, "the two meshes X Y; default: bundled asset pair")->expected(2);
  lp->add_option("--faces", args->faces, "faces per shape of each size (decimated)")
      ->delimiter(',')
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  lp->add_option("--solvers", args->solvers, "solvers to run")
      ->delimiter(',')
      ->check(CLI::IsMember(solver_names()))
      ->capture_default_str();
  lp->add_option("--tol", args->tolerance, "relative tolerance of the first-order solvers")->capture_default_str();
  lp->add_option("--clp-time-limit", args->clp_time_limit, "seconds per Clp solve; a solver that hits it is skipped at larger sizes")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  lp->add_option("--pdhg-time-limit", args->pdhg_time_limit, "seconds per PDHG solve (default none)")
      ->check(CLI::PositiveNumber);
  lp->add_option("--out", args->out, "directory for bench_lp.csv and bench_lp.png")->capture_default_str();
  lp->add_option("--repeat", args->repeat, "runs per solver and size; the fastest is reported")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  lp->add_flag("--bandwidth", args->bandwidth, "also measure the streaming bandwidth and report time per iteration against it");

  CLI::App* bandwidth = app.add_subcommand("bandwidth", "measure streaming memory bandwidth (STREAM triad, all threads)");
  auto bw = std::make_shared<BandwidthOptions>();
  bandwidth->add_option("--threads", bw->threads, "threads (0 = all)")->check(CLI::NonNegativeNumber)->capture_default_str();
  bandwidth->add_option("--repeats", bw->repeats, "best of this many runs")->check(CLI::PositiveNumber)->capture_default_str();

  return [lp, args, bw] {
    if (lp->parsed()) return run_bench_lp(*args);
    const double gbps = measure_bandwidth_gbps(*bw);
    Json out = Json::object();
    out.set("threads", bw->threads > 0 ? bw->threads : int(std::thread::hardware_concurrency()));
    out.set("array_mib", double(bw->elements) * 8.0 / (1 << 20));
    out.set("gbps", gbps);
    std::cout << out.dump() << std::endl;
    return 0;
  };
}

}  // namespace shapematch::app
