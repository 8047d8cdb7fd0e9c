#pragma once
// Which first LP of a refined level may stop as diverging (SolverParams::stop_on_divergence),
// kept apart from the level loop so that the rules are tested on their own.

#include <limits>

namespace shapematch::detail {

struct FirstLpState {
  bool refined = false;         // a level above the coarsest (the coarsest is the full space)
  bool widenings_left = false;  // local widenings left at this level
  bool ring_left = false;       // a ring left to widen to everywhere (ring < max_ring)
  bool trusted = true;          // no earlier suspicion at this level came to nothing
  bool warm_resolve = false;    // the re-solve after pricing, from the last LP's optimum
  bool watch_resolve = false;   // CoarseToFineOptions::watch_resolve
};

// Either watch: a refined level's first LP (the coarsest is the full space), not the re-solve
// after pricing unless asked for (why: below).
inline bool watchable(const FirstLpState& s) { return s.refined && (!s.warm_resolve || s.watch_resolve); }

// A diverging first LP is reason enough to widen while local widenings remain (it only adds
// variables); past that, watch_patiently below. Not the re-solve after pricing: its space only
// grew from one whose LP ended optimal, so a feasible point of about that residual is in it, and
// its iteration cap (the cold first LP's) bounds what it costs. Measured, FAUST_r 065-069 at full
// resolution (twenty-fifth session): the watch stopped such a re-solve at a primal residual under
// the tolerance; the widening it led to cost a 1 136-face rebuild and a 924 s cold LP.
inline bool watch_divergence(const FirstLpState& s) { return watchable(s) && s.widenings_left && s.trusted; }

// Where the watch is not used as above, it still watches, patiently (SolverParams::
// patient_divergence_watch), as long as something is left to widen when it stops: locally after a
// suspicion came to nothing, and out of local widenings while a ring is left (the stop then widens
// regionally and by the ring, as a proof would). Unwatched, an infeasible LP runs to its
// iteration cap, 10⁶ (TOSCA_r dog3-dog8 at full resolution: its finest LP was still climbing
// after 45 minutes; at 4.9 iterations a second on one core, 10⁶ is 57 hours).
inline bool watch_patiently(const FirstLpState& s) {
  return watchable(s) && !watch_divergence(s) && (s.widenings_left || s.ring_left);
}

// The certified bound past which a watched first LP stops too (SolverParams::divergence_bound):
// `factor` times the coarser level's energy (CoarseToFineOptions::divergence_bound_factor), only
// while a ring is left to widen to. Its stop may come on a feasible LP (one whose optimum lies
// that high, e.g. in a space already full); with a ring left every stop ends in more rings, and
// at the last one the LP runs on to its end. Measured at test scale (the finger pair under a
// factor of 10⁻⁶, any positive bound): stopped at the last ring too, it widened a full space 36
// faces at a time until the level failed. +∞: no such bound.
inline double divergence_bound(const FirstLpState& s, double factor, double coarser_energy) {
  if (!(factor > 0.0) || !(coarser_energy > 0.0) || !s.ring_left) return std::numeric_limits<double>::infinity();
  return factor * coarser_energy;
}

// Whether a level still trusts the watch: after `limit` widenings in a row on suspicions
// (first LPs the watch stopped, no proof) it does not, until a proof of infeasibility. Measured
// (thirty-fifth session): at the curvature radius 0.05, TOSCA_r horse0-5's 1 414-face level
// widened 24 times in a row on suspicions, and one of those LPs, let run, was feasible.
class SuspicionCount {
public:
  explicit SuspicionCount(int limit) : limit_(limit) {}
  bool trusted() const { return trusted_; }
  int count() const { return count_; }
  // A widening on a certified proof: the watch is trusted again.
  void proof() {
    count_ = 0;
    trusted_ = true;
  }
  // A widening on a suspicion. True where it is the one that ends the trust (to say so once).
  bool suspicion() {
    ++count_;
    if (limit_ <= 0 || !trusted_ || count_ < limit_) return false;
    trusted_ = false;
    return true;
  }
  // A suspicion with nothing left to widen locally: the next first LP waits for a proof.
  void distrust() { trusted_ = false; }
  // The state a checkpointed attempt left (LevelAttempt).
  void restore(int count, bool trusted) {
    count_ = count;
    trusted_ = trusted;
  }

private:
  int limit_;  // 0: no limit
  int count_ = 0;
  bool trusted_ = true;
};

// Whether another margin may be given where `given` were given already and at most `limit` may
// (0: no limit; CoarseToFineOptions::suspicion_margins).
inline bool margin_left(int given, int limit) { return limit <= 0 || given < limit; }

}  // namespace shapematch::detail
