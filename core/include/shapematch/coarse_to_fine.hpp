#pragma once
// Coarse-to-fine matching (§5, DESIGN.md §7): solve and round at the coarsest level, then at
// each finer level only over the product triangles near the coarser level's Γ (eq. 17).
#include "shapematch/hierarchy.hpp"
#include "shapematch/matching.hpp"
#include "shapematch/rounding.hpp"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <limits>
#include <string>

namespace shapematch {

// Where the rings of the reduced space are counted. Coarse: eq. (17) as written, N on the coarse
// level on both sides, so one ring adds a whole coarse face's width on X and on Y. Fine: the
// coarse Γ at ring 0 picks the coarse Y faces, and rings widen on the fine level: ring 1 adds one
// fine ring around their children on Y; ring k >= 2 adds k - 1 fine rings on Y and lets X faces
// at a coarse face's border also take the allowances of their fine neighbours' parents. Measured
// on FAUST_r 020-024 / 021-029 at 1000 faces (3 levels from 100): 0.93 M / 2.0 M variables
// against 2.9 M for coarse ring 1, 36 s / 180 s against 538 s / 449 s, mean geodesic error
// 0.048 / 0.051 against 0.050 / 0.065.
enum class Neighbourhood { Coarse, Fine };

// A first LP's iterate kept by variable and row identity, to start the LP of another space of
// the same meshes from it (coarse to fine: the next attempt of a level after a widening, which
// adds a few hundred faces' candidates to millions of variables; at full resolution each
// attempt's LP took 3 000-4 000 iterations, 5-8 minutes on 2 cores, from zero). Variables and
// rows the kept LP lacks start at 0; the dual is rescaled to the new LP's cost scale.
class CarriedIterate {
public:
  bool empty() const { return scale_ == 0.0; }
  // `x` may be empty: the dual alone (every variable then starts at 0). `primal_weight`: the
  // solver's ω with that iterate (0 or NaN: none).
  void keep(const MatchingLp& m, const std::vector<double>& x, const std::vector<double>& y,
            double primal_weight = 0.0);
  // Fills params.initial_x / initial_y (and initial_primal_weight, where kept) for `m` (nothing
  // where empty).
  void apply(const MatchingLp& m, SolverParams& params) const;
  // After apply: the rows of `m` the kept LP lacks (they hold only columns it lacked) get duals
  // in `y` that maximise the Lagrangian bound over them by `sweeps` sweeps of coordinate ascent,
  // the other duals fixed, instead of 0. Returns how many rows that was.
  int64_t ascend_new_rows(const MatchingLp& m, std::vector<double>& y, int sweeps) const;

  // The vertex pairs of a product triangle, hashed (its faces follow from them); a collision
  // only misplaces a warm-start value (or a carried fixing, which propagation then checks).
  static uint64_t key(const ProductTriangle& t);

