// `shapematch eval DIR`: a `match` output directory against ground truth (DESIGN.md §9).
#include "commands.hpp"
#include "json_read.hpp"
#include "shapematch/errors.hpp"
#include "shapematch/evaluation.hpp"
#include "shapematch/files.hpp"
#include "shapematch/json.hpp"
#include "shapematch/point_map.hpp"
#include "shapematch/system.hpp"

#include <spdlog/fmt/fmt.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>
#include <random>
#include <set>

namespace fs = std::filesystem;

namespace shapematch::app {
namespace {

struct EvalArgs {
  std::string dir;
  std::string gt = "identity";
  std::string gt_x, gt_y, gt_map;
  std::string gt_y_sym;  // Y's left-right-symmetric .vts (TOSCA_r, FAUST_r): also scored, the better one named
  std::string y_mesh;  // overrides report.json's y.file
  std::string pck_csv, pck_png;
  std::string errors_csv;  // one line per ground-truth pair: where X's vertex went and how far off
  std::string x_mesh;      // overrides report.json's x.file (for error_regions)
  std::string errors_ply;  // X's input mesh coloured by error
  double region_threshold = 0.1;
  int threads = 0;
};

std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char ch : s) q += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
  return q + "'";
}

// For each vertex of the matched mesh (x.ply or y.ply), its index in the input mesh.
std::vector<int> input_ids(const fs::path& dir, const std::string& side, int matched, int input) {
  const fs::path path = dir / (side + "_vertex_ids.txt");
  if (!fs::exists(path)) {
    // Written by match since it decimates; without it the meshes must be the inputs themselves.
    if (matched != input)
      throw InvalidInputError(fmt::format("{}: {}.ply has {} vertices but the input had {}, and there is no {} to "
                                          "relate them (written by newer versions of `shapematch match`)",
                                          dir.string(), side, matched, input, path.filename().string()));
    std::vector<int> ids(matched);
    for (int v = 0; v < matched; ++v) ids[v] = v;
    return ids;
  }
  std::vector<int> ids = read_vertex_list(path.string(), false, input);
  if (static_cast<int>(ids.size()) != matched)
    throw InvalidInputError(fmt::format("{}: {} lines, but {}.ply has {} vertices", path.string(), ids.size(), side,
                                        matched));
  std::vector<char> seen(input, 0);
  for (size_t v = 0; v < ids.size(); ++v) {
    if (seen[ids[v]])
      throw InvalidInputError(fmt::format("{}: line {}: input vertex {} is listed twice", path.string(), v + 1, ids[v]));
    seen[ids[v]] = 1;
  }
  return ids;
}

// Whether `file` (loaded as `input`) is the mesh the match read for this side: decimation keeps
// the vertices it keeps where they were, so the matched mesh's vertices are the input's vertices
// `ids`, up to match's shift and scale. Compared after taking out each one's centroid and RMS
// radius: the file the match read agrees to rounding (TOSCA_r dog0-dog8: 9e-16), another pose or
// shape with the same vertex count does not (dog0 or dog3 for dog8: 2.1, 2.6), and would have
// been scored as if it were Y.
void check_same_mesh(const Mesh& matched, const std::vector<int>& ids, const Mesh& input, const std::string& file,
                     const std::string& side, const fs::path& report) {
  const auto normalised = [](auto point, size_t n) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (size_t k = 0; k < n; ++k) mean += point(k);
    mean /= double(n);
    double square = 0.0;
    for (size_t k = 0; k < n; ++k) square += (point(k) - mean).squaredNorm();
    const double rms = std::sqrt(square / double(n));
    return std::pair{mean, rms > 0.0 ? rms : 1.0};
  };
  const size_t n = ids.size();
  const auto [mm, ms] = normalised([&](size_t k) { return matched.vertices[k]; }, n);
  const auto [im, is] = normalised([&](size_t k) { return input.vertices[ids[k]]; }, n);
  double worst = 0.0, reach = 0.0;
  for (size_t k = 0; k < n; ++k) {
    worst = std::max(worst, ((matched.vertices[k] - mm) / ms - (input.vertices[ids[k]] - im) / is).norm());
    reach = std::max(reach, matched.vertices[k].cwiseAbs().maxCoeff());
  }
  // The PLY is read back in single precision: a shape far from the origin against its size
  // (--keep-scale) keeps only float's share of its coordinates (a finger 1e4 out: 3e-4).
  const double tolerance = 1e-4 + 16.0 * std::ldexp(1.0, -24) * reach / ms;
  if (!(worst <= tolerance))
    throw InvalidInputError(fmt::format("{}: is not the {} mesh the match read (its vertices differ from {}'s by up to "
                                        "{:.3g} of the shape's RMS radius); give the file `match` was run on",
                                        file, side == "x" ? "X" : "Y", (report.parent_path() / (side + ".ply")).string(),
                                        worst));
}

