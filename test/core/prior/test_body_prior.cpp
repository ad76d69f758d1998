#include "kneed_walker/core/prior/body_prior.h"

#include <gtest/gtest.h>

#include <cmath>

#include "shipped_config.h"

namespace kneed_walker::core::prior {
namespace {

// The prior around the prior table's gait at 4.5 km/h, 0.7 m steps and `gait_slope_rad`, its body
// on ground of `ground_slope_rad` if given.
BodyPrior priorOn(double gait_slope_rad, std::optional<double> ground_slope_rad = std::nullopt) {
  const gait::GaitTable table = gait::loadGaitTable(test::configFile("prior_gait_table.yaml"), test::shippedWalkerModel());
  const dynamics::WalkerSimulator sim(dynamics::dimensionlessWalker(table.body));
  gait::Gait gait = gait::interpolateGait(table, 4.5, 0.7, gait_slope_rad);
  gait.stride_duration = sim.stride(gait.controls, gait.start).duration;
  return BodyPrior(WalkerPrior(sim, gait, loadPriorOptions(test::configFile("prior.yaml"))), 1.75,
                   table.body.leg_length_per_height, table.grid.gravity, ground_slope_rad);
}

BodyPrior levelPrior() { return priorOn(0.0); }

TEST(BodyPrior, SamplesStandOnTheGivenGroundPointAlongTheHeading) {
  const BodyPrior prior = levelPrior();
  common::Random random(1);
  for (dynamics::Leg leg : {dynamics::Leg::kLeft, dynamics::Leg::kRight}) {
    body::BodyPose pose;
    const BodyParticle p = prior.sample(0.0, Eigen::Vector2d(2, 3), 0.5, random, pose, leg);
    EXPECT_EQ(p.walker.walker.stance_leg, leg);
    const int side = leg == dynamics::Leg::kLeft ? 0 : 1;
    EXPECT_NEAR((pose.foot_centres[side].head<2>() - Eigen::Vector2d(2, 3)).norm(), 0.0, 0.1)
        << "the stance foot is at the given point (to its own sideways offset)";
    EXPECT_EQ(p.stance_foot_m, pose.foot_centres[side]);
    EXPECT_NEAR(std::atan2(pose.forward.y(), pose.forward.x()), 0.5, 1e-12);
    // The stance leg is on its own side: left of the walking direction for the left leg.
    const double sideways = (pose.joints[body::kLeftHip] - pose.joints[body::kRightHip]).dot(pose.left);
    EXPECT_GT(sideways, 0.1);
  }
}

TEST(BodyPrior, TheStanceFootRollsWithoutSlidingFrameToFrame) {
  const BodyPrior prior = levelPrior();
  common::Random random(2);
  body::BodyPose pose;
  BodyParticle p = prior.sample(0.1, Eigen::Vector2d(0, 0), 0.0, random, pose);
  double worst = 0;
  int frames = 0;
  for (int f = 0; f < 60; ++f) {
    const BodyParticle before = p;
    const body::BodyPose before_pose = pose;
    ASSERT_FALSE(prior.transition(p, 1.0 / 30, random, pose).fell);
    if (p.walker.walker.heel_strikes != before.walker.walker.heel_strikes) continue;
    const int side = p.walker.walker.stance_leg == dynamics::Leg::kLeft ? 0 : 1;
    // Rolling moves the foot centre by −R Δθ along the walk; anything else is a slide.
    const double turn = p.walker.walker.q[dynamics::kStanceShank] - before.walker.walker.q[dynamics::kStanceShank];
    const double radius = prior.walkerPrior().simulator().model().foot_radius * prior.legLengthM();
    const Eigen::Vector3d rolled = before_pose.foot_centres[side] - radius * turn * pose.forward;
    worst = std::max(worst, (pose.foot_centres[side] - rolled).head<2>().norm());
    ++frames;
  }
  EXPECT_GT(frames, 30);
  std::cout << "worst slide of the stance foot over a frame " << worst << " m over " << frames << " frames\n";
  // Measured 2.2e-16 m: the hold is exact up to the rounding of metre-scale positions.
  EXPECT_LT(worst, 1e-14) << "metres";
}

// On ground steeper than its gait (as the tracker walks a 10° climb with the table's 4.3° gaits:
// the prior's table has none steeper uphill; here the level gait, which the prior walks without
// a fall, on a 0.1 rad climb), the body walks on the ground: its soles
// never go under the plane and the stance sole stays on it, the hip rises with it, and the
// torso leans a third of the slopes' difference more into the climb than the gait's body does.
TEST(BodyPrior, OnGroundSteeperThanItsGaitTheBodyWalksOnTheGround) {
  const double gait_slope = 0.0, ground_slope = 0.1;
  const BodyPrior on_gait = priorOn(gait_slope), steeper = priorOn(gait_slope, ground_slope);
  EXPECT_DOUBLE_EQ(on_gait.groundSlopeRad(), gait_slope);
  EXPECT_DOUBLE_EQ(steeper.groundSlopeRad(), ground_slope);
  EXPECT_DOUBLE_EQ(steeper.slopeRad(), gait_slope);
  // The body's ground: through the particle's origin (Z = 0 there), its normal the pose's up.
  const double heading = 0.5;
  auto sole_above_m = [&](const BodyPrior& prior, const body::BodyPose& pose, const BodyParticle& p, int side) {
    const Eigen::Vector2d origin = p.placement.value.ground_origin_m;
    const Eigen::Vector3d from = pose.foot_centres[side] - Eigen::Vector3d(origin.x(), origin.y(), 0);
    const double radius = prior.walkerPrior().simulator().model().foot_radius * prior.legLengthM();
    return from.dot(pose.up) - radius * std::cos(p.placement.value.hip_abduction_rad[side]);
  };
  double leans[2] = {0, 0};
  for (int which = 0; which < 2; ++which) {
    const BodyPrior& prior = which == 0 ? on_gait : steeper;
    common::Random random(3);
    body::BodyPose pose;
    BodyParticle p = prior.sample(0.1, Eigen::Vector2d(1, 2), heading, random, pose);
    const Eigen::Vector3d waist_start = pose.joints[body::kWaist];
    double lowest_m = 1, highest_stance_m = -1, lean_sum = 0;
    int frames = 0;
    for (int f = 0; f < 45; ++f) {
      ASSERT_FALSE(prior.transition(p, 1.0 / 30, random, pose).fell) << "frame " << f;
      const int stance = p.walker.walker.stance_leg == dynamics::Leg::kLeft ? 0 : 1;
      for (int side : {0, 1}) lowest_m = std::min(lowest_m, sole_above_m(prior, pose, p, side));
      highest_stance_m = std::max(highest_stance_m, std::abs(sole_above_m(prior, pose, p, stance)));
      EXPECT_NEAR(std::acos(pose.up.z()), std::abs(prior.groundSlopeRad()), 1e-12);
      const Eigen::Vector3d up = pose.joints[body::kNeck] - pose.joints[body::kWaist];
      lean_sum += std::atan2(up.head<2>().dot(pose.forward.head<2>().normalized()), up.z());
      ++frames;
    }
    const Eigen::Vector3d climbed = pose.joints[body::kWaist] - waist_start;
    const double rise = std::atan2(climbed.z(), climbed.head<2>().norm());
    leans[which] = lean_sum / frames;
    std::cout << (which == 0 ? "on the gait's slope" : "on the steeper ground") << ": lowest sole " << lowest_m * 1e3
              << " mm, stance sole within " << highest_stance_m * 1e3 << " mm, the waist rises at "
              << rise * 180 / M_PI << " deg, the torso leans " << leans[which] * 180 / M_PI << " deg\n";
    EXPECT_GT(lowest_m, -0.02 * prior.legLengthM());  // the runtime's max_swing_penetration is 0.03 L
    EXPECT_LT(highest_stance_m, 3e-3);  // measured 0.8 mm on the gait's slope, 1.9 mm on the steeper
    EXPECT_NEAR(rise, prior.groundSlopeRad(), 0.03);  // 1.5 s: not whole strides
  }
  EXPECT_NEAR(leans[1] - leans[0], (ground_slope - gait_slope) / 3, 1e-9);
}

}  // namespace
}  // namespace kneed_walker::core::prior
