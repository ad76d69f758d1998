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
// A first gait is found by continuation from McGeer's passive walker at the seed point; every
// other grid point is then solved warm-started from its already solved neighbours (the points
// with the most solved neighbours first, on all cores; with --seed-table, that table's gait at
// the point first), and where those fail, by continuation from the nearest neighbour through
// the midpoint. A point that failed is tried again whenever neighbours have become feasible
// since its last try. The table is rewritten after every gait, so an interrupted run continues
// with --resume. With --polish, every feasible gait is then solved again from its neighbours'
// gaits, sweep after sweep, and the lowest effort kept (optimizer::polishTable).
#include <unistd.h>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <mutex>
#include <optional>

#include "kneed_walker/core/common/parallel.h"
#include "kneed_walker/core/gait/gait_table.h"
#include "kneed_walker/core/optimizer/optimal_gaits.h"
#include "kneed_walker/core/optimizer/table_polish.h"
#include "options.h"
#include "tool_main.h"
#include "package_files.h"

namespace kw = kneed_walker::core;

namespace {

// Grid neighbours (Chebyshev distance 1) of a point.
std::vector<int> neighbours(const kw::gait::GaitGrid& grid, int index) {
  const auto c = grid.cell(index);
  const int n[3] = {static_cast<int>(grid.speeds_kmh.size()),
                    static_cast<int>(grid.step_lengths_m.size()),
                    static_cast<int>(grid.slopes_rad.size())};
  std::vector<int> result;
  for (int dv = -1; dv <= 1; ++dv)
    for (int dl = -1; dl <= 1; ++dl)
      for (int ds = -1; ds <= 1; ++ds) {
        const int v = c[0] + dv, l = c[1] + dl, s = c[2] + ds;
        if ((dv || dl || ds) && v >= 0 && v < n[0] && l >= 0 && l < n[1] && s >= 0 && s < n[2])
          result.push_back(grid.index(v, l, s));
      }
  return result;
}

double gridDistance(const kw::gait::GaitGrid& grid, int a, int b) {
  const auto ca = grid.cell(a), cb = grid.cell(b);
  double d = 0;
  for (int i = 0; i < 3; ++i) d += (ca[i] - cb[i]) * (ca[i] - cb[i]);
  return std::sqrt(d);
}

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

// Re-simulates every feasible gait of `table` and marks those that no longer meet the
// optimiser's constraints (a table written before a rule was added, such as the pushing
// ground at heel strike) as failed, so that --retry-failed solves them again and --merge never
// takes them. Returns how many were marked.
int markStaleGaits(kw::gait::GaitTable& table, const kw::dynamics::BodyProportions& proportions,
                   const kw::optimizer::GaitOptimizerOptions& options, const std::string& path) {
  int stale = 0;
  for (auto& entry : table.entries) {
    if (!entry.feasible || kw::optimizer::simulatedGait(proportions, entry.gait, options).feasible()) continue;
    entry.feasible = false;
    ++stale;
  }
  if (stale > 0)
    std::fprintf(stderr, "optimize_gaits: %d gaits of %s no longer meet the constraints (re-simulated): marked failed\n",
                 stale, path.c_str());
  return stale;
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
      markStaleGaits(table, proportions, options, out);
      markStaleGaits(other, proportions, options, merge_table);
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
    markStaleGaits(table, proportions, options, out);
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

  // The seed: the grid point nearest the requested one.
  int seed = 0;
  {
    double best = 1e300;
    for (int i = 0; i < grid.size(); ++i) {
      const auto c = grid.cell(i);
      const double d = std::pow(grid.speeds_kmh[c[0]] - seed_speed, 2) +
                       std::pow(grid.step_lengths_m[c[1]] - seed_step, 2) +
                       std::pow(grid.slopes_rad[c[2]] - seed_slope, 2);
      if (d < best) best = d, seed = i;
    }
  }
  // The --seed-table, and its feasible gaits at this grid's points, tried first at each.
  std::optional<kw::gait::GaitTable> seed_from;
  std::vector<std::optional<kw::gait::Gait>> seed_gaits(grid.size());
  if (!seed_table.empty()) {
    seed_from = kw::gait::loadGaitTable(seed_table, proportions);
    const kw::gait::GaitTable on_grid = kw::gait::regridded(*seed_from, grid);
    for (int i = 0; i < grid.size(); ++i)
      if (on_grid.entries[i].feasible) seed_gaits[i] = on_grid.entries[i].gait;
  }
  // With --seed-only, only the seed table's gait nearest the seed point: the table is grown
  // from that one gait.
  auto keepOnlyNearestSeedGait = [&] {
    int nearest = -1;
    for (int i = 0; i < grid.size(); ++i)
      if (seed_gaits[i] && (nearest < 0 || gridDistance(grid, i, seed) < gridDistance(grid, nearest, seed))) nearest = i;
    for (int i = 0; i < grid.size(); ++i)
      if (i != nearest) seed_gaits[i].reset();
  };
  if (seed_only) keepOnlyNearestSeedGait();
  const bool any_feasible = std::any_of(table.entries.begin(), table.entries.end(),
                                        [](const kw::gait::GaitTableEntry& e) { return e.feasible; });
  if (!any_feasible) {
    kw::optimizer::OptimalGait gait;
    if (!seed_table.empty()) {
      // From the seed table's gait at the seed point; when that does not lead to a gait here
      // (with the prior's fixed controls imposed, a free gait can land on a pulling ground and
      // SLSQP stall), from its gaits at the next nearest points, up to 12.
      std::fprintf(stderr, "optimize_gaits: seeding from %s's gaits, nearest the seed point first...\n",
                   seed_table.c_str());
      std::vector<int> order;
      for (int i = 0; i < grid.size(); ++i)
        if (seed_gaits[i]) order.push_back(i);
      std::sort(order.begin(), order.end(),
                [&](int a, int b) { return gridDistance(grid, a, seed) < gridDistance(grid, b, seed); });
      for (size_t k = 0; k < order.size() && k < 12 && !gait.feasible(); ++k) {
        gait = kw::optimizer::optimizeGait(proportions, grid.target(order[k]), *seed_gaits[order[k]], options);
        if (gait.feasible()) seed = order[k];
      }
    }
    // Without a seed table, or when none of its gaits led to one.
    if (!gait.feasible()) {
      std::fprintf(stderr, "optimize_gaits: seeding by continuation from McGeer's passive gait...\n");
      gait = kw::optimizer::seedGait(proportions, grid.target(seed), options);
    }
    table.entries[seed] = kw::optimizer::tableEntry(gait);
    writeAtomically(out, table);
    if (!gait.feasible()) {
      std::fprintf(stderr, "optimize_gaits: the seed gait did not converge (residual %g)\n",
                   gait.periodicity_residual);
      return 1;
    }
  }

  std::mutex mutex;
  std::condition_variable changed;
  std::vector<bool> in_progress(grid.size(), false);
  int running = 0;
  const bool tty = isatty(STDERR_FILENO);
  auto progress = [&] {
    int solved = 0, feasible = 0;
    for (const auto& e : table.entries) solved += e.solved, feasible += e.feasible;
    const int width = 30, filled = width * solved / grid.size();
    const double rate = elapsed() / std::max(1, solved);
    std::fprintf(stderr, "%s[%s%s] %d/%d solved, %d feasible | %s elapsed, ~%s left%s",
                 tty ? "\r" : "", std::string(filled, '#').c_str(),
                 std::string(width - filled, '-').c_str(), solved, grid.size(), feasible,
                 clock(elapsed()).c_str(), clock(rate * (grid.size() - solved)).c_str(),
                 tty ? "" : "\n");
  };

  // The feasible neighbours of a point, bit k for the k-th of neighbours(). A point that failed
  // is tried again, from the neighbours that have become feasible since its last try (a point
  // solved early, from one neighbour, often succeeds from the ones solved after it).
  auto feasibleNeighbours = [&](int point) {
    std::uint32_t mask = 0;
    const std::vector<int> around = neighbours(grid, point);
    for (size_t k = 0; k < around.size(); ++k)
      if (table.entries[around[k]].feasible) mask |= std::uint32_t{1} << k;
    return mask;
  };
  std::vector<std::uint32_t> tried_from(grid.size(), 0);  // feasible neighbours at the last try
  // A failed gait of a resumed table counts as tried from its neighbours as they are
  // (--retry-failed solves it again from all).
  for (int i = 0; i < grid.size(); ++i)
    if (table.entries[i].solved && !table.entries[i].feasible) tried_from[i] = feasibleNeighbours(i);

  // The next point to solve: unsolved, or failed with new feasible neighbours since its last
  // try, not in progress, with the most (new) warm starts (feasible neighbours, and the seed
  // table's gait there) (nearest the seed on ties); -1 if none is ready.
  auto nextPoint = [&]() {
    int best = -1, best_count = 0;
    double best_distance = 0;
    for (int i = 0; i < grid.size(); ++i) {
      const kw::gait::GaitTableEntry& entry = table.entries[i];
      if (entry.feasible || in_progress[i]) continue;
      const std::uint32_t fresh = feasibleNeighbours(i) & ~tried_from[i];
      int count = __builtin_popcount(fresh);
      if (entry.solved && count == 0) continue;
      if (!entry.solved) count += seed_gaits[i].has_value();
      const double distance = gridDistance(grid, i, seed);
      if (count > best_count || (count == best_count && count > 0 && distance < best_distance))
        best = i, best_count = count, best_distance = distance;
    }
    return best;
  };

  auto worker = [&] {
    std::unique_lock<std::mutex> lock(mutex);
    while (true) {
      const int point = nextPoint();
      if (point < 0) {
        if (running == 0) {
          changed.notify_all();
          return;
        }
        changed.wait(lock);
        continue;
      }
      in_progress[point] = true;
      ++running;
      // Warm starts: the neighbours feasible since the last try first, each group nearest first.
      const std::uint32_t now = feasibleNeighbours(point), fresh = now & ~tried_from[point];
      const bool retry = table.entries[point].solved;
      tried_from[point] = now;
      const std::vector<int> around = neighbours(grid, point);
      std::vector<int> starts;
      for (size_t k = 0; k < around.size(); ++k)
        if (now >> k & 1) starts.push_back(static_cast<int>(k));
      std::sort(starts.begin(), starts.end(), [&](int a, int b) {
        const bool fa = fresh >> a & 1, fb = fresh >> b & 1;
        if (fa != fb) return fa;
        return gridDistance(grid, around[a], point) < gridDistance(grid, around[b], point);
      });
      for (int& k : starts) k = around[k];
      std::vector<kw::gait::Gait> warm;
      if (seed_gaits[point] && !retry) warm.push_back(*seed_gaits[point]);
      for (int n : starts) warm.push_back(table.entries[n].gait);
      lock.unlock();

      // Warm starts from the nearest solved neighbours; the least effort among feasible ones.
      const kw::gait::GaitTarget target = grid.target(point);
      kw::optimizer::OptimalGait best;
      bool found = false;
      int evaluations = 0;
      for (size_t a = 0; a < warm.size() && static_cast<int>(a) < max_attempts; ++a) {
        const kw::optimizer::OptimalGait gait = kw::optimizer::optimizeGait(proportions, target, warm[a], options);
        evaluations += gait.evaluations;
        if (gait.feasible() && (!found || gait.effort < best.effort)) {
          best = gait;
          found = true;
        } else if (!found && a == 0) {
          best = gait;
        }
        if (found) break;
      }
      // Failing that, continue from the nearest neighbour through the midpoint target.
      const size_t nearest = seed_gaits[point] && !retry ? 1 : 0;
      if (!found && warm.size() > nearest) {
        const kw::gait::Gait& neighbour = warm[nearest];
        const kw::gait::GaitTarget& from = neighbour.target;
        const kw::gait::GaitTarget middle{0.5 * (from.speed + target.speed),
                                    0.5 * (from.step_length + target.step_length),
                                    0.5 * (from.slope + target.slope)};
        const kw::optimizer::OptimalGait half = kw::optimizer::optimizeGait(proportions, middle, neighbour, options);
        evaluations += half.evaluations;
        if (half.feasible()) {
          const kw::optimizer::OptimalGait gait = kw::optimizer::optimizeGait(proportions, target, half, options);
          evaluations += gait.evaluations;
          if (gait.feasible()) {
            best = gait;
            found = true;
          }
        }
      }
      best.evaluations = evaluations;

      lock.lock();
      table.entries[point] = kw::optimizer::tableEntry(best);
      in_progress[point] = false;
      --running;
      writeAtomically(out, table);
      progress();
      changed.notify_all();
    }
  };

  progress();
  // `threads` workers take points from the shared schedule until none is left.
  kw::common::parallelFor(threads, threads, [&](int begin, int end) {
    for (int w = begin; w < end; ++w) worker();
  }, 1);

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
    // Written after every sweep: an interrupted polish keeps the sweeps it finished.
    const kw::optimizer::PolishReport report = kw::optimizer::polishTable(
        table, options, threads, polish_sweeps, 1e-3,
        [&](const kw::optimizer::PolishProgress& p) {
          if (p.sweep != last_sweep && last_sweep > 0 && tty) std::fprintf(stderr, "\n");
          last_sweep = p.sweep;
          const int width = 30, filled = width * p.done / std::max(1, p.points);
          std::fprintf(stderr, "%spolish sweep %d [%s%s] %d/%d gaits, %d improved | %s elapsed%s", tty ? "\r" : "",
                       p.sweep, std::string(filled, '#').c_str(), std::string(width - filled, '-').c_str(), p.done,
                       p.points, p.improved, clock(elapsed() - polish_start).c_str(), tty ? "" : "\n");
        },
        [&](const kw::gait::GaitTable& polished) { writeAtomically(out, polished); });
    std::fprintf(stderr, "%soptimize_gaits: polished in %d sweeps (%d solves, %s): %d gaits of lower effort, "
                 "summed effort %.4g -> %.4g\n", tty ? "\n" : "", report.sweeps, report.solves,
                 clock(elapsed() - polish_start).c_str(), report.improved_points, effort_before, summedEffort());
  }
  int feasible = 0, unreached = 0;
  for (const auto& e : table.entries) feasible += e.feasible, unreached += !e.solved;
  std::fprintf(stderr, "%soptimize_gaits: %d of %d gaits feasible, %d unreached, in %s on %d threads; wrote %s\n",
               tty ? "\n" : "", feasible, grid.size(), unreached, clock(elapsed()).c_str(),
               threads, out.c_str());
  return 0;
}

int main(int argc, char** argv) {
  return kneed_walker::tools::runTool("optimize_gaits", run, argc, argv);
}