// A coarser level's vertex map (match writes levels/level_K.txt): `x y` per line, 0-based input
// vertices of X and Y; φ over the input vertices of X, -1 where that level has no vertex.
std::vector<int> read_level_map(const fs::path& path, int x_input, int y_input) {
  std::vector<int> phi(x_input, -1);
  for (const auto& [x, y] : read_vertex_pairs(path.string(), false, x_input, y_input)) {
    if (phi[x] >= 0) throw InvalidInputError(fmt::format("{}: X vertex {} is listed twice", path.string(), x));
    phi[x] = y;
  }
  return phi;
}

// Runs tools/plot_pck.py with Debian's Python (which has matplotlib); a missing matplotlib is a
// warning, not a failed evaluation.
void plot(const std::string& csv_path, const std::string& png_path, const std::string& label) {
  const fs::path script = fs::path(data_dir()) / "tools" / "plot_pck.py";
  const std::string python = "/usr/bin/python3";
  if (std::system((python + " -c 'import matplotlib' >/dev/null 2>&1").c_str()) != 0) {
    spdlog::warn("{} cannot import matplotlib (apt install python3-matplotlib); no plot written", python);
    return;
  }
  const std::string cmd = python + " " + shell_quote(script.string()) + " " + shell_quote(csv_path) + " " +
                          shell_quote(png_path) + " " + shell_quote(label) + " >&2";
  if (std::system(cmd.c_str()) != 0) {
    spdlog::warn("plotting failed ({})", cmd);
    std::error_code ec;
    fs::remove(png_path + ".tmp", ec);  // (plot_pck.py's, where savefig wrote it and the rename failed)
  }
}

// Per ground-truth pair (0-based input vertices): X's vertex, its true image, the map's image and
// the error, empty where the map says nothing; with the symmetric ground truth its error too.
std::string errors_table(const GroundTruth& truth, const std::vector<int>& phi, const std::vector<double>& errors,
                         const std::vector<double>& symmetric) {
  std::string csv = symmetric.empty() ? "x,y_true,y_mapped,error\n" : "x,y_true,y_mapped,error,symmetric_error\n";
  for (size_t k = 0; k < truth.size(); ++k) {
    const GroundTruthPair& p = truth[k];
    csv += fmt::format("{},{},", p.x, p.y);
    if (std::isnan(errors[k])) {  // (X's vertex without an image)
      csv += symmetric.empty() ? ",\n" : ",,\n";
      continue;
    }
    csv += fmt::format("{},{}", phi[p.x], errors[k]);
    if (!symmetric.empty()) csv += fmt::format(",{}", symmetric[k]);
    csv += "\n";
  }
  return csv;
}

// X's vertices coloured by their pairs' mean error: white at 0 through yellow to red at
// `full_scale` and above; vertices of a mirrored region blue (whatever their error, so that a
// swapped part stands out from a merely inaccurate one); grey without an error (no ground truth, or
// removed by decimation).
std::vector<std::array<uint8_t, 3>> error_colors(const Mesh& x, const GroundTruth& truth,
                                                 const std::vector<double>& errors,
                                                 const std::vector<ErrorRegion>& regions, double full_scale) {
  const std::vector<double> mean = vertex_mean_errors(x.num_vertices(), truth, errors);
  std::vector<std::array<uint8_t, 3>> colors(x.num_vertices(), {160, 160, 160});
  const auto c = [](double u) { return static_cast<uint8_t>(std::lround(255 * std::clamp(u, 0.0, 1.0))); };
  for (int v = 0; v < x.num_vertices(); ++v) {
    if (std::isnan(mean[v])) continue;
    const double t = std::clamp(mean[v] / full_scale, 0.0, 1.0);
    colors[v] = t < 0.5 ? std::array<uint8_t, 3>{255, 255, c(1 - 2 * t)} : std::array<uint8_t, 3>{255, c(2 - 2 * t), 0};
  }
  for (const ErrorRegion& r : regions)
    if (r.mirrored)
      for (int v : r.x_vertices) colors[v] = {60, 90, 230};
  return colors;
}

