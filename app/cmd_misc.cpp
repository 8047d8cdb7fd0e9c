// Small subcommands: `devices`, `generate-assets` and `checkpoint`.
#include "commands.hpp"
#include "shapematch/coarse_to_fine.hpp"
#include "shapematch/device.hpp"
#include "shapematch/errors.hpp"
#include "shapematch/json.hpp"
#include "shapematch/shapes.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <string>

namespace shapematch::app {

Action add_devices_command(CLI::App& app) {
  return [] {
    const auto devices = list_devices();
    if (devices.empty()) {
      std::cout << "no Vulkan compute device found\n";
      return 1;
    }
    const DeviceInfo preferred = choose_device(-1);
    for (const auto& d : devices) {
      std::cout << (d.index == preferred.index ? "* " : "  ") << d.index << ": " << d.name << " (" << d.type
                << ", " << d.device_local_bytes / (1024 * 1024) << " MiB, max storage buffer "
                << d.max_storage_buffer_range / (1024 * 1024) << " MiB, subgroup " << d.subgroup_size << ", "
                << d.driver << ")\n";
    }
    return 0;
  };
}

// The first `keep` levels of a checkpoint and nothing after them (no attempt, no lookahead), so
// that a level can be solved again from scratch under other options: a run gone on from the
// whole file would go on in its attempt's space. The extra rings the next level inherits are
// only known for the last level held (inherit_widening), so they go with any level before it.
LevelCheckpoint keep_levels(LevelCheckpoint c, int keep, const std::string& file) {
  if (keep < 1 || keep > int(c.levels.size()))
    throw InvalidInputError(file + ": --keep-levels " + std::to_string(keep) + " is not between 1 and the " +
                            std::to_string(c.levels.size()) + " levels it holds" +
                            (c.chains.empty() ? "" : " before its lookahead"));
  if (keep < int(c.levels.size())) c.widened.clear();
  c.levels.resize(keep);
  c.chains.clear();
  c.attempt = LevelAttempt{};
  return c;
}

// Where a stopped run stands (match --checkpoint), as JSON on stdout: the levels done, the
// attempt of the level in progress and how far its rounding got. The meshes are not needed: a
// run gone on from the file checks that it fits them. With --keep-levels, the same of a new
// file holding only the first levels.
Action add_checkpoint_command(CLI::App& app) {
  auto file = std::make_shared<std::string>();
  auto keep = std::make_shared<int>(0);
  auto out = std::make_shared<std::string>();
  app.add_option("FILE", *file, "a checkpoint written by match --checkpoint")->required();
  auto* keep_opt = app.add_option("--keep-levels", *keep,
                                  "write to --out a checkpoint of the first N levels only: no attempt in progress, "
                                  "no lookahead (to solve the next level again from scratch)");
  app.add_option("--out", *out, "where --keep-levels writes (may be FILE itself)")->needs(keep_opt);
  keep_opt->needs(app.get_option("--out"));
  return [file, keep, out, keep_opt] {
    LevelCheckpoint c = load_checkpoint(*file);
    if (keep_opt->count() > 0) {
      c = keep_levels(std::move(c), *keep, *file);
      save_checkpoint(*out, c);
      *file = *out;
    }
    auto reports = [](const std::vector<LevelReport>& rs) {
      Json levels = Json::array();
      for (const LevelReport& r : rs)
        levels.push(Json::object()
                        .set("level", r.level)  // (0 = coarsest, as in report.json)
                        .set("faces_x", r.faces_x)
                        .set("faces_y", r.faces_y)
                        .set("variables", r.variables)
                        .set("ring", r.ring)
                        .set("widenings", r.widenings + r.local_widenings)
                        .set("rounds", r.rounds)
                        .set("energy", r.energy)
                        .set("lower_bound", r.lower_bound)
                        .set("gap", r.gap)
                        .set("second_start_energy", r.second_start_energy)
                        .set("second_start_kept", r.second_start_kept)
                        .set("branch_energy", r.branch_energy)
                        .set("branch_kept", r.branch_kept)
                        .set("seconds", r.seconds));
      return levels;
    };
    // The first LP under way: its divergence watch's last window (the relative primal residual
    // and gap PDHG stops on, and how far the dual bound lay above the objective, over
    // 1 + |objective|, in the LP's scaled costs as the watch's rules see it).
    auto last_window = [](const LevelAttempt& a) {
      const DivergenceWatchState& w = a.solving_watch;
      if (a.solving.empty() || w.windows == 0) return Json();
      const double objective = w.bound - w.excess[1];
      return Json(Json::object()
                      .set("windows", w.windows)
                      .set("primal_residual", w.primal)
                      .set("gap", w.gap)
                      .set("bound_above_objective", w.excess[1] / (1.0 + std::abs(objective))));
    };
    auto attempt_json = [&last_window](const LevelAttempt& a) {
      Json attempt;  // null where no level is in progress
      if (a.empty()) return attempt;
      Json rounding;
      if (const LevelAttempt::Rounding& g = a.rounding; !g.empty())
        rounding = Json::object()
                       .set("rounds", g.rounds)
                       .set("fixings_to_one", static_cast<int64_t>(g.ones.size()))
                       .set("fixing_steps", g.step_count())
                       .set("cap_scale", g.cap_scale)
                       .set("warm_start", !g.warm.empty())
                       .set("iterations", g.iterations)
                       .set("lower_bound", g.lower_bound)
                       .set("variables", g.columns)
                       .set("constraints", g.rows);
      return Json::object()
          .set("level", a.report.level)
          .set("ring", a.ring)
          .set("faces_with_extra_rings",
               static_cast<int64_t>(std::count_if(a.extra.begin(), a.extra.end(), [](int e) { return e > 0; })))
          // (past --max-ring where a proof was widened beyond it)
          .set("most_extra_rings", a.extra.empty() ? 0 : *std::max_element(a.extra.begin(), a.extra.end()))
          // (the last local proof's region, which its next LP checks again first; null: none)
          .set("proof_region", a.proof_faces.empty() ? Json()
                                                     : Json::object()
                                                           .set("faces", static_cast<int64_t>(a.proof_faces.size()))
                                                           .set("rings", a.proof_rings)
                                                           // (its size at its last recheck; -1: none yet)
                                                           .set("rechecked_rows", a.proof_rows)
                                                           .set("rechecked_columns", a.proof_cols))
          .set("proof_rechecks", a.report.proof_rechecks)
          .set("widenings", a.widenings())
          .set("propagation_widenings", a.report.propagation_widenings)
          .set("price_widenings", a.report.price_widenings)
          .set("stuck_widenings", a.report.stuck_widenings)
          .set("stuck_restarts", a.report.stuck_restarts)
          // (its next LP the re-solve after a pricing, from the iterate kept with it)
          .set("warm_resolve", !a.priced_from.empty() || (!a.solving.empty() && a.solving_resolve))
          // (its first LP under way, from the iterate kept with it: after how many iterations; null: none)
          .set("solving_iterations", a.solving.empty() ? Json() : Json(a.solving_iterations))
          // (… and its divergence watch's windows in a row of the patient rule; null: none)
          .set("solving_climbing_windows", a.solving.empty() ? Json() : Json(int64_t(a.solving_watch.climbing)))
          // (… and whether it holds that LP's whole state, to go on from exactly; null: no LP under way)
          .set("solving_exact", a.solving.empty() ? Json() : Json(a.solving_state != nullptr))
          // (… and where its divergence watch's last window left it, against the tolerance: after
          // hours in one LP, whether it is closing in; null: no LP under way, or none watched yet)
          .set("solving_last_window", last_window(a))
          .set("rounding", std::move(rounding));
    };
    Json levels = reports(c.levels);
    Json lookahead = Json::array();  // inside lookahead: both chains' levels since its split
    for (const LevelCheckpoint::Chain& chain : c.chains)
      lookahead.push(Json::object()
                         .set("leading", chain.leading)
                         .set("levels", reports(chain.pending))
                         .set("attempt", attempt_json(chain.attempt)));
    // The level in progress, where one is (inside lookahead also under its chain).
    Json attempt = attempt_json(c.in_progress());
    std::cout << Json::object()
                     .set("file", *file)
                     .set("levels_done", c.done())
                     .set("levels", std::move(levels))
                     .set("lookahead", std::move(lookahead))
                     .set("attempt", std::move(attempt))
                     .dump()
              << "\n";
    return 0;
  };
}

Action add_generate_assets_command(CLI::App& app) {
  auto dir = std::make_shared<std::string>();  // (empty: the bundled assets/, looked up when run)
  app.add_option("--out", *dir, "output directory (default: the bundled meshes' own assets/ folder)");
  return [dir] {
    if (dir->empty()) *dir = data_dir() + "/assets";
    shapes::write_bundled_assets(*dir);
    spdlog::info("wrote the bundled meshes to {}", *dir);
    return 0;
  };
}

}  // namespace shapematch::app
