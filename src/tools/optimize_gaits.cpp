// optimize_gaits: solves the paper's grid of optimal cyclic gaits (§3.3) and writes the gait
// table that ships in config/, so that users never have to run the optimiser.
//
//   rosrun kneed_walker optimize_gaits --out config/gait_table.yaml [--resume]
//                                      [--threads 0] [--retry-failed] [--max-attempts 4]
//                                      [--prior-fixed] [--seed-table config/gait_table.yaml [--seed-only]]
//                                      [--min-passing-clearance L] [--max-swing-knee-flexion rad]
//                                      [--speeds 1.5,2,...,7] [--step-lengths 0.5,...,1] [--slopes -0.075,...,0.075]
//                                      [--polish [--polish-sweeps 20]]
//   rosrun kneed_walker optimize_gaits --out config/gait_table.yaml --merge other_run.yaml
// With --prior-fixed the controls that the prior fixes are held at its values (the table
// config/prior_gait_table.yaml); without, all are optimised (config/gait_table.yaml).
//
// The table is grown from one gait (optimizer::seedTable, growTable: on all cores; with
// --seed-table, that table's gait at each point is tried first) and rewritten after every gait,
// so an interrupted run continues with --resume. With --polish, every feasible gait is then
// solved again from its neighbours' gaits, sweep after sweep, and the lowest effort kept
// (optimizer::polishTable).

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>

#include "kneed_walker/core/common/parallel.h"
#include "kneed_walker/core/gait/gait_table.h"
#include "kneed_walker/core/optimizer/optimal_gaits.h"
#include "kneed_walker/core/optimizer/table_growth.h"
#include "kneed_walker/core/optimizer/table_polish.h"
#include "options.h"
#include "progress.h"
#include "tool_main.h"
#include "package_files.h"

namespace kw = kneed_walker::core;

namespace {

// On --resume with new grid axes, each of the table's axis values that is not on the new axis
// drops the table's gaits there. A value that misses one of the table's by a rounding (0.075
// given for the table's 0.0750491578 rad, 4.3°) would drop them unasked and solve them all
// again, for minutes or hours: refused, naming both values. A value left out on purpose is
// reported with the feasible gaits it drops. Returns false after a refusal.
bool checkResumedAxis(const char* option, const std::vector<double>& given, const kw::gait::GaitTable& table,
                      int axis) {
  if (given.empty()) return true;
  const kw::gait::GaitGrid& grid = table.grid;
  const std::vector<double>& old_axis =
      axis == 0 ? grid.speeds_kmh : axis == 1 ? grid.step_lengths_m : grid.slopes_rad;
  constexpr double kSame = 1e-9, kRounding = 1e-3;  // as gait::regridded matches; km/h, m or rad
  for (size_t j = 0; j < old_axis.size(); ++j) {
    const double y = old_axis[j];
    double nearest = std::numeric_limits<double>::infinity();
    for (const double x : given)
      if (std::abs(x - y) < std::abs(nearest - y)) nearest = x;
    const double miss = std::abs(nearest - y);
    if (miss <= kSame * std::max(1.0, std::abs(y))) continue;
    int feasible = 0;
    for (int i = 0; i < grid.size(); ++i)
      feasible += table.entries[i].feasible && grid.cell(i)[axis] == static_cast<int>(j);
    if (miss < kRounding) {
      std::fprintf(stderr,
                   "optimize_gaits: %s: %.10g is not the table's %.17g (they differ by %.2g): give the table's "
                   "value to keep its %d feasible gaits there, or one at least %g from it to solve a new axis value\n",
                   option, nearest, y, miss, feasible, kRounding);
      return false;
    }
    if (feasible > 0)
      std::fprintf(stderr, "optimize_gaits: %s leaves out the table's %.17g: its %d feasible gaits are dropped\n", option,
                   y, feasible);
  }
  return true;
}

void writeAtomically(const std::string& path, const kw::gait::GaitTable& table) {
  const std::string tmp = path + ".tmp.yaml";
  kw::gait::saveGaitTable(tmp, table);
  std::filesystem::rename(tmp, path);
}

// Marks the gaits of `table` that no longer meet the constraints (optimizer::markStaleGaits),
// saying so: --retry-failed then solves them again and --merge never takes them.
void markStaleGaits(kw::gait::GaitTable& table, const kw::optimizer::GaitOptimizerOptions& options,
                    const std::string& path) {
  const int stale = kw::optimizer::markStaleGaits(table, options);
  if (stale > 0)
    std::fprintf(stderr, "optimize_gaits: %d gaits of %s no longer meet the constraints (re-simulated): marked failed\n",
                 stale, path.c_str());
}

std::string clock(double seconds) {
  const int s = static_cast<int>(seconds);
  return std::to_string(s / 60) + ":" + (s % 60 < 10 ? "0" : "") + std::to_string(s % 60);
}

}  // namespace

