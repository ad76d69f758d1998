#include "kneed_walker/core/optimizer/optimal_gaits.h"

#include "kneed_walker/core/gait/gait_table.h"
#include "shipped_config.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

namespace kneed_walker::core::optimizer {
namespace {

TEST(OptimalGaits, EffortIsEquationNine) {
  dynamics::StrideResult stride;
  stride.duration = 2.0;
  stride.integrals.squared = {0.4, 0.2, 0.6, 1.0, 5.0};  // the ankle term is not in eq. 9
  const EffortWeights w;
  const double expected = 0.62 * std::pow(0.01, 1.5) +
                          132.3 * (0.3 * 0.4 + 0.007 * 0.2 + 0.007 * 0.6 + 0.034 * 1.0) / 2.0;
  EXPECT_NEAR(gaitEffort(stride, 0.01, w), expected, 1e-15);
}

// From McGeer's passive gait to the gait table's seed, level walking at 4.5 km/h with 0.70 m
// steps for the 1.75 m reference person: a feasible optimal gait whose stride really repeats.
TEST(OptimalGaits, SeedsALevelGaitByContinuation) {
  const gait::GaitTarget level = gait::GaitGrid::paper().target(4.5, 0.7, 0.0);
  const OptimalGait gait = seedGait(dynamics::BodyProportions{}, level, GaitOptimizerOptions{});
  ASSERT_TRUE(gait.feasible()) << "residual " << gait.periodicity_residual << ", speed error "
                               << gait.speed_error << ", step error " << gait.step_length_error;
  const dynamics::WalkerSimulator sim(dynamics::dimensionlessWalker(dynamics::BodyProportions{}));
  const dynamics::StrideResult again = sim.stride(gait.controls, gait.start);
  ASSERT_TRUE(again.completed);
  EXPECT_LT((again.end.q - gait.start.q).lpNorm<Eigen::Infinity>(), 1e-6);
  EXPECT_LT((again.end.qdot - gait.start.qdot).lpNorm<Eigen::Infinity>(), 1e-6);
  EXPECT_NEAR(again.speed, level.speed, 0.01 * level.speed);
  EXPECT_NEAR(again.step_length, level.step_length, 0.01 * level.step_length);
  EXPECT_NEAR(gaitEffort(again, gait.controls.toe_off_impulse, EffortWeights{}), gait.effort,
              1e-9);
  std::cout << "level gait: effort " << gait.effort << ", period " << again.duration
            << ", toe-off impulse " << gait.controls.toe_off_impulse << ", torso stiffness "
            << gait.controls.springs.torso_stiffness << "\n";
}

// The shipped table's entry at a grid point.
const gait::GaitTableEntry& entryAt(const gait::GaitTable& table, const gait::GaitTarget& target) {
  for (int i = 0; i < table.grid.size(); ++i) {
    const gait::GaitTarget t = table.grid.target(i);
    if (std::abs(t.speed - target.speed) < 1e-12 && std::abs(t.step_length - target.step_length) < 1e-12 &&
        t.slope == target.slope)
      return table.entries[i];
  }
  throw std::invalid_argument("no such grid point");
}

// The options a table's gaits were optimised with: its fixed controls and swing bounds.
GaitOptimizerOptions tableOptions(const gait::GaitTable& table) {
  GaitOptimizerOptions options;
  options.fixed = table.fixed;
  options.min_passing_clearance = table.swing_bounds.min_passing_clearance;
  options.max_swing_knee_flexion = table.swing_bounds.max_swing_knee_flexion;
  return options;
}

// The shipped free table's feasible gait at which `measure` of its stride is largest.
const gait::GaitTableEntry& entryWithLargest(const gait::GaitTable& table,
                                             double (*measure)(const dynamics::StrideResult&)) {
  const gait::GaitTableEntry* best = nullptr;
  double largest = -std::numeric_limits<double>::infinity();
  for (const auto& e : table.entries) {
    if (!e.feasible) continue;
    const double m = measure(simulatedGait(table.body, e.gait, tableOptions(table)).stride);
    if (m > largest) largest = m, best = &e;
  }
  return *best;
}

// A gait is feasible only if the runtime's simulator walks it: the optimiser's own lets the
// swing sole pass through the ground, the prior's calls a sole deeper than
// max_swing_penetration a fall. A shipped gait that dips 0.005 L or more while passing the
// stance foot is feasible with the default 0.03 L and not with a limit of 0.004 L.
TEST(OptimalGaits, AGaitTheRuntimeSimulatorCallsAFallIsNotFeasible) {
  // The prior's table: the free one clears the ground (issue 13).
  const gait::GaitTable table = gait::loadGaitTable(test::configFile("prior_gait_table.yaml"), test::shippedWalkerModel());
  const dynamics::WalkerSimulator runtime(dynamics::dimensionlessWalker(table.body));
  const gait::GaitTableEntry* scraping = nullptr;
  for (const auto& e : table.entries)
    if (e.feasible && runtime.stride(e.gait.controls, e.gait.start).integrals.passing_clearance < -0.005) {
      scraping = &e;
      break;
    }
  ASSERT_NE(scraping, nullptr) << "no shipped gait dips 0.005 L";
  const OptimalGait as_shipped = simulatedGait(table.body, scraping->gait);
  EXPECT_TRUE(as_shipped.walks_at_runtime);
  EXPECT_TRUE(as_shipped.feasible());
  GaitOptimizerOptions strict;
  strict.simulation.max_swing_penetration = 0.004;
  const OptimalGait strictly = simulatedGait(table.body, scraping->gait, strict);
  EXPECT_TRUE(strictly.stride.completed);  // the optimiser's stride function walks through
  EXPECT_FALSE(strictly.walks_at_runtime);
  EXPECT_FALSE(strictly.feasible());
}

// The landing inequality beside eq. 10 is active in the prior's shipped table: at the gait that
// lands softest at the bound, 0.01, the cheapest gait would push
// off so hard that its landing would need less. From it, the optimiser with the bound lowered to 0.008
// finds a cheaper gait that lands lower; with the bound raised to 0.012 it lands at least that
// hard, at more effort. (Larger changes of the bound are not asked: SLSQP with finite
// differences, started that far from the constraint, stalls. The table tool's continuation
// handles those.)
TEST(OptimalGaits, HoldsTheLandingImpulseAboveItsBound) {
  const gait::GaitTable table = gait::loadGaitTable(test::configFile("prior_gait_table.yaml"), test::shippedWalkerModel());
  const gait::GaitTableEntry& shipped =
      entryWithLargest(table, [](const dynamics::StrideResult& s) {
        return s.landing_impulse >= 0.0099 ? -s.landing_impulse : -1.0;  // at the bound, not below it
      });
  const gait::GaitTarget uphill = shipped.gait.target;
  const GaitOptimizerOptions bounded = tableOptions(table);
  const OptimalGait as_shipped = simulatedGait(table.body, shipped.gait, bounded);
  ASSERT_TRUE(as_shipped.feasible()) << "residual " << as_shipped.periodicity_residual;
  EXPECT_NEAR(as_shipped.effort, shipped.quality.effort, 1e-9 * shipped.quality.effort);
  EXPECT_NEAR(as_shipped.stride.landing_impulse, bounded.min_landing_impulse, 1e-4);

  GaitOptimizerOptions unbounded = bounded, raised = bounded;
  unbounded.min_landing_impulse = 0.008;  // lowered; removed, the optimum would land on a pulling ground
  raised.min_landing_impulse = 0.012;
  const OptimalGait lower = optimizeGait(table.body, uphill, shipped.gait, unbounded);
  const OptimalGait harder = optimizeGait(table.body, uphill, shipped.gait, raised);
  std::cout << "landing impulse (effort): shipped " << as_shipped.stride.landing_impulse << " ("
            << as_shipped.effort << "), unbounded " << lower.stride.landing_impulse << " (" << lower.effort
            << "), bound 0.012: " << harder.stride.landing_impulse << " (" << harder.effort << ")\n";
  ASSERT_TRUE(lower.feasible());
  EXPECT_LT(lower.effort, as_shipped.effort - 1e-3);
  ASSERT_TRUE(harder.feasible()) << "residual " << harder.periodicity_residual << ", speed error "
                                 << harder.speed_error << ", step error " << harder.step_length_error;
  EXPECT_GT(harder.stride.landing_impulse, raised.min_landing_impulse - 5e-4);
  EXPECT_GT(harder.effort, as_shipped.effort + 1e-3);
  EXPECT_TRUE(simulatedGait(table.body, harder, raised).feasible());
}

// The clearance inequality beside eq. 10 (GaitOptimizerOptions::min_passing_clearance; the free
// table is solved with 0.01 L): at a gait where it is active (the lowest passing clearance of
// the table, 0.0100 L), the optimiser without the bound finds a cheaper gait that passes lower,
// and that gait is not feasible with the bound.
TEST(OptimalGaits, HoldsTheSwingSoleAboveTheClearanceBound) {
  const gait::GaitTable table = gait::loadGaitTable(test::configFile("gait_table.yaml"), test::shippedWalkerModel());
  const GaitOptimizerOptions bounded = tableOptions(table);
  ASSERT_EQ(bounded.min_passing_clearance, 0.01);
  const gait::GaitTableEntry& at_bound =
      entryWithLargest(table, [](const dynamics::StrideResult& s) { return -s.integrals.passing_clearance; });
  const OptimalGait as_shipped = simulatedGait(table.body, at_bound.gait, bounded);
  ASSERT_TRUE(as_shipped.feasible());
  EXPECT_NEAR(as_shipped.stride.integrals.passing_clearance, 0.01, 1e-5);
  GaitOptimizerOptions unbounded = bounded;
  unbounded.min_passing_clearance = -std::numeric_limits<double>::infinity();
  const OptimalGait lower = optimizeGait(table.body, at_bound.gait.target, at_bound.gait, unbounded);
  std::cout << "passing clearance (effort): shipped " << as_shipped.stride.integrals.passing_clearance << " ("
            << as_shipped.effort << "), without the bound " << lower.stride.integrals.passing_clearance << " ("
            << lower.effort << ")\n";
  ASSERT_TRUE(lower.feasible()) << "residual " << lower.periodicity_residual;
  EXPECT_LT(lower.effort, as_shipped.effort);
  EXPECT_LT(lower.stride.integrals.passing_clearance, 0.01 - 1e-4);
  const OptimalGait checked = simulatedGait(table.body, lower, bounded);
  EXPECT_FALSE(checked.clears_the_ground);
  EXPECT_FALSE(checked.feasible());
}

// The knee inequality beside eq. 10 (GaitOptimizerOptions::max_swing_knee_flexion; the free
// table is solved with 1.31 rad): at the gait whose swing knee flexes most (at the bound), the
// optimiser without the bound finds a cheaper gait that flexes further, and that gait is not
// feasible with the bound.
TEST(OptimalGaits, HoldsTheSwingKneeUnderItsFlexionBound) {
  const gait::GaitTable table = gait::loadGaitTable(test::configFile("gait_table.yaml"), test::shippedWalkerModel());
  const GaitOptimizerOptions bounded = tableOptions(table);
  ASSERT_EQ(bounded.max_swing_knee_flexion, 1.31);
  const gait::GaitTableEntry& at_bound =
      entryWithLargest(table, [](const dynamics::StrideResult& s) { return s.integrals.max_swing_knee_flexion; });
  const OptimalGait as_shipped = simulatedGait(table.body, at_bound.gait, bounded);
  ASSERT_TRUE(as_shipped.feasible());
  EXPECT_NEAR(as_shipped.stride.integrals.max_swing_knee_flexion, 1.31, 1e-5);
  GaitOptimizerOptions unbounded = bounded;
  unbounded.max_swing_knee_flexion = std::numeric_limits<double>::infinity();
  const OptimalGait folded = optimizeGait(table.body, at_bound.gait.target, at_bound.gait, unbounded);
  std::cout << "swing knee peak (effort): shipped " << as_shipped.stride.integrals.max_swing_knee_flexion << " rad ("
            << as_shipped.effort << "), without the bound " << folded.stride.integrals.max_swing_knee_flexion
            << " rad (" << folded.effort << ")\n";
  // Periodic and on target; SLSQP ends this solve with the clearance bound not quite met, so
  // feasible() is not asked of it.
  ASSERT_TRUE(folded.stride.completed && folded.walks_at_runtime);
  EXPECT_LT(folded.periodicity_residual, 1e-6);
  EXPECT_LT(folded.speed_error, 0.01);
  EXPECT_LT(folded.step_length_error, 0.01);
  EXPECT_LT(folded.effort, as_shipped.effort);
  EXPECT_GT(folded.stride.integrals.max_swing_knee_flexion, 1.31 + 1e-4);
  const OptimalGait checked = simulatedGait(table.body, folded, bounded);
  EXPECT_FALSE(checked.knee_within_bound);
  EXPECT_FALSE(checked.feasible());
}

// A solve whose stride diverged (NaN speed and step length, unbounded effort) is recorded so
// that the table still loads: optimize_gaits wrote such an entry once, and neither --resume
// nor any reader could open the table again.
TEST(OptimalGaits, ADivergedGaitIsRecordedReadably) {
  gait::GaitTable table = gait::loadGaitTable(test::configFile("gait_table.yaml"), test::shippedWalkerModel());
  OptimalGait diverged;
  static_cast<gait::Gait&>(diverged) = table.entries[0].gait;
  diverged.stride.completed = false;
  diverged.stride.speed = diverged.stride.step_length = std::numeric_limits<double>::quiet_NaN();
  diverged.effort = std::numeric_limits<double>::quiet_NaN();
  diverged.periodicity_residual = std::numeric_limits<double>::infinity();
  table.entries[0] = tableEntry(diverged);
  EXPECT_FALSE(table.entries[0].feasible);
  const std::string path = testing::TempDir() + "diverged_gait_table.yaml";
  gait::saveGaitTable(path, table);
  const gait::GaitTable back = gait::loadGaitTable(path, test::shippedWalkerModel());
  std::remove(path.c_str());
  EXPECT_TRUE(back.entries[0].solved);
  EXPECT_FALSE(back.entries[0].feasible);
  EXPECT_EQ(back.entries[0].quality.speed, 0.0);
  EXPECT_EQ(back.entries[0].quality.step_length, 0.0);
  EXPECT_EQ(back.entries[0].quality.effort, std::numeric_limits<double>::infinity());
}

}  // namespace
}  // namespace kneed_walker::core::optimizer
