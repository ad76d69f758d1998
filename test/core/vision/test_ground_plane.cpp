#include "kneed_walker/core/vision/ground_plane.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>

namespace kneed_walker::core::vision {
namespace {

TEST(GroundPlane, RisesAlongItsUphillHeading) {
  const GroundPlane ground{Eigen::Vector2d(1, 2), 0.1, M_PI / 2};
  EXPECT_DOUBLE_EQ(ground.height(Eigen::Vector2d(1, 2)), 0.0);
  EXPECT_NEAR(ground.height(Eigen::Vector2d(1, 3)), std::tan(0.1), 1e-15);
  EXPECT_NEAR(ground.height(Eigen::Vector2d(5, 2)), 0.0, 1e-15) << "level across the slope";
  EXPECT_NEAR(ground.normal().norm(), 1.0, 1e-15);
  EXPECT_NEAR(ground.normal().dot(Eigen::Vector3d(0, 1, std::tan(0.1))), 0.0, 1e-15);
}

TEST(GroundPlane, WrittenBesideACalibrationAndReadBack) {
  const std::string path = ::testing::TempDir() + "/kneed_walker_ground.yml";
  const GroundPlane ground{Eigen::Vector2d(-15.5, 13.25), 0.075, 1.96};
  {
    cv::FileStorage file(path, cv::FileStorage::WRITE);
    file << "image_width" << 768;  // another program's key
    writeGroundPlane(file, ground);
  }
  const GroundPlane back = loadGroundPlane(path);
  EXPECT_NEAR((back.point_m - ground.point_m).norm(), 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(back.slope_rad, ground.slope_rad);
  EXPECT_DOUBLE_EQ(back.uphill_heading_rad, ground.uphill_heading_rad);
  std::remove(path.c_str());
}

TEST(GroundPlane, ACalibrationWithoutItIsLevelAndBadValuesAreRefused) {
  const std::string path = ::testing::TempDir() + "/kneed_walker_no_ground.yml";
  std::ofstream(path) << "%YAML:1.0\n---\nimage_width: 768\n";
  const GroundPlane level = loadGroundPlane(path);
  EXPECT_EQ(level.slope_rad, 0.0);
  EXPECT_EQ(level.height(Eigen::Vector2d(3, 4)), 0.0);
  std::ofstream(path) << "%YAML:1.0\n---\nground_slope_rad: .nan\nground_point_mm: [1]\n";
  try {
    loadGroundPlane(path);
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("ground_slope_rad must be finite"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("ground_point_mm must list 2 numbers"), std::string::npos) << e.what();
  }
  std::remove(path.c_str());
}

}  // namespace
}  // namespace kneed_walker::core::vision