int run(int argc, char** argv) {
  CLI::App app{"Solves the grid of optimal cyclic gaits and writes the gait table."};
  std::string out;
  bool resume = false, retry_failed = false;
  int threads = 0, max_attempts = 4;
  double seed_speed = 4.5, seed_step = 0.7, seed_slope = 0.0;
  app.add_option("--out", out, "gait table to write (YAML)")->required();
  app.add_flag("--resume", resume, "continue the table in --out");
  app.add_flag("--retry-failed", retry_failed, "with --resume: solve failed points again");
  app.add_option("--threads", threads, "worker threads; 0 = all cores")->check(CLI::Range(0, 256));
  app.add_option("--max-attempts", max_attempts, "warm starts tried per point")->check(CLI::Range(1, 26));
  bool prior_fixed = false;
  app.add_flag("--prior-fixed", prior_fixed,
               "hold the prior's fixed controls (knee and torso damping, torso rest angle; paper 3.4) "
               "instead of optimising them: the prior's table");
  std::string seed_table, merge_table;
  CLI::Option* merge_option = app.add_option("--merge", merge_table,
                 "fold this table's gaits into --out where they have the lower effort, then exit "
                 "(the optimiser finds local optima: keep the better of two runs)")->check(CLI::ExistingFile);
  app.add_option("--seed-table", seed_table,
                 "warm-start the seed point from this table's gait there instead of by continuation "
                 "from McGeer's passive gait, and try its gait at every point first (for --prior-fixed: "
                 "the free table's gaits reach points that no solved neighbour does)")->check(CLI::ExistingFile);
  bool seed_only = false, polish = false;
  int polish_sweeps = 20;
  CLI::Option* polish_flag = app.add_flag("--polish", polish,
               "after solving, lower the effort of the table's gaits: each feasible gait solved again from its "
               "feasible neighbours' gaits (one step along an axis), the lowest effort kept, sweep after sweep "
               "until none improves (the first neighbour that leads to a gait is not always the best start)")
      ->excludes(merge_option);
  app.add_option("--polish-sweeps", polish_sweeps, "with --polish: at most this many sweeps")
      ->check(CLI::Range(1, 100))->capture_default_str()->needs(polish_flag);
  app.add_flag("--seed-only", seed_only,
               "with --seed-table: take only its gait nearest the seed point, and build every other point from "
               "the solved ones (the table grown from one gait)");
  app.add_option("--seed-speed", seed_speed, "seed grid point: speed, km/h")
      ->check(kneed_walker::tools::FiniteRange(0.1, 20))->capture_default_str();
  app.add_option("--seed-step", seed_step, "seed grid point: step length, m")
      ->check(kneed_walker::tools::FiniteRange(0.1, 3))->capture_default_str();
  app.add_option("--seed-slope", seed_slope, "seed grid point: slope, rad")
      ->check(kneed_walker::tools::FiniteRange(-0.5, 0.5))->capture_default_str();
  std::vector<double> speeds_kmh, step_lengths_m, slopes_rad;
  app.add_option("--speeds", speeds_kmh,
                 "the grid's speeds, km/h, ascending, comma-separated (default the paper's 3-7 by 0.5; "
                 "with --resume, the table is carried over to the new grid)")
      ->delimiter(',')->check(kneed_walker::tools::FiniteRange(0.5, 20));
  app.add_option("--step-lengths", step_lengths_m,
                 "the grid's step lengths, m, ascending, comma-separated (default the paper's 0.5-1.0 by 0.1)")
      ->delimiter(',')->check(kneed_walker::tools::FiniteRange(0.1, 3));
  app.add_option("--slopes", slopes_rad,
                 "the grid's ground slopes, rad, positive uphill, ascending, comma-separated (default the "
                 "paper's -4.3 to 4.3 degrees by 2.15)")
      ->delimiter(',')->check(kneed_walker::tools::FiniteRange(-0.3, 0.3));
  kw::optimizer::GaitOptimizerOptions options;
  CLI::Option* clearance_option =
      app.add_option("--min-passing-clearance", options.min_passing_clearance,
                     "hold the swing sole at least this high while it passes the stance foot, leg lengths (a hard "
                     "constraint beside eq. 10; the table records it, and --resume and --merge take the table's "
                     "unless given; off for a new table unless given; the shipped free table: 0.01); --resume and "
                     "--merge mark the table's gaits that pass lower failed")
          ->check(kneed_walker::tools::FiniteRange(-0.05, 0.1));
  CLI::Option* flexion_option =
      app.add_option("--max-swing-knee-flexion", options.max_swing_knee_flexion,
                     "hold the swing knee's flexion at most this, rad (a third inequality, recorded and taken as "
                     "--min-passing-clearance is; the walker's knee has no flexion stop, and under the clearance "
                     "bound some optima fold it past 90 degrees; the shipped free table: 1.31)")
          ->check(kneed_walker::tools::FiniteRange(0.1, 3.0));
  std::string walker_model = kneed_walker::tools::packageFile("config/walker_model.yaml");
  app.add_option("--walker-model", walker_model, "body proportions of the walker (the table records them)")
      ->check(CLI::ExistingFile)->capture_default_str();
  if (!kneed_walker::tools::refuseEmptyArguments("optimize_gaits", argc, argv)) return 1;
  CLI11_PARSE(app, argc, argv);
  // The swing bounds to solve with: those given, else (resuming or merging) the table's.
  auto takeSwingBounds = [&](kw::gait::GaitTable& table) {
    if (clearance_option->count() == 0) options.min_passing_clearance = table.swing_bounds.min_passing_clearance;
    if (flexion_option->count() == 0) options.max_swing_knee_flexion = table.swing_bounds.max_swing_knee_flexion;
    table.swing_bounds = {options.min_passing_clearance, options.max_swing_knee_flexion};
  };
  for (const auto& [axis, name] : {std::pair{&speeds_kmh, "--speeds"}, std::pair{&step_lengths_m, "--step-lengths"},
                                   std::pair{&slopes_rad, "--slopes"}}) {
    if (axis->size() == 1) {
      std::fprintf(stderr, "optimize_gaits: %s needs at least two values (a grid axis)\n", name);
      return 1;
    }
    for (size_t i = 1; i < axis->size(); ++i)
      if (!((*axis)[i - 1] < (*axis)[i])) {
        std::fprintf(stderr, "optimize_gaits: %s must be ascending without repeats (%g then %g)\n", name,
                     (*axis)[i - 1], (*axis)[i]);
        return 1;
      }
  }
  if (seed_only && seed_table.empty()) {
    std::fprintf(stderr, "optimize_gaits: --seed-only needs --seed-table\n");
    return 1;
  }
  threads = kw::common::resolveThreads(threads);
  kw::dynamics::BodyProportions proportions;
  try {
    proportions = kw::dynamics::loadBodyProportions(walker_model);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "optimize_gaits: %s\n", e.what());
    return 1;
  }

  if (!merge_table.empty()) {
    try {
      kw::gait::GaitTable table = kw::gait::loadGaitTable(out, proportions);
      kw::gait::GaitTable other = kw::gait::loadGaitTable(merge_table, proportions);
      takeSwingBounds(table);
      other.swing_bounds = table.swing_bounds;  // its gaits are checked against them next
      markStaleGaits(table, options, out);
      markStaleGaits(other, options, merge_table);
      const int taken = kw::gait::keepLowerEffort(table, other);
      writeAtomically(out, table);
      int feasible = 0;
      for (const auto& e : table.entries) feasible += e.feasible;
      std::fprintf(stderr, "optimize_gaits: took %d gaits of lower effort from %s; %d of %d feasible; wrote %s\n",
                   taken, merge_table.c_str(), feasible, table.grid.size(), out.c_str());
      return 0;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "optimize_gaits: %s\n", e.what());
      return 1;
    }
  }

  // Hours of work must not be lost to an unwritable --out: write the table's temporary file
  // once before starting.
  {
    const std::string probe = out + ".tmp.yaml";
    std::FILE* file = std::fopen(probe.c_str(), "w");
    if (!file) {
      std::fprintf(stderr, "optimize_gaits: --out %s: cannot write there\n", out.c_str());
      return 1;
    }
    std::fclose(file);
    std::filesystem::remove(probe);
  }

  kw::gait::GaitTable table;
  // The grid asked for: the paper's, or the table's own when resuming, with the axes given.
  auto requestedGrid = [&](kw::gait::GaitGrid grid) {
    if (!speeds_kmh.empty()) grid.speeds_kmh = speeds_kmh;
    if (!step_lengths_m.empty()) grid.step_lengths_m = step_lengths_m;
    if (!slopes_rad.empty()) grid.slopes_rad = slopes_rad;
    return grid;
  };
  if (resume && std::filesystem::exists(out)) {
    table = kw::gait::loadGaitTable(out, proportions);
    if (!checkResumedAxis("--speeds", speeds_kmh, table, 0) || !checkResumedAxis("--step-lengths", step_lengths_m, table, 1) ||
        !checkResumedAxis("--slopes", slopes_rad, table, 2))
      return 1;
    table = kw::gait::regridded(table, requestedGrid(table.grid));
    if (prior_fixed && !table.fixed)
      throw std::invalid_argument(out + " was optimised freely: --prior-fixed cannot resume it");
    if (prior_fixed && *table.fixed != kw::gait::FixedControls{}) {
      // The prior's fixed values changed since the table was made: its gaits take the new ones,
      // and those that then no longer close their cycle are marked failed just below (a gait on
      // the level keeps its torso rest angle, 0 either way).
      std::fprintf(stderr, "optimize_gaits: %s holds other fixed controls than the prior's: its gaits take the prior's\n",
                   out.c_str());
      table.fixed = kw::gait::FixedControls{};
      for (auto& entry : table.entries)
        entry.gait.controls = kw::gait::withFixedControls(entry.gait.controls, *table.fixed);
    }
    takeSwingBounds(table);
    markStaleGaits(table, options, out);
    if (retry_failed)
      for (auto& e : table.entries)
        if (e.solved && !e.feasible) e.solved = false;
  } else {
    table.grid = requestedGrid(kw::gait::GaitGrid::paper());
    table.grid.leg_length_per_height = proportions.leg_length_per_height;
    table.body = proportions;
    table.entries.resize(table.grid.size());
    if (prior_fixed) table.fixed = kw::gait::FixedControls{};
    table.swing_bounds = {options.min_passing_clearance, options.max_swing_knee_flexion};
  }
  options.fixed = table.fixed;
  const kw::gait::GaitGrid& grid = table.grid;
  const auto start_time = std::chrono::steady_clock::now();
  auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  };

  kw::optimizer::GrowthOptions growth;
  growth.threads = threads;
  growth.max_attempts = max_attempts;
  growth.seed_point = kw::optimizer::nearestGridPoint(grid, seed_speed, seed_step, seed_slope);
  // The --seed-table's feasible gaits at this grid's points, tried first at each; with
  // --seed-only, only its gait nearest the seed point (the table grown from that one gait).
  if (!seed_table.empty()) {
    const kw::gait::GaitTable on_grid = kw::gait::regridded(kw::gait::loadGaitTable(seed_table, proportions), grid);
    growth.first_tries.resize(grid.size());
    for (int i = 0; i < grid.size(); ++i)
      if (on_grid.entries[i].feasible) growth.first_tries[i] = on_grid.entries[i].gait;
    if (seed_only) kw::optimizer::keepOnlyNearestFirstTry(growth, grid);
  }
  if (std::none_of(table.entries.begin(), table.entries.end(), [](const auto& e) { return e.feasible; })) {
    std::fprintf(stderr, "optimize_gaits: seeding %s...\n",
                 seed_table.empty() ? "by continuation from McGeer's passive gait"
                                    : ("from " + seed_table + "'s gaits nearest the seed point, else by continuation "
                                       "from McGeer's passive gait").c_str());
    const kw::optimizer::OptimalGait gait = kw::optimizer::seedTable(table, options, growth);
    writeAtomically(out, table);
    if (!gait.feasible()) {
      std::fprintf(stderr, "optimize_gaits: the seed gait did not converge (residual %g)\n",
                   gait.periodicity_residual);
      return 1;
    }
  }

  kneed_walker::tools::ProgressReport report;
  auto progress = [&](const kw::optimizer::GrowthProgress& p) {
    const double rate = elapsed() / std::max(1, p.solved);
    report.update(p.solved, p.points,
                  "solved, " + std::to_string(p.feasible) + " feasible | " + clock(elapsed()) + " elapsed, ~" +
                      clock(rate * (p.points - p.solved)) + " left");
  };
  kw::optimizer::GrowthProgress before{0, 0, grid.size()};
  for (const auto& e : table.entries) before.solved += e.solved, before.feasible += e.feasible;
  progress(before);
  kw::optimizer::growTable(table, options, growth,
                           [&](const kw::gait::GaitTable& grown, const kw::optimizer::GrowthProgress& p) {
                             writeAtomically(out, grown);
                             progress(p);
                           });
  report.finish();

  // Written here too: a resume that solved no point may still have re-marked stale gaits or
  // regridded the table, and the workers only write after solving one.
  writeAtomically(out, table);
  if (polish) {
    const double polish_start = elapsed();
    auto summedEffort = [&] {
      double sum = 0;
      for (const auto& e : table.entries)
        if (e.feasible) sum += e.quality.effort;
      return sum;
    };
    const double effort_before = summedEffort();
    int last_sweep = 0;
    kneed_walker::tools::ProgressReport sweep_report;
    // Written after every sweep: an interrupted polish keeps the sweeps it finished.
    const kw::optimizer::PolishReport report = kw::optimizer::polishTable(
        table, options, threads, polish_sweeps, 1e-3,
        [&](const kw::optimizer::PolishProgress& p) {
          if (p.sweep != last_sweep) {  // each sweep its own bar
            sweep_report.finish();
            sweep_report = kneed_walker::tools::ProgressReport();
          }
          last_sweep = p.sweep;
          sweep_report.update(p.done, p.points,
                              "gaits of polish sweep " + std::to_string(p.sweep) + ", " + std::to_string(p.improved) +
                                  " improved | " + clock(elapsed() - polish_start) + " elapsed");
        },
        [&](const kw::gait::GaitTable& polished) { writeAtomically(out, polished); });
    sweep_report.finish();
    std::fprintf(stderr, "optimize_gaits: polished in %d sweeps (%d solves, %s): %d gaits of lower effort, "
                 "summed effort %.4g -> %.4g\n", report.sweeps, report.solves,
                 clock(elapsed() - polish_start).c_str(), report.improved_points, effort_before, summedEffort());
  }
  int feasible = 0, unreached = 0;
  for (const auto& e : table.entries) feasible += e.feasible, unreached += !e.solved;
  std::fprintf(stderr, "optimize_gaits: %d of %d gaits feasible, %d unreached, in %s on %d threads; wrote %s\n",
               feasible, grid.size(), unreached, clock(elapsed()).c_str(),
               threads, out.c_str());
  return 0;
}

int main(int argc, char** argv) {
  return kneed_walker::tools::runTool("optimize_gaits", run, argc, argv);
}
