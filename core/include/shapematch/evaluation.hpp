#pragma once
// Evaluation of a vertex map against ground truth (DESIGN.md §9): geodesic errors on the
// full-resolution Y normalised by √area(Y), the PCK curve, and orientation flips.
#include "shapematch/mesh.hpp"
#include "shapematch/point_map.hpp"

#include <array>
#include <string>
#include <vector>

namespace shapematch {

// One ground-truth correspondence between the full-resolution inputs, 0-based: vertex x of X
// corresponds to vertex y of Y.
struct GroundTruthPair {
  int x = 0;
  int y = 0;
};
using GroundTruth = std::vector<GroundTruthPair>;

// Vertex i ↔ vertex i (shared connectivity); the vertex counts must be equal.
GroundTruth identity_ground_truth(int x_vertices, int y_vertices);
// FAUST_r / TOSCA_r `.vts` files: one 1-based vertex per line, line k of `x_path` (a vertex of X)
// ↔ line k of `y_path` (a vertex of Y).
GroundTruth read_vts_ground_truth(const std::string& x_path, const std::string& y_path, int x_vertices,
                                  int y_vertices);
// Two 1-based columns per line, "x_vertex y_vertex": column 1 is a vertex of X, column 2 of Y;
// blank lines and `#` comments skipped. TOPKIDS kidXX_ref.txt maps kidXX → kid00, so X = kidXX and Y =
// kid00. Each line is one sample: a pair written twice counts twice, as a pair repeated in .vts
// files does (FAUST_r's and TOSCA_r's repeat pairs; the published means count every line).
GroundTruth read_map_ground_truth(const std::string& path, int x_vertices, int y_vertices);
// The same two columns with either base (match's levels/level_K.txt are 0-based).
GroundTruth read_vertex_pairs(const std::string& path, bool one_based, int x_vertices, int y_vertices);

// A true map of the matched meshes from ground truth between the files they came from
// (CoarseToFineOptions::truth): for every vertex v of the matched X (x_ids[v]: its vertex of
// x_file), the vertex of the matched Y (y_ids likewise) nearest in space to the Y side of the
// ground-truth pair whose X side is nearest in space to x_ids[v]. In space, not on the surface:
// where two parts nearly touch it can take the other part. Throws InvalidInputError where the
// ground truth is empty.
std::vector<int> truth_at(const Mesh& x_file, const Mesh& y_file, const std::vector<int>& x_ids,
                          const std::vector<int>& y_ids, const GroundTruth& truth);

// One vertex index per line (map_x_to_y.txt, x_vertex_ids.txt; `.vts` with one_based), each in
// [0, num_vertices) after subtracting the base; returned 0-based. Throws IoError or
// InvalidInputError "<path>: line N: <problem>".
std::vector<int> read_vertex_list(const std::string& path, bool one_based, int num_vertices);

struct EvaluationOptions {
  double pck_max = 0.25;   // PCK thresholds 0, pck_step, …, pck_max (in units of √area(Y))
  double pck_step = 0.01;
  int threads = 0;         // geodesic solves in parallel; 0: all hardware threads
};

struct GeodesicErrors {
  std::vector<double> errors;  // d_Y(φ(x_k), y_k) / √area(Y) per evaluated pair, in ground-truth order
  std::vector<size_t> pair;    // the ground-truth pair of each error (its index in the truth)
  int points = 0;              // ground-truth pairs whose x has an image under φ
  double mean = 0, median = 0;
  std::vector<std::array<double, 2>> pck;  // (threshold t, fraction of points with error ≤ t)
  double auc = 0;                          // area under the PCK curve over [0, pck_max], divided by pck_max
  int geodesic_solves = 0;                 // distinct source vertices marched from
};

// `phi[i]` is the vertex of Y that vertex i of X maps to, or -1 where the map says nothing (such
// ground-truth pairs are left out). Distances are solved once per distinct vertex on whichever
// side (predicted or true) has fewer, and not at all for exact hits. Throws InvalidInputError if
// no pair can be evaluated or an index is out of range.
GeodesicErrors geodesic_errors(const Mesh& y, const std::vector<int>& phi, const GroundTruth& truth,
                               const EvaluationOptions& options = {});

// A predicted point on Y for the point-map version: the corners of a face of Y (vertex indices of
// the mesh given to geodesic_errors) and barycentric weights; corners[0] < 0 where the map says
// nothing.
struct MappedPoint {
  std::array<int, 3> corners{-1, -1, -1};
  std::array<double, 3> bary{};
};

// The same for points: the distance from a point inside a face is interpolated linearly from its
// corners' distances (at most one edge length too long, and exact at the corners). Marches from
// the true vertices.
GeodesicErrors geodesic_errors(const Mesh& y, const std::vector<MappedPoint>& phi, const GroundTruth& truth,
                               const EvaluationOptions& options = {});

// One error per ground-truth pair (`pairs` of them), NaN for a pair left out (its X vertex without
// an image): GeodesicErrors::errors spread back over the pairs.
std::vector<double> pair_errors(size_t pairs, const GeodesicErrors& errors);

// Per vertex of X (`vertices` of them): the mean of its pairs' errors (one per pair of `truth`,
// NaN skipped), NaN for a vertex without any.
std::vector<double> vertex_mean_errors(int vertices, const GroundTruth& truth, const std::vector<double>& errors);

// A connected part of X whose ground-truth points are mapped more than a threshold off: where a
// match went wrong. With a symmetric ground truth, a part whose error against it is under half the
// direct one was matched to its mirror image (a left leg to the right one: the energy and
// intrinsic features cannot tell them apart, and one such part can hold most of a pair's error).
struct ErrorRegion {
  int vertices = 0;          // X vertices with an error in it
  int points = 0;            // ground-truth pairs
  double error_share = 0;    // its pairs' errors over all pairs' errors
  double mean_error = 0;
  double mean_symmetric_error = -1;  // -1: no symmetric ground truth
  bool mirrored = false;
  std::vector<int> x_vertices;  // sorted
};

// The regions of X whose vertices' mean pair error exceeds `threshold`, largest share of the error
// first. A vertex without an error (no ground truth, or removed by decimation) takes the verdict of
// the nearest one with an error (in edges; ties to the lower vertex), so regions connect across
// gaps in the ground truth without joining through them. `errors` and `symmetric` (empty: none)
// hold one error per pair of `truth` (pair_errors), NaN in the same places.
std::vector<ErrorRegion> error_regions(const Mesh& x, const GroundTruth& truth, const std::vector<double>& errors,
                                       const std::vector<double>& symmetric, double threshold);

// Pair by pair, without X's connectivity (for a coarse level's few points): the share of the
// error in pairs mapped more than `threshold` off whose symmetric error is under half the direct
// one. `errors` and `symmetric` as for error_regions (both given); 0 where there is no error.
double mirrored_error_share(const std::vector<double>& errors, const std::vector<double>& symmetric, double threshold);

// The PCK curve of `errors` at thresholds 0, step, …, max, and its normalised area (trapezoids).
std::vector<std::array<double, 2>> pck_curve(const std::vector<double>& errors, double max, double step);
double pck_auc(const std::vector<std::array<double, 2>>& pck);

struct OrientationFlips {
  int faces = 0;       // faces of X
  int flips = 0;       // image triangle on Y faces against the mean of Y's normals at its corners
  int degenerate = 0;  // image with a repeated (or collinear) vertex: neither flipped nor kept
};

// Carries every face of X through `map_x_to_y` (one vertex of Y per vertex of X) and compares the
// image triangle's normal with the area-weighted vertex normals of Y at its three corners.
OrientationFlips count_orientation_flips(const Mesh& x, const Mesh& y, const std::vector<int>& map_x_to_y);
// The same for a point map (one point of Y per vertex of X), judged by image_orientation of points.
OrientationFlips count_orientation_flips(const Mesh& x, const Mesh& y, const std::vector<SurfacePoint>& map_x_to_y);

}  // namespace shapematch