// The files eval is asked to write, checked before any geodesic is solved (a full-resolution
// evaluation takes minutes): each writable, no two the same, none a file it reads (the match
// output's own files, the meshes report.json names, the ground truth, the meshes given). Files
// of its own in the match directory (an earlier eval's) may be written again.
void check_outputs(const EvalArgs& args, const fs::path& dir, const JsonNode& report) {
  const std::vector<std::pair<const char*, const std::string*>> outputs = {
      {"--pck-csv", &args.pck_csv}, {"--pck-png", &args.pck_png}, {"--errors-csv", &args.errors_csv},
      {"--errors-ply", &args.errors_ply}};
  std::set<fs::path> inputs;
  const auto key = [](const std::string& path) {
    std::error_code ec;
    const fs::path p = fs::weakly_canonical(path, ec);
    return ec ? fs::absolute(path).lexically_normal() : p;
  };
  for (const char* own : {"report.json", "map_x_to_y.txt", "map_x_to_y_points.txt", "map_y_to_x.txt",
                          "map_y_to_x_points.txt", "x_vertex_ids.txt", "y_vertex_ids.txt", "x.ply", "y.ply",
                          "graph_surface.txt", "match.png"})
    inputs.insert(key((dir / own).string()));
  std::error_code ec;
  for (auto it = fs::directory_iterator(dir / "levels", ec); !ec && it != fs::directory_iterator(); it.increment(ec))
    inputs.insert(key(it->path().string()));
  for (const char* side : {"x", "y"}) {
    const JsonNode* s = report.get(side);
    const JsonNode* file = s ? s->get("file") : nullptr;
    if (file && file->kind == JsonNode::Kind::String) inputs.insert(key(file->text));
  }
  for (const std::string* in : {&args.gt_x, &args.gt_y, &args.gt_y_sym, &args.gt_map, &args.x_mesh, &args.y_mesh})
    if (!in->empty()) inputs.insert(key(*in));
  std::map<fs::path, const char*> seen;
  for (const auto& [option, path] : outputs) {
    if (path->empty()) continue;
    check_writable_file(*path);
    const fs::path k = key(*path);
    if (inputs.count(k)) throw InvalidInputError(*path + ": " + option + " would overwrite a file eval reads");
    if (const auto [at, fresh] = seen.emplace(k, option); !fresh)
      throw InvalidInputError(*path + ": named by both " + at->second + " and " + option);
  }
}

