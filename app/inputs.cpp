#include "inputs.hpp"

#include "commands.hpp"
#include "shapematch/errors.hpp"

#include <spdlog/spdlog.h>

namespace shapematch::app {

void add_pair_options(CLI::App& app, PairArgs& args) {
  app.add_option("x", args.x, "first mesh (OFF, OBJ, PLY, STL); default: bundled asset");
  app.add_option("y", args.y, "second mesh; default: bundled asset");
  app.add_option("--faces", args.faces, "decimate both meshes to about N faces first (0: keep)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_flag("--keep-scale", args.keep_scale, "do not normalise both shapes to unit area");
  app.add_option("--bending", args.bending, "bending weight")->capture_default_str();
  app.add_option("--lame", args.lame, "Lamé parameters λ,μ of the membrane")->delimiter(',')->expected(2);
}

MeshPair load_pair(const PairArgs& args) {
  if (args.x.empty() != args.y.empty()) throw InvalidInputError("give both meshes X and Y, or neither");
  MeshPair p;
  p.x_file = args.x.empty() ? default_mesh_x() : args.x;
  p.y_file = args.y.empty() ? default_mesh_y() : args.y;
  LoadOptions load;
  load.normalize_area = !args.keep_scale;
  p.x = load_mesh(p.x_file, load);
  p.y = load_mesh(p.y_file, load);
  p.x_input_vertices = p.x.num_vertices();
  p.y_input_vertices = p.y.num_vertices();
  p.x = decimate(p.x, args.faces > 0 ? args.faces : p.x.num_faces(), &p.x_ids);
  p.y = decimate(p.y, args.faces > 0 ? args.faces : p.y.num_faces(), &p.y_ids);
  p.gx = compute_geometry(p.x);
  p.gy = compute_geometry(p.y);
  spdlog::info("X: {} ({} faces), Y: {} ({} faces)", p.x.name, p.x.num_faces(), p.y.name, p.y.num_faces());
  return p;
}

MatchingLpOptions matching_options(const PairArgs& args) {
  MatchingLpOptions o;
  o.energy.bending_weight = args.bending;
  o.energy.lame_lambda = args.lame.at(0);
  o.energy.lame_mu = args.lame.at(1);
  return o;
}

}  // namespace shapematch::app
