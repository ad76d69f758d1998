#include "kneed_walker/core/synthetic/synthetic_scene.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <cmath>
#include <cstdio>

namespace kneed_walker::core::synthetic {
namespace {

const vision::Camera& petsCamera() {
  static const vision::Camera camera =
      vision::Camera::load(std::string(KNEED_WALKER_SHARED_DIR) + "/data/pets2009/View_001_camera.yml", 0.001);
  return camera;
}

// A standing pose (the walker upright, both feet together) at a ground point.
body::BodyPose standingPose(const Eigen::Vector2d& at_m, body::BodyShape& shape) {
  static const dynamics::WalkerSimulator sim(dynamics::dimensionlessWalker(dynamics::BodyProportions{}));
  dynamics::WalkerState state;
  state.stance_foot_x = 0;
  body::BodyPlacement placement;
  placement.ground_origin_m = at_m;
  shape = body::BodyShape::forHeight(1.75);
  return body::bodyPose(sim.map(), state, 0.0, placement, shape, 0.53 * 1.75);
}

TEST(SyntheticScene, PersonIsPaintedWhereTheBodyProjects) {
  const vision::Camera& camera = petsCamera();
  const Eigen::Vector2d at = camera.groundPoint({500, 450})->head<2>();
  body::BodyShape shape;
  const body::BodyPose pose = standingPose(at, shape);
  const cv::Mat empty(camera.height(), camera.width(), CV_8UC3, cv::Scalar(0, 255, 0));
  cv::Mat image = empty.clone();
  const PersonAppearance look;
  drawPerson(image, camera, pose, shape, look);
  // Every joint's pixel is painted (none is left green), and nothing far from the body is.
  cv::Rect box;
  for (const Eigen::Vector3d& joint : pose.joints) {
    const Eigen::Vector2d p = *camera.project(joint);
    const cv::Vec3b colour = image.at<cv::Vec3b>(static_cast<int>(p.y()), static_cast<int>(p.x()));
    EXPECT_NE(colour, cv::Vec3b(0, 255, 0)) << "joint pixel " << p.transpose() << " not painted";
    box |= cv::Rect(static_cast<int>(p.x()), static_cast<int>(p.y()), 1, 1);
  }
  const cv::Vec3b torso = image.at<cv::Vec3b>(
      static_cast<int>(0.5 * (camera.project(pose.joints[body::kWaist])->y() + camera.project(pose.joints[body::kNeck])->y())),
      static_cast<int>(camera.project(pose.joints[body::kWaist])->x()));
  EXPECT_EQ(torso, cv::Vec3b(look.shirt[0], look.shirt[1], look.shirt[2]));
  cv::Mat changed;
  cv::inRange(image, cv::Scalar(0, 255, 0), cv::Scalar(0, 255, 0), changed);
  changed = 255 - changed;
  const cv::Rect painted = cv::boundingRect(changed);
  box = cv::Rect(box.x - 30, box.y - 30, box.width + 60, box.height + 60);
  EXPECT_EQ(painted & box, painted) << "paint outside the body's neighbourhood";
  EXPECT_GT(cv::countNonZero(changed), 500) << "a person about 110 px tall covers more pixels";
}

TEST(SyntheticScene, TexturedGroundIsSeededAndHasASky) {
  const vision::Camera& camera = petsCamera();
  vision::GroundPlane ground;
  const cv::Mat a = texturedGround(camera, ground, 1), b = texturedGround(camera, ground, 1),
                c = texturedGround(camera, ground, 2);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(a, c, cv::NORM_L1), 0.0);
  // The PETS camera looks down: its image bottom sees the ground (tiles of many shades).
  cv::Mat bottom;
  cv::cvtColor(a.rowRange(400, 576), bottom, cv::COLOR_BGR2GRAY);
  cv::Scalar mean, sd;
  cv::meanStdDev(bottom, mean, sd);
  EXPECT_GT(sd[0], 8.0) << "the paving has texture";
  // Tilted upwards, a camera sees the sky at the top of its image.
  const Eigen::Matrix3d up_tilt = Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::Matrix3d level_view = (Eigen::Matrix3d() << 1, 0, 0, 0, 0, -1, 0, 1, 0).finished();
  const Eigen::Matrix3d k = (Eigen::Matrix3d() << 300, 0, 160, 0, 300, 120, 0, 0, 1).finished();
  const vision::Camera tilted(k, {}, up_tilt * level_view, Eigen::Vector3d(0, 1.5, 0), 320, 240);
  const cv::Mat sky = texturedGround(tilted, ground, 1);
  const cv::Vec3b top = sky.at<cv::Vec3b>(5, 160), low = sky.at<cv::Vec3b>(235, 160);
  EXPECT_GT(top[0], top[2]) << "sky is blue";
  EXPECT_LT(low[0], low[2] + 30) << "the ground below is not";
}

TEST(SyntheticScene, OccluderCrossesTheLineOfSightOnTime) {
  const vision::Camera& camera = petsCamera();
  const Eigen::Vector3d target(camera.groundPoint({500, 450})->x(), camera.groundPoint({500, 450})->y(), 0.9);
  const Occluder occluder = crossingOccluder(camera, target, 1.5, Eigen::Vector2d(1, 0));
  EXPECT_LT(occluder.velocity_mps.head<2>().dot(Eigen::Vector2d(1, 0)), 0) << "moves against the walker";
  const Eigen::Vector2d pixel = *camera.project(target);
  auto covered = [&](double t) {
    cv::Mat image(camera.height(), camera.width(), CV_8UC3, cv::Scalar(0, 0, 0));
    drawOccluder(image, camera, occluder, t);
    return image.at<cv::Vec3b>(static_cast<int>(pixel.y()), static_cast<int>(pixel.x())) != cv::Vec3b(0, 0, 0);
  };
  EXPECT_TRUE(covered(1.5));
  EXPECT_FALSE(covered(0.0));
  EXPECT_FALSE(covered(3.0));
}

TEST(SyntheticScene, SensorNoiseHasItsSigmaAndSeed) {
  const cv::Mat grey(200, 200, CV_8UC3, cv::Scalar(128, 128, 128));
  cv::Mat a = grey.clone(), b = grey.clone(), c = grey.clone();
  addSensorNoise(a, 4.0, 9);
  addSensorNoise(b, 4.0, 9);
  addSensorNoise(c, 4.0, 10);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(a, c, cv::NORM_L1), 0.0);
  cv::Mat difference;
  cv::subtract(a, grey, difference, cv::noArray(), CV_32F);
  cv::Scalar mean, sd;
  cv::meanStdDev(difference.reshape(1), mean, sd);
  EXPECT_NEAR(sd[0], 4.0, 0.2);
  EXPECT_NEAR(mean[0], 0.0, 0.1);
}

// The median of a video's frames removes what moves through it.
}  // namespace
}  // namespace kneed_walker::core::synthetic
