// `shapematch bench lp`: the paper's Fig. 4 (LP solve time against problem size, one line per
// solver) with Clp in place of CPLEX; `shapematch bench bandwidth`: the streaming memory
// bandwidth that bounds one PDHG iteration; `shapematch bench match`: whole match runs, at
// growing sizes (time and memory scaling) or over a list of pairs with their evaluation.
#include "commands.hpp"
#include "json_read.hpp"
#include "shapematch/coarse_to_fine.hpp"
#include "shapematch/errors.hpp"
#include "shapematch/files.hpp"
#include "shapematch/json.hpp"
#include "shapematch/matching.hpp"
#include "shapematch/pdhg.hpp"
#include "shapematch/system.hpp"

#include <spdlog/fmt/fmt.h>
#include <spdlog/spdlog.h>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <barrier>
#include <cerrno>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <sstream>
#include <string_view>
#include <thread>

namespace shapematch::app {
namespace {

namespace fs = std::filesystem;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// ---------------------------------------------------------------------------------------------
// Bandwidth

struct BandwidthOptions {
  int threads = 0;              // 0 = all CPUs this process may use, as the native PDHG backend does
  int64_t elements = 1 << 24;   // per array: 3 × 128 MiB, far beyond any last-level cache
  int repeats = 10;             // best of, so that a neighbour's burst on a shared machine does not count
};

// STREAM triad a = b + s·c on all threads, each on the slice it touched first (so its pages are
// local). Bytes are counted STREAM's way, 24 per element without write-allocate, the same
// convention as pdhg_bytes_per_iteration.
// The threads it runs: at most the CPUs this process may use (more only share them, and
// thousands fail to start), as match's --threads.
int bandwidth_threads(const BandwidthOptions& options) {
  return options.threads > 0 ? std::min(options.threads, worker_threads()) : worker_threads();
}

double measure_bandwidth_gbps(const BandwidthOptions& options) {
  const int threads = bandwidth_threads(options);
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
  double setup_seconds = kNaN;  // of seconds, before the first iteration (PDHG)
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
  return fmt::format("{}\n{}\n{} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g}\n", r.status, one_line(r.device),
                     r.iterations, r.seconds, r.objective, r.lower_bound, r.peak_rss_mb, r.solver_rss_mb, r.setup_seconds);
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
  for (double* v : {&r.seconds, &r.objective, &r.lower_bound, &r.peak_rss_mb, &r.solver_rss_mb, &r.setup_seconds}) {
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
  if (r.solver.rfind("pdhg", 0) == 0) out.setup_seconds = r.setup_seconds;
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
  std::vector<std::string> pair;  // X Y; default: the bundled finger pair
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
      "faces_x,faces_y,variables,constraints,nonzeros,solver,device,status,iterations,seconds,setup_seconds,"
      "seconds_per_iteration,peak_rss_mb,solver_rss_mb,objective,lower_bound,rel_diff_best,"
      "bytes_per_iteration,achieved_gbps,bandwidth_ratio\n";
  for (const BenchRow& r : rows) {
    // The iterations' own time: the set-up (PDHG's scaling, ‖A‖ estimate and upload) is its own column.
    const double iterating = r.run.seconds - (std::isfinite(r.run.setup_seconds) ? r.run.setup_seconds : 0.0);
    const double per_iteration = r.run.iterations > 0 ? iterating / double(r.run.iterations) : kNaN;
    const double bound = r.bytes_per_iteration / (bandwidth_gbps * 1e9);  // seconds, NaN unless both known
    text += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", r.faces_x, r.faces_y, r.variables,
                        r.constraints, r.nonzeros, csv_text(r.solver), csv_text(r.run.device), csv_text(r.run.status),
                        r.run.iterations, csv_number(r.run.seconds), csv_number(r.run.setup_seconds),
                        csv_number(per_iteration),
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

// tools/<script> with Debian's Python, which has matplotlib; a missing matplotlib is a warning,
// not a failed benchmark. Returns the PNG path, or "" when there is none.
std::string plot(const std::string& script_name, const std::string& csv_path, const std::string& png_path) {
  const fs::path script = fs::path(data_dir()) / "tools" / script_name;
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

// A benchmark's --out folder (and `sub` in it), made where missing: one line naming it where it
// cannot be (a file there, no permission), before any run, not "internal error".
void make_output_folder(const fs::path& out, const fs::path& sub = {}) {
  const fs::path folder = sub.empty() ? out : out / sub;
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec || !fs::is_directory(folder))
    throw IoError(folder.string() + ": cannot make this output folder (" + (ec ? ec.message() : "a file is there") + ")");
}

int run_bench_lp(BenchLpArgs args) {
  if (args.pair.empty()) args.pair = default_bench_lp_pair();
  std::sort(args.faces.begin(), args.faces.end());  // "timed out, skip larger sizes" needs ascending sizes
  make_output_folder(args.out);
  const std::string csv_path = (fs::path(args.out) / "bench_lp.csv").string();
  const std::string png_path = (fs::path(args.out) / "bench_lp.png").string();
  check_writable_file(csv_path);
  check_writable_file(png_path);

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
      if (pdhg)
        row.bytes_per_iteration =
            solver == "pdhg-cpu-f32" ? pdhg_bytes_per_iteration_f32(m.lp) : pdhg_bytes_per_iteration(m.lp);
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
  out.set("csv", csv_path).set("plot", plot("plot_bench.py", csv_path, png_path));
  out.set("bandwidth_gbps", bandwidth_gbps);
  std::cout << out.dump() << std::endl;
  return 0;
}

// ---------------------------------------------------------------------------------------------
// bench match: whole `match` (and `eval`) runs as child processes of this executable, so that
// each one is timed, measured and, past the time limit, killed on its own.

struct ChildRun {
  std::string status;  // "ok", "timed out", "interrupted" (SIGINT, SIGTERM) or "failed: <reason>"
  double seconds = kNaN;
  double peak_rss_mb = kNaN;
};

// The child's reason: its first stderr line that is not a log line ("[12:00:00.000] ..."), which
// is the "shapematch: error: ..." line or CLI11's complaint about an option.
std::string failure_reason(const fs::path& err_path, int wstatus) {
  std::ifstream in(err_path);
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '[') continue;
    for (const std::string prefix : {"shapematch: error: ", "shapematch: "})
      if (line.rfind(prefix, 0) == 0) {
        line.erase(0, prefix.size());
        break;
      }
    return line;
  }
  if (WIFSIGNALED(wstatus)) return fmt::format("killed by signal {} (out of memory?)", WTERMSIG(wstatus));
  return fmt::format("exit code {}", WEXITSTATUS(wstatus));
}

// Runs this executable with `args`: stdout to `out_path` (empty: with stderr), stderr to
// `err_path`. posix_spawn (vfork underneath) rather than fork, so that the child does not start
// as a copy of this process and the ru_maxrss that wait4 reports is its own peak.
ChildRun run_child(const std::vector<std::string>& args, const std::string& out_path, const std::string& err_path,
                   double time_limit, bool append_err = false) {
  static const std::string exe = fs::read_symlink("/proc/self/exe").string();
  std::vector<std::string> words{exe};
  words.insert(words.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);

  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  posix_spawn_file_actions_addopen(&files, STDERR_FILENO, err_path.c_str(),
                                   O_WRONLY | O_CREAT | (append_err ? O_APPEND : O_TRUNC), 0644);
  if (out_path.empty())
    posix_spawn_file_actions_adddup2(&files, STDERR_FILENO, STDOUT_FILENO);
  else
    posix_spawn_file_actions_addopen(&files, STDOUT_FILENO, out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  Stopwatch clock;
  pid_t pid = 0;
  const int started = posix_spawn(&pid, exe.c_str(), &files, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&files);
  if (started != 0) throw SolverError(fmt::format("bench: cannot start {}: {}", exe, std::strerror(started)));

  int wstatus = 0;
  rusage usage{};
  bool killed = false;
  while (true) {
    const pid_t done = wait4(pid, &wstatus, WNOHANG, &usage);
    if (done == pid) break;
    if (done < 0 && errno != EINTR) throw SolverError(std::string("bench: wait4: ") + std::strerror(errno));
    if (!killed && clock.seconds() > time_limit) {
      kill(pid, SIGKILL);
      killed = true;
    }
    // Polling keeps the measured wall time within 2 ms of the child's, at no measurable cost.
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ChildRun r;
  r.seconds = clock.seconds();
  r.peak_rss_mb = double(usage.ru_maxrss) / 1024.0;  // KiB on Linux
  if (killed)
    r.status = "timed out";
  else if (WIFEXITED(wstatus) && WEXITSTATUS(wstatus) == 0)
    r.status = "ok";
  else if (WIFSIGNALED(wstatus) && (WTERMSIG(wstatus) == SIGINT || WTERMSIG(wstatus) == SIGTERM))
    r.status = "interrupted";  // (match --checkpoint saves before it goes: --resume goes on from there)
  else
    r.status = "failed: " + failure_reason(err_path, wstatus);
  return r;
}

struct BenchMatchArgs {
  std::vector<std::string> pair;  // scaling: X Y; default: the bundled pair
  std::string pairs_file;         // pairs mode when given
  std::vector<std::string> faces;  // face counts or "full"
  std::string out = "bench";
  double time_limit = 600.0;
  std::vector<std::string> match_args;  // after `--`, passed to every match run
  bool resume = false;                  // pairs: reuse the rows an earlier run of the same command finished
  int jobs = 1;                         // pairs: runs at once, each with its share of the CPUs
};

// One match run (a size or a pair); NaN where it did not get that far.
struct MatchRow {
  std::string name;  // the faces asked for, or the pair
  double faces_x = kNaN, faces_y = kNaN, levels = kNaN, variables = kNaN, rounds = kNaN;
  double energy = kNaN, lower_bound = kNaN, gap = kNaN;
  double max_level_gap = kNaN;  // the largest of the levels' gaps (issue 5 asks for each level's)
  double mean_error = kNaN, median_error = kNaN, symmetric_mean_error = kNaN, flips = kNaN;
  double point_mean_error = kNaN, point_flips = kNaN;  // the point map's (eval's `point_map`)
  // The share of the error in points matched to their mirror image (eval's, with the symmetric
  // truth): a pair whose error is one swapped leg shows here.
  double mirrored_share = kNaN;
  double resumed_after_level = kNaN;  // levels taken from a checkpoint (their time is not in `run`)
  // `run`'s seconds plus those of the runs whose checkpoint it went on from (NaN where one of
  // them is not on record: a harness stopped during it).
  double total_seconds = kNaN;
  ChildRun run;
};

int faces_value(const std::string& faces) { return faces == "full" ? 0 : std::stoi(faces); }

std::string absolute_path(const std::string& path) { return fs::absolute(path).lexically_normal().string(); }

// The size and rounds are the finest level's: the coarser levels only narrow its product space.
void read_report(const fs::path& dir, MatchRow& row) {
  const JsonNode report = read_json_file((dir / "report.json").string());
  if (const JsonNode* x = report.get("x")) row.faces_x = x->number_or_nan("faces");
  if (const JsonNode* y = report.get("y")) row.faces_y = y->number_or_nan("faces");
  const JsonNode* levels = report.get("levels");
  if (levels && levels->kind == JsonNode::Kind::Array && !levels->members.empty()) {
    row.levels = double(levels->members.size());
    const JsonNode& finest = levels->members.back().second;
    row.variables = finest.number_or_nan("variables");
    row.rounds = finest.number_or_nan("rounds");
    for (const auto& [key, level] : levels->members) {
      const double g = level.number_or_nan("gap");
      if (std::isfinite(g) && !(g <= row.max_level_gap)) row.max_level_gap = g;
    }
  }
  row.energy = report.number_or_nan("energy");
  row.lower_bound = report.number_or_nan("lower_bound");
  row.resumed_after_level = report.number_or_nan("resumed_after_level");
  row.gap = report.number_or_nan("gap");
}

// Each of --jobs runs' share of this process's CPUs.
int threads_per_job(const BenchMatchArgs& args) { return std::max(1, worker_threads() / std::max(1, args.jobs)); }

// The arguments of `match` for one run, less its output directory.
std::vector<std::string> match_command(const BenchMatchArgs& args, const std::string& x, const std::string& y,
                                       const std::string& faces) {
  std::vector<std::string> cmd{"match", x, y};
  if (!faces.empty()) cmd.insert(cmd.end(), {"--faces", faces});
  cmd.insert(cmd.end(), args.match_args.begin(), args.match_args.end());
  return cmd;
}

// The options after `--`, checked once before any run: a typo would otherwise fail every pair in
// turn, each row "failed" and bench's exit 0. Those the benchmark sets itself are refused.
void check_match_args(const std::vector<std::string>& args) {
  if (std::find(args.begin(), args.end(), "--") != args.end())
    throw InvalidInputError("bench match: a second `--` among the match options (everything after the first is theirs)");
  for (const std::string& a : args)
    for (const std::string own : {"-o", "--out", "--faces", "--checkpoint"})
      if (a == own || a.rfind(own + "=", 0) == 0 || (own == "-o" && a.size() > 2 && a.rfind("-o", 0) == 0))
        throw InvalidInputError(fmt::format("bench match: {} after `--` is set by the benchmark for each run", own));
  CLI::App probe;
  add_match_command(probe);
  std::vector<std::string> reversed(args.rbegin(), args.rend());  // (CLI11 takes them last first)
  try {
    probe.parse(reversed);
    check_finite_options(probe);
  } catch (const CLI::Success&) {  // (--help: the match options are `shapematch match --help`'s)
    throw InvalidInputError("bench match: --help after `--`: the options there are those of `shapematch match --help`");
  } catch (const CLI::ParseError& e) {
    throw InvalidInputError(fmt::format("bench match: the match options after `--`: {}", e.what()));
  }
}

// `match X Y` into `dir` (kept for inspection, its log beside it as dir.match.log). With a
// `checkpoint` file the run goes on from it where it exists and saves its levels there;
// `started` is called once the previous run's outputs are gone, before this one starts.
void run_match_child(const BenchMatchArgs& args, const std::string& x, const std::string& y, const std::string& faces,
                     const fs::path& dir, MatchRow& row, const fs::path& checkpoint = {},
                     const std::function<void()>& started = {}) {
  // A failed run must not leave the previous benchmark's output looking like its own, nor the
  // record that --resume trusts.
  fs::remove_all(dir);
  for (const char* suffix : {".run.json", ".eval.json"}) fs::remove(dir.string() + suffix);
  if (checkpoint.empty()) fs::remove(dir.string() + ".ckpt");  // (made with options not on record)
  if (started) started();
  std::vector<std::string> cmd = match_command(args, x, y, faces);
  cmd.insert(cmd.end(), {"-o", dir.string()});
  // (Not part of the command --resume compares: it changes where a run starts, not its Γ's options.)
  if (!checkpoint.empty()) cmd.insert(cmd.end(), {"--checkpoint", checkpoint.string()});
  // Runs side by side share the CPUs (not part of the command --resume compares: the count
  // changes no Γ), unless the match options say how.
  if (args.jobs > 1 && std::find(cmd.begin(), cmd.end(), "--threads") == cmd.end())
    cmd.insert(cmd.end(), {"--threads", std::to_string(threads_per_job(args))});
  // Going on from a checkpoint, the log goes on too: the levels it holds were logged before.
  const bool going_on = !checkpoint.empty() && fs::exists(checkpoint);
  row.run = run_child(cmd, "", dir.string() + ".match.log", args.time_limit, going_on);
  if (row.run.status != "ok") return;
  try {
    read_report(dir, row);
  } catch (const Error& e) {
    row.run.status = std::string("failed: ") + e.what();
  }
}

void log_row(const MatchRow& row) {
  if (row.run.status == "ok")
    spdlog::info("{}: {}×{} faces, energy {:.6g}, gap {:.2g}, {:.2f} s, peak {:.0f} MiB", row.name, row.faces_x,
                 row.faces_y, row.energy, row.gap, row.run.seconds, row.run.peak_rss_mb);
  else if (std::isfinite(row.run.seconds))
    spdlog::warn("{}: {} ({:.2f} s)", row.name, row.run.status, row.run.seconds);
  else
    spdlog::warn("{}: {}", row.name, row.run.status);
}

std::string csv_int(double v) { return std::isfinite(v) ? fmt::format("{:.0f}", v) : std::string(); }

std::string fixed(double v, int decimals) {
  return std::isfinite(v) ? fmt::format("{:.{}f}", v, decimals) : std::string();
}

// A Markdown table padded into aligned columns, so that it reads as plain text too.
std::string markdown_table(const std::vector<std::string>& header, std::vector<std::vector<std::string>> rows) {
  for (auto& row : rows)
    for (std::string& cell : row) {
      std::string escaped;
      for (char ch : cell) escaped += ch == '|' ? std::string("\\|") : std::string(1, ch);
      cell = std::move(escaped);
    }
  std::vector<size_t> width(header.size());
  for (size_t c = 0; c < header.size(); ++c) {
    width[c] = std::max<size_t>(3, header[c].size());
    for (const auto& row : rows) width[c] = std::max(width[c], row[c].size());
  }
  auto line = [&](const std::vector<std::string>& cells) {
    std::string text = "|";
    for (size_t c = 0; c < cells.size(); ++c) text += fmt::format(" {:<{}} |", cells[c], width[c]);
    return text + "\n";
  };
  std::string text = line(header) + "|";
  for (size_t w : width) text += std::string(w + 2, '-') + "|";
  text += "\n";
  for (const auto& row : rows) text += line(row);
  return text;
}

std::string csv_line(const std::vector<std::string>& cells) {
  std::string text;
  for (size_t c = 0; c < cells.size(); ++c) {
    if (c) text += ',';
    text += csv_text(cells[c]);
  }
  return text + "\n";
}

// ---- scaling mode

const std::vector<std::string> kScalingHeader{"faces_requested", "faces_x", "faces_y",   "levels",
                                              "variables",       "rounds",  "energy",    "lower_bound",
                                              "gap",             "max_level_gap", "seconds", "peak_rss_mb", "status"};

// `csv` chooses full precision over readable widths.
std::vector<std::vector<std::string>> scaling_cells(const std::vector<MatchRow>& rows, bool csv) {
  std::vector<std::vector<std::string>> cells;
  for (const MatchRow& r : rows)
    cells.push_back({r.name, csv_int(r.faces_x), csv_int(r.faces_y), csv_int(r.levels), csv_int(r.variables),
                     csv_int(r.rounds), csv_number(r.energy, csv ? 12 : 6), csv_number(r.lower_bound, csv ? 12 : 6),
                     csv_number(r.gap, csv ? 4 : 3), csv_number(r.max_level_gap, csv ? 4 : 3),
                     csv ? csv_number(r.run.seconds) : fixed(r.run.seconds, 2),
                     csv ? csv_number(r.run.peak_rss_mb, 5) : fixed(r.run.peak_rss_mb, 0), r.run.status});
  return cells;
}

std::string scaling_csv(const std::vector<MatchRow>& rows) {
  std::string text = csv_line(kScalingHeader);
  for (const auto& row : scaling_cells(rows, true)) text += csv_line(row);
  return text;
}

int run_bench_scaling(const BenchMatchArgs& args) {
  const std::vector<std::string> pair = args.pair.empty() ? std::vector<std::string>{default_mesh_x(), default_mesh_y()}
                                                          : args.pair;
  const std::string x = absolute_path(pair[0]), y = absolute_path(pair[1]);
  std::vector<std::string> sizes = args.faces;
  if (sizes.empty()) sizes = {"500", "1000", "2000", "4000", "full"};
  // Ascending with "full" last, so that a size that timed out can skip the larger ones.
  auto order = [](const std::string& s) { return s == "full" ? INT_MAX : faces_value(s); };
  std::stable_sort(sizes.begin(), sizes.end(), [&](const auto& a, const auto& b) { return order(a) < order(b); });

  const fs::path out(args.out);
  make_output_folder(out, "runs");
  const std::string csv_path = (out / "bench_match.csv").string();
  std::vector<MatchRow> rows;
  bool gave_up = false;
  for (const std::string& size : sizes) {
    MatchRow row;
    row.name = size;
    if (gave_up) {
      row.run.status = "skipped (a smaller size timed out)";
    } else {
      spdlog::info("match at {} faces", size);
      run_match_child(args, x, y, std::to_string(faces_value(size)), out / "runs" / ("faces_" + size), row);
      gave_up = row.run.status == "timed out";
    }
    log_row(row);
    rows.push_back(std::move(row));
    // Rewritten after every run, so that a long benchmark that is stopped keeps what it measured.
    write_file_atomic(csv_path, scaling_csv(rows));
  }
  const std::string png = plot("plot_bench_match.py", csv_path, (out / "bench_match.png").string());

  std::cout << markdown_table(kScalingHeader, scaling_cells(rows, false)) << std::flush;
  spdlog::info("wrote {}{}", csv_path, png.empty() ? "" : " and " + png);
  return 0;
}

// ---- pairs mode

struct PairSpec {
  std::string x, y;
  std::vector<std::string> truth;  // the options of `eval` that name the ground truth
};

// One pair per line, `X Y [identity | A.vts B.vts [B.sym.vts] | map FILE] [# comment]`; relative paths are
// relative to the file, so that a pairs file can travel with its data set.
std::vector<PairSpec> read_pairs_file(const std::string& path) {
  std::ifstream in = open_for_reading(path);
  const fs::path base = fs::absolute(path).parent_path();
  auto resolve = [&](const std::string& p) {
    const fs::path q(p);
    return (q.is_absolute() ? q : base / q).lexically_normal().string();
  };
  std::vector<PairSpec> pairs;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    std::istringstream words(line);
    std::vector<std::string> w{std::istream_iterator<std::string>(words), {}};
    // A comment runs from a word that starts with '#' to the end of the line.
    w.erase(std::find_if(w.begin(), w.end(), [](const std::string& word) { return word[0] == '#'; }), w.end());
    if (w.empty()) continue;
    const bool identity = w.size() == 2 || (w.size() == 3 && w[2] == "identity");
    const bool map = w.size() == 4 && w[2] == "map";
    const bool symmetric = w.size() == 5;
    if (!identity && w.size() != 4 && !symmetric)
      throw InvalidInputError(fmt::format("{}:{}: expected `X Y [identity | A.vts B.vts [B.sym.vts] | map FILE]`, found {} field{}",
                                          path, number, w.size(), w.size() == 1 ? "" : "s"));
    PairSpec p{resolve(w[0]), resolve(w[1]), {}};
    if (identity)
      p.truth = {"--gt", "identity"};
    else if (map)
      p.truth = {"--gt-map", resolve(w[3])};
    else
      p.truth = {"--gt-x", resolve(w[2]), "--gt-y", resolve(w[3])};
    if (symmetric) p.truth.insert(p.truth.end(), {"--gt-y-sym", resolve(w[4])});
    pairs.push_back(std::move(p));
  }
  if (pairs.empty()) throw InvalidInputError(path + ": no pairs (one `X Y [ground truth]` per line)");
  return pairs;
}

// The median over the rows that succeeded; a failed row's numbers are partial or missing.
double median_ok(const std::vector<MatchRow>& rows, double (*value)(const MatchRow&)) {
  std::vector<double> v;
  for (const MatchRow& r : rows)
    if (r.run.status == "ok" && std::isfinite(value(r))) v.push_back(value(r));
  if (v.empty()) return kNaN;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

const std::vector<std::string> kPairsHeader{"pair",        "faces_x", "faces_y", "seconds", "total_seconds",
                                            "peak_rss_mb", "energy",  "lower_bound", "gap", "max_level_gap",
                                            "rounds",      "mean_geodesic_error", "median_geodesic_error",
                                            "symmetric_mean_geodesic_error", "mirrored_error_share", "orientation_flips",
                                            "point_mean_geodesic_error", "point_orientation_flips",
                                            "resumed_after_level", "status"};

// The rows plus a last one of medians; `csv` chooses full precision over readable widths.
std::vector<std::vector<std::string>> pairs_cells(const std::vector<MatchRow>& rows, bool csv) {
  auto num = [&](double v, int digits, int decimals) { return csv ? csv_number(v, digits) : fixed(v, decimals); };
  auto general = [&](double v, int digits) { return csv_number(v, csv ? digits : 4); };
  std::vector<std::vector<std::string>> cells;
  for (const MatchRow& r : rows)
    cells.push_back({r.name, csv_int(r.faces_x), csv_int(r.faces_y), num(r.run.seconds, 6, 2),
                     num(r.total_seconds, 6, 2), num(r.run.peak_rss_mb, 5, 0), general(r.energy, 12), general(r.lower_bound, 12),
                     general(r.gap, 4), general(r.max_level_gap, 4), csv_int(r.rounds), num(r.mean_error, 6, 4),
                     num(r.median_error, 6, 4),
                     num(r.symmetric_mean_error, 6, 4), num(r.mirrored_share, 4, 2), csv_int(r.flips),
                     num(r.point_mean_error, 6, 4),
                     csv_int(r.point_flips), csv_int(r.resumed_after_level), r.run.status});
  const auto ok = std::count_if(rows.begin(), rows.end(), [](const MatchRow& r) { return r.run.status == "ok"; });
  cells.push_back({csv ? "median" : "**median**", "", "",
                   num(median_ok(rows, [](const MatchRow& r) { return r.run.seconds; }), 6, 2),
                   num(median_ok(rows, [](const MatchRow& r) { return r.total_seconds; }), 6, 2),
                   num(median_ok(rows, [](const MatchRow& r) { return r.run.peak_rss_mb; }), 5, 0), "", "",
                   general(median_ok(rows, [](const MatchRow& r) { return r.gap; }), 4),
                   general(median_ok(rows, [](const MatchRow& r) { return r.max_level_gap; }), 4), "",
                   num(median_ok(rows, [](const MatchRow& r) { return r.mean_error; }), 6, 4),
                   num(median_ok(rows, [](const MatchRow& r) { return r.median_error; }), 6, 4),
                   num(median_ok(rows, [](const MatchRow& r) { return r.symmetric_mean_error; }), 6, 4), "", "",
                   num(median_ok(rows, [](const MatchRow& r) { return r.point_mean_error; }), 6, 4), "", "",
                   fmt::format("{} of {} ok", ok, rows.size())});
  return cells;
}

std::string pairs_csv(const std::vector<MatchRow>& rows) {
  std::string text = csv_line(kPairsHeader);
  for (const auto& row : pairs_cells(rows, true)) text += csv_line(row);
  return text;
}

// The errors from `eval`'s JSON.
void read_errors(const std::string& json_path, MatchRow& row) {
  const JsonNode result = read_json_file(json_path);
  row.mean_error = result.number_or_nan("mean_geodesic_error");
  row.median_error = result.number_or_nan("median_geodesic_error");
  row.symmetric_mean_error = result.number_or_nan("symmetric_mean_geodesic_error");
  row.flips = result.number_or_nan("orientation_flips");
  row.mirrored_share = result.number_or_nan("mirrored_error_share");
  if (const JsonNode* points = result.get("point_map")) {
    row.point_mean_error = points->number_or_nan("mean_geodesic_error");
    row.point_flips = points->number_or_nan("orientation_flips");
  }
}

// Fills the errors from `eval`'s JSON; a failed evaluation keeps the match's numbers.
void evaluate(const BenchMatchArgs& args, const PairSpec& pair, const fs::path& dir, MatchRow& row) {
  std::vector<std::string> cmd{"eval", dir.string()};
  cmd.insert(cmd.end(), pair.truth.begin(), pair.truth.end());
  if (args.jobs > 1) cmd.insert(cmd.end(), {"--threads", std::to_string(threads_per_job(args))});
  const std::string json_path = dir.string() + ".eval.json";
  const ChildRun e = run_child(cmd, json_path, dir.string() + ".eval.log", args.time_limit);
  if (e.status != "ok") {
    row.run.status = "eval " + e.status;
    return;
  }
  try {
    read_errors(json_path, row);
  } catch (const Error& error) {
    row.run.status = std::string("eval failed: ") + error.what();
  }
}

// ---- resuming a list of pairs

Json strings_json(const std::vector<std::string>& words) {
  Json a = Json::array();
  for (const std::string& w : words) a.push(w);
  return a;
}

std::vector<std::string> strings_of(const JsonNode* node) {
  std::vector<std::string> words;
  if (!node || node->kind != JsonNode::Kind::Array) return words;
  for (const auto& [key, item] : node->members) {
    if (item.kind != JsonNode::Kind::String) return {};  // no command has an empty argument list
    words.push_back(item.text);
  }
  return words;
}

// Beside each pair's run: what was asked and how it ended, written once its row is final. Full
// resolution tables take hours per list on 2 cores; --resume picks such a list up where it stopped.
// How far a pair's checkpoint had got: the levels it holds, then the widenings of the level in
// progress (each started an attempt that a run gone on from it does not repeat), then the rounds
// of that attempt's rounding. Levels -1: none used.
struct CheckpointProgress {
  int levels = -1;
  int ahead = 0;  // inside a level of lookahead, the first chain has done it
  int widenings = 0, rounds = 0;
  auto operator<=>(const CheckpointProgress&) const = default;
};

// `checkpoint_before`: how far the pair's checkpoint had got when the run started.
void write_run_record(const fs::path& dir, const std::vector<std::string>& match, const PairSpec& pair,
                      double time_limit, const MatchRow& row, CheckpointProgress checkpoint_before = {}) {
  Json record = Json::object();
  record.set("match", strings_json(match));
  record.set("truth", strings_json(pair.truth));
  record.set("time_limit", time_limit);
  if (checkpoint_before.levels >= 0) {
    record.set("checkpoint_levels_before", checkpoint_before.levels);
    record.set("checkpoint_chain_ahead_before", checkpoint_before.ahead);
    record.set("checkpoint_widenings_before", checkpoint_before.widenings);
    record.set("checkpoint_rounds_before", checkpoint_before.rounds);
  }
  record.set("status", row.run.status);
  record.set("seconds", row.run.seconds);
  record.set("total_seconds", row.total_seconds);
  record.set("peak_rss_mb", row.run.peak_rss_mb);
  write_file_atomic(dir.string() + ".run.json", record.dump() + "\n");
}

// `--flag=value`: the flag and its value in one word.
bool flag_with_value(std::string_view word, std::string_view flag) {
  return word.size() > flag.size() && word.starts_with(flag) && word[flag.size()] == '=';
}

// What a recorded command asked for, apart from where it ran: less `--threads N` (the count
// changes no Γ: the CPU kernels split their work in fixed chunks), `--backend` and `--device`
// (their LPs differ only in rounding error), and with its files by name only (a list moved to
// another machine or folder, as the device queue's is, names the same meshes and ground truth).
std::vector<std::string> what_asked(std::vector<std::string> cmd) {
  static constexpr std::array<std::string_view, 3> kWhere{"--threads", "--backend", "--device"};
  for (size_t i = 0; i < cmd.size();) {
    const std::string_view word = cmd[i];
    const auto where = std::find_if(kWhere.begin(), kWhere.end(),
                                    [&](std::string_view flag) { return word == flag || flag_with_value(word, flag); });
    if (where == kWhere.end()) ++i;
    else if (word == *where && i + 1 < cmd.size()) cmd.erase(cmd.begin() + i, cmd.begin() + i + 2);
    else cmd.erase(cmd.begin() + i);
  }
  // `match X Y …`: the meshes; a truth list: every value (a flag's is a path, or `identity`).
  const bool is_match = !cmd.empty() && cmd[0] == "match";
  for (size_t i = 0; i < cmd.size(); ++i)
    if (is_match ? (i == 1 || i == 2) : !cmd[i].starts_with("--")) cmd[i] = fs::path(cmd[i]).filename().string();
  return cmd;
}

// `--backend` and `--device` as given (empty where not).
std::vector<std::string> where_run(const std::vector<std::string>& cmd) {
  std::vector<std::string> where;
  for (size_t i = 0; i < cmd.size(); ++i)
    for (std::string_view flag : {"--backend", "--device"})
      if (cmd[i] == flag && i + 1 < cmd.size()) where.insert(where.end(), {cmd[i], cmd[i + 1]});
      else if (flag_with_value(cmd[i], flag)) where.push_back(cmd[i]);
  return where;
}

// How far a pair's checkpoint (match --checkpoint) got; {0, 0} where there is none, or one that
// does not read back (the run then starts afresh and replaces it).
CheckpointProgress checkpoint_progress(const fs::path& checkpoint) {
  if (!fs::exists(checkpoint)) return {0, 0};
  try {
    const LevelCheckpoint c = load_checkpoint(checkpoint.string());
    const LevelAttempt& a = c.in_progress();
    return {c.done(), c.first_chain_ahead() ? 1 : 0, a.empty() ? 0 : a.widenings(), a.rounding.rounds};
  } catch (const Error& e) {
    spdlog::warn("{}; starting afresh", e.what());
    fs::remove(checkpoint);
    return {0, 0};
  }
}

// The row of an earlier run of the same command (and ground truth), if one finished; a run that
// timed out counts only under a time limit no longer than its own, and only where it left its
// checkpoint no further on than it found it (one that got further goes on from there: full
// resolution's coarse levels take a quarter to a half of a run). An evaluation that failed is
// run again (cheap). False: run the pair; `earlier` is then the seconds of the runs that made the
// checkpoint it goes on from, where it keeps one (NaN where not on record).
bool resume_row(const BenchMatchArgs& args, const PairSpec& pair, const std::vector<std::string>& match,
                const fs::path& dir, MatchRow& row, double& earlier) {
  const std::string path = dir.string() + ".run.json";
  const fs::path checkpoint = dir.string() + ".ckpt";
  earlier = 0.0;
  if (!fs::exists(path)) {
    fs::remove(checkpoint);  // (whatever made it is not on record)
    return false;
  }
  try {
    const JsonNode record = read_json_file(path);
    const std::vector<std::string> recorded_match = strings_of(record.get("match"));
    if (what_asked(recorded_match) != what_asked(match) ||
        what_asked(strings_of(record.get("truth"))) != what_asked(pair.truth)) {
      // Its checkpoint is of those options: set aside, not deleted (a flag spelt otherwise, say
      // `--wks on` for the default, would otherwise cost the hours its levels took).
      std::string aside;
      if (fs::exists(checkpoint)) {
        aside = checkpoint.string() + ".other-options";
        fs::rename(checkpoint, aside);
      }
      spdlog::info("{}: the recorded run had other options; running it again{}", row.name,
                   aside.empty() ? "" : " (its checkpoint kept as " + aside + ")");
      return false;
    }
    // (A record from before total_seconds: its own seconds, checkpoints it went on from unknown.)
    const double recorded_total = record.get("total_seconds") ? record.number_or_nan("total_seconds")
                                                              : record.number_or_nan("seconds");
    const JsonNode* status = record.get("status");
    if (!status || status->kind != JsonNode::Kind::String) return false;
    if (status->text == "started") {  // the harness was stopped during the run: its seconds unknown
      earlier = kNaN;
      return false;
    }
    earlier = recorded_total;
    // Stopped by SIGINT or SIGTERM (a Ctrl-C, a batch system): its checkpoint was saved as it went.
    if (status->text == "interrupted") {
      spdlog::info("{}: interrupted; running it again{}", row.name, fs::exists(checkpoint) ? ", from its checkpoint" : "");
      return false;
    }
    // Another backend or device: its row is not this one's, but the levels it checkpointed are
    // (a run that ran out of a GPU's time goes on from them on the CPU, or on another GPU).
    if (const std::vector<std::string> was = where_run(recorded_match); was != where_run(match)) {
      std::string elsewhere;
      for (const std::string& word : was) elsewhere += (elsewhere.empty() ? "" : " ") + word;
      spdlog::info("{}: the recorded run ran elsewhere ({}); running it again{}", row.name,
                   elsewhere.empty() ? "the default backend" : elsewhere,
                   fs::exists(checkpoint) ? ", from its checkpoint" : "");
      return false;
    }
    if (status->text == "timed out") {
      if (!(record.number_or_nan("time_limit") >= args.time_limit)) return false;
      auto recorded = [&](const char* key) {
        const double v = record.number_or_nan(key);
        return v >= 0 ? static_cast<int>(v) : 0;
      };
      const CheckpointProgress before{recorded("checkpoint_levels_before"), recorded("checkpoint_chain_ahead_before"),
                                      recorded("checkpoint_widenings_before"), recorded("checkpoint_rounds_before")};
      if (const CheckpointProgress now = checkpoint_progress(checkpoint); now > before) {
        spdlog::info("{}: timed out after its checkpoint went from {} levels (and {} widenings of the next, {} rounds "
                     "of its rounding) to {} (and {}, {}){}; going on from it",
                     row.name, before.levels, before.widenings, before.rounds, now.levels, now.widenings, now.rounds,
                     now.ahead > before.ahead && now.levels == before.levels
                         ? ", the first lookahead chain having done the next"
                         : "");
        return false;
      }
    }
    row.run.status = status->text;
    row.run.seconds = record.number_or_nan("seconds");
    row.total_seconds = recorded_total;
    row.run.peak_rss_mb = record.number_or_nan("peak_rss_mb");
    const bool matched = row.run.status == "ok" || row.run.status.rfind("eval ", 0) == 0;
    if (!matched) return true;
    read_report(dir, row);
    if (row.run.status == "ok") {
      read_errors(dir.string() + ".eval.json", row);
    } else {
      row.run.status = "ok";
      evaluate(args, pair, dir, row);
      write_run_record(dir, match, pair, args.time_limit, row);
    }
    return true;
  } catch (const Error& e) {  // a record or output that does not read back: measure again
    spdlog::warn("{}: cannot resume ({}); running it again", row.name, e.what());
    row = MatchRow{.name = row.name};
    return false;
  }
}

int run_bench_pairs(const BenchMatchArgs& asked) {
  if (asked.faces.size() > 1)
    throw InvalidInputError("--faces: one size with --pairs (a list of sizes is for the scaling mode, --pair)");
  // Read before any run, so that a malformed file costs nothing.
  const std::vector<PairSpec> pairs = read_pairs_file(asked.pairs_file);
  // No more runs at once than pairs, so that each gets its share of the CPUs.
  BenchMatchArgs args = asked;
  args.jobs = static_cast<int>(std::clamp<size_t>(pairs.size(), 1, std::max(1, asked.jobs)));
  const std::string faces = args.faces.empty() ? std::string() : std::to_string(faces_value(args.faces[0]));
  const fs::path out(args.out);
  make_output_folder(out, "runs");
  const std::string csv_path = (out / "bench_pairs.csv").string(), md_path = (out / "bench_pairs.md").string();
  // Names and directories first, in the file's order, so that they do not depend on which run
  // ends first.
  std::vector<MatchRow> rows(pairs.size());
  std::vector<fs::path> dirs(pairs.size());
  std::map<std::string, int> times_seen;
  std::set<std::string> taken;
  for (size_t i = 0; i < pairs.size(); ++i) {
    MatchRow& row = rows[i];
    row.name = fs::path(pairs[i].x).stem().string() + "-" + fs::path(pairs[i].y).stem().string();
    // Named after the pair, so that --resume finds a run again in a list that grew or was
    // reordered; a pair that comes again (e.g. with other ground truth) is counted: X-Y.2, X-Y.3
    // (past any name taken already, e.g. by a pair whose own stem ends in .2).
    const int seen = ++times_seen[row.name];
    std::string name = seen == 1 ? row.name : fmt::format("{}.{}", row.name, seen);
    while (taken.count(name)) name = fmt::format("{}.{}", row.name, ++times_seen[row.name]);
    taken.insert(name);
    dirs[i] = out / "runs" / name;
    row.name = name;  // (the tables' rows named as their runs: X-Y.2 too)
  }
  // The tables list the rows finished so far, in the file's order, rewritten as each one ends.
  std::vector<char> finished(pairs.size(), 0);
  std::mutex table_mutex;
  auto finish = [&](size_t i) {
    const std::lock_guard lock(table_mutex);
    log_row(rows[i]);
    finished[i] = 1;
    std::vector<MatchRow> so_far;
    for (size_t k = 0; k < rows.size(); ++k)
      if (finished[k]) so_far.push_back(rows[k]);
    write_file_atomic(csv_path, pairs_csv(so_far));
    write_file_atomic(md_path, markdown_table(kPairsHeader, pairs_cells(so_far, false)));
  };
  auto run_pair = [&](size_t i) {
    const PairSpec& pair = pairs[i];
    MatchRow& row = rows[i];
    const std::vector<std::string> match = match_command(args, pair.x, pair.y, faces);
    double earlier = 0.0;
    if (args.resume && resume_row(args, pair, match, dirs[i], row, earlier)) {
      spdlog::info("pair {} of {}: {} (resumed from {}.run.json)", i + 1, pairs.size(), row.name, dirs[i].string());
    } else {
      spdlog::info("pair {} of {}: {}", i + 1, pairs.size(), row.name);
      // Ground truth that is not there fails the row before its match (a missing mesh fails the
      // match at once; a missing .vts would be found only by eval, after the whole match).
      for (size_t k = 1; k < pair.truth.size(); ++k)
        if (pair.truth[k - 1].rfind("--gt-", 0) == 0 && !fs::is_regular_file(pair.truth[k])) {
          row.run.status = "failed: " + pair.truth[k] + ": ground truth not found";
          spdlog::warn("{}: {}", row.name, row.run.status);
          finish(i);
          return;
        }
      // With --resume, a checkpoint, so that a run stopped in a fine level loses only that level.
      const fs::path checkpoint = args.resume ? fs::path(dirs[i].string() + ".ckpt") : fs::path();
      // A run killed while saving its checkpoint leaves the temporary file (files.hpp, one per
      // process id): nothing reads it, so it goes before the next run.
      if (std::error_code ec; fs::is_directory(dirs[i].parent_path(), ec))
        for (const auto& entry : fs::directory_iterator(dirs[i].parent_path(), ec))
          if (entry.path().filename().string().rfind(dirs[i].filename().string() + ".ckpt.tmp-", 0) == 0)
            fs::remove(entry.path(), ec);
      CheckpointProgress before = args.resume ? checkpoint_progress(checkpoint) : CheckpointProgress{};
      auto attempt = [&] {
        run_match_child(args, pair.x, pair.y, faces, dirs[i], row, checkpoint, [&] {
          if (!args.resume) return;
          MatchRow started = row;
          started.run.status = "started";
          write_run_record(dirs[i], match, pair, args.time_limit, started, before);
        });
      };
      attempt();
      // The checkpoint's fault, maybe (another build): once more afresh. Not for other failures
      // (an LP refused for the memory available would fail at the same level again, and the
      // checkpoint holds the levels before it).
      if (before.levels > 0 && row.run.status.rfind("failed", 0) == 0 &&
          row.run.status.find("checkpoint") != std::string::npos) {
        spdlog::warn("{}: failed going on from its checkpoint ({}); once more afresh", row.name, row.run.status);
        fs::remove(checkpoint);
        before = {0, 0};
        row = MatchRow{.name = row.name};
        attempt();
      }
      row.total_seconds = row.run.seconds + (before.levels > 0 ? earlier : 0.0);
      if (row.run.status == "ok") evaluate(args, pair, dirs[i], row);
      write_run_record(dirs[i], match, pair, args.time_limit, row, before);
      // (A finished run needs no checkpoint; removed after its record.)
      if (args.resume && row.run.status == "ok") fs::remove(checkpoint);
    }
    finish(i);
  };
  const int jobs = args.jobs;
  if (jobs == 1) {
    for (size_t i = 0; i < pairs.size(); ++i) run_pair(i);
  } else {
    spdlog::info("{} runs at once, {} threads each", jobs, threads_per_job(args));
    std::atomic<size_t> next{0};
    std::exception_ptr failure;
    std::mutex failure_mutex;
    std::vector<std::thread> workers;
    for (int w = 0; w < jobs; ++w)
      workers.emplace_back([&] {
        for (size_t i; (i = next.fetch_add(1)) < pairs.size();) {
          try {
            run_pair(i);
          } catch (...) {  // a run's own failure is a row; this is the harness's (a full disk…)
            const std::lock_guard lock(failure_mutex);
            if (!failure) failure = std::current_exception();
            next = pairs.size();
          }
        }
      });
    for (auto& w : workers) w.join();
    if (failure) std::rethrow_exception(failure);
  }
  std::cout << markdown_table(kPairsHeader, pairs_cells(rows, false)) << std::flush;
  spdlog::info("wrote {} and {}", csv_path, md_path);
  return 0;
}

}  // namespace

Action add_bench_command(CLI::App& app) {
  app.require_subcommand(1);
  CLI::App* lp = app.add_subcommand("lp", "time every LP solver on the matching LP at growing sizes (CSV + plot)");
  auto args = std::make_shared<BenchLpArgs>();
  lp->add_option("--pair", args->pair, "the two meshes X Y; default: the bundled finger pair")->expected(2);
  lp->add_option("--faces", args->faces, "faces per shape of each size (decimated)")
      ->delimiter(',')
      ->check(positive_number())
      ->capture_default_str();
  lp->add_option("--solvers", args->solvers, "solvers to run")
      ->delimiter(',')
      ->check(CLI::IsMember(solver_names()))
      ->capture_default_str();
  lp->add_option("--tol", args->tolerance, "relative tolerance of the first-order solvers")
      ->check(positive_number())
      ->capture_default_str();
  lp->add_option("--clp-time-limit", args->clp_time_limit, "seconds per Clp solve; a solver that hits it is skipped at larger sizes")
      ->check(positive_number())
      ->capture_default_str();
  lp->add_option("--pdhg-time-limit", args->pdhg_time_limit, "seconds per PDHG solve (default none)")
      ->check(positive_number());
  lp->add_option("--out", args->out, "directory for bench_lp.csv and bench_lp.png")->capture_default_str();
  lp->add_option("--repeat", args->repeat, "runs per solver and size; the fastest is reported")
      ->check(positive_number())
      ->capture_default_str();
  lp->add_flag("--bandwidth", args->bandwidth, "also measure the streaming bandwidth and report time per iteration against it");

  CLI::App* bandwidth = app.add_subcommand("bandwidth", "measure streaming memory bandwidth (STREAM triad, all threads)");
  auto bw = std::make_shared<BandwidthOptions>();
  bandwidth->add_option("--threads", bw->threads, "threads (0 = all)")->check(non_negative_number())->capture_default_str();
  bandwidth->add_option("--repeats", bw->repeats, "best of this many runs")->check(positive_number())->capture_default_str();

  CLI::App* match = app.add_subcommand(
      "match", "time whole match runs at growing sizes, or match and evaluate a list of pairs (CSV, Markdown, plot)");
  auto m = std::make_shared<BenchMatchArgs>();
  auto* pair = match->add_option("--pair", m->pair, "scaling: the two meshes X Y; default: bundled asset pair")->expected(2);
  match->add_option("--pairs", m->pairs_file, "pairs mode: a file of lines `X Y [identity | A.vts B.vts [B.sym.vts] | map FILE]`")
      ->excludes(pair);
  const CLI::Validator size(
      [](std::string& s) -> std::string {
        if (s == "full") return {};
        char* end = nullptr;
        const long n = std::strtol(s.c_str(), &end, 10);
        return !s.empty() && *end == '\0' && n > 0 && n <= INT_MAX ? "" : "'" + s + "' is neither a face count nor `full`";
      },
      "INT|full");
  match->add_option("--faces", m->faces,
                    "faces per shape; scaling: one run per entry (default 500,1000,2000,4000,full); pairs: one size "
                    "(default: match's)")
      ->delimiter(',')
      ->allow_extra_args(false)  // one comma-separated word, so that `--faces full -- ARGS` ends at `--`
      ->check(size);
  match->add_option("--out", m->out, "directory for the tables, the plot and runs/")->capture_default_str();
  match->add_option("--time-limit", m->time_limit, "seconds per child run (match, eval); then it is killed")
      ->check(positive_number())
      ->capture_default_str();
  match->add_flag("--resume", m->resume,
                  "pairs: reuse each pair's row where this --out already holds a finished run of the same command and "
                  "ground truth (runs/X-Y.run.json); runs keep a checkpoint (runs/X-Y.ckpt), and one that timed "
                  "out is tried again, from its checkpoint, under a longer --time-limit or where its checkpoint "
                  "got further (or was made on another --backend or --device)")
      ->needs(match->get_option("--pairs"));
  match->add_option("--jobs", m->jobs,
                    "pairs: runs at once (a GPU machine with many cores); each match and eval gets its share of "
                    "the CPUs as --threads")
      ->check(positive_number())
      ->needs(match->get_option("--pairs"))
      ->capture_default_str();
  match->add_option("match-args", m->match_args, "after `--`: options for every match run, verbatim");

  return [lp, args, match, m, bw] {
    if (lp->parsed()) return run_bench_lp(*args);
    if (match->parsed()) {
      check_match_args(m->match_args);
      return m->pairs_file.empty() ? run_bench_scaling(*m) : run_bench_pairs(*m);
    }
    if (bw->threads > bandwidth_threads(*bw))
      spdlog::warn("bench bandwidth: --threads {} is more than the {} CPUs this process may use: {} threads",
                   bw->threads, worker_threads(), bandwidth_threads(*bw));
    const double gbps = measure_bandwidth_gbps(*bw);
    Json out = Json::object();
    out.set("threads", bandwidth_threads(*bw));
    out.set("array_mib", double(bw->elements) * 8.0 / (1 << 20));
    out.set("gbps", gbps);
    std::cout << out.dump() << std::endl;
    return 0;
  };
}

}  // namespace shapematch::app