  // What it holds, for a checkpoint (LevelAttempt::priced_from): the nonzero primal values by key
  // (keys sorted), the kept LP's closedness rows' product edges (sorted) and all its duals.
  struct Parts {
    std::vector<uint64_t> keys;
    std::vector<double> values;
    std::vector<int64_t> row_edge;
    std::vector<double> y;
    int64_t closedness_rows = 0;
    double scale = 0.0, primal_weight = 0.0;
  };
  Parts parts() const;
  // The same parts without copies, for writing one out (a checkpoint's at 30 M variables: some
  // hundred MB each): the nonzero primal values by key (sorted), and the rest as in Parts.
  const std::vector<std::pair<uint64_t, double>>& values_by_key() const { return x_; }
  const std::vector<int64_t>& row_edges() const { return row_edge_; }
  const std::vector<double>& duals() const { return y_; }
  int64_t closedness_rows() const { return closedness_rows_; }
  double scale() const { return scale_; }
  double primal_weight() const { return primal_weight_; }
  // Throws InvalidInputError where the parts do not fit together (sizes, order, values).
  static CarriedIterate from_parts(Parts p);

private:
  std::vector<std::pair<uint64_t, double>> x_;  // sorted by key; only the nonzero values
  std::vector<int64_t> row_edge_;
  std::vector<double> y_;
  int64_t closedness_rows_ = 0;
  double scale_ = 0.0;
  double primal_weight_ = 0.0;
};

struct CoarseToFineOptions {
  HierarchyOptions hierarchy;
  Neighbourhood neighbourhood = Neighbourhood::Fine;  // measured: as accurate, 2.5-15x faster
  int ring = 1;      // N(f) = faces within this many rings of f's vertices (eq. 17)
  int max_ring = 3;  // widen up to this when a reduced LP is infeasible
  // The ring at the levels below the finest with at most coarse_ring_faces faces (on X; 0: `ring`
  // everywhere). There ring 1 held the chain in the tube around a coarser Γ that was wrong in
  // places; ring 2 lets those levels move away from it, at 2-3x their LP sizes. Measured, FAUST_r
  // 020-021 at full resolution: with ring 1, X's left arm went wrong at the 532-face level
  // (level maps: its points 0.16 off there, 0.21 at the end) and the run ended at energy 21.75,
  // error 0.0377; with ring 2 at the 200- to 3 760-face levels, energy 13.12, error 0.0194, in
  // 18 minutes against 9 (ring 2 only up to 1 414 faces: level 4 as good, 5.36 against 6.18, but
  // the finest level's LP at 15.3 and its rounding thrashing; stopped after 21 minutes).
  // docs/results-log.md, twenty-second session.
  int coarse_ring = 2;
  int coarse_ring_faces = 4000;
  // First widen only near the proof of infeasibility (the places where propagation finds a
  // contradiction, or a Farkas certificate's rows), up to this many times per level, before
  // widening everywhere. Measured, FAUST_r 021-029 at 1000 faces (3 levels from 100, bending
  // 0.1): local 25 s, 1.17 M variables, error 0.065; global 165 s, 2.0 M, error 0.054. At 2000
  // faces (020-024): 141 s against 477 s. At full resolution (10 002 faces) 020-024 needed 8
  // local widenings (of 9 to 1006 faces); after 6 the global one made 22.8 M variables.
  bool local_widening = true;
  int max_local_widenings = 24;
  // Local widenings where unit propagation found the contradiction (before any LP) are counted
  // apart, up to this many per level: each costs a rebuild of the space (about 4 s at 4 000 faces,
  // 12 s at full resolution), not an LP. Measured, FAUST_r 026-029 and 016-026 at 4 000 faces:
  // 24 such widenings of 5-300 faces each, each revealing the next contradiction next to it, used
  // up max_local_widenings, and the ring then widened everywhere (4.9 M → 9.0 M and 10.1 M
  // variables; 508 s with a gap of 7.4 %, and over 600 s).
  int max_propagation_widenings = 64;
  // Where propagation's contradiction comes back in the π row of the same face after a widening
  // there, the widening missed it: the k-th return widens every X face within
  // 1 + recurring_margin·k fine rings of the proof (and those that map next to its Y side)
  // at once to max_ring + 3, instead of one ring at a time. 0: off. Measured, FAUST_r 065-069 at
  // full resolution: 27 of level 6's 52 propagation widenings were Y face 6 939's π row (639
  // variables every time), in 4-step series per place (docs/results-log.md, twenty-fifth session).
  int recurring_margin = 2;
  // A return whose widening would take more than this share of the X faces is widened at its
  // proof as any other contradiction instead (one ring, the proof's X faces). Its margin is
  // counted from every X face that maps near its Y side, which after one such widening reaches
  // far: measured, TOSCA_r victoria0-victoria4 without WKS at full resolution, the first return
  // took 432 faces to ring 6 (10.1 M -> 16.0 M variables), the next 3 179 (45.4 M), an LP
  // that one core cannot solve in an hour. 0: no limit.
  double recurring_max_share = 0.1;
  // The ring such a return widens to: max_ring + this (1 to 3, where local widenings stop). Each
  // return takes hundreds of faces there at once (TOSCA_r david0-david6 without WKS at full
  // resolution, level 6: three returns of 639, 451 and 678 faces to ring 6, 10.6 M -> 28.9 M
  // variables in two minutes of rebuilds, seventy-seventh session).
  int recurring_beyond = 3;
  // How far past max_ring a local proof's own faces (those its first LP stalled on, proved
  // infeasible there) may widen, one ring per proof (1 to 12). The other widenings stop at
  // max_ring + 3. Measured, TOSCA_r dog3-dog8 at full resolution: seven stalled faces infeasible
  // at 4 extra rings, feasible at 5 (eighty-fifth session); horse0-horse10: a region of 186 faces,
  // 155 of them at ring 6, proved infeasible by twelve rechecks in a row whose widenings around them
  // left it as it was (eighty-ninth session).
  int proof_beyond = 3;
  // Let the divergence watch stop the re-solve after pricing too (as before the twenty-sixth
  // session). Off: that re-solve starts at the optimum of a space it contains, and stops at the
  // cold first LP's iterations anyway (detail::watch_divergence says why).
  bool watch_resolve = false;
  // Where this many widenings in a row at a level came from a first LP that the divergence watch
  // stopped (a suspicion, no proof), the level's next first LPs are watched patiently (only a long
  // climb stops them; detail::watch_patiently), until a proof. 0: no limit. Measured, TOSCA_r
  // horse0-5 and centaur0-2 at R = 0.05 on an H200: 24 suspicions in a row each at their 1 414-face
  // level (6.2 % → 21.6 % of the full space), and one such first LP, let run, was feasible
  // (docs/results-log.md, thirty-fifth session). 1 since the forty-ninth session: the local
  // widenings of the second and third suspicions cured no measured LP (FAUST_r 029-063, TOSCA_r
  // dog3-dog8 and centaur0-centaur2 at μ = 10), the region widening after them did;
  // centaur0-centaur2's level 5 from level 4's checkpoint: 40:56 against 47:40 with 3, one watched
  // LP against three, energy 3.96548 against 3.96513.
  int max_suspected_widenings = 1;
  // Where max_suspected_widenings ends the watch, every X face within this many fine rings of the
  // faces widened so far at the level gets one more ring before the patiently watched LP, each
  // time. The suspicions' own places (the window's dual growth) are narrow: measured, FAUST_r
  // 029-063 at μ = 10, level 6: suspicions widened 497, 24, 47, 9, 17, 14, 15 faces, mostly faces
  // widened already, while the two unwatched LPs' Farkas proofs named 13 and 853; 100 minutes on
  // one core without a round (forty-fourth session). With 2 (forty-fifth session, from level 5's
  // checkpoint): after the same first three suspicions it widened 1 334 faces, the unwatched LP
  // (11.2 M variables) was optimal in 4.4 minutes, and level 6 ended in 31 minutes, gap 1.12 %,
  // error 0.0221 (0.0317 at μ = 1). 0: off.
  int suspicion_rings = 2;
  // At most this many suspicion_rings margins per ring of a level (0: one at every suspicion that
  // ends the watch's trust, as before the seventy-seventh session). Each one widens around every
  // widening so far, so a second one costs far more than the first: measured, TOSCA_r
  // horse0-horse10 at full resolution, level 6: the first margin (3 593 faces) took the LP from
  // 15.5 M to 22.0 M variables; after its proof (10 faces) and a second suspicion (28 faces) the
  // second (4 717 faces) took it to 29.1 M, each first LP there 30-60 minutes on one core, while the
  // places that the proof and the suspicion named were a few dozen faces (docs/results-log.md,
  // seventy-sixth session). The measured cure (FAUST_r 029-063, above) was one margin.
  int suspicion_margins = 1;
  // Which faces that margin is drawn around: every X face widened so far at the level (widened,
  // as before the seventy-eighth session) or only those the suspicion itself named (named: the X
  // faces on the rows where PDHG diverged, its local widening's first choice, whether or not that
  // widening went on to the Y side or past max_ring). At full resolution the first
  // is the space's largest amplifier: TOSCA_r david0-david6 without WKS, level 6, the margin took
  // 2 937 faces (29.0 M → 32.3 M variables) where the suspicion named 84 (docs/results-log.md,
  // seventy-seventh session); the measured cure on FAUST_r 029-063 (above) was the first.
  enum class MarginScope { widened, named };
  MarginScope suspicion_margin_scope = MarginScope::widened;
  // A watched first LP of a refined level (divergence watch, quick or patient) also stops as
  // diverging where its dual proves its optimum above this many times the coarser level's energy
  // (SolverParams::divergence_bound): no Γ of that space is one the level wants, and widening is
  // what a stop leads to. The finest LP's optimum against the coarser level's energy, measured at
  // full resolution: 0.58 (TOSCA_r horse0-horse5, 2.66 against 4.56) to 1.24 (david0-david6 without
  // WKS, level 2 from 1). The watch's own rules let a plainly infeasible LP climb for eight windows:
  // TOSCA_r david0-david6 without WKS, `--suspicion-margin-around named`, level 6: its bound 7.0
  // against an objective of 3.19 and a coarser energy of 3.04, residual flat at 1.06e-2, ω 1 580,
  // after 45 minutes on one core (seventy-eighth session). Only while a ring is left
  // (detail::divergence_bound says why); the bound is the whole LP's, what propagation fixed
  // included. 0: off.
  double divergence_bound_factor = 2.0;
  // Where the zero-cost pre-test (RoundingOptions::feasibility_iterations) proves a level's first
  // LP infeasible for the first time at its ring, every X face within this many fine rings of the
  // faces widened so far gets one more ring too, as after the suspicion that the divergence watch
  // would have raised on that LP (suspicion_rings). A proof widens less than a suspicion with its
  // margin, and the narrower space held worse matchings (FAUST_r 016-020 at 3 000 faces: energy
  // 2.18881 against 2.10551, docs/results-log.md, sixty-eighth session). 0: off.
  int zero_cost_proof_rings = 2;
  // Start the first LP of a widened space from the previous attempt's iterate (its dual reset
  // where it diverged), by variable and row identity. Off: measured at full resolution (FAUST_r
  // 020-024) after a diverging attempt, the widened LP took 3 008 iterations warm against 2 048
  // cold, and stopped at a worse point (objective 24.15 against 23.47); on a feasible narrower
  // LP (test) it saves 60 %.
  bool warm_widening = false;
  // Warm starts (a pricing's re-solve, warm_widening, stuck_carry) also start from the primal
  // weight ω their iterate's solve ended with, not from PDHG's initial one (see
  // SolverParams::initial_primal_weight). Off: measured on FAUST_r 026-029 at 4 000 faces, the
  // re-solves after pricing took 320/192, 832/384, 576/768 (cap), 1 280 (cap), 768/448
  // iterations at levels 2-6 against 320/256, 896/384, 384/384, 960/576, 640/… with ω from 1
  // (122 s against 128 s, energy 10.70 against 10.62): the new rows' duals at 0, not ω, are
  // what the re-solve spends its iterations on.
  bool carry_primal_weight = false;
  // Fine X faces whose parent's space was widened locally at the level before (for whatever
  // reason) start with that many extra rings, up to this: where the coarser level needed room,
  // the finer one tends to need it too, and each widening found there costs a rebuild and often
  // an LP (at full resolution a diverging first LP takes 55-215 s). 0: off. Measured at 1,
  // FAUST_r 026-029 at full resolution (with price_dual_sweeps 4): 2 524 of 9 998 faces started
  // widened at the finest level, which still diverged once; 814 s against 623 s, but energy 17.71
  // against 24.67 and error 0.0213 against 0.0265 (one pair: not yet the default). Again without
  // the sweeps (twentieth session, 2 cores): 15:41 against 9:21, energy 18.85, error 0.0214; on
  // an H100 it took 016-026 (which the defaults never finished) to the end in 5.2 minutes.
  int inherit_widening = 0;
  // Fine rings of X faces around the proof that widen with it. Measured: 4 kept 021-029 at 1000
  // faces slightly closer to the global widening (error 0.065 against 0.070 at 0, 25 s against
  // 20 s), but on 020-024 at 2000 faces it widened 1311 of 2000 faces and still left an LP that
  // PDHG needed 111 s to prove infeasible; at 0 one widening of 335 faces gave a feasible LP.
  int widen_margin = 0;
  // Once propagation has no more contradictions to show at a level where it found some, every X
  // face within this many fine rings of the faces widened so far gets one more ring before the
  // first LP: PDHG takes minutes to show an infeasibility that propagation misses (FAUST_r
  // 020-024 at full resolution: 141 s, after two propagation widenings). 0: off. Measured with 3
  // there: no diverging attempt, but 12.96 M variables against 11.2 M and an LP bound of 20.72
  // against 23.47 — a more fractional LP whose rounding met infeasible LPs for 40 rounds.
  int widen_around = 0;
  // Where the finer levels' rounding is stuck (RoundingOptions::stuck_after: LPs after its
  // fixings failing round after round for this many times its first LP's seconds, or out of
  // rounds), widen the space around the failed parts as after an infeasible LP (a local
  // widening) and solve the level again. 0: off (rounding goes on; out of rounds, the level
  // starts afresh in a space widened around the open rows). Measured at full resolution: FAUST_r
  // 020-021 stuck after 21 rounds, 2 112 faces widened, the level's second attempt verified (gap
  // 2.0 %); 021-024 likewise (gap 1.0 %): the first completed runs of those pairs.
  double stuck_after = 1.0;
  // With stuck_after: go on from the stuck rounding's fixings to 1 (less those over the faces
  // widened) instead of starting afresh, the widened LP solved again at the end for its bound
  // (cold where the stuck rounding was gone on from a checkpoint, or the carried attempt is).
  // Off: measured on FAUST_r 020-021, the carried attempt's LPs (2-3 M variables, capped at the
  // first LP's iterations) stayed unconverged, and its rounds failed and were trimmed for
  // 10+ minutes, where a fresh attempt finished in 7 (its first LP included).
  bool stuck_carry = false;
  // With stuck_carry: the fixings dropped are those over the X faces just widened and over every
  // X face within this many fine rings of them (0: the widened faces' alone), so that the carried
  // attempt re-solves a margin around what failed instead of keeping the narrow space's choices
  // right up to it.
  int stuck_carry_margin = 0;
  // With stuck_after: the first this many times a level's rounding is stuck, it starts again in
  // the same space from its fixings to 1 so far, with its own state afresh (its undo history,
  // refuted fixings, cap scale and warm start: round 1 solves what the fixings leave, cold), as a
  // run gone on from a rounding checkpoint does (its fixings in their undo steps, as since the
  // seventy-third session; before, as one step); stuck again after that, it widens as above.
  // Why: FAUST_r 026-029 without WKS at full resolution thrashed for 60 minutes (rounds undone as
  // infeasible, releases, doubled caps) and, gone on from its round-51 checkpoint with that state
  // dropped, finished in 49 rounds and 5:25; a stuck widening solves the whole level again
  // (round 1 alone took 370-870 s there on one core). 0: off: 043-063 with WKS, gone on twice
  // that way, thrashed on (its LPs stay at their cap), and a restart keeps what the narrow space
  // cuts off (the test pair: energy 11.86 against 6.93 after the stuck widening). A restarted
  // rounding stuck again widens as above (afresh, or with stuck_carry from its fixings: since the
  // eighty-second session; before, afresh either way); an attempt gone on from a stuck rounding's
  // carried fixings is not restarted: stuck, it widens.
  int stuck_restarts = 0;
  // After a refined level's first LP (optimal), price the product triangles that one more fine
  // ring on every X face would add against its dual; where some price below zero (by more than
  // price_threshold, in energy units, and than the kept columns' low tail, set by the columns
  // propagation fixed to 0 before the LP: see price_wider_space), widen
  // their X faces by one ring and solve again from that LP's iterate, before rounding: up to
  // this many times per level. 0: off. Measured at full resolution (FAUST_r, 2 cores): 020-024
  // energy 20.48 -> 15.11 (error 0.0210 -> 0.0173, 17:48 -> 16:28), 020-021 27.30 -> 21.64
  // (23:08 -> 15:25: no stuck rounding), TOSCA_r horse0-horse5 61.86 -> 52.81 (gap 2.32 % ->
  // 0.91 %); at 4000 faces 14.97 -> 11.96, but 71 -> 136 s. 021-024 did not finish with it (its
  // level 6 spent every local widening on propagation conflicts).
  int price_widenings = 2;
  double price_threshold = 1e-4;
  // While price_widenings remain, the first LP is solved to this looser tolerance, priced, and
  // (where nothing prices below) solved on from there to its own (RoundingOptions::probe);
  // 0 or not above the LP's tolerance: price the optimum itself. Off: measured with 1e-2, FAUST_r
  // 026-029 at 4 000 faces took 85 s against 103 s (energy 10.07 against 10.62, error 0.0232
  // against 0.0229), but at full resolution the looser duals priced 7 326 columns below zero on
  // 600 faces (against 633 on 172), the finest level diverged twice, and its last LP, warm from a
  // loose iterate, took 2 944 iterations (197 s) against 448: stopped after 11 minutes.
  double price_tolerance = 0.0;
  // The re-solve after pricing starts the new rows' duals where this many sweeps of coordinate
  // ascent on the Lagrangian bound put them (CarriedIterate::apply), not at 0. 0: off. Measured
  // at full resolution: the bound stalls far below (-1 888 against -2 014 at 0, objective 17.4)
  // and the re-solves took as many iterations (768 and 512 against 768 and 448).
  int price_dual_sweeps = 0;
  // More fine rings on Y at every ring (fine neighbourhood): a wider space from the start, paid
  // for in variables, against infeasible reduced LPs whose proof PDHG must find (slow at
  // 10 k faces).
  int y_margin = 0;
  MatchingLpOptions matching;  // its features (if any) have one row per vertex of the input meshes
  RoundingOptions rounding;
  // LP tolerance of the levels below the finest (0: the rounding's own). Their Γ only chooses the
  // next level's space, so it need not be certified as tightly. Measured, FAUST_r 021-029 at
  // 2000 faces (4 levels): 56 s against 97 s at 1e-4 everywhere, the same finest gap (0.4 %) and
  // error 0.047 against 0.052. It holds also where the finest level's is looser: at full
  // resolution with 3e-3 everywhere, level 5's (3760 faces) first LP stopped after 1024
  // iterations and its rounding thrashed (25 of 30 rounds infeasible and undone) where 1e-3 took
  // 91 s.
  double coarse_tolerance = 1e-3;
  // The coarsest level alone decides the global structure (front–back, head–tail), and which
  // size gets it right varies: on TOSCA_r at 500 faces, 100 faces flipped the horse and the
  // man where 200 did not, and 200 did worse on the cat and the woman. Where the hierarchy has a
  // second level of its own size (HierarchyOptions::second_faces), that level is solved twice:
  // refined from the coarsest, and over its full product space; the Γ of lower energy goes on
  // (on those 8 pairs, the lower final energy was the lower error 7 times; the 8th was a
  // left-right swap). The full-space rounding fixes batches where its LP is fractional
  // (fractional_batch below): a poor Γ there only loses the comparison.
  bool second_start = true;
  double second_start_fractional_batch = 0.125;
  // Beside a refined Γ, the second start's rounding gives up once its rounds after the first have
  // done this many times its first LP's work (RoundingOptions::give_up_after), and the
  // alternative thresholds still try (RoundingOptions::alternatives_after_failure). Measured at
  // 500 faces on 13 pairs (docs/results-log.md, twenty-sixth session): it gave up in two. FAUST_r
  // 020-024: the same Γ in 93 s instead of 176. The galloping horse: the refined Γ went on,
  // energy 5.675 and error 0.108 against 6.399 and 0.500 (its second start's Γ was lower at 200
  // faces and ended higher). In the others, and at full resolution, the later rounds did at most
  // 35 % of round 1's work. 0: no budget.
  double second_start_budget = 1.0;
  // Where the second start and the refined Γ both exist, both go on, each refined, through this
  // many more levels (never the finest), and the chain of lower energy there goes on. Measured
  // on 8 FAUST_r pairs at 4 000 faces (6 levels, decided at the fourth, 894 faces): the chain
  // that led at 200 faces stayed ahead in 6 (the same Γ, 15-25 % more time); in 065-069 the other
  // one won, and the finest energy went 16.51 → 13.07, the error 0.035 → 0.028. 0: decide at the
  // second level by its energy.
  int lookahead_levels = 2;
  // Inside lookahead, a chain whose rounding at a level gets stuck (stuck_after) drops out there
  // instead of restarting (stuck_restarts) or widening and solving the level again, while the
  // other chain goes on (its report there has lookahead_other_stuck): it is an
  // alternative, not the only Γ. Where the other chain then finds no Γ at that level either, the
  // dropped one solves the level again as usual. Why: FAUST_r 016-026 with WKS at μ = 10 (45th
  // session) spent 2 h 24 min in level 4's first chain, stuck and widened three times (2.9 M to
  // 4.7 M variables, 5-11 min per first LP on one core), and did not finish.
  bool lookahead_drop_stuck = false;
  // At the level where lookahead decides, the chain that solves it second stops after the first
  // LP of an attempt (not a carried one, stuck_carry) whose certified bound is at or above the
  // first chain's energy there: no Γ in that attempt's space could win the decision (ties keep
  // the first), and its rounding would
  // be spent for nothing. Why: FAUST_r 016-026 at μ = 10, level 4: the first chain's Γ had
  // energy 2.916 in 2 minutes; the second chain's LP bound was 4.05, and its rounding ran for over
  // two hours (stuck, widened three times). Not a bound over a space widened later (the
  // attempt's only; widenings move it little: 4.09, 4.047, 4.046 over its three attempts there).
  bool lookahead_bound_drop = true;
  // A directory: every first LP that a rounding solves is written there (write_lp) as
  // level<L>-<NNN>.smlp, NNN counting all first LPs of the run, for solving it again on its own
  // (`shapematch lp --from`). Empty: none.
  std::string dump_first_lps;
  // A directory: every later round's part that Clp took RoundingOptions::slow_part_seconds or
  // more on is written there as level<L>-slow-<NNN>.smlp (write_lp). Empty: none.
  std::string dump_slow_parts;
  // A diagnostic, not an input of matching: a true map of the matched meshes, for every input
  // vertex of X its true input vertex of Y (-1: unknown; truth_at in evaluation.hpp makes one
  // from ground truth). Non-empty: the coarsest level's space is truth_space around it (each X
  // vertex's image there: the coarsest Y vertex nearest in space to its true vertex), and there
  // is no second start. A run with it against one without says whether the energy or the search
  // prefers a wrong matching: TOSCA_r victoria0–victoria4 without WKS (sixty-fifth session) ended
  // wrong at every level with a gap of 1.4 %, which cannot tell the two apart; at 100 faces the
  // search had missed a lower matching near the truth (docs/results-log.md, sixty-sixth session).
  std::vector<int> truth;
  int truth_rings = 2;
  // The coarsest level decides the global structure, and its LP is often fractional there: an
  // image spread over two places (left and right, head and tail), which iterative fixing mixes.
  // Where its rounding ends more than branch_gap above the LP's bound, a dive of up to
  // branch_depth steps splits on the X vertex whose image the LP spreads most between two places
  // of Y (most_split_image: balls of branch_rings edges, the second holding at least
  // branch_min_split of its mass), rounds the space with that vertex kept to each place, keeps the
  // Γ of least energy and goes on from the lower side. A side whose LP's bound is at or above the
  // best energy so far is not rounded. The level's bound stays the full space's. Why: at 100
  // faces `--truth` found matchings near the truth below the plain run's energy on david0–david6
  // (gap 87 %), victoria0–victoria4 and two FAUST_r pairs without WKS and on dog0–dog8 with it
  // (docs/results-log.md, sixty-sixth session). 0: off (sixty-seventh session: it lowers the
  // energy, not always the error; at full resolution the coarsest gap is under 1 % on 37 of 40 pairs).
  // Rings 1 rather than 2: a place of 2 rings holds a local spread whole (TOSCA_r cat0-cat9, gap
  // 5.4 %, nothing to split); at 100 faces with WKS, 1 ring lowered 6 of the 7 pairs above 1 %, 2 rings 3.
  int branch_depth = 0;
  int branch_rings = 1;
  double branch_min_split = 0.2;
  double branch_gap = 0.01;
  // With a checkpoint (run's `checkpoint`), where a level's rounding has got is saved after its
  // rounds at most this often (LevelAttempt::rounding; 0: after every round), and (where not 0)
  // with at most a twentieth of the time spent saving: each save writes every level's Γ, a few
  // hundred kB at full resolution, and with lp_checkpoint_seconds the next round's warm start
  // (181 MB in 3 s at 29 M variables), while the last rounds take seconds or less each.
  double rounding_checkpoint_seconds = 10.0;
  // With a checkpoint, a refined level's first LP (the attempt's, or the re-solve after a pricing)
  // saves its iterate with the attempt at most this often (LevelAttempt::solving), so that a run
  // gone on from it starts that LP there rather than from zero. At full resolution on one core such
  // an LP runs 30-60 minutes (TOSCA_r david0-david6 without WKS, level 6: 7 296 iterations in
  // 3 731 s, seventy-seventh session), and every stop inside it lost all of it. Each save writes
  // the iterate (about 16 bytes per nonzero primal value and per closedness row: some hundred MB
  // at 30 M variables, a few seconds). As often inside a rounding's rounds from fixings (their
  // costed solves), the checkpoint after the round before is saved again with the round's iterate
  // so far as its warm start (RoundingOptions::round_snapshot). 0: never.
  double lp_checkpoint_seconds = 600.0;
};

// Pricing: the reduced costs c_j − A_jᵀy of `other`'s columns, in energy units, against a dual
// `y` of `m`'s LP mapped to `other`'s rows by identity (rows `m` lacks at 0). Where `other` is a
// wider space of the same meshes and `y` is optimal for `m`, none below zero means `m`'s optimum
// is `other`'s too (the mapped y stays dual feasible with the same objective); one below zero
// says the narrower space may cut off a lower energy there.
std::vector<double> reduced_costs(const MatchingLp& m, const std::vector<double>& y, const MatchingLp& other);

// The reduced product space of eq. (17): every product triangle (f_a, f_b) of the fine meshes
// such that some (f'_a, f'_b) of the coarse Γ has χ(f_a) ∈ N(f'_a) and ψ(f_b) ∈ N(f'_b).
// Degenerate fine elements (vertices, edges) inherit the parents of their incident faces.
// `extra_rings` (empty, or one count per fine X face) grows a face's candidates on Y by that many
// more fine rings: the local widening after an infeasible reduced LP. `y_margin` (fine
// neighbourhood only) grows every face's candidates on Y by that many fine rings at every ring.
// Enumerated directly: memory is linear in the number of product triangles kept.
std::vector<ProductTriangle> reduced_product_space(const MeshLevel& fine_x, const MeshLevel& fine_y,
                                                   const Mesh& coarse_x, const Mesh& coarse_y,
                                                   const std::vector<ProductTriangle>& coarse_gamma, int ring,
                                                   Neighbourhood neighbourhood,
                                                   const std::vector<int>& extra_rings = {}, int y_margin = 0);

// The extra rings a fine X face keeps where the reduced space's ring grows from ring − 1 to `ring`
// (coarse to fine's ring widening): its extra rings on top of the new ring up to `max_ring`, and
// at least its reach on Y as reduced_product_space gives it (on the fine neighbourhood ring 1 and
// ring 2 reach alike: a face widened past max_ring, cut back to it, would lose what a proof there
// needed). On the coarse neighbourhood, whose ring is a coarse one, every extra ring is kept.
int extra_rings_after_ring_step(int extra, int ring, int max_ring, Neighbourhood neighbourhood, int y_margin = 0);

// The product triangles of x × y each of whose corners (a, b) has b within `rings` edges of
// image[a] (one entry per vertex of x; -1: any b). At rings 0 with the identity as image, the
// identity matching (and degenerate triangles never qualify there: their corners repeat on one
// side only). Enumerated from the full space: for the coarsest level.
std::vector<ProductTriangle> truth_space(const Mesh& x, const Mesh& y, const std::vector<int>& image, int rings);

// Where the LP values x over `space` spread an X vertex's image: per vertex a of x, the mass at
// each b of y is the sum of x over the product triangles with a corner (a, b); its first place is
// the ball of `rings` edges around its heaviest b, its second the ball around the heaviest b
// outside the first, and its split the share of its mass in the second place outside the first.
// The vertex of largest split (not one marked in `skip`; the lowest index on a tie; -1 where no
// vertex has mass), with both places as masks over y's vertices.
struct ImageSplit {
  int vertex = -1;
  double split = 0.0;
  std::vector<char> first, second;
};
ImageSplit most_split_image(const ProductSpace& space, const std::vector<double>& x, int rings,
                            const std::vector<char>& skip = {});

// The product triangles of `space` whose corners pair X vertex `vertex` only with vertices of Y
// marked in `allowed`.
std::vector<ProductTriangle> keep_images(const ProductSpace& space, int vertex, const std::vector<char>& allowed);

// (A new field goes into checkpoint.cpp's each_field too, so that checkpoints keep it.)
struct LevelReport {
  int level = 0;  // 0 = coarsest
  int faces_x = 0, faces_y = 0;
  int64_t variables = 0;       // product triangles kept
  int64_t full_variables = 0;  // the full product space at this level, for comparison
  int64_t constraints = 0;
  int ring = -1;               // ring of the reduced space (-1: full space)
  int widenings = 0;           // times the ring was widened everywhere after an infeasible reduced LP
  int local_widenings = 0;     // times it was widened only near the proof of infeasibility
  int margin_widenings = 0;    // of those, past max_ring near the proof or with a margin around it
  int64_t widened_faces = 0;   // fine X faces widened locally, summed over those times
  int stuck_widenings = 0;     // of the local widenings, those where rounding was stuck (stuck_after)
  int stuck_restarts = 0;      // times rounding was stuck and started again from its fixings (stuck_restarts)
  int price_widenings = 0;     // of the local widenings, those where pricing found columns below zero
  int propagation_widenings = 0;  // of the local widenings, those where propagation found the contradiction
  int recurring_widenings = 0;    // of those, where it came back in the same π row (recurring_margin)
  // Times the region of a local proof (LocalInfeasible) was checked again in the widened LP before
  // solving it; where still infeasible it widened there again at once (a local widening too).
  int proof_rechecks = 0;
  int64_t inherited_faces = 0; // fine X faces that started with extra rings (inherit_widening)
  int64_t carried_fixings = 0; // fixings to 1 the last of those went on from
  int64_t iterations_bound = 0;  // of the LP solved again for the bound after one
  int rounds = 0;
  int64_t iterations = 0;      // LP iterations over all rounds of the accepted ring (seconds
                               // include an infeasible attempt's, which ends within a few dozen)
  double lower_bound = 0.0, energy = 0.0, gap = 0.0;
  double threshold = 0.5;      // the rounding threshold whose Γ was kept (RoundingOptions::alternative_thresholds)
  int roundings = 1;           // roundings run from the accepted LP (1 + the alternatives tried)
  double seconds = 0.0;
  double peak_rss_mb = 0.0;
  // The second start (level 1 only): its energy, NaN where it did not run or found no Γ, and
  // whether its Γ was kept.
  double second_start_energy = std::numeric_limits<double>::quiet_NaN();
  bool second_start_kept = false;  // with lookahead: whether the chain that went on started there
  // Lookahead (CoarseToFineOptions::lookahead_levels), at the level where the two chains were
  // compared: the other chain's energy (NaN elsewhere, or where it found no Γ), and whether the
  // chain of higher energy at the second level won.
  double lookahead_other_energy = std::numeric_limits<double>::quiet_NaN();
  bool lookahead_switched = false;
  // There too, where the other chain stopped after its first LP because that LP's bound was at or
  // above this chain's energy (CoarseToFineOptions::lookahead_bound_drop): that bound (NaN
  // elsewhere; lookahead_other_energy is then NaN).
  double lookahead_other_bound = std::numeric_limits<double>::quiet_NaN();
  // At the level where a lookahead chain dropped out stuck (lookahead_drop_stuck), the other's.
  bool lookahead_other_stuck = false;
  // The coarsest level's dive (CoarseToFineOptions::branch_depth): the sides rounded, the least
  // energy among them (NaN where none was rounded or none found a Γ), and whether a side's Γ
  // went on (the level's rounds, iterations and threshold are then that side's rounding's).
  int branch_roundings = 0;
  double branch_energy = std::numeric_limits<double>::quiet_NaN();
  bool branch_kept = false;
  // The level's Γ, the one that went on (on the level's meshes, x_levels()/y_levels()): match
  // writes a vertex map per level from it, so that eval can say at which level an error arose.
  std::vector<ProductTriangle> gamma;
};

struct CoarseToFineResult {
  std::vector<LevelReport> levels;
  MatchingLp finest;        // the finest level's LP; its space refers to the matcher's meshes
  RoundingResult rounding;  // the finest level's rounding
};

// Where the level in progress had widened to when its last attempt started: a run gone on from
// it starts that level in the same space with the same widening budgets left, instead of
// widening again from the coarser Γ (measured, FAUST_r 065-069 at full resolution on the H200:
// 275 of the finest level's 375 s went to attempts that widened and started again).
struct LevelAttempt {
  int ring = -1;                 // -1: no level in progress
  std::vector<int> extra;        // extra fine rings per X face of the level in progress
  int local = 0, propagated = 0, priced = 0;  // widenings spent of max_local_widenings, …
  bool regional_done = false, around_done = false;
  int suspicions = 0;            // diverging first LPs in a row, and whether the watch is trusted
  bool trusted = true;
  // The margin after a proof at zero cost (zero_cost_proof_rings) was given at this ring: once per
  // ring, also across a stop (version 9; before, a run gone on from here could give it again).
  bool zero_cost_margin_given = false;
  // The suspicion_rings margins given at this ring (version 11; before, none counted).
  int suspicion_margins = 0;
  // The X faces and rings of the last local proof widened at (LocalInfeasible), which this
  // attempt checks again before its LP (version 17; before, none: its LP was solved). Empty: none.
  std::vector<int> proof_faces;
  int proof_rings = 0;
  // Its relaxation's rows and columns at its last recheck (version 20; -1: none yet): a recheck of
  // the same size after a widening elsewhere goes on to the wider widenings (solve_refined).
  int64_t proof_rows = -1, proof_cols = -1;
  // Where the attempt is the re-solve after a pricing widened the space: the iterate it starts
  // from (the priced LP's), and the cold first LP's iterations and seconds, which cap it and scale
  // its rounding (version 13; before, a run gone on from here solved it cold: TOSCA_r
  // david0-david6 without WKS at full resolution, level 6, 32.5 M variables, about an hour on one
  // core against 704 iterations warm on the same level of the other run). Empty elsewhere.
  CarriedIterate priced_from;
  int64_t cold_iterations = 0;
  double cold_seconds = 0.0;
  // Where the attempt's first LP (or that re-solve, `solving_resolve`) was under way: its iterate
  // after `solving_iterations` iterations and `solving_seconds` (CoarseToFineOptions::
  // lp_checkpoint_seconds), which a run gone on from here starts it from, without the zero-cost
  // pre-test it had passed, its divergence watch on only where it was (`solving_watched`: the
  // pre-test turns it off where it finds a point), counting those iterations and seconds where
  // the rounding scales with them (version 13; its seconds and watch flag 14; before, a run gone
  // on from here solved it from zero). Empty elsewhere.
  CarriedIterate solving;
  int64_t solving_iterations = 0;
  double solving_seconds = 0.0;
  bool solving_resolve = false;
  bool solving_watched = true;
  // Its divergence watch at the last window before `solving` was taken, which the LP gone on from
  // there watches on from (version 16; before, its windows started over).
  DivergenceWatchState solving_watch;
  // … and its whole state there (version 19; none before, or from pdhg-cpu-f32): a run gone on
  // from here makes the iterations the uninterrupted LP would have made, bit for bit, where it
  // builds the same LP with the same solver (its fingerprint); else it goes on from `solving`.
  std::shared_ptr<const SolverState> solving_state;
  LevelReport report;            // its counts so far (widenings, widened faces, …); no Γ
  // Where the attempt's rounding had got, saved after its rounds (at most every few seconds): a
  // run gone on from it builds the same LP, fixes `ones` before its round 1 and keeps round 1's
  // bound (measured on the H200, 17 runs at once: a finest level's rounding takes 100-300 s, which
  // a stop inside it lost). Empty (no rounds) where it had not finished round 1. Not kept: the
  // rounding's own state (undo history, stall and stuck counts), which begins afresh (the
  // fixings a proof blamed too, RoundingOptions::remember_refuted), but for the steps its fixings
  // were made in and its next round's warm start (`warm`); and it is not saved where the level's
  // LP is small enough for alternative thresholds.
  struct Rounding {
    int64_t columns = 0, rows = 0;   // of the attempt's LP, which a run gone on from it checks
    std::vector<int64_t> ones;       // the rounding's fixings to 1 so far (RoundingOptions::decided)
    std::vector<int32_t> steps;      // the undo step of each (parallel; version 10; empty: one step)
    int rounds = 0;                  // done, and their LP iterations
    int64_t iterations = 0;
    double lower_bound = 0.0;        // certified by round 1 (NaN for a carried start: none of the space)
    double reference_seconds = 0.0;  // round 1's cold solve (RoundingOptions::reference_*)
    int64_t reference_iterations = 0;
    double cap_scale = 1.0;          // RoundingOptions::start_cap_scale (version 12; before: 1)
    // The next round's warm start (RoundingOptions::decided; saved inside that round, its iterate
    // so far: round_snapshot), which the run gone on from here starts its round 1 from (version
    // 14, where lp_checkpoint_seconds > 0; empty: cold).
    CarriedIterate warm;
    bool empty() const { return rounds == 0; }
    // How many steps its fixings form (one where `steps` is empty, none without fixings).
    int64_t step_count() const {
      if (steps.empty()) return ones.empty() ? 0 : 1;
      std::vector<int32_t> s = steps;
      std::sort(s.begin(), s.end());
      return std::unique(s.begin(), s.end()) - s.begin();
    }
  } rounding;
  bool empty() const { return ring < 0; }
  int widenings() const { return report.widenings + report.local_widenings; }  // so far
};

// The state between two levels, so that a run can stop after a level and another go on from it
// (match --checkpoint): the reports of the levels done, the last one's Γ being what the next
// refines, and that level's extra rings per X face (inherit_widening). Every level but the
// finest is a checkpoint. Each new attempt of the next level (a widening) updates `attempt`,
// the finest level's too, and so does its rounding as it goes (LevelAttempt::rounding), where a
// single chain goes on (not inside lookahead).
struct LevelCheckpoint {
  uint64_t hierarchy = 0;          // CoarseToFineMatcher::fingerprint() of the run that wrote it
  std::vector<LevelReport> levels; // levels 0 … levels.size() - 1, done (with lookahead: before its split)
  std::vector<int> widened;
  LevelAttempt attempt;            // of level levels.size(), where one is in progress
  // Inside lookahead (CoarseToFineOptions::lookahead_levels), before its decision: both chains,
  // the leading one first, each with its reports since the split (levels.size() onwards; the
  // last one's Γ is what its next level refines) and its last level's extra rings. `widened` and
  // `attempt` are then empty. (Before, a run stopped inside lookahead kept only its coarsest
  // level: eight of seventeen full-resolution runs in a 170 s call on the H200, 39th session.)
  // The chains solve a level one after the other, so inside a level the first may hold one
  // report more than the second; the chain at the level in progress holds its attempt. (Before,
  // a stop there lost the level: FAUST_r 016-026, 45th session, 2 h 24 min in one chain's level 4.)
  struct Chain {
    std::vector<LevelReport> pending;
    std::vector<int> widened;
    bool leading = true;
    LevelAttempt attempt;  // of level done(), where this chain is at it
  };
  std::vector<Chain> chains;       // none or two
  // The levels both chains have done; the level in progress, if any, is the next.
  int done() const {
    size_t pending = chains.empty() ? 0 : chains.front().pending.size();
    for (const Chain& c : chains) pending = std::min(pending, c.pending.size());
    return int(levels.size() + pending);
  }
  // The attempt of the level in progress: `attempt`, or a chain's (empty where none).
  const LevelAttempt& in_progress() const {
    for (const Chain& c : chains)
      if (!c.attempt.empty()) return c.attempt;
    return attempt;
  }
  // Inside a level of lookahead: whether the first chain has done it (and the second is at it).
  bool first_chain_ahead() const { return chains.size() == 2 && chains[0].pending.size() > chains[1].pending.size(); }
};
// Binary, versioned. save: atomically (files.hpp); load: IoError naming the file where it is
// missing, not a checkpoint, or cut short.
void save_checkpoint(const std::string& path, const LevelCheckpoint& checkpoint);
LevelCheckpoint load_checkpoint(const std::string& path);
namespace detail {
// In an earlier version's layout (1 up to the current), what it lacks left out: for tests that
// older files still load.
void save_checkpoint_as(const std::string& path, const LevelCheckpoint& checkpoint, uint32_t version);
}  // namespace detail

// Stateful: owns both hierarchies, so the result's space stays valid while the matcher lives.
class CoarseToFineMatcher {
public:
  CoarseToFineMatcher(const Mesh& x, const Mesh& y, CoarseToFineOptions options = {});
  // Per-vertex descriptors of the input meshes (rows = input vertices) for the feature term.
  void set_features(Eigen::MatrixXd fx, Eigen::MatrixXd fy);

