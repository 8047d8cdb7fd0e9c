#include "shapematch/evaluation.hpp"

#include "shapematch/errors.hpp"
#include "shapematch/files.hpp"
#include "shapematch/geodesic.hpp"
#include "shapematch/geometry.hpp"
#include "shapematch/system.hpp"

#include <algorithm>
#include <atomic>
#include <charconv>
#include <cmath>
#include <exception>
#include <fstream>
#include <limits>
#include <mutex>
#include <sstream>
#include <thread>

namespace shapematch {
namespace {

// The lines of a text file without their line ends; trailing blank lines dropped.
std::vector<std::string> read_lines(const std::string& path) {
  std::ifstream in = open_for_reading(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    lines.push_back(std::move(line));
  }
  if (in.bad()) throw IoError(path + ": read error");
  while (!lines.empty() && lines.back().find_first_not_of(" \t") == std::string::npos) lines.pop_back();
  if (lines.empty()) throw InvalidInputError(path + ": no vertex indices (empty file)");
  return lines;
}

std::vector<std::string> split(const std::string& line) {
  std::istringstream s(line);
  std::vector<std::string> tokens;
  for (std::string t; s >> t;) tokens.push_back(t);
  return tokens;
}

std::string where(const std::string& path, size_t line) { return path + ": line " + std::to_string(line + 1) + ": "; }

// A vertex index as written (base 0 or 1) → 0-based, checked against the mesh size.
int parse_vertex(const std::string& token, int base, int num_vertices, const std::string& path, size_t line) {
  long long value = 0;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (ec != std::errc() || end != token.data() + token.size())
    throw InvalidInputError(where(path, line) + "'" + token + "' is not a vertex index");
  if (value < base || value - base >= num_vertices)
    throw InvalidInputError(where(path, line) + "vertex " + token + " is not in " + std::to_string(base) + ".." +
                            std::to_string(num_vertices - 1 + base) + " (the mesh has " +
                            std::to_string(num_vertices) + " vertices)");
  return static_cast<int>(value - base);
}

// Rows of `columns` indices each. In a list (.vts) a blank line inside the file would shift the
// "line k ↔ line k" pairing, so it is an error rather than skipped; a file of pairs holds each
// pair on its line, and skips blank lines and `#` comments (a header written by hand, a note
// after a pair).
std::vector<std::vector<int>> read_rows(const std::string& path, int columns, int base,
                                        const std::vector<int>& num_vertices, bool pairs = false) {
  const std::vector<std::string> lines = read_lines(path);
  std::vector<std::vector<int>> rows;
  rows.reserve(lines.size());
  for (size_t i = 0; i < lines.size(); ++i) {
    // (In a file of pairs, `#` starts a comment, on its own line or after a pair.)
    const std::string line = pairs ? lines[i].substr(0, lines[i].find('#')) : lines[i];
    if (pairs && line.find_first_not_of(" \t") == std::string::npos) continue;
    const std::vector<std::string> tokens = split(line);
    if (static_cast<int>(tokens.size()) != columns)
      throw InvalidInputError(where(path, i) + "expected " + std::to_string(columns) + " vertex ind" +
                              (columns == 1 ? "ex" : "ices") + ", got " + std::to_string(tokens.size()));
    std::vector<int> row;
    for (int c = 0; c < columns; ++c) row.push_back(parse_vertex(tokens[c], base, num_vertices[c], path, i));
    rows.push_back(std::move(row));
  }
  return rows;
}

}  // namespace

std::vector<int> truth_at(const Mesh& x_file, const Mesh& y_file, const std::vector<int>& x_ids,
                          const std::vector<int>& y_ids, const GroundTruth& truth) {
  if (truth.empty()) throw InvalidInputError("true map: the ground truth has no pairs");
  // The nearest of `candidates` (vertices of `mesh`) to p: a plain scan, run once per vertex.
  auto nearest = [](const Mesh& mesh, const auto& candidates, auto vertex_of, const Eigen::Vector3d& p) {
    double best = std::numeric_limits<double>::infinity();
    size_t arg = 0;
    for (size_t k = 0; k < candidates.size(); ++k)
      if (const double d = (mesh.vertices[vertex_of(candidates[k])] - p).squaredNorm(); d < best) {
        best = d;
        arg = k;
      }
    return arg;
  };
  for (const GroundTruthPair& g : truth)
    if (g.x < 0 || g.x >= x_file.num_vertices() || g.y < 0 || g.y >= y_file.num_vertices())
      throw InvalidInputError("true map: a ground-truth pair names a vertex the meshes lack");
  for (int id : y_ids)
    if (id < 0 || id >= y_file.num_vertices()) throw InvalidInputError("true map: a vertex id Y lacks");
  // Exact where they can be: a vertex with a pair of its own, an image that was kept.
  std::vector<int> pair_of(x_file.num_vertices(), -1), kept_as(y_file.num_vertices(), -1);
  for (size_t k = 0; k < truth.size(); ++k)
    if (pair_of[truth[k].x] < 0) pair_of[truth[k].x] = static_cast<int>(k);
  for (size_t w = 0; w < y_ids.size(); ++w) kept_as[y_ids[w]] = static_cast<int>(w);
  std::vector<int> image(x_ids.size(), -1);
  for (size_t v = 0; v < x_ids.size(); ++v) {
    if (x_ids[v] < 0 || x_ids[v] >= x_file.num_vertices()) throw InvalidInputError("true map: a vertex id X lacks");
    const int k = pair_of[x_ids[v]];
    const GroundTruthPair& g =
        k >= 0 ? truth[k]
               : truth[nearest(x_file, truth, [](const GroundTruthPair& t) { return t.x; }, x_file.vertices[x_ids[v]])];
    image[v] = kept_as[g.y] >= 0
                   ? kept_as[g.y]
                   : static_cast<int>(nearest(y_file, y_ids, [](int id) { return id; }, y_file.vertices[g.y]));
  }
  return image;
}

std::vector<int> read_vertex_list(const std::string& path, bool one_based, int num_vertices) {
  std::vector<int> list;
  for (const auto& row : read_rows(path, 1, one_based ? 1 : 0, {num_vertices})) list.push_back(row[0]);
  return list;
}

GroundTruth identity_ground_truth(int x_vertices, int y_vertices) {
  if (x_vertices != y_vertices)
    throw InvalidInputError("identity ground truth: X has " + std::to_string(x_vertices) + " vertices and Y has " +
                            std::to_string(y_vertices) + "; vertex i <-> vertex i needs equal counts");
  GroundTruth gt(x_vertices);
  for (int i = 0; i < x_vertices; ++i) gt[i] = {i, i};
  return gt;
}

GroundTruth read_vts_ground_truth(const std::string& x_path, const std::string& y_path, int x_vertices,
                                  int y_vertices) {
  const std::vector<int> xs = read_vertex_list(x_path, true, x_vertices);
  const std::vector<int> ys = read_vertex_list(y_path, true, y_vertices);
  if (xs.size() != ys.size())
    throw InvalidInputError(y_path + ": " + std::to_string(ys.size()) + " lines, but " + x_path + " has " +
                            std::to_string(xs.size()) + " (line k of one corresponds to line k of the other)");
  GroundTruth gt(xs.size());
  for (size_t k = 0; k < xs.size(); ++k) gt[k] = {xs[k], ys[k]};
  return gt;
}

GroundTruth read_vertex_pairs(const std::string& path, bool one_based, int x_vertices, int y_vertices) {
  GroundTruth gt;
  for (const auto& row : read_rows(path, 2, one_based ? 1 : 0, {x_vertices, y_vertices}, true))
    gt.push_back({row[0], row[1]});
  if (gt.empty()) throw InvalidInputError(path + ": no vertex pairs (only comments)");
  return gt;
}

GroundTruth read_map_ground_truth(const std::string& path, int x_vertices, int y_vertices) {
  return read_vertex_pairs(path, true, x_vertices, y_vertices);
}

std::vector<std::array<double, 2>> pck_curve(const std::vector<double>& errors, double max, double step) {
  if (!(step > 0) || !(max >= 0) || !std::isfinite(max))
    throw InvalidInputError("PCK: need a positive step and a finite, non-negative maximum threshold");
  std::vector<double> sorted = errors;
  std::sort(sorted.begin(), sorted.end());
  const int steps = static_cast<int>(std::floor(max / step + 1e-9));
  std::vector<std::array<double, 2>> pck;
  for (int i = 0; i <= steps; ++i) {
    // i·step rather than a running sum, so that thresholds print as 0.07, not 0.06999…
    const double t = i * step;
    const auto below = std::upper_bound(sorted.begin(), sorted.end(), t) - sorted.begin();
    pck.push_back({t, sorted.empty() ? 0.0 : static_cast<double>(below) / static_cast<double>(sorted.size())});
  }
  return pck;
}

double pck_auc(const std::vector<std::array<double, 2>>& pck) {
  if (pck.empty()) return 0;
  const double width = pck.back()[0] - pck.front()[0];
  if (!(width > 0)) return pck.front()[1];
  double area = 0;
  for (size_t i = 1; i < pck.size(); ++i) area += (pck[i][0] - pck[i - 1][0]) * (pck[i][1] + pck[i - 1][1]) / 2;
  return area / width;
}

std::vector<double> pair_errors(size_t pairs, const GeodesicErrors& errors) {
  if (errors.pair.size() != errors.errors.size()) throw InvalidInputError("pair_errors: errors without their pairs");
  std::vector<double> out(pairs, std::numeric_limits<double>::quiet_NaN());
  for (size_t k = 0; k < errors.errors.size(); ++k) {
    if (errors.pair[k] >= pairs) throw InvalidInputError("pair_errors: a pair past the ground truth");
    out[errors.pair[k]] = errors.errors[k];
  }
  return out;
}

std::vector<double> vertex_mean_errors(int vertices, const GroundTruth& truth, const std::vector<double>& errors) {
  if (errors.size() != truth.size()) throw InvalidInputError("vertex errors: one error per ground-truth pair expected");
  std::vector<double> sum(vertices, 0.0);
  std::vector<int> count(vertices, 0);
  for (size_t k = 0; k < truth.size(); ++k) {
    if (std::isnan(errors[k])) continue;
    const int v = truth[k].x;
    if (v < 0 || v >= vertices) throw InvalidInputError("vertex errors: a ground-truth vertex X lacks");
    sum[v] += errors[k];
    ++count[v];
  }
  for (int v = 0; v < vertices; ++v) sum[v] = count[v] > 0 ? sum[v] / count[v] : std::numeric_limits<double>::quiet_NaN();
  return sum;
}

std::vector<ErrorRegion> error_regions(const Mesh& x, const GroundTruth& truth, const std::vector<double>& errors,
                                       const std::vector<double>& symmetric, double threshold) {
  if (errors.size() != truth.size()) throw InvalidInputError("error_regions: one error per ground-truth pair expected");
  if (!symmetric.empty()) {
    if (symmetric.size() != errors.size()) throw InvalidInputError("error_regions: one symmetric error per pair expected");
    for (size_t k = 0; k < errors.size(); ++k)
      if (std::isnan(errors[k]) != std::isnan(symmetric[k]))
        throw InvalidInputError("error_regions: the symmetric errors leave out other pairs than the direct ones");
  }
  const int n = x.num_vertices();
  // Each vertex's pairs: their errors summed (direct and symmetric) and counted.
  std::vector<double> err_sum(n, 0.0), sym_sum(n, 0.0);
  std::vector<int> points(n, 0);
  double total = 0;
  for (size_t k = 0; k < truth.size(); ++k) {
    if (std::isnan(errors[k])) continue;
    const int v = truth[k].x;
    if (v < 0 || v >= n) throw InvalidInputError("error_regions: a ground-truth vertex X lacks");
    err_sum[v] += errors[k];
    if (!symmetric.empty()) sym_sum[v] += symmetric[k];
    ++points[v];
    total += errors[k];
  }
  std::vector<std::vector<int>> neighbours(n);
  for (const auto& f : x.faces)
    for (int i = 0; i < 3; ++i) {
      neighbours[f[i]].push_back(f[(i + 1) % 3]);
      neighbours[f[(i + 1) % 3]].push_back(f[i]);
    }
  // Above the threshold or not, for every vertex: a vertex's own verdict (its pairs' mean), else
  // the nearest rated vertex's (breadth first from all rated vertices at once, in vertex order).
  std::vector<int> above(n, -1);
  std::vector<int> queue;
  for (int v = 0; v < n; ++v)
    if (points[v] > 0) above[v] = err_sum[v] / points[v] > threshold, queue.push_back(v);
  for (size_t head = 0; head < queue.size(); ++head)
    for (int w : neighbours[queue[head]])
      if (above[w] < 0) above[w] = above[queue[head]], queue.push_back(w);
  std::vector<char> seen(n, 0);
  std::vector<ErrorRegion> regions;
  for (int s = 0; s < n; ++s) {
    if (above[s] != 1 || seen[s]) continue;
    ErrorRegion r;
    double err = 0, sym = 0;
    std::vector<int> stack{s};
    seen[s] = 1;
    while (!stack.empty()) {
      const int v = stack.back();
      stack.pop_back();
      if (points[v] > 0) {
        r.x_vertices.push_back(v);
        r.points += points[v];
        err += err_sum[v];
        sym += sym_sum[v];
      }
      for (int w : neighbours[v])
        if (!seen[w] && above[w] == 1) seen[w] = 1, stack.push_back(w);
    }
    std::sort(r.x_vertices.begin(), r.x_vertices.end());
    r.vertices = static_cast<int>(r.x_vertices.size());
    r.error_share = total > 0 ? err / total : 0;
    r.mean_error = err / r.points;
    if (!symmetric.empty()) {
      r.mean_symmetric_error = sym / r.points;
      r.mirrored = r.mean_symmetric_error < r.mean_error / 2;
    }
    regions.push_back(std::move(r));
  }
  std::stable_sort(regions.begin(), regions.end(),
                   [](const ErrorRegion& a, const ErrorRegion& b) { return a.error_share > b.error_share; });
  return regions;
}

double mirrored_error_share(const std::vector<double>& errors, const std::vector<double>& symmetric, double threshold) {
  if (symmetric.size() != errors.size()) throw InvalidInputError("mirrored_error_share: one symmetric error per pair expected");
  double total = 0, mirrored = 0;
  for (size_t k = 0; k < errors.size(); ++k) {
    if (std::isnan(errors[k])) continue;
    total += errors[k];
    if (errors[k] > threshold && symmetric[k] < errors[k] / 2) mirrored += errors[k];
  }
  return total > 0 ? mirrored / total : 0.0;
}

GeodesicErrors geodesic_errors(const Mesh& y, const std::vector<int>& phi, const GroundTruth& truth,
                               const EvaluationOptions& options) {
  std::vector<MappedPoint> points(phi.size());
  for (size_t v = 0; v < phi.size(); ++v) points[v] = {{phi[v], phi[v], phi[v]}, {1.0, 0.0, 0.0}};
  return geodesic_errors(y, points, truth, options);
}

GeodesicErrors geodesic_errors(const Mesh& y, const std::vector<MappedPoint>& phi, const GroundTruth& truth,
                               const EvaluationOptions& options) {
  const int ny = y.num_vertices();
  GeodesicErrors r;
  // A pair whose prediction misses the truth: distances from `source` to up to three targets,
  // weighted.
  struct Pending {
    int source;
    std::array<int, 3> targets;
    std::array<double, 3> weights;
    int n;
    size_t point;
  };
  std::vector<Pending> pending;
  std::vector<char> is_pred(ny, 0), is_true(ny, 0);
  int distinct_pred = 0, distinct_true = 0;
  bool all_vertices = true;
  for (const GroundTruthPair& p : truth) {
    if (p.x < 0 || p.x >= static_cast<int>(phi.size()) || p.y < 0 || p.y >= ny)
      throw InvalidInputError("evaluation: ground-truth pair (" + std::to_string(p.x) + ", " + std::to_string(p.y) +
                              ") is outside the map (" + std::to_string(phi.size()) + " X vertices) or Y (" +
                              std::to_string(ny) + " vertices)");
    const MappedPoint& m = phi[p.x];
    if (m.corners[0] < 0) continue;
    Pending q{p.y, {}, {}, 0, r.errors.size()};
    for (int i = 0; i < 3; ++i) {
      if (m.bary[i] <= 0) continue;
      if (m.corners[i] < 0 || m.corners[i] >= ny)
        throw InvalidInputError("evaluation: the map sends X vertex " + std::to_string(p.x) + " to vertex " +
                                std::to_string(m.corners[i]) + ", but Y has " + std::to_string(ny) + " vertices");
      q.targets[q.n] = m.corners[i];
      q.weights[q.n++] = m.bary[i];
    }
    if (q.n == 0) throw InvalidInputError("evaluation: X vertex " + std::to_string(p.x) + " maps to a point without weights");
    r.errors.push_back(0.0);
    r.pair.push_back(static_cast<size_t>(&p - truth.data()));
    if (q.n == 1 && q.targets[0] == p.y) continue;  // exactly zero: no solve needed
    all_vertices = all_vertices && q.n == 1;
    for (int i = 0; i < q.n; ++i)
      if (!is_pred[q.targets[i]]) is_pred[q.targets[i]] = 1, ++distinct_pred;
    if (!is_true[p.y]) is_true[p.y] = 1, ++distinct_true;
    pending.push_back(q);
  }
  r.points = static_cast<int>(r.errors.size());
  if (r.points == 0)
    throw InvalidInputError("evaluation: none of the " + std::to_string(truth.size()) +
                            " ground-truth pairs has an X vertex with an image under the map");

  if (!pending.empty()) {
    // A vertex map may march from whichever side has fewer distinct vertices (distances are
    // nearly symmetric); points march from the truth.
    if (all_vertices && distinct_pred < distinct_true)
      for (Pending& p : pending) std::swap(p.source, p.targets[0]);
    std::sort(pending.begin(), pending.end(), [](const Pending& a, const Pending& b) { return a.source < b.source; });
    std::vector<size_t> group_begin;
    for (size_t i = 0; i < pending.size(); ++i)
      if (i == 0 || pending[i].source != pending[i - 1].source) group_begin.push_back(i);
    group_begin.push_back(pending.size());
    const size_t groups = group_begin.size() - 1;
    r.geodesic_solves = static_cast<int>(groups);

    const GeodesicDistance geodesic(y);
    const double scale = 1.0 / std::sqrt(surface_area(y));
    std::atomic<size_t> next{0};
    std::exception_ptr failure;  // the first exception of any worker, rethrown on this thread
    std::mutex failure_mutex;
    auto work = [&] {
      try {
        std::vector<int> targets;
        for (size_t g; (g = next++) < groups;) {
          targets.clear();
          for (size_t i = group_begin[g]; i < group_begin[g + 1]; ++i)
            targets.insert(targets.end(), pending[i].targets.begin(), pending[i].targets.begin() + pending[i].n);
          const std::vector<double> d = geodesic.to_vertices(pending[group_begin[g]].source, targets);
          size_t k = 0;
          for (size_t i = group_begin[g]; i < group_begin[g + 1]; ++i) {
            double e = 0;
            for (int t = 0; t < pending[i].n; ++t) e += pending[i].weights[t] * d[k++];
            r.errors[pending[i].point] = e * scale;
          }
        }
      } catch (...) {
        next = groups;
        const std::lock_guard lock(failure_mutex);
        if (!failure) failure = std::current_exception();
      }
    };
    int threads = options.threads > 0 ? options.threads : worker_threads();
    threads = static_cast<int>(std::clamp<size_t>(threads, 1, groups));
    std::vector<std::thread> pool;
    for (int t = 1; t < threads; ++t) pool.emplace_back(work);
    work();
    for (auto& t : pool) t.join();
    if (failure) std::rethrow_exception(failure);
  }

  double sum = 0;
  for (double e : r.errors) sum += e;
  r.mean = sum / r.points;
  std::vector<double> sorted = r.errors;
  const size_t half = sorted.size() / 2;
  std::nth_element(sorted.begin(), sorted.begin() + half, sorted.end());
  r.median = sorted[half];
  if (sorted.size() % 2 == 0) r.median = (r.median + *std::max_element(sorted.begin(), sorted.begin() + half)) / 2;
  r.pck = pck_curve(r.errors, options.pck_max, options.pck_step);
  r.auc = pck_auc(r.pck);
  return r;
}

namespace {

// Each face of X carried through `map` (vertex indices or points of Y); collinear images count
// with the collapsed ones: they have no orientation to compare.
template <class Map>
OrientationFlips count_images(const Mesh& x, const Mesh& y, const Map& map) {
  const Geometry gy = compute_geometry(y);
  OrientationFlips r;
  r.faces = x.num_faces();
  for (const auto& f : x.faces) {
    const int o = image_orientation(y, gy, map[f[0]], map[f[1]], map[f[2]]);
    r.degenerate += o == 0;
    r.flips += o < 0;
  }
  return r;
}

}  // namespace

OrientationFlips count_orientation_flips(const Mesh& x, const Mesh& y, const std::vector<SurfacePoint>& map_x_to_y) {
  if (static_cast<int>(map_x_to_y.size()) != x.num_vertices())
    throw InvalidInputError("orientation flips: the point map has " + std::to_string(map_x_to_y.size()) +
                            " entries, X has " + std::to_string(x.num_vertices()) + " vertices");
  for (const SurfacePoint& p : map_x_to_y)
    if (p.face < 0 || p.face >= y.num_faces())
      throw InvalidInputError("orientation flips: the point map names face " + std::to_string(p.face) +
                              ", but Y has " + std::to_string(y.num_faces()) + " faces");
  return count_images(x, y, map_x_to_y);
}

OrientationFlips count_orientation_flips(const Mesh& x, const Mesh& y, const std::vector<int>& map_x_to_y) {
  if (static_cast<int>(map_x_to_y.size()) != x.num_vertices())
    throw InvalidInputError("orientation flips: the map has " + std::to_string(map_x_to_y.size()) +
                            " entries, X has " + std::to_string(x.num_vertices()) + " vertices");
  for (int v : map_x_to_y)
    if (v < 0 || v >= y.num_vertices())
      throw InvalidInputError("orientation flips: the map sends a vertex to " + std::to_string(v) + ", but Y has " +
                              std::to_string(y.num_vertices()) + " vertices");
  return count_images(x, y, map_x_to_y);
}

}  // namespace shapematch
