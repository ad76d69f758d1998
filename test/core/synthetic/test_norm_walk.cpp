#include "kneed_walker/core/synthetic/norm_walk.h"

#include <gtest/gtest.h>

#include <cmath>

#include "shipped_config.h"

namespace kneed_walker::core::synthetic {
namespace {

const gait::GaitNorms& norms() {
  static const gait::GaitNorms n =
      gait::loadGaitNorms(std::string(KNEED_WALKER_SHARED_DIR) + "/data/gait/Schwartz2008_Joint_Rotations.csv");
  return n;
}

NormWalkOptions options(double start_kmh, double end_kmh) {
  NormWalkOptions o;
  o.start_speed_kmh = start_kmh;
  o.end_speed_kmh = end_kmh;
  o.duration_s = 4.0;
  o.fps = 25;
  o.start_m = {-15.0, -10.0};
  o.heading_rad = 2.5;
  return o;
}

double degrees(double rad) { return rad * 180 / M_PI; }

// The walk goes where it is headed at the asked speed (mean over whole strides), from the
// asked start, with steps and a cadence people have at that speed.
TEST(NormWalk, WalksAtTheAskedSpeedWithHumanSteps) {
  for (const double kmh : {3.5, 5.5}) {
    const NormWalkOptions o = options(kmh, kmh);
    const SyntheticWalk walk = synthesizeNormWalk(norms(), test::shippedWalkerModel(), o);
    ASSERT_EQ(walk.frames.size(), 101u);
    const auto& first = walk.frames.front();
    EXPECT_LT((first.pose.foot_centres[first.walker.stance_leg == dynamics::Leg::kLeft ? 0 : 1].head<2>() - o.start_m).norm(), 1e-9);
    // Whole strides: from the first heel strike to the last one of the same leg.
    std::vector<std::size_t> strikes;
    for (std::size_t i = 1; i < walk.frames.size(); ++i)
      if (walk.frames[i].walker.heel_strikes != walk.frames[i - 1].walker.heel_strikes) strikes.push_back(i);
    ASSERT_GE(strikes.size(), 5u);
    const std::size_t steps = (strikes.size() - 1) - (strikes.size() - 1) % 2;  // an even number: whole strides
    const std::size_t a = strikes.front(), b = strikes[steps];
    const Eigen::Vector3d travelled = walk.frames[b].pose.joints[body::kWaist] - walk.frames[a].pose.joints[body::kWaist];
    const double speed_kmh = 3.6 * travelled.norm() / (walk.frames[b].time_s - walk.frames[a].time_s);
    EXPECT_NEAR(speed_kmh, kmh, 0.05 * kmh + 0.15) << "whole strides " << a << "-" << b;  // frames quantise the strikes
    EXPECT_NEAR(std::atan2(travelled.y(), travelled.x()), o.heading_rad, 0.02);
    const double step_m = travelled.norm() / static_cast<double>(steps);
    const double cadence_per_min = 60.0 * kmh / 3.6 / step_m;
    std::cout << kmh << " km/h: step " << step_m << " m, cadence " << cadence_per_min << " steps/min\n";
    EXPECT_GT(step_m, 0.5);
    EXPECT_LT(step_m, 0.9);
    EXPECT_GT(cadence_per_min, 90);
    EXPECT_LT(cadence_per_min, 140);
  }
}

// The stance foot rolls without slipping and no foot goes below the ground; the swing knee
// bends as the norms' (about 60 degrees at free speed), more than the stance knee.
TEST(NormWalk, FeetStayOnTheGroundAndTheSwingKneeBends) {
  const SyntheticWalk walk = synthesizeNormWalk(norms(), test::shippedWalkerModel(), options(4.7, 4.7));
  const double foot_radius_m = test::shippedWalkerModel().foot_radius * walk.leg_length_m;
  double largest_slide_m = 0, lowest_m = 1, swing_knee_peak = 0, stance_knee_peak = 0;
  for (std::size_t i = 0; i < walk.frames.size(); ++i) {
    const SyntheticFrame& f = walk.frames[i];
    for (int side : {0, 1}) lowest_m = std::min(lowest_m, f.pose.foot_centres[side].z() - foot_radius_m * std::cos(f.placement.hip_abduction_rad[side]));
    const dynamics::Vector5& q = f.walker.q;
    swing_knee_peak = std::max(swing_knee_peak, degrees(q[dynamics::kSwingThigh] - q[dynamics::kSwingShank]));
    stance_knee_peak = std::max(stance_knee_peak, degrees(q[dynamics::kStanceThigh] - q[dynamics::kStanceShank]));
    if (i == 0 || f.walker.heel_strikes != walk.frames[i - 1].walker.heel_strikes) continue;
    const int side = f.walker.stance_leg == dynamics::Leg::kLeft ? 0 : 1;
    const double turn = f.walker.q[dynamics::kStanceShank] - walk.frames[i - 1].walker.q[dynamics::kStanceShank];
    const Eigen::Vector3d rolled = walk.frames[i - 1].pose.foot_centres[side] - foot_radius_m * turn * f.pose.forward;
    largest_slide_m = std::max(largest_slide_m, (f.pose.foot_centres[side] - rolled).norm());
  }
  std::cout << "largest stance-foot slide " << largest_slide_m * 1e3 << " mm, lowest sole " << lowest_m * 1e3
            << " mm, knee peaks: swing " << swing_knee_peak << " deg, stance " << stance_knee_peak << " deg\n";
  EXPECT_LT(largest_slide_m, 1e-9);  // measured 6e-14 m
  EXPECT_GT(lowest_m, -1e-3);        // measured -0.07 mm: contact changes are found to 1 ms
  EXPECT_NEAR(swing_knee_peak, 59.1, 1.0);  // the free-speed norm's peak (4.7 km/h is v* = 0.43)
  EXPECT_NEAR(stance_knee_peak, 23, 3);     // loading response (the norm: about 20 degrees)
}

// Up and down a 10 degree hill (the paper's Fig. 5 grade): the walk rises along its heading as
// the ground does, both feet stay on the sloped ground (the stance foot rolling without
// slipping), and the torso leans into the hill by a third of the slope more than on the level.
TEST(NormWalk, WalksUpAndDownAHillOnItsGround) {
  const double gamma = 10 * M_PI / 180;
  const SyntheticWalk level = synthesizeNormWalk(norms(), test::shippedWalkerModel(), options(4.5, 4.5));
  const auto mean_torso_lean = [](const SyntheticWalk& walk) {  // from the vertical, forward positive
    double sum = 0;
    for (const SyntheticFrame& f : walk.frames) {
      const Eigen::Vector3d up = f.pose.joints[body::kNeck] - f.pose.joints[body::kWaist];
      sum += std::atan2(up.head<2>().dot(Eigen::Vector2d(std::cos(f.placement.heading_rad), std::sin(f.placement.heading_rad))), up.z());
    }
    return sum / static_cast<double>(walk.frames.size());
  };
  for (const double slope : {gamma, -gamma}) {
    NormWalkOptions o = options(4.5, 4.5);
    o.slope_rad = slope;
    const SyntheticWalk walk = synthesizeNormWalk(norms(), test::shippedWalkerModel(), o);
    EXPECT_DOUBLE_EQ(walk.ground.slope_rad, slope);
    EXPECT_DOUBLE_EQ(walk.ground.uphill_heading_rad, o.heading_rad);
    const double foot_radius_m = test::shippedWalkerModel().foot_radius * walk.leg_length_m;
    double lowest_m = 1, highest_lower_m = -1, largest_slide_m = 0;  // soles above the ground
    for (std::size_t i = 0; i < walk.frames.size(); ++i) {
      const SyntheticFrame& f = walk.frames[i];
      double lower_m = 1;
      for (int side : {0, 1}) {
        const Eigen::Vector3d& centre = f.pose.foot_centres[side];
        const double above_m = (centre - Eigen::Vector3d(centre.x(), centre.y(), walk.ground.height(centre.head<2>())))
                                   .dot(walk.ground.normal());
        lower_m = std::min(lower_m, above_m - foot_radius_m * std::cos(f.placement.hip_abduction_rad[side]));
      }
      lowest_m = std::min(lowest_m, lower_m);
      highest_lower_m = std::max(highest_lower_m, lower_m);
      if (i == 0 || f.walker.heel_strikes != walk.frames[i - 1].walker.heel_strikes) continue;
      const int side = f.walker.stance_leg == dynamics::Leg::kLeft ? 0 : 1;
      const double turn = f.walker.q[dynamics::kStanceShank] - walk.frames[i - 1].walker.q[dynamics::kStanceShank];
      const Eigen::Vector3d rolled = walk.frames[i - 1].pose.foot_centres[side] - foot_radius_m * turn * f.pose.forward;
      largest_slide_m = std::max(largest_slide_m, (f.pose.foot_centres[side] - rolled).norm());
    }
    const Eigen::Vector3d travelled = walk.frames.back().pose.joints[body::kWaist] - walk.frames.front().pose.joints[body::kWaist];
    const double rise = std::atan2(travelled.z(), travelled.head<2>().norm());
    const double lean_gain = mean_torso_lean(walk) - mean_torso_lean(level);
    std::cout << degrees(slope) << " deg: lowest sole " << lowest_m * 1e3 << " mm, the lower sole at most "
              << highest_lower_m * 1e3 << " mm above the ground, largest slide " << largest_slide_m * 1e3
              << " mm, waist rises at " << degrees(rise) << " deg, torso leans " << degrees(lean_gain) << " deg more\n";
    EXPECT_GT(lowest_m, -1e-3);  // contact changes are found to 1 ms, as on the level
    EXPECT_LT(highest_lower_m, 1e-3);  // and in every frame a foot stands on it
    EXPECT_LT(largest_slide_m, 1e-9);
    EXPECT_NEAR(rise, slope, 0.02);  // whole frames, not whole strides: the hip's bob
    EXPECT_NEAR(lean_gain, slope / 3, 0.01);
    EXPECT_LT((walk.frames.front().pose.foot_centres[walk.frames.front().walker.stance_leg == dynamics::Leg::kLeft ? 0 : 1]
                   .head<2>() - o.start_m).norm(), 1e-9);
  }
}

// A walk that slows from 6.5 to 3.5 km/h: the first second is faster than the last, by about
// the ratio asked, and the steps get shorter.
TEST(NormWalk, SlowsDownAsAsked) {
  NormWalkOptions o = options(6.5, 3.5);
  o.duration_s = 5.0;
  const SyntheticWalk walk = synthesizeNormWalk(norms(), test::shippedWalkerModel(), o);
  auto speed_kmh = [&](std::size_t from, std::size_t to) {
    return 3.6 * (walk.frames[to].pose.joints[body::kWaist] - walk.frames[from].pose.joints[body::kWaist]).norm() /
           (walk.frames[to].time_s - walk.frames[from].time_s);
  };
  const std::size_t n = walk.frames.size();
  EXPECT_NEAR(speed_kmh(0, 25), 6.2, 0.5);
  EXPECT_NEAR(speed_kmh(n - 26, n - 1), 3.8, 0.5);
  const double nominal_fast = normStrideLength(norms(), test::shippedWalkerModel(), 6.5 / 3.6 / std::sqrt(9.81 * walk.leg_length_m));
  const double nominal_slow = normStrideLength(norms(), test::shippedWalkerModel(), 3.5 / 3.6 / std::sqrt(9.81 * walk.leg_length_m));
  EXPECT_GT(nominal_fast, nominal_slow * 1.1);
}

TEST(NormWalk, SameSeedSameWalkAndBadOptionsNamed) {
  const SyntheticWalk a = synthesizeNormWalk(norms(), test::shippedWalkerModel(), options(4.5, 4.5));
  const SyntheticWalk b = synthesizeNormWalk(norms(), test::shippedWalkerModel(), options(4.5, 4.5));
  NormWalkOptions other = options(4.5, 4.5);
  other.seed = 2;
  const SyntheticWalk c = synthesizeNormWalk(norms(), test::shippedWalkerModel(), other);
  for (std::size_t i = 0; i < a.frames.size(); ++i)
    for (int j = 0; j < body::kNumBodyJoints; ++j) ASSERT_EQ(a.frames[i].pose.joints[j], b.frames[i].pose.joints[j]);
  EXPECT_NE(a.frames.back().pose.joints[body::kLeftKnee], c.frames.back().pose.joints[body::kLeftKnee]);

  NormWalkOptions bad = options(4.5, 4.5);
  bad.end_speed_kmh = std::nan("");
  bad.person_height_m = 3;
  try {
    synthesizeNormWalk(norms(), test::shippedWalkerModel(), bad);
    FAIL() << "bad options accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("end_speed_kmh must lie in [0.5, 10]"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("person_height_m"), std::string::npos) << e.what();
  }
  EXPECT_THROW(nominalDimensionlessSpeed("Brisk"), std::out_of_range);
  EXPECT_DOUBLE_EQ(nominalDimensionlessSpeed("Free"), 0.43);
}

}  // namespace
}  // namespace kneed_walker::core::synthetic
