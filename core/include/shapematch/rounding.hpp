#pragma once
// Rounding the LP relaxation to a binary discrete graph surface by iterative fixing (§4.1,
// DESIGN.md §6), and reading the result (DESIGN.md §8).
#include "shapematch/errors.hpp"
#include "shapematch/lp.hpp"
#include "shapematch/product_space.hpp"

#include <functional>

namespace shapematch {

struct RoundingRound;

struct RoundingOptions {
  double threshold = 0.5;      // fix every variable above this to 1
  // Rounds that go forward (fix, search, or wait on a part at its cap) without bringing the free
  // variables to a new low, at most; then fail (InfeasibleError, naming the open rows) rather
  // than return a wrong answer. Rounds that do are progress and not counted: counted all, 200
  // ended a level-5 rounding of TOSCA_r cat2-cat9 (full resolution, cheap rounds with
  // --feasibility-later and --feasibility-skip-below) in 2.5 minutes while it
  // went from 641 k free variables to 268 k one fixing a round, and coarse to fine widened to
  // 11.3 M variables; not counted, the level finished 239 rounds after (docs/results-log.md,
  // seventy-fifth session).
  int max_rounds = 50;
  // Rounds that go forward in all, at most, new lows or not; then fail as above (0: no limit). A
  // budget for a bounded run (library callers and tests; no command-line flag), not a sign of
  // being stuck.
  int max_total_rounds = 0;
  // Rounds after the first with fewer free variables than this use Clp's dual simplex: exact,
  // and a vertex, so most of it is already 0/1 (0: never). The first-order solver's approximate
  // solutions made the last few thousand variables of FAUST at 4000 faces thrash for 50 rounds.
  int64_t exact_below = 30000;
  // Caps the exact solver's pivots on a part at this many per column (at least 1 000 columns'
  // worth); a part that reaches the cap goes to the first-order solver, as where Clp gives up
  // (0: no cap). Clp's dual simplex took 147 000 pivots (7.5 minutes) to prove a part of fewer
  // than 30 000 columns infeasible in FAUST_r 021-024's finest rounding, and 55 000 (10.5 minutes)
  // in deformation-transfer cat 0002-0009's; the optimal parts of those runs took at most 0.2
  // pivots per column of their round, the infeasible ones 0.7. At 2 (deformation-transfer cat
  // 0002-0009's level 6, fifty-eighth session) the cap bit on parts of 26 610 and 29 011 columns
  // after 149 and 597-646 s (about 11 ms a pivot), where without it one such part had taken over
  // 15 minutes; smaller caps not measured: off.
  double exact_pivots_per_column = 0.0;
  // Stops the exact solver on a part after this many seconds (Clp's clock: CPU time; 0: no limit);
  // the part goes to the first-order solver, and so do the parts of its size or larger for the
  // rest of this rounding (after the pivot cap's too; the LP's own time limit caps it as well). Measured (seventieth session, FAUST_r 043-063's level 6
  // at full resolution): 30 minutes of trims at 40-45 k free variables, Clp at 150-165 s on parts
  // of 24-26 k columns and 400 s to prove one infeasible, where PDHG proved such parts in 0.1-8 s;
  // those parts given to PDHG (--exact-below 10000), the level finished in 39 s. A minute is
  // several times what Clp took on an optimal part of that run.
  double exact_part_seconds = 60.0;
  // Where no variable exceeds the threshold (a fractional LP), DESIGN.md fixes the single
  // largest. On fractional levels that cost one full LP solve per face (TOSCA cat, 200 faces:
  // 9 rounds of 20–150 s fixed 36 variables to 1). Instead fix the largest variables of up to
  // this fraction of the open faces, none sharing a face with another, each at least half the
  // largest value (0: the single largest). Measured both ways on that pair only: 5.5 against
  // 12.5 minutes, but a worse Γ (docs/architecture.md).
  double fractional_batch = 0.125;
  // Replace the "pockets" that A x = b admits but Theorem 1 does not foresee (close_pockets).
  // Off by default: measured on FAUST_r 020-024 at 2000 faces, 14 pockets closed took the torn
  // vertices from 6 + 6 to 0 + 1 but the energy from 10.09 to 10.80 (gap 0.18 % -> 7.9 %), the
  // error unchanged (0.0328). Collapsing a star onto a point is the costliest continuous repair.
  bool close_pockets = false;
  // PDHG iterations of a round after the first, at most this many times the first LP's (and at
  // least later_round_min_iterations); then the round fixes from its iterate. Those rounds only choose fixings, the
  // bound is the first LP's, and every fixing is checked by propagation and, at the end, A x = b
  // exactly. Measured on FAUST_r 020-024 at full resolution: the first LP converged in 12 160
  // iterations, round 2's (a few million variables) sat at residual 2e-4 with its bound rising
  // past its objective for 39 000 iterations (20 minutes) without an answer. 0: no limit. A
  // capped LP whose certified bound is over 50 % above its objective is undone as infeasible.
  double later_round_iterations = 2.0;
  int64_t later_round_min_iterations = 2000;
  // Where round 1's LP stops as diverging (SolverParams::stop_on_divergence), the rows its stalled
  // primal iterate leaves furthest from b (|Ax − b| over a tenth of the largest) are blamed too,
  // beside the dual growth's: a creeping LP's growth is no ray yet (its Farkas rate negative) and
  // spreads over thousands of rows, while a residual that stalls through widenings sits where the
  // space cannot close. Measured why (TOSCA_r dog3-dog8 at full resolution): its finest first LPs
  // stalled at 3.65-3.7e-3 at 9.6, 12.7 and 14.4 M variables, through widenings of 1 583 faces
  // on such growths. The rows are logged either way (debug).
  bool blame_residual = false;
  // Where round 1's LP stops as diverging, look for a proof of infeasibility near
  // the rows its stalled primal iterate leaves furthest from b: the LP cut down to the rows of the
  // columns over the X faces within 0, 1, 2 … rings of theirs, a face row's far columns merged (a
  // relaxation, so a Farkas ray there proves the whole LP infeasible), while it has at most this
  // many columns (0: off). A proof replaces the guess: the error (LocalInfeasible) is certified,
  // names the ray's rows alone and the X faces the stalled rows lie on. None found is logged
  // (debug) and changes nothing. Not where round 1 starts from start_ones (a proof would be of the
  // LP with those fixings).
  int64_t local_proof_columns = 0;
  int local_proof_depth = 8;
  double local_proof_seconds = 600.0;  // in all
  // Its solver: a first-order one, whose dual at zero cost is checked as a Farkas ray (on
  // dog3-dog8's first region, 76 811 rows and 287 251 columns: a proof in 0.97 s), or Clp's dual
  // simplex, whose ray is sparse but which ran into the time cap there.
  std::string local_proof_solver = "pdhg-cpu";
  // Later rounds' first-order parts start from the primal weight ω that the last solve of their
  // columns ended with (the geometric mean over the part's columns), instead of lp's own
  // (initial_primal_weight; PDHG's start at 1 where that is 0). Those rounds start from the last
  // iterate, while the LPs of a full-resolution level settle at ω 5-200 (its first LP's log):
  // a capped round may spend its iterations climbing back. Measured at 2 000 faces only, no
  // gain (docs/results-log.md, fifty-first session): off.
  bool carry_weights = false;
  // A round whose LP stopped at its cap in some parts fixes only from the parts that converged;
  // the others go on from their iterate next round, and are fixed from an unconverged iterate
  // only after one round more with nothing else left. Off: measured on FAUST_r 020-024 at full
  // resolution it cost a round (47 s) and 0.24 % energy (24.626 against 24.568), and FAUST_r
  // 020-021 did not complete with it either (docs/results-log.md, eleventh session).
  // (Always on, with or without this option: a part that fails where no fixing of the last round
  // touches it goes on from its iterate with twice the cap where it only looks infeasible at its
  // cap, and releases the fixings of every round around it where it is proved infeasible or
  // still looks it at 16x the cap.)
  bool converged_first = false;
  // Where the candidates of a round clash (propagation refutes fixing them all), a round whose LP
  // has more free variables than this fixes each candidate that does not clash with the larger
  // ones before it; smaller rounds halve the batch until it goes through (and solve again for
  // the rest). Measured on FAUST_r 020-024: at 2000 faces (round 1: 0.9 M variables) halving
  // took 15 rounds, 1 s in all, energy 10.0997, error 0.0326; greedy 2 rounds, 10.1155, 0.0333.
  // At full resolution (round 1: 7.5 M variables) halving left 2.3 M variables to round 2, whose
  // LP alone ran 12-20 minutes. 0: always greedy.
  int64_t greedy_above = 2'000'000;
  // A greedy round fixes only candidates away from the LP's undecided part: none of their rows
  // holds a free variable valued in (greedy_unsure, 1 − greedy_unsure), nor lies within
  // greedy_margin − 1 closedness steps of one (0: fix every candidate). Where under a quarter of
  // the batch qualifies, only values in (0.3, 0.7) count; where none does then, greedy_fallback.
  // Measured at full resolution: without it the LPs after greedy rounds were infeasible round
  // after round; with it, none of rounds 2-5 (docs/results-log.md, seventh session).
  double greedy_unsure = 0.1;
  int greedy_margin = 1;
  // Where no candidate qualifies even then, the largest of each undecided region, at most this
  // share of the batch (at least one); 1: the whole batch (the default up to the fifty-first
  // session). Up to the seventy-first session the largest share regardless of regions (see
  // away_from_undecided for the regions' measurement).
  // Counted in the -v logs of eighteen full-resolution runs or segments (tools/greedy_rounds.py;
  // docs/results-log.md, fifty-first session): after a whole-batch fallback the next LP was
  // infeasible 16 times in 30 (from an optimal LP) and 5 in 5 (from one at its cap), against
  // 0-7 % after rounds whose candidates stood away from (0.1, 0.9). With 0.125 (fifty-second
  // session, one thread each): 0 of 26 such rounds in three pairs; TOSCA_r centaur2-4 13 min
  // against 23, FAUST_r 016-020 36 min against over 100 (the whole batch: stuck three times in
  // its level 6 and not finished), and FAUST_r 024-043, which had never finished, in 23 min.
  double greedy_fallback = 0.125;
  // The fixings to 1 an infeasibility proof blamed are left out of the candidates (while any
  // other remains) at the state they were made from also after undoing earlier fixings took the
  // rounding away from it and back (a state is its variables' values). Without it they were
  // forgotten there: FAUST_r 043-065 at full resolution (a seventy-second session run), level 6's
  // rounding went round one cycle of 17 rounds (the same states, LP iterations and objectives,
  // the same two candidates fixed by the fallback and blamed) at least four times
  // (docs/results-log.md, seventy-third session).
  bool remember_refuted = true;
  // Rounds after the first solve each connected component of their LP (rows joined through a
  // shared column) on its own: the parts below exact_below exactly, the others with the
  // first-order solver and their own cap, and an infeasible part's proof blames only the
  // fixings around it. Late in rounding the open faces form separate patches; as one LP, every
  // patch waited for the slowest and was rounded from its unconverged iterate.
  bool split_parts = true;
  // Where rounding stalls on a small remainder (its free variables no fewer than their fewest
  // for search_stall rounds in a row, and at most search_below of them), each part of it is
  // finished by a depth-first search over exact LPs (at most search_nodes each), and where a part
  // has no binary solution the fixings around it are released (within 2 LP steps, 4, 8 … where
  // the same part fails again; at most max_releases times) rather than undone in the order they
  // were made. Measured, TOSCA_r horse0-5 at full resolution: 150 rounds fixed and undid the
  // same few variables of a 1 082-variable remainder in 2 parts, each solved exactly with a
  // fractional vertex, until max_rounds; with the search, a 2 272-variable remainder (10 parts)
  // was finished in 16 nodes and one release of 447 fixings, and the pair verified
  // (docs/results-log.md). 0: never.
  int64_t search_below = 20000;
  int search_stall = 3;
  int64_t search_nodes = 2000;
  // The search goes back, where both values of a branch have failed, to the deepest decision
  // that the failures' proofs needed (their Farkas rays, or the rows propagation stopped at,
  // checked on those decisions alone), not to the one above it. False: back one level at a time.
  bool search_backjump = true;
  // Where the search proves parts without a binary solution (every failure with a Farkas vector),
  // release the fixings outside them that those proofs rest on, rather than every fixing within
  // 2, 4, 8 … LP steps of them (which stays the fallback). False: always the latter.
  bool search_proof_release = true;
  // Where the same part fails again and the next release around it would reach beyond this many
  // LP steps (where it starts, or where nothing nearer was left to release), the rounding is
  // stuck there instead (a StuckError naming the part's rows where
  // stuck_after is set, else an InfeasibleError): coarse to fine widens around it. A release
  // that reaches far frees most fixings (measured, TOSCA_r horse0-horse5 at full resolution:
  // 9 588 of about 11 000 within 8 steps, an 8.2 M-variable LP of over an hour on one thread),
  // and the same part failed after releases of 59, 267 and 2 939. 0: no cap (the default).
  int release_reach_cap = 0;
  int max_releases = 12;
  // Where a part's LP has failed after this many trims of the last fixing in a row (each failure
  // sharing a row with the next), release the fixings around it (as above) instead of trimming
  // again: the trims only reach the last round's fixings. 0: never (the default). Measured, FAUST_r
  // 024-043 at full resolution: without it (an H200), four failures in a row trimmed 19, 16 and
  // 1 fixings and then halved the rest, and the level was solved again in a widened space four
  // times before the run's 8.5-minute limit; with 1 (2 cores), the releases took the rounding on without a stuck widening for 31
  // rounds, but the rounds after a release fixed 15-40 variables each from capped LPs, and the
  // stall rule gave up into a widening of 4 730 faces, after which the level finished (verified,
  // the pair's first completed run; docs/results-log.md, thirtieth session).
  int release_after_trims = 0;
  // Where an LP after fixings is proved infeasible by a Farkas certificate whose margin outweighs
  // everything undoing the last fixing could take off it (so the LP before that fixing is
  // infeasible too), release the fixings of any step that carry the margin, heaviest first, until
  // the certificate no longer holds, instead of trimming the last fixing (certificate_blame.hpp).
  // Why: TOSCA_r horse0-horse5 at full resolution (seventy-ninth session's log, without it): after
  // a round from a capped LP, trims of the last fixing by proof blamed 18 of 75, 3 of 57 and 1 of
  // 54 fixings in turn, each after 5-15 minutes of zero-cost solving, until the stuck rule widened
  // the level. Measured at test scale only (the rounding tests' cycle carried in steps: 3 rounds
  // and one infeasible LP against 5 and two); not yet seen firing at 3 000 faces or above
  // (docs/results-log.md, eightieth session).
  bool certificate_release = true;
  int max_backtracks = 200;    // fixings undone after an infeasible LP (each one more, smaller LP
                               // solve) since the last round with fewer free variables than any
                               // before it (the round after a release is one), then fail with
                               // InfeasibleError naming the open rows
  // Fixings to 1 made before round 1: a partial Γ carried over from an attempt in a narrower
  // space (coarse to fine, after widening where that attempt got stuck). Each that fits is
  // fixed (in order; the rest are dropped), and round 1 solves what they leave, so its bound is
  // no bound of the whole LP: the result's lower_bound is then certified from `start_dual` (one
  // value per row, e.g. an earlier first LP's dual mapped over; −∞ without it).
  std::vector<int64_t> start_ones;
  // With start_ones: the step of the undo history each was fixed in (parallel to it, as `decided`
  // gives them), each step then fixed as its own, in the steps' order: a run gone on from a checkpoint
  // undoes its last step first where its LP fails, as the run that saved it would have, rather
  // than trimming all of them as one fixing. Empty: one step.
  std::vector<int32_t> start_steps;
  std::vector<double> start_dual;
  // A cold solve of the whole LP, where round 1 is a warm LP that understates it: a start from
  // carried fixings (a smaller LP) or coarse to fine's re-solve after pricing (from a nearby
  // optimum). Its seconds scale stuck_after, its iterations the later rounds' cap. 0: this
  // rounding's own round 1.
  double reference_seconds = 0.0;
  int64_t reference_iterations = 0;
  // The multiple of the later rounds' iteration cap to start from (at least 1; at most 16, where
  // the doubling stops): a run gone on from a checkpoint (coarse to fine keeps it there) starts
  // where the saved rounding had got, not at 1. Measured, TOSCA_r horse0-horse5 at full
  // resolution (seventy-seventh session): gone on at 1 after the saved rounding had doubled it,
  // its first round fixed from an iterate at the 1x cap again, the next LP was infeasible, and the
  // fixing was undone whole and the cap doubled again: 15 minutes to get back where it had been.
  double start_cap_scale = 1.0;
  // Round 1's iterations at most (0: lp.max_iterations alone). Coarse to fine caps a warm solve
  // after pricing at the cold solve's count: measured on the cat at full resolution, such a
  // re-solve crept to tolerance in 11 328 iterations (17 minutes) against 4 480 cold.
  int64_t first_max_iterations = 0;
  // Before round 1's LP (a first LP, not one from start_ones), solve it without its costs for at
  // most this many iterations, cold (PDHG only): an infeasible one is proved there, and the
  // InfeasibleError names the clash alone; a feasible one goes on to its costed solve, unwatched
  // for divergence where the pre-test converged (RoundingRound::feasibility_iterations).
  // Measured (sixty-eighth session): full-resolution first LPs of TOSCA_r horse0-horse10 (13.9 M
  // columns) proved infeasible at zero cost in 704 iterations (3 minutes on one core), where the
  // costed solve of the attempt before them took 1.5 hours; at 3 000 faces 192-320 against a
  // costed divergence stop at 1 024-1 536 and proof at 2 560-5 632. Feasible LPs converge without
  // costs not always sooner than with them (192-3 072 against 1 216-3 136 cold): the cap bounds
  // what the pre-test costs them. Off by default: a proof widens less than the divergence watch's
  // suspicion with its margin, and at 3 000 faces two of three pairs ended 2-4 % higher in energy
  // and 4-9 % in mean error for it (match --feasibility-first 1024 is the measured setting). With
  // the margin since (CoarseToFineOptions::zero_cost_proof_rings) one of them is back; the other's
  // loss came from a false suspicion's widening that a pre-test avoids.
  // 0: off.
  int64_t feasibility_iterations = 0;
  // The same for the later rounds: each part the first-order solver would solve is first solved
  // at zero cost, cold, for at most this many iterations; where one is proved infeasible there,
  // its certificate is the round's proof and no costed solve runs (the round has failed);
  // otherwise the costed solves run as before.
  // Why: at full resolution a later round's infeasible LP takes the costed solve 13 000-23 000
  // iterations to prove (FAUST_r 043-063 without WKS, level 6: 70-900 s per round on one core, a
  // dozen such rounds in a row), and a failed part proved again at zero cost took 320-1 920
  // (sixtieth session). Measured there with 2 048 (sixty-ninth session): three rounds proved in
  // 1 344-1 408 iterations (33-38 s against 40-140), one LP proved that the costed solve had left
  // at its cap; but parts within the tolerance of feasible at zero cost that the costed solve then
  // proves infeasible pay both, and feasible rounds about 40 s. The skip below (a part whose
  // costed solve ends optimal first is not pre-tested) took that cost away: with both, TOSCA_r
  // cat2-cat9 and horse0-horse5 finished level 5's full-resolution rounding in 2-16 minutes, and at
  // 3 000 faces three pairs ended within 0.7 % in energy and 0.0001 in mean error of the run
  // without (docs/results-log.md, seventy-fifth and seventy-sixth sessions). Hence on: 8 192.
  int64_t later_feasibility_iterations = 8192;
  // With later_feasibility_iterations: each part's costed solve runs first for at most this many
  // iterations, from the round's warm start (where its cap is larger, and the pre-test's cache
  // does not pass it anyway); a part optimal by then skips its pre-test (its result stands), the
  // others are pre-tested and their costed solve goes on from there. 0: off, every part pre-tested
  // first. Measured on FAUST_r 043-065 without WKS, level 6 from one checkpoint (476 k free
  // variables), 12 minutes side by side: with 512, 101 rounds against 48 and 283 k free variables
  // against 471 k; but its round 89 took an LP as optimal in 64 iterations (relative residual
  // 2.64e-3, under `tol` 3e-3) that the pre-test, run on the same state from its checkpoint,
  // proved infeasible in 3 712 iterations (seventy-fourth session): hence the bound in a row
  // below. With it, TOSCA_r cat2-cat9 (WKS, --feasibility-later 8192 --feasibility-tol 1e-5
  // --exact-below 10000) from a checkpoint in level 5's rounding (641 k free variables; rounds of
  // 12-19 s, 11-18 s of them the pre-tests): level 5 finished in 239 rounds (2:43) and level 6 in
  // 49 rounds after its first LPs, the pair's first full-resolution Γ, where every part
  // pre-tested first was at 445 k free variables after 15 minutes (docs/results-log.md,
  // seventy-fifth session).
  int64_t later_feasibility_skip_below = 512;
  // … and only where that solve's relative primal residual is at most this (0: any optimal one).
  // The LP above ended at 2.64e-3; from the same checkpoint 1e-3 kept the 512 run's path for 32
  // rounds (no pre-test it let run proved anything there) at 34 rounds in 12 minutes against 91:
  // 0, the bound in a row does that job.
  double later_feasibility_skip_residual = 0.0;
  // … and only where that solve's largest violation of a row (‖Ax−b‖∞, LpResult::row_residual)
  // is at most this (0: any). The LP above ended 0.034 off in a row; rounding's costed solves of
  // feasible LPs at full resolution ended at most 0.018 off, most 0.002-0.006 (467 solves,
  // seventy-second session): a bound in a row tells what the relative one could not at 3e-3.
  // On cat2-cat9 above, 554 first-iteration solves ended optimal, 4 of them 0.021-0.024 off (each
  // pre-tested, none proved infeasible), the others at most 0.014.
  double later_feasibility_skip_row = 0.02;
  // The tolerance of the zero-cost solves: both pre-tests, and the re-proof of a part the costed
  // solve proved infeasible (0: the LP's own). At zero cost PDHG's "optimal" says only that the
  // relative residual is under it; at full resolution 3e-3 of 1 + |b| let parts through that had
  // no feasible point (sixty-ninth session), so a tighter one keeps solving those until a proof or
  // the cap. Measured (seventieth session, FAUST_r 043-063's thrashing level-6 rounding): with
  // later_feasibility_iterations 8 192 and 1e-5, round 1's LP that every other setting had fixed
  // from was proved infeasible at zero cost (2 624 iterations), and the rounding went from 1.70 M
  // free variables to 50 k in 26 minutes where the others stayed at 1.4 M after 40; either alone
  // did not. At 3 000 faces the same energies, 11 % slower. The default since the
  // seventy-sixth session, with later_feasibility_iterations (see there).
  double feasibility_tolerance = 1e-5;
  // Where the LPs after fixings have failed (infeasible, or looking it at their cap) round after
  // round, at least stuck_rounds of them taking over this many times round 1's seconds in all,
  // give up with a StuckError naming the last failed parts' rows and carrying the fixings to 1
  // made so far, so that the caller can widen the space there and solve again, afresh or from
  // them (coarse to fine does). Measured, FAUST_r 020-021 at full resolution: trimming the last
  // fixing, and releasing the fixings around the failed part, both ran for 15+ minutes
  // (docs/results-log.md). Running out of rounds (max_rounds, max_total_rounds) then ends in a
  // StuckError too. 0: never (rounding goes on as before).
  double stuck_after = 0.0;
  int stuck_rounds = 4;
  // With stuck_after: stuck also where the free variables have reached no new low for this many
  // rounds taking over stuck_after × round 1's seconds, whatever their LPs did (rounds that fix
  // and are undone in turn never fail stuck_rounds times in a row). Measured at full resolution:
  // FAUST_r 020-024 without WKS, level 5, 41 rounds and 6 minutes between 20 k and 50 k free
  // variables after a low of 11 k; the longest such stall in runs that finished, 12 rounds and
  // 15 s against a 113 s first LP. Counted afresh after every release of fixings (a failed LP's
  // or a search's). 0: off.
  int stuck_stalled = 12;
  // Give up (StuckError) once the rounds after round 1 have done over this many times round 1's
  // work in all, whatever they did: a budget for a rounding whose Γ is optional (coarse to fine's
  // second start). Work is LP iterations times free variables (round 1's: reference_iterations
  // where given), not seconds, so that the same run gives up at the same round. 0: none.
  double give_up_after = 0.0;
  std::string solver = "pdhg-cpu";
  // Parameters of every LP solve. Later rounds' warm starts are filled in; a warm start given
  // here over the whole LP (as many values as it has columns and rows) starts round 1.
  SolverParams lp;
  // Called once with round 1's iterate over the whole LP (fixed variables at their values, rows
  // that propagation emptied at 0), also when rounding then fails: where a diverging LP makes
  // coarse to fine widen the space, the widened LP can start from it (warm_widening, off by
  // default: measured slower). After divergence, the rows on
  // which the dual grew (over 1 % of the largest growth) are 0: there it had left for infinity.
  // Not called after a proven infeasible LP (no iterate).
  // `primal_weight`: the solver's ω where it stopped (LpResult::primal_weight; NaN if none).
  std::function<void(const std::vector<double>& x, const std::vector<double>& y, double primal_weight)> first_iterate;
  // Called with round 1's LP (what propagation left free, as solved; not its warm start) just
  // before it is solved, where round 1 is a first LP (not one from carried fixings).
  std::function<void(const LpProblem& lp)> first_lp;
  // Called with each later round's part that the exact solver took slow_part_seconds or more on
  // (as solved), for solving it again on its own with other solvers or settings.
  std::function<void(const LpProblem& part)> slow_part;
  double slow_part_seconds = 10.0;
  // Called after each round (after `progress`) with the decisions so far, the fixings to 1 that
  // rounding chose (sorted; not what propagation forced, which follows from them), the step of
  // its undo history each belongs to (0 the oldest; parallel to them), and round 1's certified
  // bound: where the rounding has got, for a checkpoint (coarse to fine) that a later run goes on
  // from with start_ones and start_steps; and the next round's warm start over the whole LP (the
  // last iterate kept), which such a run can start its round 1 from (`lp`'s initial_x/y).
  std::function<void(const RoundingRound& round, const std::vector<int64_t>& ones, const std::vector<int32_t>& steps,
                     double first_bound, const std::vector<double>& x, const std::vector<double>& y)>
      decided;
  // Where probe_tolerance is above lp.tolerance and `probe` is set, round 1's LP is solved first
  // to probe_tolerance and `probe` gets that iterate (over the whole LP, as first_iterate's) if it
  // was optimal there; it may throw to abandon the rounding (coarse to fine prices a wider space
  // with it). The solve then goes on from that iterate and its primal weight to lp.tolerance;
  // round 1 reports both solves' iterations. A probe that ends otherwise (diverging, infeasible,
  // at a limit) is round 1's result.
  double probe_tolerance = 0.0;
  std::function<void(const std::vector<double>& x, const std::vector<double>& y, double primal_weight)> probe;
  // Where set and snapshot_seconds > 0: called every snapshot_seconds at most during round 1's
  // first-order solve (not its pre-test, not later rounds) with the point it would restart from,
  // over the whole LP as first_iterate's, its iterations and seconds so far (a probe's included,
  // and resumed_*), and whether that solve had the divergence watch on (the pre-test can turn it
  // off), for a checkpoint that a later run starts that LP from (SolverParams::snapshot). Its
  // `state` is the solve's whole state over the LP round 1 solves (SolverParams::exact_state).
  std::function<void(const SolveSnapshot& whole, bool watched)> first_snapshot;
  double snapshot_seconds = 0.0;
  // Where set and snapshot_seconds > 0: called every snapshot_seconds at most during each round
  // from fixings (a later round, or round 1 from start_ones), in its parts' costed first-order
  // solves (not their pre-tests, nor the short first solves that may skip one), until a part
  // fails, with the next round's warm start as it would be were the round
  // to end there, over the whole LP as `decided`'s (the parts solved so far as they ended, the one
  // under way where it is, the others as they started): for a checkpoint beside the last `decided`
  // one, so that a later run starts that round there rather than from the round before's iterate.
  // (With the primal weight of the part under way.) Also where a stop (request_stop) comes before
  // the round's LP saved anything (a part's pre-test or first short solve), with the round's warm
  // start and ω 0, before the Stopped goes on: the caller's last `decided` may not have been saved.)
  std::function<void(const std::vector<double>& x, const std::vector<double>& y, double primal_weight)> round_snapshot;
  // Round 1's LP goes on from such a snapshot (its warm start in `lp`) after these: they count in
  // round 1's iterations and seconds wherever those scale the later rounds (where reference_*
  // are not given) and in its snapshots.
  int64_t resumed_iterations = 0;
  double resumed_seconds = 0.0;
  // … and from this whole state of it (a first_snapshot's), exactly, where it is that LP's: the
  // same iterations as uninterrupted (SolverParams::resume_state); else from the warm start.
  std::shared_ptr<const SolverState> resumed_state;
  // Where the LP has at most alternatives_below columns, the rounding runs again from round 1's
  // iterate with each of these thresholds (round 1 then only confirms that optimum), and the Γ of
  // least energy is returned, with the threshold that found it. Fixing by a threshold is greedy,
  // and which variables cross it first decides where a coarse level lands: on FAUST_r 020-024 at
  // 200 faces, 0.5 ended at 2.851 and 0.7 at 2.741 (LP bound 2.628), and two full-resolution runs
  // that differed at their 200-face level by 2.906 against 2.958 ended at 15.1 against 19.9
  // (docs/results-log.md). An alternative that fails (no Γ, stuck, an LP that gives up) is dropped.
  // Not with start_ones. Empty: one rounding.
  std::vector<double> alternative_thresholds = {0.7};
  int64_t alternatives_below = 1'500'000;
  // Where the rounding at `threshold` fails (no Γ, stuck, an LP that gives up) after an optimal
  // round 1, the alternatives still run from that optimum, and the error is rethrown only where
  // none finds a Γ. For a rounding whose Γ is optional and that has a budget (give_up_after;
  // coarse to fine's second start): measured, FAUST_r 020-024 at 500 faces, the 200-face full
  // space's rounding at 0.5 spent 135 s after its 25 s round 1 (three of its LPs failed) before
  // it ended at 2.783, where 0.7 found 2.634 in 7 s.
  bool alternatives_after_failure = false;
};

struct RoundingRound {
  int round = 0;
  int64_t variables = 0;       // free variables in this round's LP
  int64_t constraints = 0;
  int64_t fixed_to_one = 0;    // fixed after this round's solve
  int64_t fixed_to_zero = 0;   // forced to 0 by propagation
  LpStatus status = LpStatus::Optimal;
  int64_t iterations = 0;
  int64_t parts = 1;           // independent parts its LP was solved in (split_parts)
  int64_t exact_parts = 0;     // of those, solved by the exact solver
  // PDHG's primal weight ω in the round's largest first-order solve: asked to start from (0: the
  // solver's own; round 1: its first solve's, before any probe) and ended with (NaN: none).
  double start_primal_weight = 0.0;
  double primal_weight = std::numeric_limits<double>::quiet_NaN();
  double objective = 0.0;      // of this round's LP, including the fixed part
  double seconds = 0.0;
  // Round 1's solve at zero cost before it (RoundingOptions::feasibility_iterations), not counted
  // in iterations and seconds.
  int64_t feasibility_iterations = 0;
  double feasibility_seconds = 0.0;
  // Of a later round's seconds, those of its parts' zero-cost pre-tests
  // (RoundingOptions::later_feasibility_iterations): measured, FAUST_r 043-065's level 6 spent 79 %
  // of its end game's seconds there (docs/results-log.md, seventy-third session).
  double later_pretest_seconds = 0.0;
  bool undone = false;         // the fixing made the LP infeasible and was replaced by a smaller one
  double cap_scale = 1.0;      // the later rounds' iteration cap multiple after this round
  int64_t searched_parts = 0;  // parts finished by search (search_below); iterations: its nodes
  bool search = false;         // finished by search (search_below), not by an LP
  int64_t released = 0;        // fixings released around parts without a binary solution (search)
                               // or around a failed part no fixing of the last round touched
  // Of a release around a part (released, not by proofs): how far it reached, in LP steps, and
  // the fixings made before it. A far release frees most of them (TOSCA_r cat2-cat9 without WKS at
  // full resolution: 8 830, after releases of 390, 280 and 950 in its end game); the log says so.
  int release_depth = 0;
  int64_t release_pool = 0;
  int64_t search_proof_released = 0;  // fixings released that a search's proofs rest on
                                      // (RoundingOptions::search_proof_release; also in released)
  int64_t certificate_released = 0;  // fixings released where an infeasibility proof lies
                                     // (RoundingOptions::certificate_release)
};

struct RoundingResult {
  std::vector<int64_t> gamma;  // selected variables (indices into the space), sorted
  double energy = 0.0;         // Σ energy of Γ, unscaled
  int64_t pockets_closed = 0;  // pockets replaced after rounding (close_pockets)
  double lower_bound = 0.0;    // certified bound of the first LP
  double gap = 0.0;            // (energy − bound) / |bound|
  LpResult first_lp;           // the relaxation before any fixing (with start_ones: after those)
  std::vector<RoundingRound> rounds;  // of the rounding that found Γ
  double threshold = 0.5;      // the threshold that found Γ (RoundingOptions::alternative_thresholds)
  std::vector<std::pair<double, double>> tried;  // (threshold, energy) of every rounding run; NaN: no Γ
};

// Rounding gave up where the LPs after its fixings kept failing (RoundingOptions::stuck_after):
// rows() are the failed parts' rows; ones() the fixings to 1 it had made and steps() the undo
// step of each (as RoundingOptions::decided gives them), and x(), y() its last iterate over the
// whole LP, to go on from in a wider space.
class StuckError : public InfeasibleError {
public:
  StuckError(const std::string& what, std::vector<int64_t> rows, std::vector<int64_t> ones, std::vector<double> x,
             std::vector<double> y, std::vector<int32_t> steps = {})
      : InfeasibleError(what, std::move(rows)), ones_(std::move(ones)), steps_(std::move(steps)), x_(std::move(x)),
        y_(std::move(y)) {}
  const std::vector<int64_t>& ones() const { return ones_; }
  const std::vector<int32_t>& steps() const { return steps_; }
  const std::vector<double>& x() const { return x_; }
  const std::vector<double>& y() const { return y_; }

private:
  std::vector<int64_t> ones_;
  std::vector<int32_t> steps_;
  std::vector<double> x_, y_;
};

// Round 1's LP proved infeasible by the zero-cost pre-test (RoundingOptions::feasibility_iterations):
// coarse to fine gives such a proof the margin the divergence watch's suspicion would have had
// (CoarseToFineOptions::zero_cost_proof_rings).
class ZeroCostInfeasible : public InfeasibleError {
public:
  using InfeasibleError::InfeasibleError;
};

// Round 1's LP proved infeasible by a local proof near its stalled rows (RoundingOptions::
// local_proof_columns): the X faces the proof grew from and how many rings out it was found, so
// coarse to fine can check the same region again in a widened LP before solving it (a
// full-resolution first LP takes an hour to stall again where a widening did not help).
class LocalInfeasible : public InfeasibleError {
public:
  LocalInfeasible(const std::string& what, std::vector<int64_t> rows, std::vector<int> x_faces, int rings)
      : InfeasibleError(what, std::move(rows), true), x_faces_(std::move(x_faces)), rings_(rings) {}
  const std::vector<int>& x_faces() const { return x_faces_; }
  int rings() const { return rings_; }

private:
  std::vector<int> x_faces_;
  int rings_ = 0;
};

// Calls `progress(round)` after each round (for a progress line); may be empty.
RoundingResult round_to_graph_surface(const ProductSpace& space, const LpProblem& lp, const std::vector<double>& energy,
                                      const RoundingOptions& options = {},
                                      const std::function<void(const RoundingRound&)>& progress = {});

// (energy − bound) / |bound|, and 0 where the energy meets the bound to rounding error.
double relative_gap(double energy, double bound);

// Unit propagation of A x = b over binary x with nothing fixed, leaving out the rows marked in
// `skip` (empty: none): the row where it finds a contradiction, or -1 if it finds none.
int64_t propagation_conflict(const LpProblem& lp, const std::vector<char>& skip = {});

// A pocket: an edge u-w of X stretched over the whole star of a connected set K of vertices of
// Y, u paired with exactly K and w with the star's rim (product triangles (u, w, w) x (k, b1, b2)
// and (w, u, u) x (r, k1, k2)), where nothing else pairs u with K. It satisfies A x = b, but
// relates u to K apart from the rest of u's fibre: a tear (Theorem 1 says A x = b rules tears
// out; it does not). The same star collapsed onto w ((w, w, w) x each face) has the same
// boundary and covers the same faces, and tears nothing; likewise with X and Y swapped.
// Measured on FAUST_r 020-024 at 2000 faces (Γ saved by match): 15 pockets, torn vertices
// 6 + 6 -> 0 + 1, with one tip (12) and two. Replaces every pocket whose replacement is in the
// space; returns the new Γ (sorted) and counts the pockets in `closed`.
std::vector<int64_t> close_pockets(const ProductSpace& space, const std::vector<int64_t>& gamma,
                                   int64_t* closed = nullptr);

// A x = b checked exactly in integers for the 0/1 vector with ones at `gamma`.
bool satisfies_exactly(const LpProblem& lp, const std::vector<int64_t>& gamma);

// What Theorem 1 promises, checked on a result.
struct GraphSurfaceCheck {
  bool covers_x = false, covers_y = false;      // every face of X (Y) in exactly one product triangle
  bool orientation = false;                     // every real face mapped with its own cyclic order
  // Every point related to a connected set of the other shape (see check_graph_surface):
  bool continuous = false;                      // no discontinuous vertex or edge on either side
  int64_t discontinuous_vertices_x = -1;        // vertices of X whose fibre in Y is disconnected
  int64_t discontinuous_vertices_y = -1;
  int64_t discontinuous_edges_x = -1;           // edges of X whose relation (interior and end
  int64_t discontinuous_edges_y = -1;           // points) to Y is disconnected
  bool ok() const { return covers_x && covers_y && orientation && continuous; }
};
GraphSurfaceCheck check_graph_surface(const ProductSpace& space, const std::vector<int64_t>& gamma);

// Vertex maps read off Γ: for every vertex one partner on the other shape, preferring partners
// from product triangles that are real on both sides; then, where a vertex's faces map to
// inverted (or degenerate) triangles, another partner from its fibre that inverts fewer.
struct VertexMaps {
  std::vector<int> x_to_y;
  std::vector<int> y_to_x;
};
VertexMaps vertex_maps(const ProductSpace& space, const std::vector<int64_t>& gamma, bool untangle = true);

}  // namespace shapematch
