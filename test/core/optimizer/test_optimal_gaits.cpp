#include "kneed_walker/core/optimizer/optimal_gaits.h"

#include "kneed_walker/core/gait/gait_table.h"

#include <gtest/gtest.h>

#include <cmath>

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

}  // namespace
}  // namespace kneed_walker::core::optimizer
