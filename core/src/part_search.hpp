#pragma once
// The depth-first search that finishes a late round's part (RoundingOptions::search_below),
// declared apart from the rounding loop so that it is tested on its own.
#include "shapematch/lp.hpp"

#include <cstdint>
#include <optional>
#include <vector>

namespace shapematch::detail {

// How a search for a binary solution of one part ended. `infeasible`: the part's LP itself, at the
// root, has no solution (its fixings are wrong as an LP round would find them).
enum class SearchEnd { found, none, node_limit, infeasible };

struct SearchStats {
  int64_t failures = 0;       // nodes that failed (LP infeasible or propagation)
  int64_t short_nogoods = 0;  // failures whose proof holds with fewer than all decisions above
  int64_t jumps = 0;          // retreats that passed over levels the failures did not depend on
  int64_t levels_skipped = 0;  // the levels those retreats passed over
};

// One failed node's proof, where the search ends in `none`: a Farkas vector `d` over the part's
// rows (sparse: row, value), positive margin on the part's root state with `decisions` (column,
// value) and their propagation. Each holds with the part's fixings as they stand; all together
// are the search's proof, and the fixings outside the part that their margins rest on are the
// ones to release (rounding.cpp).
struct SearchProof {
  std::vector<std::pair<int64_t, double>> d;
  std::vector<std::pair<int64_t, int>> decisions;
};

// A binary solution of A x = b (one part of a late round's LP), by depth-first search: at each
// node the exact LP over what is still free; an integral optimum ends it, otherwise it branches
// on the largest fractional variable, 1 before 0, with propagation after every fixing. Complete:
// `none` is a proof that no binary solution exists (the fixings around the part are wrong),
// `infeasible` one that not even the LP has a solution. `value` gets one 0/1 per column on `found`.
// With `root`, the root node's LP result is kept there, or taken from there where it holds one (a
// search that goes on from a call that stopped after the root solves it once).
//
// With `backjump`, a failed node's proof (the exact solver's Farkas ray, or the row at which
// propagation failed) names the decisions it needs: those of its weight (certificate_blame.hpp)
// with the failing one, checked by propagating them alone from the root, where the proof must
// still hold. Where both values of a branch have failed, the search goes back to the deepest
// decision that either failure needed, not to the one above it (conflict-directed backjumping):
// a part's remainder is a handful of patches, and a dead end in one was otherwise searched again
// under every combination of the decisions made in the others.
//
// With `proofs`, on `none`, every failure's proof, each with the decisions it needs; emptied where
// one failure had none to give, or past 256 of them (then the search says nothing about where to
// release).
SearchEnd search_part(const LpProblem& plp, LpSolver& exact, const SolverParams& params, int64_t max_nodes,
                      std::vector<int8_t>& value, int64_t& nodes, std::optional<LpResult>* root = nullptr,
                      bool backjump = true, SearchStats* stats = nullptr, std::vector<SearchProof>* proofs = nullptr);

}  // namespace shapematch::detail
