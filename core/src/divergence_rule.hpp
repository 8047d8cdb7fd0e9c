#pragma once
// Which first LP of a refined level may stop as diverging (SolverParams::stop_on_divergence),
// kept apart from the level loop so that the rule is tested on its own.

namespace shapematch::detail {

struct FirstLpState {
  bool refined = false;         // a level above the coarsest (the coarsest is the full space)
  bool widenings_left = false;  // local widenings left at this level
  bool trusted = true;          // no earlier suspicion at this level came to nothing
  bool warm_resolve = false;    // the re-solve after pricing, from the last LP's optimum
  bool watch_resolve = false;   // CoarseToFineOptions::watch_resolve
};

// A diverging first LP is reason enough to widen while local widenings remain (it only adds
// variables); the last attempts wait for a proof. Not the re-solve after pricing: its space only
// grew from one whose LP ended optimal, so a feasible point of about that residual is in it, and
// its iteration cap (the cold first LP's) bounds what it costs. Measured, FAUST_r 065-069 at full
// resolution (twenty-fifth session): the watch stopped such a re-solve at a primal residual under
// the tolerance; the widening it led to cost a 1 136-face rebuild and a 924 s cold LP.
inline bool watch_divergence(const FirstLpState& s) {
  if (!s.refined || !s.widenings_left || !s.trusted) return false;
  return !s.warm_resolve || s.watch_resolve;
}

}  // namespace shapematch::detail
