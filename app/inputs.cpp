#include "inputs.hpp"

#include "commands.hpp"
#include "shapematch/descriptors.hpp"
#include "shapematch/errors.hpp"
#include "shapematch/system.hpp"

#include <spdlog/spdlog.h>

namespace shapematch::app {

void add_pair_options(CLI::App& app, PairArgs& args) {
  app.add_option("x", args.x, "first mesh (OFF, OBJ, PLY, STL); default: bundled asset");
  app.add_option("y", args.y, "second mesh; default: bundled asset");
  app.add_option("--faces", args.faces, "decimate both meshes to about N faces first (0: keep)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_flag("--keep-scale", args.keep_scale, "do not normalise both shapes to unit area");
  app.add_flag("--close-holes", args.close_holes,
               "close each boundary loop with a fan around a new vertex instead of rejecting an open mesh");
  app.add_option("--bending", args.bending, "bending weight")->check(non_negative_number())->capture_default_str();
  app.add_option("--lame", args.lame, "Lamé parameters λ,μ of the membrane")->delimiter(',')->expected(2);
  app.add_option("--feature-weight", args.feature_weight, "weight μ of the feature term (0: off)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--degenerate-penalty", args.degenerate_penalty,
                 "extra cost per unit area of every degenerate product triangle")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--curvature-radius", args.curvature_radius,
                 "average the bending term's mean curvature over this radius, in units of √area (0: per vertex)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--membrane", args.membrane, "membrane energy: compressive (default) or svk (the paper's St. Venant–Kirchhoff)")
      ->check(CLI::IsMember({"svk", "compressive"}))
      ->capture_default_str();
  app.add_option("--features-x", args.features_x, "per-vertex descriptors of X (text rows or .npy)");
  app.add_option("--features-y", args.features_y, "per-vertex descriptors of Y (text rows or .npy)");
  app.add_option("--wks", args.wks, "Wave Kernel Signature as the features: on, off, auto (on unless --features-x/y)")
      ->check(CLI::IsMember({"on", "off", "auto"}))
      ->capture_default_str();
  app.add_option("--wks-eigenpairs", args.wks_eigenpairs, "Laplace eigenpairs of the WKS")
      ->check(CLI::Range(2, 2000))
      ->capture_default_str();
}

namespace {

// `rows` (one per vertex of the file) extended by a row for each vertex closing a hole (those
// after the file's, each the centre of its hole's fan): the mean of its neighbours' rows.
Eigen::MatrixXd with_fan_rows(const Eigen::MatrixXd& rows, const Mesh& mesh) {
  const int file = static_cast<int>(rows.rows()), n = mesh.num_vertices();
  if (file == n) return rows;
  Eigen::MatrixXd all = Eigen::MatrixXd::Zero(n, rows.cols());
  all.topRows(file) = rows;
  std::vector<int> count(n, 0);
  for (const auto& f : mesh.faces)
    for (int k = 0; k < 3; ++k)
      if (f[k] >= file)
        for (int other : {f[(k + 1) % 3], f[(k + 2) % 3]})
          if (other < file) {  // (each ring vertex is in two of the fan's faces: counted twice, evenly)
            all.row(f[k]) += rows.row(other);
            ++count[f[k]];
          }
  for (int v = file; v < n; ++v)
    if (count[v] > 0) all.row(v) /= count[v];
  return all;
}

}  // namespace

MeshPair load_pair(const PairArgs& args) {
  if (args.x.empty() != args.y.empty()) throw InvalidInputError("give both meshes X and Y, or neither");
  MeshPair p;
  p.x_file = args.x.empty() ? default_mesh_x() : args.x;
  p.y_file = args.y.empty() ? default_mesh_y() : args.y;
  LoadOptions load;
  load.normalize_area = !args.keep_scale;
  load.close_holes = args.close_holes;
  auto load_one = [&](const std::string& file, int& file_vertices) {
    try {
      MeshReport report;
      Mesh mesh = load_mesh(file, load, &report);
      file_vertices = mesh.num_vertices() - report.closed_holes;  // (each closed hole added one vertex, last)
      return mesh;
    } catch (const InvalidInputError& e) {
      const std::string what = e.what();
      if (what.find(": not closed:") == std::string::npos) throw;
      throw InvalidInputError(what + "; --close-holes fills each hole with a fan");
    }
  };
  p.x = load_one(p.x_file, p.x_file_vertices);
  p.y = load_one(p.y_file, p.y_file_vertices);
  if (args.features_x.empty() != args.features_y.empty())
    throw InvalidInputError("give both --features-x and --features-y, or neither");
  const bool user = !args.features_x.empty();
  if (user && args.wks == "on") throw InvalidInputError("--wks on and --features-x/y exclude each other");
  if (args.feature_weight == 0 && (user || args.wks == "on"))
    spdlog::warn("features given but --feature-weight is 0: the feature term is off");
  Stopwatch clock;
  if (args.feature_weight > 0 && user) {
    // One row per vertex of the file; a closed hole's fan vertex gets the mean of its ring's rows.
    p.features_x = with_fan_rows(load_features(args.features_x, p.x_file_vertices), p.x);
    p.features_y = with_fan_rows(load_features(args.features_y, p.y_file_vertices), p.y);
    if (p.features_x.cols() != p.features_y.cols())
      throw InvalidInputError(fmt::format("{} has {} columns but {} has {}", args.features_x, p.features_x.cols(),
                                          args.features_y, p.features_y.cols()));
    p.features = "user";
  } else if (args.feature_weight > 0 && args.wks != "off") {
    // On the input meshes, before any decimation: the spectrum of the finer mesh is the better one.
    WksOptions wo;
    wo.eigenpairs = args.wks_eigenpairs;
    p.features_x = wave_kernel_signature(p.x, wo);
    p.features_y = wave_kernel_signature(p.y, wo);
    p.features = "wks";
  } else {
    p.features = "none";
  }
  p.features_seconds = clock.seconds();
  p.x_input_vertices = p.x.num_vertices();
  p.y_input_vertices = p.y.num_vertices();
  const int x_input_faces = p.x.num_faces(), y_input_faces = p.y.num_faces();
  p.x = decimate(p.x, args.faces > 0 ? args.faces : p.x.num_faces(), &p.x_ids);
  p.y = decimate(p.y, args.faces > 0 ? args.faces : p.y.num_faces(), &p.y_ids);
  if (p.features_x.size() > 0) {
    p.features_x = select_rows(p.features_x, p.x_ids);
    p.features_y = select_rows(p.features_y, p.y_ids);
  }
  // (The input's face count too where it was decimated: `match` decimates to 100 faces unless
  // told --faces 0, which a run meant at full resolution easily forgets.)
  const auto faces = [](const Mesh& m, int input) {
    return m.num_faces() == input ? fmt::format("{} faces", input)
                                  : fmt::format("{} faces, decimated from {}", m.num_faces(), input);
  };
  spdlog::info("X: {} ({}), Y: {} ({}){}", p.x.name, faces(p.x, x_input_faces), p.y.name, faces(p.y, y_input_faces),
               p.x.num_faces() == x_input_faces && p.y.num_faces() == y_input_faces ? ""
                                                                                    : " (--faces 0 keeps the input)");
  return p;
}

MatchingLpOptions matching_options(const PairArgs& args, const MeshPair& pair) {
  MatchingLpOptions o;
  o.energy.degenerate_penalty = args.degenerate_penalty;
  o.energy.curvature_radius = args.curvature_radius;
  o.energy.membrane = args.membrane == "svk" ? MembraneModel::StVenantKirchhoff : MembraneModel::Compressive;
  o.energy.feature_weight = pair.features_x.size() > 0 ? args.feature_weight : 0.0;
  o.features_x = pair.features_x;
  o.features_y = pair.features_y;
  o.energy.bending_weight = args.bending;
  o.energy.lame_lambda = args.lame.at(0);
  o.energy.lame_mu = args.lame.at(1);
  return o;
}

}  // namespace shapematch::app
