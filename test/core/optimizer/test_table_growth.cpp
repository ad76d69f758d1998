#include "kneed_walker/core/optimizer/table_growth.h"

#include "shipped_config.h"

#include <gtest/gtest.h>

#include <string>
#include <tuple>

namespace kneed_walker::core::optimizer {
namespace {

// The level 4 km/h 0.7 m gait of the free table before its polish (test_table_polish.cpp's
// fixture) on a small grid around it: 3.5-4 km/h, 0.6-0.7 m steps, level.
gait::GaitTable smallTable() {
  const gait::GaitTable gaits = gait::loadGaitTable(
      std::string(KNEED_WALKER_SOURCE_DIR) + "/test/core/optimizer/data/unpolished_level_gaits.yaml",
      test::shippedWalkerModel());
  gait::GaitGrid grid = gaits.grid;
  grid.speeds_kmh = {3.5, 4.0};
  grid.step_lengths_m = {0.6, 0.7};
  grid.slopes_rad = {0.0};
  return gait::regridded(gaits, grid);
}

// From one gait, every other point of the grid is solved from its neighbours, on two workers:
// each point is solved (after_point sees the solved count grow, or a failed point solved again
// from new neighbours), the 3.5 km/h 0.6 m point (solvable from the 4 km/h 0.7 m gait) is
// feasible, every gait called feasible is (re-simulated, under the table's bounds) and the
// counts returned are the table's.
TEST(TableGrowth, SolvesEveryPointFromItsNeighbours) {
  gait::GaitTable table = smallTable();
  const int size = table.grid.size();
  int given = 0;
  for (const auto& e : table.entries) given += e.feasible;
  ASSERT_EQ(given, 1);  // the fixture's 4.5 km/h gait is off this grid
  GrowthOptions growth;
  growth.threads = 2;
  growth.seed_point = nearestGridPoint(table.grid, 4.0, 0.7, 0.0);
  int calls = 0, last_solved = given;
  const GrowthProgress result = growTable(table, GaitOptimizerOptions{}, growth,
                                          [&](const gait::GaitTable&, const GrowthProgress& p) {
                                            ++calls;
                                            EXPECT_TRUE(p.solved == last_solved + 1 || p.solved == last_solved);
                                            last_solved = p.solved;
                                          });
  EXPECT_EQ(result.points, size);
  EXPECT_EQ(result.solved, size);
  EXPECT_GE(calls, size - given);
  EXPECT_TRUE(table.entries[nearestGridPoint(table.grid, 3.5, 0.6, 0.0)].feasible);
  GaitOptimizerOptions bounds;
  bounds.min_passing_clearance = table.swing_bounds.min_passing_clearance;
  bounds.max_swing_knee_flexion = table.swing_bounds.max_swing_knee_flexion;
  int feasible = 0;
  for (int i = 0; i < size; ++i) {
    ASSERT_TRUE(table.entries[i].solved) << "point " << i;
    if (!table.entries[i].feasible) continue;
    ++feasible;
    EXPECT_TRUE(simulatedGait(table.body, table.entries[i].gait, bounds).feasible()) << "point " << i;
  }
  EXPECT_EQ(feasible, result.feasible);
}

// The seed: the given gait nearest the seed point (keepOnlyNearestFirstTry keeps it alone) is
// solved at its own point, which becomes the seed point.
TEST(TableGrowth, SeedsFromTheNearestGivenGait) {
  const gait::GaitTable given = smallTable();
  gait::GaitTable table = given;
  for (auto& e : table.entries) e = gait::GaitTableEntry{};
  GrowthOptions growth;
  growth.first_tries.resize(table.grid.size());
  for (int i = 0; i < table.grid.size(); ++i)
    if (given.entries[i].feasible) growth.first_tries[i] = given.entries[i].gait;
  growth.seed_point = nearestGridPoint(table.grid, 3.5, 0.6, 0.0);
  keepOnlyNearestFirstTry(growth, table.grid);
  const int from = nearestGridPoint(table.grid, 4.0, 0.7, 0.0);
  for (int i = 0; i < table.grid.size(); ++i) EXPECT_EQ(growth.first_tries[i].has_value(), i == from) << i;
  const OptimalGait gait = seedTable(table, GaitOptimizerOptions{}, growth);
  EXPECT_TRUE(gait.feasible());
  EXPECT_EQ(growth.seed_point, from);
  EXPECT_TRUE(table.entries[from].feasible);
  for (int i = 0; i < table.grid.size(); ++i) EXPECT_EQ(table.entries[i].solved, i == from) << i;
}

// Settings that mean nothing are refused, naming the setting.
TEST(TableGrowth, RefusesMeaninglessSettings) {
  gait::GaitTable table = smallTable();
  GrowthOptions too_few_threads, no_attempts, too_many_attempts, wrong_tries;
  too_few_threads.threads = -1;
  no_attempts.max_attempts = 0;
  too_many_attempts.max_attempts = 27;
  wrong_tries.first_tries.resize(2);
  for (const auto& [growth, name] : {std::tuple{too_few_threads, "threads"}, std::tuple{no_attempts, "max_attempts"},
                                     std::tuple{too_many_attempts, "max_attempts"},
                                     std::tuple{wrong_tries, "first_tries"}}) {
    try {
      growTable(table, GaitOptimizerOptions{}, growth);
      ADD_FAILURE() << name << " was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace kneed_walker::core::optimizer
