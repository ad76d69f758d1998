#include "kneed_walker/core/synthetic/synthetic_walk.h"

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include <cmath>
#include <iostream>

#include "kneed_walker/core/vision/camera.h"
#include "shipped_config.h"

namespace kneed_walker::core::synthetic {
namespace {

const std::string kSource = KNEED_WALKER_SOURCE_DIR;

const gait::GaitTable& table() {
  static const gait::GaitTable t = gait::loadGaitTable(kSource + "/config/prior_gait_table.yaml",
                                                       test::shippedWalkerModel());
  return t;
}
const prior::PriorOptions& prior() {
  static const prior::PriorOptions p = prior::loadPriorOptions(kSource + "/config/prior.yaml");
  return p;
}

SyntheticWalkOptions walkOptions(std::uint64_t seed) {
  SyntheticWalkOptions o;
  o.seed = seed;
  o.duration_s = 4.0;
  o.fps = 15;
  o.start_m = {-15.0, -10.0};
  o.heading_rad = 2.5;
  return o;
}

TEST(SyntheticWalk, SameSeedSameWalk) {
  const SyntheticWalk a = synthesizeWalk(table(), prior(), walkOptions(5));
  const SyntheticWalk b = synthesizeWalk(table(), prior(), walkOptions(5));
  const SyntheticWalk c = synthesizeWalk(table(), prior(), walkOptions(6));
  ASSERT_EQ(a.frames.size(), 61u);
  ASSERT_EQ(a.frames.size(), b.frames.size());
  for (size_t i = 0; i < a.frames.size(); ++i)
    for (int j = 0; j < body::kNumBodyJoints; ++j) ASSERT_EQ(a.frames[i].pose.joints[j], b.frames[i].pose.joints[j]);
  EXPECT_NE(a.frames.back().pose.joints[body::kWaist], c.frames.back().pose.joints[body::kWaist]);
}

// The walk starts where asked and goes at about the asked speed: the prior perturbs the gait
// but keeps near it.
TEST(SyntheticWalk, WalksFromTheStartAtTheAskedSpeed) {
  for (const auto& [speed_kmh, step_m] : {std::pair{3.5, 0.6}, std::pair{5.0, 0.8}}) {
    SyntheticWalkOptions o = walkOptions(2);
    o.speed_kmh = speed_kmh;
    o.step_length_m = step_m;
    const SyntheticWalk walk = synthesizeWalk(table(), prior(), o);
    const body::BodyPose& first = walk.frames.front().pose;
    const int stance = walk.frames.front().walker.stance_leg == dynamics::Leg::kLeft ? 0 : 1;
    EXPECT_LT((first.foot_centres[stance].head<2>() - o.start_m).norm(), 0.25);
    const Eigen::Vector3d travelled = walk.frames.back().pose.joints[body::kWaist] - first.joints[body::kWaist];
    const double speed = travelled.head<2>().norm() / walk.frames.back().time_s * 3.6;
    std::cout << "asked " << speed_kmh << " km/h, walked " << speed << " km/h\n";
    EXPECT_NEAR(speed, speed_kmh, 0.15 * speed_kmh);
  }
}

// A speed change (issue 13): a walk asked to slow from 7 to 3 km/h over 6 s, its steps
// shortening from 0.8 to 0.5 m, starts at about the profile's speed and slows by more than
// 1.5 km/h. Each stride walks the gait of its heel strike's moment, and the walker takes a
// stride or two to settle on a new gait, so the walk lags the profile: measured 6.6 km/h over
// the first 1.5 s and 4.5 over the last, where the profile's means are 6.5 and 3.5.
TEST(SyntheticWalk, SlowsDownWhenAskedToChangeSpeed) {
  SyntheticWalkOptions o = walkOptions(4);
  o.speed_kmh = 7.0;
  o.step_length_m = 0.8;
  o.end_speed_kmh = 3.0;
  o.end_step_length_m = 0.5;
  o.duration_s = 6.0;
  const SyntheticWalk walk = synthesizeWalk(table(), prior(), o);
  const int window = static_cast<int>(1.5 * o.fps);
  auto speedKmh = [&](int from) {
    const Eigen::Vector3d d = walk.frames[from + window].pose.joints[body::kWaist] - walk.frames[from].pose.joints[body::kWaist];
    return d.head<2>().norm() / (window / o.fps) * 3.6;
  };
  const double early = speedKmh(0), late = speedKmh(static_cast<int>(walk.frames.size()) - 1 - window);
  std::cout << "walked " << early << " km/h over the first 1.5 s, " << late << " over the last; "
            << walk.attempts << " prior samples\n";
  EXPECT_NEAR(early, 6.5, 0.6);
  EXPECT_LT(late, early - 1.5);
  EXPECT_GT(late, 3.0);
  // Without the change, the same walk keeps its speed.
  o.end_speed_kmh.reset();
  o.end_step_length_m.reset();
  const SyntheticWalk steady = synthesizeWalk(table(), prior(), o);
  const Eigen::Vector3d d = steady.frames.back().pose.joints[body::kWaist] - steady.frames.front().pose.joints[body::kWaist];
  EXPECT_NEAR(d.head<2>().norm() / o.duration_s * 3.6, 7.0, 0.7);
}

// Acceptance (issue 5): the ground truth's stance foot does not slide. The foot rolls, so its
// centre must move by −R Δθ along the walking direction and keep R above the ground; whatever
// else it moves, summed over each stance, must stay below 1 mm.
TEST(SyntheticWalk, StanceFootDoesNotSkate) {
  for (double slope : {0.0, 0.075}) {
    SyntheticWalkOptions o = walkOptions(3);
    o.slope_rad = slope;
    o.speed_kmh = 4.0;  // inside the prior table's feasible gaits at both slopes
    o.step_length_m = 0.8;
    o.duration_s = 6.0;
    const SyntheticWalk walk = synthesizeWalk(table(), prior(), o);
    const double radius_m = dynamics::dimensionlessWalker(dynamics::BodyProportions{}).foot_radius * walk.leg_length_m;
    double skate = 0, worst = 0, worst_height = 0;
    int stances = 0;
    for (size_t i = 1; i < walk.frames.size(); ++i) {
      const SyntheticFrame &before = walk.frames[i - 1], &after = walk.frames[i];
      if (after.walker.heel_strikes != before.walker.heel_strikes) {
        worst = std::max(worst, skate);
        skate = 0;
        ++stances;
        continue;
      }
      const int side = after.walker.stance_leg == dynamics::Leg::kLeft ? 0 : 1;
      const double turn = after.walker.q[dynamics::kStanceShank] - before.walker.q[dynamics::kStanceShank];
      const Eigen::Vector3d rolled = -radius_m * turn * after.pose.forward;
      skate += (after.pose.foot_centres[side] - before.pose.foot_centres[side] - rolled).norm();
      const Eigen::Vector3d centre = after.pose.foot_centres[side];
      const double height = walk.ground.normal().dot(
          centre - Eigen::Vector3d(centre.x(), centre.y(), walk.ground.height(centre.head<2>())));
      worst_height = std::max(worst_height, std::abs(height - radius_m));
    }
    worst = std::max(worst, skate);
    std::cout << "slope " << slope << ": " << stances << " heel strikes, worst skate over a stance "
              << worst * 1e3 << " mm, foot centre off its height by " << worst_height * 1e3 << " mm\n";
    EXPECT_GE(stances, 6);
    // Measured 1.4e-14 m level (the rolling contact is exact: rounding only) and 0.035 mm at
    // 4.3° on 0.8 m steps (0.13 mm on 0.7 m steps; as for the foot's height below: on a slope
    // the walker's ground moves by tan γ along the walk).
    EXPECT_LT(worst, slope == 0 ? 1e-12 : 1e-3);
    // Exact on the level; on a slope, moving the body over the foot along the walk moves the
    // walker's ground by tan γ of that (measured 0.070 mm over 6 s at 4.3°, 0.17 mm on 0.7 m
    // steps).
    EXPECT_LT(worst_height, slope == 0 ? 1e-12 : 5e-4);
  }
}

// Acceptance (issue 5): the ground truth's joints project as cv::projectPoints projects them.
TEST(SyntheticWalk, ProjectedJointsAgreeWithOpenCv) {
  const vision::Camera camera = vision::Camera::load(std::string(KNEED_WALKER_SHARED_DIR) + "/data/pets2009/View_001_camera.yml", 0.001);
  const SyntheticWalk walk = synthesizeWalk(table(), prior(), walkOptions(4));
  std::vector<cv::Point3d> points;
  for (const SyntheticFrame& frame : walk.frames)
    for (const Eigen::Vector3d& j : frame.pose.joints) points.emplace_back(j.x(), j.y(), j.z());
  cv::Mat k, r, rvec, t;
  cv::eigen2cv(camera.intrinsics(), k);
  cv::eigen2cv(camera.rotation(), r);
  cv::Rodrigues(r, rvec);
  cv::eigen2cv(camera.translation(), t);
  std::vector<cv::Point2d> expected;
  cv::projectPoints(points, rvec, t, k, camera.distortion(), expected);
  double worst = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const auto pixel = camera.project({points[i].x, points[i].y, points[i].z});
    ASSERT_TRUE(pixel.has_value());
    worst = std::max(worst, (*pixel - Eigen::Vector2d(expected[i].x, expected[i].y)).norm());
  }
  std::cout << points.size() << " joints; worst difference " << worst << " px\n";
  EXPECT_LT(worst, 1e-11);  // measured 3.4e-13 px: see Camera.ProjectionAgreesWithOpenCv*
}

TEST(SyntheticWalk, BadOptionsAreRefusedNamingTheField) {
  SyntheticWalkOptions o = walkOptions(1);
  o.fps = 0;
  o.person_height_m = 3;
  const auto problems = validate(o);
  ASSERT_EQ(problems.size(), 2u);
  EXPECT_NE(problems[0].find("fps"), std::string::npos);
  EXPECT_NE(problems[1].find("person_height_m"), std::string::npos);
  EXPECT_THROW(synthesizeWalk(table(), prior(), o), std::invalid_argument);
  o = walkOptions(1);
  o.speed_kmh = 12;
  EXPECT_THROW(synthesizeWalk(table(), prior(), o), std::out_of_range) << "outside the gait table";
}

}  // namespace
}  // namespace kneed_walker::core::synthetic
