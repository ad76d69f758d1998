#include "kneed_walker/core/optimizer/table_polish.h"

#include <array>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <vector>

#include "kneed_walker/core/common/parallel.h"

namespace kneed_walker::core::optimizer {
namespace {

// The face neighbours of a grid point: one step along one axis.
std::vector<int> faceNeighbours(const gait::GaitGrid& grid, int index) {
  const std::array<int, 3> cell = grid.cell(index);
  const std::array<int, 3> sizes = {static_cast<int>(grid.speeds_kmh.size()),
                                    static_cast<int>(grid.step_lengths_m.size()),
                                    static_cast<int>(grid.slopes_rad.size())};
  std::vector<int> around;
  for (int axis = 0; axis < 3; ++axis)
    for (int step : {-1, 1}) {
      std::array<int, 3> next = cell;
      next[axis] += step;
      if (next[axis] >= 0 && next[axis] < sizes[axis]) around.push_back(grid.index(next[0], next[1], next[2]));
    }
  return around;
}

}  // namespace

PolishReport polishTable(gait::GaitTable& table, const GaitOptimizerOptions& given, int threads, int max_sweeps,
                         double min_improvement, const std::function<void(const PolishProgress&)>& progress,
                         const std::function<void(const gait::GaitTable&)>& after_sweep) {
  if (threads < 0) throw std::invalid_argument("polishTable: threads must be >= 0 (0: all cores)");
  if (max_sweeps < 1) throw std::invalid_argument("polishTable: max_sweeps must be >= 1");
  if (!(min_improvement >= 0 && min_improvement < 1))
    throw std::invalid_argument("polishTable: min_improvement must lie in [0, 1)");
  GaitOptimizerOptions options = given;
  options.fixed = table.fixed;
  options.min_passing_clearance = table.swing_bounds.min_passing_clearance;
  options.max_swing_knee_flexion = table.swing_bounds.max_swing_knee_flexion;
  const gait::GaitGrid& grid = table.grid;
  const int size = grid.size();
  PolishReport report;
  std::vector<bool> ever_improved(size, false);
  // The points whose gait the last sweep replaced (all, before the first sweep: every
  // neighbour is new to every point).
  std::vector<bool> replaced(size, true);
  for (int sweep = 1; sweep <= max_sweeps; ++sweep) {
    // This sweep's work: each feasible point with the warm starts new to it.
    std::vector<int> points;
    std::vector<std::vector<int>> starts;
    for (int i = 0; i < size; ++i) {
      if (!table.entries[i].feasible) continue;
      std::vector<int> from;
      for (int n : faceNeighbours(grid, i))
        if (table.entries[n].feasible && replaced[n]) from.push_back(n);
      if (from.empty()) continue;
      points.push_back(i);
      starts.push_back(std::move(from));
    }
    if (points.empty()) break;
    report.sweeps = sweep;
    const std::vector<gait::GaitTableEntry> before = table.entries;  // what every start reads
    std::vector<std::optional<OptimalGait>> better(points.size());
    std::vector<int> solves(points.size(), 0);
    std::mutex mutex;
    PolishProgress state{sweep, 0, static_cast<int>(points.size()), 0};
    common::parallelFor(static_cast<int>(points.size()), threads, [&](int begin, int end) {
      for (int k = begin; k < end; ++k) {
        const int point = points[k];
        double best_effort = before[point].quality.effort * (1 - min_improvement);
        for (int n : starts[k]) {
          OptimalGait gait = optimizeGait(table.body, grid.target(point), before[n].gait, options);
          ++solves[k];
          if (gait.feasible() && gait.effort < best_effort) {
            best_effort = gait.effort;
            better[k] = std::move(gait);
          }
        }
        if (progress) {
          const std::lock_guard<std::mutex> lock(mutex);
          ++state.done;
          state.improved += better[k].has_value();
          progress(state);
        }
      }
    }, 1);
    std::fill(replaced.begin(), replaced.end(), false);
    bool any_replaced = false;
    for (size_t k = 0; k < points.size(); ++k) {
      report.solves += solves[k];
      if (!better[k]) continue;
      table.entries[points[k]] = tableEntry(*better[k]);
      replaced[points[k]] = true;
      ever_improved[points[k]] = true;
      any_replaced = true;
    }
    if (after_sweep) after_sweep(table);
    if (!any_replaced) break;
  }
  for (bool improved : ever_improved) report.improved_points += improved;
  return report;
}

}  // namespace kneed_walker::core::optimizer
