#include "kneed_walker/core/optimizer/table_growth.h"

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <limits>
#include <mutex>
#include <stdexcept>

#include "kneed_walker/core/common/parallel.h"

namespace kneed_walker::core::optimizer {
namespace {

// Grid neighbours (Chebyshev distance 1) of a point: at most 26.
std::vector<int> neighbours(const gait::GaitGrid& grid, int index) {
  const auto c = grid.cell(index);
  const int n[3] = {static_cast<int>(grid.speeds_kmh.size()), static_cast<int>(grid.step_lengths_m.size()),
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

// Distance between two points in grid cells.
double gridDistance(const gait::GaitGrid& grid, int a, int b) {
  const auto ca = grid.cell(a), cb = grid.cell(b);
  double d = 0;
  for (int i = 0; i < 3; ++i) d += (ca[i] - cb[i]) * (ca[i] - cb[i]);
  return std::sqrt(d);
}

// The options a table's gaits are solved with: its fixed controls and swing bounds.
GaitOptimizerOptions forTable(const gait::GaitTable& table, GaitOptimizerOptions options) {
  options.fixed = table.fixed;
  options.min_passing_clearance = table.swing_bounds.min_passing_clearance;
  options.max_swing_knee_flexion = table.swing_bounds.max_swing_knee_flexion;
  return options;
}

GrowthProgress countSolved(const gait::GaitTable& table) {
  GrowthProgress progress{0, 0, table.grid.size()};
  for (const gait::GaitTableEntry& e : table.entries) progress.solved += e.solved, progress.feasible += e.feasible;
  return progress;
}

// The schedule of growTable: which point next, and from which warm starts. Not thread-safe:
// the workers hold one mutex around it.
class Schedule {
 public:
  Schedule(const gait::GaitTable& table, const GrowthOptions& growth)
      : table_(table), growth_(growth), in_progress_(table.grid.size(), false), tried_from_(table.grid.size(), 0) {
    // A failed gait of a resumed table counts as tried from its neighbours as they are.
    for (int i = 0; i < table.grid.size(); ++i)
      if (table.entries[i].solved && !table.entries[i].feasible) tried_from_[i] = feasibleNeighbours(i);
  }

  // The next point: unsolved, or failed with new feasible neighbours since its last try, not in
  // progress, with the most (new) warm starts (feasible neighbours, and its first try) (nearest
  // the seed on ties); -1 if none is ready.
  int nextPoint() const {
    int best = -1, best_count = 0;
    double best_distance = 0;
    for (int i = 0; i < table_.grid.size(); ++i) {
      const gait::GaitTableEntry& entry = table_.entries[i];
      if (entry.feasible || in_progress_[i]) continue;
      const std::uint32_t fresh = feasibleNeighbours(i) & ~tried_from_[i];
      int count = __builtin_popcount(fresh);
      if (entry.solved && count == 0) continue;
      if (!entry.solved) count += firstTry(i) != nullptr;
      const double distance = gridDistance(table_.grid, i, growth_.seed_point);
      if (count > best_count || (count == best_count && count > 0 && distance < best_distance))
        best = i, best_count = count, best_distance = distance;
    }
    return best;
  }

  // Takes `point` into work: its warm starts, the first try first (on the first try only), then
  // the neighbours feasible since the last try, then the others, each group nearest first. The
  // nearest neighbour's index among them is `nearest`.
  std::vector<gait::Gait> begin(int point, size_t& nearest) {
    in_progress_[point] = true;
    const std::uint32_t now = feasibleNeighbours(point), fresh = now & ~tried_from_[point];
    const bool retry = table_.entries[point].solved;
    tried_from_[point] = now;
    const std::vector<int> around = neighbours(table_.grid, point);
    std::vector<int> starts;
    for (size_t k = 0; k < around.size(); ++k)
      if (now >> k & 1) starts.push_back(static_cast<int>(k));
    std::sort(starts.begin(), starts.end(), [&](int a, int b) {
      const bool fa = fresh >> a & 1, fb = fresh >> b & 1;
      if (fa != fb) return fa;
      return gridDistance(table_.grid, around[a], point) < gridDistance(table_.grid, around[b], point);
    });
    std::vector<gait::Gait> warm;
    if (firstTry(point) && !retry) warm.push_back(*firstTry(point));
    nearest = warm.size();
    for (int k : starts) warm.push_back(table_.entries[around[k]].gait);
    return warm;
  }
  void end(int point) { in_progress_[point] = false; }

 private:
  // The feasible neighbours of a point, bit k for the k-th of neighbours().
  std::uint32_t feasibleNeighbours(int point) const {
    std::uint32_t mask = 0;
    const std::vector<int> around = neighbours(table_.grid, point);
    for (size_t k = 0; k < around.size(); ++k)
      if (table_.entries[around[k]].feasible) mask |= std::uint32_t{1} << k;
    return mask;
  }
  const gait::Gait* firstTry(int point) const {
    return growth_.first_tries.empty() || !growth_.first_tries[point] ? nullptr : &*growth_.first_tries[point];
  }

  const gait::GaitTable& table_;
  const GrowthOptions& growth_;
  std::vector<bool> in_progress_;
  std::vector<std::uint32_t> tried_from_;  // feasible neighbours at the last try
};

// A point's gait from its warm starts: the first that leads to a feasible gait (up to
// max_attempts), else by continuation from the nearest neighbour through the midpoint target.
OptimalGait solvePoint(const gait::GaitTable& table, const GaitOptimizerOptions& options, int point,
                       const std::vector<gait::Gait>& warm, size_t nearest, int max_attempts) {
  const gait::GaitTarget target = table.grid.target(point);
  OptimalGait best;
  bool found = false;
  int evaluations = 0;
  for (size_t a = 0; a < warm.size() && static_cast<int>(a) < max_attempts && !found; ++a) {
    OptimalGait gait = optimizeGait(table.body, target, warm[a], options);
    evaluations += gait.evaluations;
    found = gait.feasible();
    if (found || a == 0) best = std::move(gait);
  }
  if (!found && warm.size() > nearest) {
    const gait::Gait& neighbour = warm[nearest];
    const gait::GaitTarget& from = neighbour.target;
    const gait::GaitTarget middle{0.5 * (from.speed + target.speed), 0.5 * (from.step_length + target.step_length),
                                  0.5 * (from.slope + target.slope)};
    const OptimalGait half = optimizeGait(table.body, middle, neighbour, options);
    evaluations += half.evaluations;
    if (half.feasible()) {
      OptimalGait gait = optimizeGait(table.body, target, half, options);
      evaluations += gait.evaluations;
      if (gait.feasible()) best = std::move(gait);
    }
  }
  best.evaluations = evaluations;
  return best;
}

}  // namespace

int nearestGridPoint(const gait::GaitGrid& grid, double speed_kmh, double step_length_m, double slope_rad) {
  int nearest = 0;
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < grid.size(); ++i) {
    const auto c = grid.cell(i);
    const double d = std::pow(grid.speeds_kmh[c[0]] - speed_kmh, 2) +
                     std::pow(grid.step_lengths_m[c[1]] - step_length_m, 2) +
                     std::pow(grid.slopes_rad[c[2]] - slope_rad, 2);
    if (d < best) best = d, nearest = i;
  }
  return nearest;
}

void keepOnlyNearestFirstTry(GrowthOptions& growth, const gait::GaitGrid& grid) {
  int nearest = -1;
  for (int i = 0; i < static_cast<int>(growth.first_tries.size()); ++i)
    if (growth.first_tries[i] &&
        (nearest < 0 || gridDistance(grid, i, growth.seed_point) < gridDistance(grid, nearest, growth.seed_point)))
      nearest = i;
  for (int i = 0; i < static_cast<int>(growth.first_tries.size()); ++i)
    if (i != nearest) growth.first_tries[i].reset();
}

OptimalGait seedTable(gait::GaitTable& table, const GaitOptimizerOptions& given, GrowthOptions& growth) {
  const GaitOptimizerOptions options = forTable(table, given);
  const gait::GaitGrid& grid = table.grid;
  OptimalGait gait;
  // From the given gaits nearest the seed point: with the prior's fixed controls imposed, a
  // free gait can land on a pulling ground and SLSQP stall, so up to 12 are tried.
  std::vector<int> order;
  for (int i = 0; i < static_cast<int>(growth.first_tries.size()); ++i)
    if (growth.first_tries[i]) order.push_back(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return gridDistance(grid, a, growth.seed_point) < gridDistance(grid, b, growth.seed_point);
  });
  for (size_t k = 0; k < order.size() && k < 12 && !gait.feasible(); ++k) {
    gait = optimizeGait(table.body, grid.target(order[k]), *growth.first_tries[order[k]], options);
    if (gait.feasible()) growth.seed_point = order[k];
  }
  if (!gait.feasible()) gait = seedGait(table.body, grid.target(growth.seed_point), options);
  table.entries[growth.seed_point] = tableEntry(gait);
  return gait;
}

GrowthProgress growTable(gait::GaitTable& table, const GaitOptimizerOptions& given, const GrowthOptions& growth,
                         const std::function<void(const gait::GaitTable&, const GrowthProgress&)>& after_point) {
  if (growth.threads < 0) throw std::invalid_argument("growTable: threads must be >= 0 (0: all cores)");
  if (growth.max_attempts < 1 || growth.max_attempts > 26)
    throw std::invalid_argument("growTable: max_attempts must lie in [1, 26]");
  if (!growth.first_tries.empty() && static_cast<int>(growth.first_tries.size()) != table.grid.size())
    throw std::invalid_argument("growTable: first_tries must be empty or one per grid point");
  const GaitOptimizerOptions options = forTable(table, given);
  const int threads = common::resolveThreads(growth.threads);
  Schedule schedule(table, growth);
  std::mutex mutex;
  std::condition_variable changed;
  int running = 0;
  auto worker = [&] {
    std::unique_lock<std::mutex> lock(mutex);
    while (true) {
      const int point = schedule.nextPoint();
      if (point < 0) {
        if (running == 0) {
          changed.notify_all();
          return;
        }
        changed.wait(lock);
        continue;
      }
      ++running;
      size_t nearest = 0;
      const std::vector<gait::Gait> warm = schedule.begin(point, nearest);
      lock.unlock();
      const OptimalGait gait = solvePoint(table, options, point, warm, nearest, growth.max_attempts);
      lock.lock();
      table.entries[point] = tableEntry(gait);
      schedule.end(point);
      --running;
      if (after_point) after_point(table, countSolved(table));
      changed.notify_all();
    }
  };
  // `threads` workers take points from the shared schedule until none is left.
  common::parallelFor(threads, threads, [&](int begin, int end) {
    for (int w = begin; w < end; ++w) worker();
  }, 1);
  return countSolved(table);
}

int markStaleGaits(gait::GaitTable& table, const GaitOptimizerOptions& given) {
  const GaitOptimizerOptions options = forTable(table, given);
  int stale = 0;
  for (gait::GaitTableEntry& entry : table.entries) {
    if (!entry.feasible || simulatedGait(table.body, entry.gait, options).feasible()) continue;
    entry.feasible = false;
    ++stale;
  }
  return stale;
}

}  // namespace kneed_walker::core::optimizer
