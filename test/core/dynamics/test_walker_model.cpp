#include "kneed_walker/core/dynamics/walker_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>

namespace kneed_walker::core::dynamics {
namespace {

TEST(WalkerModel, DefaultProportionsAreValidAndAddUp) {
  const BodyProportions p;
  EXPECT_TRUE(validate(p).empty());
}

TEST(WalkerModel, ScalesToAPerson) {
  const WalkerModel m = scaleToPerson(BodyProportions{}, 1.75, 70.0);
  // walker-model.md §1: for 70 kg, 1.75 m, L = 0.93 m, thigh 7.0 kg / 0.43 m, shank+foot
  // 4.3 kg / 0.50 m, foot radius 0.19 m, torso ≈ 47.5 kg.
  EXPECT_NEAR(m.legLength(), 0.9275, 1e-9);
  EXPECT_NEAR(m.thigh.mass, 7.0, 1e-9);
  EXPECT_NEAR(m.thigh.length, 0.4267, 1e-3);
  EXPECT_NEAR(m.shank.mass, 4.34, 1e-9);
  EXPECT_NEAR(m.shank.length, 0.5009, 1e-3);
  EXPECT_NEAR(m.foot_radius, 0.1855, 1e-3);
  EXPECT_NEAR(m.torso.mass, 47.32, 1e-9);
  EXPECT_NEAR(m.totalMass(), 70.0, 1e-9);
  EXPECT_NEAR(m.thigh.inertia(), 7.0 * std::pow(0.135 * 0.9275, 2), 1e-12);
  EXPECT_THROW(scaleToPerson(BodyProportions{}, 0.0, 70.0), std::invalid_argument);
}

TEST(WalkerModel, McGeerWalkerIsDimensionless) {
  const WalkerModel m = mcGeerPassiveWalker();
  EXPECT_NEAR(m.legLength(), 1.0, 1e-12);
  EXPECT_NEAR(m.totalMass(), 1.0, 1e-12);
  EXPECT_DOUBLE_EQ(m.gravity, 1.0);
  EXPECT_DOUBLE_EQ(m.torso.com_along, 0.0) << "the torso is reduced to a hip mass";
  EXPECT_DOUBLE_EQ(m.foot_radius, 0.2);
}

TEST(WalkerModel, ShippedConfigLoadsAndMatchesTheDefaults) {
  const BodyProportions p =
      loadBodyProportions(std::string(KNEED_WALKER_SOURCE_DIR) + "/config/walker_model.yaml");
  const BodyProportions d;
  EXPECT_DOUBLE_EQ(p.leg_length_per_height, d.leg_length_per_height);
  EXPECT_DOUBLE_EQ(p.torso.mass, d.torso.mass);
  EXPECT_DOUBLE_EQ(p.torso.com_along, d.torso.com_along);
  EXPECT_DOUBLE_EQ(p.thigh.radius_of_gyration, d.thigh.radius_of_gyration);
  EXPECT_DOUBLE_EQ(p.shank.com_forward, d.shank.com_forward);
  EXPECT_DOUBLE_EQ(p.foot_radius, d.foot_radius);
  EXPECT_DOUBLE_EQ(p.foot_offset_angle, d.foot_offset_angle);
}

TEST(WalkerModel, BadConfigIsRefusedNamingEachProblem) {
  const std::string path = testing::TempDir() + "bad_walker_model.yaml";
  std::ofstream(path) << "%YAML:1.0\nfoot_radius: big\nthigh:\n  mass: 0.5\n  colour: 3\n"
                         "knee_height: 0.3\n";
  try {
    loadBodyProportions(path);
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("foot_radius must be a number"), std::string::npos) << what;
    EXPECT_NE(what.find("thigh.colour is not a known key"), std::string::npos) << what;
    EXPECT_NE(what.find("knee_height is not a known key"), std::string::npos) << what;
    EXPECT_NE(what.find("mass fractions add up to"), std::string::npos) << what;
  }
  std::remove(path.c_str());
  EXPECT_THROW(loadBodyProportions(path), std::invalid_argument) << "missing file";
}

}  // namespace
}  // namespace kneed_walker::core::dynamics