int run_eval(const EvalArgs& args) {
  Stopwatch total;
  const fs::path dir(args.dir);
  if (!fs::is_directory(dir)) throw IoError(args.dir + ": not a directory (expected an output of `shapematch match`)");
  const fs::path report_path = dir / "report.json";
  const JsonNode report = read_json_file(report_path.string());
  check_outputs(args, dir, report);
  auto field = [&](const std::string& side, const std::string& key, JsonNode::Kind kind) -> const JsonNode& {
    const JsonNode* s = report.get(side);
    const JsonNode* v = s ? s->get(key) : nullptr;
    if (!v || v->kind != kind)
      throw InvalidInputError(report_path.string() + ": no " + side + "." + key + " of the expected type");
    return *v;
  };
  const int x_input = static_cast<int>(field("x", "vertices_input", JsonNode::Kind::Number).number);
  const int y_input = static_cast<int>(field("y", "vertices_input", JsonNode::Kind::Number).number);
  // The files' own vertices, which ground truth indexes: with --close-holes the fans' vertices
  // come after them and have no truth (outputs from before this field: the same count).
  const auto file_vertices = [&](const std::string& side, int input) {
    const JsonNode* s = report.get(side);
    const JsonNode* v = s ? s->get("vertices_file") : nullptr;
    return v && v->kind == JsonNode::Kind::Number ? std::min(static_cast<int>(v->number), input) : input;
  };
  const int x_file_vertices = file_vertices("x", x_input), y_file_vertices = file_vertices("y", y_input);

  // The meshes as matched: their own scale, the indices of the maps refer to them.
  LoadOptions as_matched;
  as_matched.normalize_area = false;
  const Mesh xm = load_mesh((dir / "x.ply").string(), as_matched);
  const Mesh ym = load_mesh((dir / "y.ply").string(), as_matched);
  const fs::path map_path = dir / "map_x_to_y.txt";
  const std::vector<int> map = read_vertex_list(map_path.string(), false, ym.num_vertices());
  if (static_cast<int>(map.size()) != xm.num_vertices())
    throw InvalidInputError(fmt::format("{}: {} lines, but x.ply has {} vertices", map_path.string(), map.size(),
                                        xm.num_vertices()));
  const std::vector<int> x_ids = input_ids(dir, "x", xm.num_vertices(), x_input);
  const std::vector<int> y_ids = input_ids(dir, "y", ym.num_vertices(), y_input);

  // Errors are measured on the full-resolution Y; its scale cancels in d / √area.
  const std::string y_file = args.y_mesh.empty() ? field("y", "file", JsonNode::Kind::String).text : args.y_mesh;
  if (!fs::exists(y_file))
    throw IoError(y_file + ": cannot open (Y of " + report_path.string() +
                  "; run eval where match ran, or give --y-mesh)");
  // Y as it was read for matching: with its holes closed, if they were (the added vertices come last).
  LoadOptions as_input;
  const JsonNode* match_options = report.get("options");
  const JsonNode* close_holes = match_options ? match_options->get("close_holes") : nullptr;
  as_input.close_holes = close_holes && close_holes->kind == JsonNode::Kind::Bool && close_holes->number != 0;
  const Mesh y_full = load_mesh(y_file, as_input);
  if (y_full.num_vertices() != y_input)
    throw InvalidInputError(fmt::format("{}: {} vertices, but Y had {} when it was matched", y_file,
                                        y_full.num_vertices(), y_input));
  check_same_mesh(ym, y_ids, y_full, y_file, "y", report_path);

  // X's input mesh, for error_regions only (eval needs Y otherwise): report.json's or --x-mesh;
  // loaded and checked before any geodesic is solved. Its own coordinates: --errors-ply writes it.
  std::string x_file = args.x_mesh;
  if (x_file.empty()) {
    const JsonNode* xs = report.get("x");
    const JsonNode* xf = xs ? xs->get("file") : nullptr;
    if (xf && xf->kind == JsonNode::Kind::String) x_file = xf->text;
  }
  // Needed where asked for (--x-mesh, --errors-ply): then a one-line error; else a warning, so that
  // an evaluation that never needed X does not fail for it (bench match evaluates every pair).
  const bool x_needed = !args.x_mesh.empty() || !args.errors_ply.empty();
  if (!args.errors_ply.empty()) {
    std::string ext = fs::path(args.errors_ply).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return std::tolower(ch); });
    if (ext != ".ply") throw InvalidInputError(args.errors_ply + ": --errors-ply writes PLY (vertex colours): name it .ply");
  }
  std::optional<Mesh> x_full;
  try {
    if (x_file.empty() || !fs::exists(x_file))
      throw IoError((x_file.empty() ? std::string("X") : x_file) + ": cannot open (X of " + report_path.string() +
                    (args.x_mesh.empty() ? "; give --x-mesh)" : ")"));
    LoadOptions x_as_input = as_input;
    x_as_input.normalize_area = false;
    Mesh x = load_mesh(x_file, x_as_input);
    if (x.num_vertices() != x_input)
      throw InvalidInputError(fmt::format("{}: {} vertices, but X had {} when it was matched", x_file, x.num_vertices(),
                                          x_input));
    check_same_mesh(xm, x_ids, x, x_file, "x", report_path);
    x_full = std::move(x);
  } catch (const Error& e) {
    if (x_needed) throw;
    spdlog::warn("{}: no error regions", e.what());
  }

  GroundTruth truth;
  std::string truth_name;
  if (!args.gt_map.empty()) {
    truth = read_map_ground_truth(args.gt_map, x_file_vertices, y_file_vertices);
    truth_name = args.gt_map;
  } else if (!args.gt_x.empty()) {
    truth = read_vts_ground_truth(args.gt_x, args.gt_y, x_file_vertices, y_file_vertices);
    truth_name = args.gt_x + " <-> " + args.gt_y;
  } else {
    truth = identity_ground_truth(x_file_vertices, y_file_vertices);
    truth_name = "identity";
  }
  // Intrinsic symmetries make a left-right swapped map as good as the direct one to the energy
  // and to WKS; benchmarks on these data sets score the better of the two.
  GroundTruth symmetric_truth;
  if (!args.gt_y_sym.empty()) symmetric_truth = read_vts_ground_truth(args.gt_x, args.gt_y_sym, x_file_vertices, y_file_vertices);

  // φ on the input vertices of X; those that decimation removed have no image.
  std::vector<int> phi(x_input, -1);
  for (int v = 0; v < xm.num_vertices(); ++v) phi[x_ids[v]] = y_ids[map[v]];
  EvaluationOptions options;
  options.threads = args.threads;
  const GeodesicErrors errors = geodesic_errors(y_full, phi, truth, options);
  std::optional<GeodesicErrors> symmetric;
  if (!args.gt_y_sym.empty()) symmetric = geodesic_errors(y_full, phi, symmetric_truth, options);
  const OrientationFlips flips = count_orientation_flips(xm, ym, map);
  // The coarser levels' maps, scored the same way on the points each level kept.
  Json levels = Json::array();
  for (int k = 1;; ++k) {
    const fs::path path = dir / "levels" / fmt::format("level_{}.txt", k);
    if (!fs::exists(path)) break;
    const std::vector<int> level_phi = read_level_map(path, x_input, y_input);
    const GeodesicErrors e = geodesic_errors(y_full, level_phi, truth, options);
    Json level = Json::object()
                     .set("level", k)
                     .set("points", e.points)
                     .set("mean_geodesic_error", e.mean)
                     .set("median_geodesic_error", e.median);
    std::string mirrored;
    if (symmetric) {
      // Where a part went to its mirror image: from which level on (pair by pair: too few points
      // at the coarse levels for regions).
      const GeodesicErrors es = geodesic_errors(y_full, level_phi, symmetric_truth, options);
      const double share = mirrored_error_share(pair_errors(truth.size(), e), pair_errors(truth.size(), es),
                                                args.region_threshold);
      level.set("symmetric_mean_geodesic_error", es.mean).set("mirrored_error_share", share);
      mirrored = fmt::format("; {:.0f} % of it mirrored", 100 * share);
    }
    levels.push(level);
    spdlog::info("level {}: mean geodesic error {:.4f} (median {:.4f}) over {} points{}", k, e.mean, e.median, e.points,
                 mirrored);
  }
  // The point map (written by match since it has one): the same scores for points, whose
  // corners are vertices of the matched Y, i.e. input vertices of Y.
  // A point map file of match's, one line per vertex of `from` (named as match wrote it).
  auto read_points = [](const fs::path& path, const Mesh& target, const Mesh& from, const char* from_name) {
    std::vector<SurfacePoint> points = read_point_map(path.string(), target);
    if (static_cast<int>(points.size()) != from.num_vertices())
      throw InvalidInputError(fmt::format("{}: {} lines, but {} has {} vertices", path.string(), points.size(),
                                          from_name, from.num_vertices()));
    return points;
  };
  const fs::path points_path = dir / "map_x_to_y_points.txt";
  std::optional<GeodesicErrors> point_errors, point_symmetric;
  std::optional<OrientationFlips> point_flips;
  if (fs::exists(points_path)) {
    const std::vector<SurfacePoint> points = read_points(points_path, ym, xm, "x.ply");
    std::vector<MappedPoint> phi_points(x_input);
    for (int v = 0; v < xm.num_vertices(); ++v) {
      const auto& f = ym.faces[points[v].face];
      phi_points[x_ids[v]] = {{y_ids[f[0]], y_ids[f[1]], y_ids[f[2]]}, points[v].bary};
    }
    point_errors = geodesic_errors(y_full, phi_points, truth, options);
    if (!args.gt_y_sym.empty())
      point_symmetric = geodesic_errors(y_full, phi_points, symmetric_truth, options);
    point_flips = count_orientation_flips(xm, ym, points);
  }
  // The other direction's point map (faces of Y inverted), where match wrote it.
  const fs::path back_path = dir / "map_y_to_x_points.txt";
  std::optional<OrientationFlips> back_flips;
  if (point_flips && fs::exists(back_path))
    back_flips = count_orientation_flips(ym, xm, read_points(back_path, xm, ym, "y.ply"));

  const std::vector<double> per_pair = pair_errors(truth.size(), errors);
  const std::vector<double> per_pair_sym = symmetric ? pair_errors(truth.size(), *symmetric) : std::vector<double>{};
  // Where the error lies, on X's input mesh.
  std::optional<std::vector<ErrorRegion>> regions;
  if (x_full) regions = error_regions(*x_full, truth, per_pair, per_pair_sym, args.region_threshold);

  std::string csv = "threshold,fraction\n";
  Json pck = Json::array();
  for (const auto& [t, fraction] : errors.pck) {
    pck.push(Json(Json::Array{Json(t), Json(fraction)}));
    csv += fmt::format("{},{}\n", t, fraction);
  }

  Json out = Json::object();
  out.set("dir", args.dir)
      .set("ground_truth", truth_name)
      .set("ground_truth_pairs", static_cast<int64_t>(truth.size()))
      .set("points", errors.points)
      .set("mean_geodesic_error", errors.mean)
      .set("median_geodesic_error", errors.median)
      .set("auc", errors.auc)
      .set("pck", pck)
      .set("faces", flips.faces)
      .set("orientation_flips", flips.flips)
      .set("degenerate_faces", flips.degenerate)
      .set("geodesic_solves", errors.geodesic_solves)
      .set("levels", levels)
      .set("seconds", total.seconds());
  if (regions) {
    Json list = Json::array();
    for (size_t i = 0; i < regions->size() && i < 5; ++i) {
      const ErrorRegion& r = (*regions)[i];
      Json j = Json::object()
                   .set("vertices", r.vertices)
                   .set("points", r.points)
                   .set("error_share", r.error_share)
                   .set("mean_geodesic_error", r.mean_error);
      if (symmetric) j.set("symmetric_mean_geodesic_error", r.mean_symmetric_error).set("mirrored", r.mirrored);
      list.push(j);
    }
    out.set("error_region_threshold", args.region_threshold)
        .set("error_regions_found", static_cast<int64_t>(regions->size()))
        .set("error_regions", list);
  }
  if (point_errors) {
    Json pm = Json::object()
                  .set("mean_geodesic_error", point_errors->mean)
                  .set("median_geodesic_error", point_errors->median)
                  .set("auc", point_errors->auc)
                  .set("orientation_flips", point_flips->flips)
                  .set("degenerate_faces", point_flips->degenerate);
    if (back_flips)
      pm.set("y_to_x_orientation_flips", back_flips->flips).set("y_to_x_degenerate_faces", back_flips->degenerate);
    if (point_symmetric)
      pm.set("symmetric_mean_geodesic_error", point_symmetric->mean)
          .set("best_mean_geodesic_error", std::min(point_errors->mean, point_symmetric->mean));
    out.set("point_map", pm);
  }
  if (symmetric) {
    const bool sym_better = symmetric->mean < errors.mean;
    out.set("symmetric_ground_truth", args.gt_x + " <-> " + args.gt_y_sym)
        .set("symmetric_mean_geodesic_error", symmetric->mean)
        .set("symmetric_median_geodesic_error", symmetric->median)
        .set("best_ground_truth", sym_better ? "symmetric" : "direct")
        .set("best_mean_geodesic_error", std::min(errors.mean, symmetric->mean))
        .set("mirrored_error_share", mirrored_error_share(per_pair, per_pair_sym, args.region_threshold));
  }
  // The files asked for, last (the one most likely to fail first): nothing written by an
  // evaluation that failed.
  if (!args.errors_ply.empty())
    save_mesh(*x_full, args.errors_ply, error_colors(*x_full, truth, per_pair, *regions, 0.25));
  if (!args.errors_csv.empty()) write_file_atomic(args.errors_csv, errors_table(truth, phi, per_pair, per_pair_sym));
  if (!args.pck_csv.empty()) write_file_atomic(args.pck_csv, csv);
  if (!args.pck_png.empty()) {
    // The plot reads a CSV: the one asked for, or a temporary one.
    std::string csv_path = args.pck_csv;
    if (csv_path.empty()) {
      csv_path = (fs::temp_directory_path() / ("shapematch-pck-" + std::to_string(std::random_device{}()) + ".csv"))
                     .string();
      write_file_atomic(csv_path, csv);
    }
    plot(csv_path, args.pck_png, fs::path(args.dir).lexically_normal().filename().string());
    if (args.pck_csv.empty()) fs::remove(csv_path);
  }
  std::cout << out.dump() << "\n";
  spdlog::info("mean geodesic error {:.4f} (median {:.4f}) over {} points, AUC {:.3f}; {} of {} faces flipped, {} "
               "degenerate",
               errors.mean, errors.median, errors.points, errors.auc, flips.flips, flips.faces, flips.degenerate);
  if (point_errors)
    spdlog::info("point map: mean geodesic error {:.4f} (median {:.4f}); {} of {} faces flipped, {} degenerate",
                 point_errors->mean, point_errors->median, point_flips->flips, point_flips->faces,
                 point_flips->degenerate);
  if (symmetric)
    spdlog::info("against the symmetric ground truth: mean {:.4f} (median {:.4f})", symmetric->mean, symmetric->median);
  if (regions && !regions->empty()) {
    const ErrorRegion& r = regions->front();
    spdlog::info("{} regions of X mapped more than {} off; the largest share: {} vertices, {:.0f} % of the error, mean "
                 "{:.4f}{}",
                 regions->size(), args.region_threshold, r.vertices, 100 * r.error_share, r.mean_error,
                 !symmetric ? ""
                 : r.mirrored
                     ? fmt::format(" (against the symmetric ground truth {:.4f}: matched to its mirror image)",
                                   r.mean_symmetric_error)
                     : fmt::format(" (against the symmetric ground truth {:.4f})", r.mean_symmetric_error));
  }
  return 0;
}

}  // namespace

