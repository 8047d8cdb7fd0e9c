#pragma once
// What `lp` and `match` share: the mesh pair, its preprocessing and the energy options.
#include "shapematch/geometry.hpp"
#include "shapematch/matching.hpp"
#include "validators.hpp"

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

namespace shapematch::app {

struct PairArgs {
  std::string x, y;  // empty: the bundled pair
  int faces = 0;     // decimate both to about this many faces; 0 keeps them
  bool keep_scale = false;
  bool close_holes = false;  // fill boundary loops instead of rejecting open meshes
  double bending = EnergyOptions{}.bending_weight;
  std::vector<double> lame{1.0, 1.0};
  // The feature term (DESIGN.md §5): user descriptors, or the Wave Kernel Signature.
  std::string features_x, features_y;
  std::string wks = "auto";  // on, off, auto (on unless user features are given)
  // On by default since measured (docs/results-log.md, "The feature term with the whole chain"):
  // FAUST_r at 1000 faces 0.098 → 0.051 mean error over 8 pairs, TOSCA_r at 500 no worse. 10
  // since the forty-fourth session: at full resolution FAUST_r 029-069 0.0327 -> 0.0287 and
  // 026-063 0.0312 -> 0.0261, up to 1 414 faces lower on all nine pairs tried (forty-third).
  double feature_weight = 10.0;
  double degenerate_penalty = 0.0;
  // 0.05 since measured at full resolution (docs/results-log.md, thirty-fourth session): FAUST_r
  // 021-029's error 0.0319 -> 0.0170 (the one above issue 6's 0.03), 020-024 0.0169 -> 0.0177,
  // TOSCA_r dog0-dog3 0.0276 -> 0.0287. The library keeps the paper's per-vertex H (EnergyOptions).
  double curvature_radius = 0.05;
  std::string membrane = "compressive";
  int wks_eigenpairs = 100;
};

// Registers x, y, --faces, --keep-scale, --bending and --lame.
void add_pair_options(CLI::App& app, PairArgs& args);

struct MeshPair {
  Mesh x, y;
  int x_input_vertices = 0, y_input_vertices = 0;  // as matched (with --close-holes, the fans' vertices too)
  int x_file_vertices = 0, y_file_vertices = 0;    // in the files (what ground truth and user features index)
  std::vector<int> x_ids, y_ids;  // each vertex's index in its input file (decimation keeps a subset)
  Eigen::MatrixXd features_x, features_y;  // one row per vertex of x and y; empty without a feature term
  std::string features;                    // "wks", "user" or "none"
  double features_seconds = 0.0;
  std::string x_file, y_file;
};

// Loads (the bundled pair when none is given), validates, decimates and computes features.
MeshPair load_pair(const PairArgs& args);

MatchingLpOptions matching_options(const PairArgs& args, const MeshPair& pair);

}  // namespace shapematch::app