  const MeshHierarchy& x_levels() const { return hx_; }
  const MeshHierarchy& y_levels() const { return hy_; }

  using Progress = std::function<void(const LevelReport& level, const RoundingRound& round)>;
  using Checkpointing = std::function<void(const LevelCheckpoint&)>;
  // `resume`: go on after its levels instead of starting at the coarsest; they are taken as they
  // are, whatever options made them (so a finer level's options can be tried without solving the
  // coarse ones again). InvalidInputError where it was written for other hierarchies.
  // `checkpoint`: called after every level that can be a checkpoint, before each later attempt
  // of the level after it, and after that attempt's rounds (at most every
  // rounding_checkpoint_seconds).
  // `progress`: after every round of a level's attempt, numbered on from the rounds before a
  // rounding checkpoint it went on from or a stuck restart (after round k, the first is k + 1;
  // the second start's own rounding counts from 1); round 1 gone on from inside its first LP
  // counts that LP's iterations and seconds before the save too.
  CoarseToFineResult run(const Progress& progress = {}, const LevelCheckpoint* resume = nullptr,
                         const Checkpointing& checkpoint = {}) const;
  // A hash of both hierarchies (every level's faces and input vertices): equal for equal inputs
  // and hierarchy options.
  uint64_t fingerprint() const;
  // Throws InvalidInputError (one line, no file name) where `checkpoint` does not fit these
  // hierarchies: another fingerprint, no level or every level, a Γ out of the levels' meshes, an
  // attempt whose extra rings or level are not those of the level after them, lookahead chains
  // not two, of different lengths, or beside an attempt.
  void check(const LevelCheckpoint& checkpoint) const;

private:
  // Level l's rounding options: the coarse tolerance below the finest level.
  RoundingOptions rounding_for(int l) const;
  // Level l's ring before any widening: coarse_ring at the small levels below the finest.
  int ring_at(int l) const;
  // Inside lookahead: drop_when_stuck, a stuck rounding throws its StuckError instead of
  // widening (lookahead_drop_stuck); where `beat` is finite, an attempt whose first LP's bound is
  // at or above it throws instead of rounding (lookahead_bound_drop).
  struct ChainRules {
    bool drop_when_stuck = false;
    double beat = std::numeric_limits<double>::quiet_NaN();
    double coarser_energy = std::numeric_limits<double>::quiet_NaN();  // the Γ it starts from (divergence_bound_factor)
  };
  // Level l from the coarser level's Γ (the full space at l = 0), widening where it is
  // infeasible; throws InfeasibleError when the largest ring is. Replaces `gamma` with level l's.
  // `widened`: on entry the coarser level's extra rings per X face (inherit_widening; empty:
  // none), on return this level's.
  // `resume`: an attempt of this level to start from (null: none); `attempted`: called before
  // every attempt after the first, with the state it starts from. `rules`: a lookahead chain's.
  void solve_refined(int l, const EnergyModel& model, LevelReport& rep, std::vector<ProductTriangle>& gamma,
                     CoarseToFineResult& result, const Progress& progress, std::vector<int>& widened,
                     const LevelAttempt* resume, const std::function<void(LevelAttempt&&)>& attempted,
                     const ChainRules& rules) const;
  // The second start at level l: the full product space, rounded. Fills `rep` (a copy of the
  // level's, with the second start's numbers), `gamma`, and at the finest level `finest`'s LP
  // and rounding; false where it found no Γ.
  bool solve_second_start(int l, const EnergyModel& model, LevelReport& rep, std::vector<ProductTriangle>& gamma,
                          CoarseToFineResult& finest, const Progress& progress, bool optional) const;

  // The coarsest level's dive (CoarseToFineOptions::branch_depth) from its LP `m`, rounded as
  // `rr` with round 1's iterate `x`: where a side's Γ is lower, `m`, `rr`, `rep` and `gamma`
  // become that side's (`rr` keeping the full space's bound).
  void branch_coarsest(MatchingLp& m, RoundingResult& rr, const std::vector<double>& x, const EnergyModel& model,
                       LevelReport& rep, std::vector<ProductTriangle>& gamma) const;

  std::vector<int> coarsest_truth() const;  // CoarseToFineOptions::truth on the coarsest meshes

  CoarseToFineOptions options_;
  MeshHierarchy hx_, hy_;
  bool second_level_ = false;  // level 1 is HierarchyOptions::second_faces on both shapes
  Eigen::MatrixXd fx_, fy_;
  std::shared_ptr<std::atomic<int>> dumped_ = std::make_shared<std::atomic<int>>(0);  // dump_first_lps
  std::shared_ptr<std::atomic<int>> dumped_slow_ = std::make_shared<std::atomic<int>>(0);  // dump_slow_parts
};

}  // namespace shapematch
