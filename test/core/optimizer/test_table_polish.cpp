#include "kneed_walker/core/optimizer/table_polish.h"

#include "shipped_config.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <tuple>

namespace kneed_walker::core::optimizer {
namespace {

// Two level gaits of the free table shipped before its polish (c9015b0; 4 and 4.5 km/h, 0.7 m steps); the
// 4.5 km/h one is a poor local optimum (effort 0.282).
gait::GaitTable unpolishedGaits() {
  return gait::loadGaitTable(std::string(KNEED_WALKER_SOURCE_DIR) + "/test/core/optimizer/data/unpolished_level_gaits.yaml",
                             test::shippedWalkerModel());
}

int indexOf(const gait::GaitGrid& grid, double speed_kmh) {
  for (int i = 0; i < grid.size(); ++i) {
    const auto cell = grid.cell(i);
    if (grid.speeds_kmh[cell[0]] == speed_kmh && cell[1] == 0 && cell[2] == 0) return i;
  }
  throw std::invalid_argument("no such point");
}

// Solved again from its neighbour's gait, the 4.5 km/h point reaches a far lower effort; the
// polished table's gaits are all still feasible (re-simulated), none costs more than before, the
// points without a gait stay without, and the sweeps stop when one improves nothing.
TEST(TablePolish, LowersTheEffortOfAPoorLocalOptimum) {
  const gait::GaitTable before = unpolishedGaits();
  gait::GaitTable table = before;
  int sweeps_seen = 0;
  const PolishReport report = polishTable(table, GaitOptimizerOptions{}, 1, 20, 1e-3, {},
                                          [&](const gait::GaitTable&) { ++sweeps_seen; });
  EXPECT_EQ(sweeps_seen, report.sweeps);
  const int fast = indexOf(table.grid, 4.5), slow = indexOf(table.grid, 4.0);
  ASSERT_TRUE(table.entries[fast].feasible);
  EXPECT_LT(table.entries[fast].quality.effort, 0.5 * before.entries[fast].quality.effort);
  EXPECT_GE(report.improved_points, 1);
  EXPECT_GE(report.sweeps, 2);  // the last sweep found nothing better
  EXPECT_GE(report.solves, 2);
  GaitOptimizerOptions bounds;
  bounds.min_passing_clearance = table.swing_bounds.min_passing_clearance;
  bounds.max_swing_knee_flexion = table.swing_bounds.max_swing_knee_flexion;
  for (int i = 0; i < table.grid.size(); ++i) {
    ASSERT_EQ(table.entries[i].feasible, before.entries[i].feasible) << "point " << i;
    if (!table.entries[i].feasible) continue;
    const OptimalGait again = simulatedGait(table.body, table.entries[i].gait, bounds);
    EXPECT_TRUE(again.feasible()) << "point " << i;
    EXPECT_NEAR(again.effort, table.entries[i].quality.effort, 1e-6 * (1 + again.effort)) << "point " << i;
    EXPECT_LE(table.entries[i].quality.effort, before.entries[i].quality.effort) << "point " << i;
  }
  std::cout << "4.5 km/h: effort " << before.entries[fast].quality.effort << " -> " << table.entries[fast].quality.effort
            << "; 4 km/h: " << before.entries[slow].quality.effort << " -> " << table.entries[slow].quality.effort
            << "; " << report.sweeps << " sweeps, " << report.solves << " solves\n";
}

// A sweep reads only the table it began with: the same table on one thread and on two.
TEST(TablePolish, GivesTheSameTableOnAnyNumberOfThreads) {
  gait::GaitTable one = unpolishedGaits(), two = unpolishedGaits();
  polishTable(one, GaitOptimizerOptions{}, 1);
  polishTable(two, GaitOptimizerOptions{}, 2);
  for (int i = 0; i < one.grid.size(); ++i) {
    ASSERT_EQ(one.entries[i].feasible, two.entries[i].feasible);
    EXPECT_EQ(one.entries[i].quality.effort, two.entries[i].quality.effort) << "point " << i;
    EXPECT_EQ(one.entries[i].gait.start.q, two.entries[i].gait.start.q) << "point " << i;
  }
}

// A table is polished under its own swing bounds, not the options': with the table's clearance
// bound raised above the 0.0105 L at which the 4.5 km/h point's cheaper gait passes, that gait
// may not replace the shipped one, even though the options ask for a lower one.
TEST(TablePolish, SolvesWithTheTablesOwnBounds) {
  gait::GaitTable table = unpolishedGaits();
  table.swing_bounds.min_passing_clearance = 0.0106;
  const gait::GaitTable before = table;
  GaitOptimizerOptions lower;
  lower.min_passing_clearance = 0.0;
  polishTable(table, lower, 1);
  for (int i = 0; i < table.grid.size(); ++i) {
    const gait::GaitTableEntry& entry = table.entries[i];
    if (!entry.feasible || entry.quality.effort == before.entries[i].quality.effort) continue;
    const OptimalGait again = simulatedGait(table.body, entry.gait, lower);
    EXPECT_GE(again.stride.integrals.passing_clearance, 0.0106 - 1e-6) << "point " << i;
    EXPECT_LE(again.stride.integrals.max_swing_knee_flexion, table.swing_bounds.max_swing_knee_flexion + 1e-6);
  }
}

// Settings that mean nothing are refused, naming the setting.
TEST(TablePolish, RefusesMeaninglessSettings) {
  gait::GaitTable table = unpolishedGaits();
  for (const auto& [threads, sweeps, improvement, name] :
       {std::tuple{-1, 20, 1e-3, "threads"}, std::tuple{1, 0, 1e-3, "max_sweeps"},
        std::tuple{1, 20, std::nan(""), "min_improvement"}, std::tuple{1, 20, 1.0, "min_improvement"},
        std::tuple{1, 20, -0.1, "min_improvement"}}) {
    try {
      polishTable(table, GaitOptimizerOptions{}, threads, sweeps, improvement);
      ADD_FAILURE() << name << " was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace kneed_walker::core::optimizer
