#pragma once
// PDHG's divergence watch (SolverParams::stop_on_divergence), kept apart from the driver so that
// its rules are tested on the numbers measured where they were set.
#include "shapematch/lp.hpp"

#include <cmath>

namespace shapematch::detail {

// Looks at the iterate once per window (kWindow iterations): its primal residual, relative gap,
// objective cᵀx and dual bound. An infeasible LP's bound climbs without limit while its primal
// residual stalls above zero; a feasible one's gap closes.
class DivergenceWatch {
public:
  static constexpr long kWindow = 512;

  // `patient`: only the creeping climb below counts, and for kPatientWindows windows in a row: for
  // a first LP whose earlier suspicions came to nothing, or one out of local widenings
  // (detail::watch_patiently; coarse to fine used to let those run unwatched:
  // measured, TOSCA_r dog3-dog8 at full resolution: a 12.7 M-variable LP, residual flat at
  // 3.65-3.69e-3 against a tolerance of 3e-3 from 5 000 to 16 000 iterations while its bound rose
  // 2.19 → 2.78 above an objective of 2.18, 45 minutes on one thread, under a cap of 10⁶).
  explicit DivergenceWatch(double tolerance, bool patient = false, const DivergenceWatchState& from = {})
      : tolerance_(tolerance), patient_(patient), s_(from) {}

  // Where it stands, for a snapshot (a watch made from it goes on the same way).
  const DivergenceWatchState& state() const { return s_; }

  // At the end of a window: true where the LP is to be stopped as diverging.
  bool diverging(double primal, double gap, double objective, double bound) {
    const double scale = 1.0 + std::abs(objective);
    const double excess = bound - objective;
    bool stop = false;
    if (s_.windows > 0) {
      // A residual that stopped falling, with the bound far above the objective and rising
      // (measured on a 10 k-face reduced matching LP: residual flat at 2e-2 while the bound rose
      // from 35 to 48 in 1 024 iterations; feasible LPs of that size cut their residual 20× in
      // such a window). Below the tolerance the residual alone says little: there the gap must be
      // far above it and have grown (a 1 474-face reduced LP at tolerance 1e-3 sat at residual
      // 5.6e-4 with its bound 4.3 above an objective of 8.6, still rising, for 35 000 iterations).
      const bool flat = primal >= 0.8 * s_.primal;
      // The rules below that fire while the residual still falls wait until it is near feasible:
      // far from it, cᵀx and the bound say little yet. Measured, TOSCA_r horse0-5 at the curvature
      // radius 0.05, the 1 414-face level's first LP (tolerance 1e-3): at 1 024 iterations residual
      // 6.0e-2, gap 0.20, the bound 1.44 above an objective of 2.87 and rising, so the gap rule
      // stopped it; let run, it was feasible (residual 1.9e-3 at 1 536, gap 2.1e-3 at 3 840). The
      // infeasible LPs these rules were set on (tests/test_pdhg.cpp) stopped at 1.2e-2 and below.
      const bool near = primal < kNearFeasible;
      const bool stalled = primal > tolerance_ || (gap > 10.0 * tolerance_ && gap > s_.gap);
      stop = flat && stalled && bound - objective > 0.1 * scale && bound - s_.bound > 0.05 * scale;
      // A gap that grew past 10× the tolerance with the bound over 5 % above the objective and
      // rising, even while the residual still falls: over the 2 990 PDHG solves logged in full-
      // resolution runs, every one that stopped optimal stayed short of this, and FAUST_r 020-024's
      // and 021-024's infeasible finest LPs meet it at 1 024 iterations (gap 3.7e-2 and 5.0e-2,
      // bound 7 % and 10 % above), 1 024 and 512 iterations before the rule above.
      stop = stop || (near && gap > 10.0 * tolerance_ && gap > s_.gap && bound - objective > 0.05 * scale &&
                      bound > s_.bound);
      // A slower climb counts too where it held kCreepingWindows windows in a row: the bound above
      // the objective, the gap growing, the residual flat (TOSCA_r horse0-5's finest LP: residual
      // 1.2e-3 → 1.0e-3 while the gap grew 4.3e-3 → 3.8e-2 over 3 600 iterations, its bound rising
      // about 1.1 per window against an objective of 63).
      const bool creep = flat && bound > objective && gap > tolerance_ && gap > s_.gap;
      s_.creeping = creep ? s_.creeping + 1 : 0;
      stop = stop || s_.creeping >= kCreepingWindows;
      // Patient: the bound must also rise each window, and the rules above and below do not count
      // (the LP the thirty-fifth session let run, feasible, had its residual falling 30x).
      s_.climbing = creep && bound > s_.bound ? s_.climbing + 1 : 0;
      if (patient_) stop = s_.climbing >= kPatientWindows;
      // The bound pulling away from the objective for three windows in a row, whatever the
      // residual does once near feasible: above it and further each window, at the last more than
      // twice as far as at the first, the gap above the tolerance (FAUST_r 020-024's second infeasible finest
      // LPs: excess 0.17, 0.48, 0.98 at 512-1 536 iterations, stopped by the rules above at
      // 2 048, or at 3 584 with 0.15, 0.25, 0.26, 0.43, 0.54, …; the cat's at 2 560 instead of
      // 3 584). No LP that ended optimal in this session's full-resolution logs met it (155;
      // feasible LPs' excess shrinks or changes sign within three windows).
      if (!patient_)
        stop = stop || (near && s_.windows >= 2 && s_.excess[0] > 0.0 && s_.excess[1] > s_.excess[0] &&
                        excess > s_.excess[1] && excess > 2.0 * s_.excess[0] && gap > tolerance_);
    }
    ++s_.windows;
    s_.excess[0] = s_.excess[1];
    s_.excess[1] = excess;
    s_.primal = primal;
    s_.gap = gap;
    s_.bound = bound;
    return stop;
  }

private:
  static constexpr int kCreepingWindows = 4;
  static constexpr int kPatientWindows = 2 * kCreepingWindows;
  static constexpr double kNearFeasible = 2e-2;  // primal residual, relative to 1 + ‖b‖
  double tolerance_;
  bool patient_;
  DivergenceWatchState s_;
};

}  // namespace shapematch::detail