Action add_eval_command(CLI::App& app) {
  auto a = std::make_shared<EvalArgs>();
  app.add_option("dir", a->dir, "output directory of `shapematch match`")->required();
  auto* gt = app.add_option("--gt", a->gt, "ground truth: vertex i of X <-> vertex i of Y")
                 ->check(CLI::IsMember({"identity"}))
                 ->capture_default_str();
  auto* gx = app.add_option("--gt-x", a->gt_x, "1-based .vts file of X (FAUST_r/TOSCA_r): line k <-> line k of --gt-y");
  auto* gy = app.add_option("--gt-y", a->gt_y, "1-based .vts file of Y");
  auto* gm = app.add_option("--gt-map", a->gt_map,
                            "two 1-based columns per line, X vertex then Y vertex (TOPKIDS kidXX_ref.txt: X = kidXX, "
                            "Y = kid00)");
  auto* gs = app.add_option("--gt-y-sym", a->gt_y_sym,
                            "Y's left-right-symmetric .vts (e.g. B.sym.vts): scored too, and the better of the two named");
  gs->needs(gx);
  gx->needs(gy);
  gy->needs(gx);
  gt->excludes(gx)->excludes(gy)->excludes(gm);
  gm->excludes(gx)->excludes(gy);
  app.add_option("--y-mesh", a->y_mesh, "full-resolution Y (default: the y.file of report.json)");
  app.add_option("--pck-csv", a->pck_csv, "write the PCK curve as CSV (threshold,fraction)");
  app.add_option("--pck-png", a->pck_png, "plot the PCK curve (needs python3-matplotlib)");
  app.add_option("--errors-csv", a->errors_csv,
                 "write each ground-truth pair's error as CSV (x,y_true,y_mapped,error[,symmetric_error]; 0-based "
                 "input vertices)");
  app.add_option("--x-mesh", a->x_mesh, "full-resolution X, for error_regions (default: the x.file of report.json)");
  app.add_option("--errors-ply", a->errors_ply,
                 "write X's input mesh as PLY coloured by error: white 0, yellow, red at 0.25 and above; blue: parts "
                 "matched to their mirror image (with --gt-y-sym); grey: no ground truth");
  app.add_option("--region-threshold", a->region_threshold,
                 "error_regions: connected parts of X whose points are mapped more than this off (in √area(Y))")
      ->check(CLI::Validator(
          [](std::string& text) {
            const double t = std::strtod(text.c_str(), nullptr);
            return std::isfinite(t) && t > 0 ? std::string() : std::string("must be a positive number");
          },
          "POSITIVE"))
      ->capture_default_str();
  app.add_option("--threads", a->threads, "geodesic solves in parallel (0: all cores)")
      ->check(non_negative_number())
      ->capture_default_str();
  return [a] { return run_eval(*a); };
}

}  // namespace shapematch::app
