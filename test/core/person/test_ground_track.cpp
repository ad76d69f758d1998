#include "kneed_walker/core/person/ground_track.h"

#include <Eigen/Cholesky>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "rendered_walk.h"

namespace kneed_walker::core::person {
namespace {

const std::string kRobotEyeCamera = std::string(KNEED_WALKER_SOURCE_DIR) + "/test/sequences/robot_eye_camera.yml";

// A flat grey scene 200 × 160 and a dark rectangle standing in it, rows [top, bottom], columns
// [left, right]; `bottom_share` of the row below it is covered too (the pixel grid's mix).
cv::Mat rectangleScene(int top, int bottom, int left, int right, double bottom_share = 0) {
  cv::Mat image(160, 200, CV_8UC3, cv::Scalar(150, 160, 170));
  const cv::Vec3b person(30, 40, 50), scene(150, 160, 170);
  for (int y = top; y <= bottom; ++y)
    for (int x = left; x <= right; ++x) image.at<cv::Vec3b>(y, x) = person;
  if (bottom + 1 < image.rows)
    for (int x = left; x <= right; ++x) {
      cv::Vec3b mixed;
      for (int c = 0; c < 3; ++c) mixed[c] = cv::saturate_cast<uchar>(bottom_share * person[c] + (1 - bottom_share) * scene[c]);
      image.at<cv::Vec3b>(bottom + 1, x) = mixed;
    }
  return image;
}

vision::BackgroundModel emptyScene() {
  std::vector<cv::Mat> frames;
  for (int i = 0; i < 5; ++i) {
    frames.push_back(rectangleScene(0, -1, 0, -1));
    synthetic::addSensorNoise(frames.back(), 1.0, 10 + i);
  }
  return vision::BackgroundModel::learn(frames);
}

TEST(GroundTrack, TheEdgesOfASharpSilhouetteLieHalfAPixelPastItsLastRows) {
  const vision::BackgroundModel background = emptyScene();
  const cv::Mat image = rectangleScene(40, 129, 80, 109);
  const auto m = measureSilhouette(image, background, {0, 0, 200, 160}, {70, 30, 50, 110}, {});
  ASSERT_TRUE(m);
  EXPECT_NEAR(m->foot_v_px, 129.5, 0.05);
  EXPECT_NEAR(m->head_v_px, 39.5, 0.05);
  EXPECT_NEAR(m->centre_u_px, 94.5, 0.05);
  EXPECT_TRUE(m->foot_seen && m->head_seen && m->centre_seen);
}

// A threshold puts the edge on one side of a partly covered row; matting finds it inside.
TEST(GroundTrack, APartlyCoveredRowMovesTheEdgeByItsShare) {
  const vision::BackgroundModel background = emptyScene();
  for (const double share : {0.25, 0.5, 0.75}) {
    const auto m = measureSilhouette(rectangleScene(40, 129, 80, 109, share), background, {0, 0, 200, 160},
                                     {70, 30, 50, 110}, {});
    ASSERT_TRUE(m);
    EXPECT_NEAR(m->foot_v_px, 129.5 + share, 0.05) << "share " << share;
  }
}

TEST(GroundTrack, AnEdgeCutByTheSearchRegionOrTheImageIsNotSeen) {
  const vision::BackgroundModel background = emptyScene();
  const auto at_bottom = measureSilhouette(rectangleScene(60, 159, 80, 109), background, {0, 0, 200, 160},
                                           {70, 50, 50, 110}, {});
  ASSERT_TRUE(at_bottom);
  EXPECT_FALSE(at_bottom->foot_seen);
  EXPECT_TRUE(at_bottom->head_seen);
  const auto cut = measureSilhouette(rectangleScene(40, 129, 80, 109), background, {60, 60, 100, 100},
                                     {70, 30, 50, 110}, {});
  ASSERT_TRUE(cut);
  EXPECT_FALSE(cut->head_seen);
  EXPECT_TRUE(cut->foot_seen);
  EXPECT_FALSE(measureSilhouette(rectangleScene(40, 129, 80, 109), background, {0, 0, 200, 160},
                                 {150, 30, 40, 110}, {}))
      << "nothing of the person inside the expected box: no measurement";
}

// A prediction that has drifted: the expected box holds more background than person, and a
// small part of the person. The person is still the one measured.
TEST(GroundTrack, APersonMostlyOutsideTheExpectedBoxIsStillMeasured) {
  const vision::BackgroundModel background = emptyScene();
  const auto m = measureSilhouette(rectangleScene(40, 129, 80, 109), background, {0, 0, 200, 160},
                                   {100, 30, 60, 110}, {});
  ASSERT_TRUE(m);
  EXPECT_NEAR(m->centre_u_px, 94.5, 0.05);
  EXPECT_NEAR(m->foot_v_px, 129.5, 0.05);
}

// Two people side by side merge into one region twice as wide as one: it is not measured.
TEST(GroundTrack, PeopleMergedIntoOneRegionAreNotMeasured) {
  const vision::BackgroundModel background = emptyScene();
  cv::Mat image = rectangleScene(40, 129, 60, 89);
  rectangleScene(40, 129, 90, 119).colRange(90, 120).copyTo(image.colRange(90, 120));
  EXPECT_TRUE(measureSilhouette(image, background, {0, 0, 200, 160}, {55, 30, 40, 110}, {}))
      << "60 px wide for a box of 40: one person with a long stride";
  const cv::Mat merged = rectangleScene(40, 129, 50, 109);
  EXPECT_FALSE(measureSilhouette(merged, background, {0, 0, 200, 160}, {55, 30, 25, 110}, {}))
      << "60 px wide for a box of 25";
}

// Measurements drawn from the filter's own model (pixel noise only; the nearer foot's offset the
// same in every walking direction, so that the truth's and the filter's agree): the filter's
// covariance must match its errors. The mean normalised squared position error over many runs
// is the position's 2 degrees of freedom when it does.
TEST(GroundTrack, TheFilterIsConsistentWithItsOwnModel) {
  const vision::Camera camera = vision::Camera::load(kRobotEyeCamera, 0.001);
  GroundTrackOptions options;
  options.centre_sd_m = options.near_foot_sd_m = options.head_sd_m = 0;
  options.near_foot_along_m = options.near_foot_across_m = 0.1;
  options.centre_sd_px = 1.0;
  options.foot_row_sd_px = options.head_row_sd_px = 0.7;
  options.acceleration_sd = 0.3;
  std::mt19937_64 random(5);
  std::normal_distribution<double> normal;
  double nees_sum = 0, nees_smoothed_sum = 0;
  int count = 0, count_smoothed = 0;
  for (int run = 0; run < 100; ++run) {
    GroundTracker tracker(camera, {}, options);
    GroundTrackVector truth;
    truth << -1 + 0.2 * normal(random), 6 + 0.5 * normal(random), 1.2, 0.1, 1.75;
    tracker.start(truth.head<2>() + Eigen::Vector2d(0.3, 0.5), 1.75, 0.0);
    std::vector<GroundTrackVector> truths;
    for (int frame = 0; frame < 45; ++frame) {
      const double dt = 1.0 / 30;
      if (frame > 0) {
        for (const auto& [p, v] : {std::pair{kX, kVx}, std::pair{kY, kVy}}) {
          // The exact discretisation of white acceleration noise.
          const double q = options.acceleration_sd * options.acceleration_sd;
          const double a = normal(random), b = normal(random);
          const double dv = std::sqrt(q * dt) * a;
          const double dp = std::sqrt(q * dt * dt * dt / 12) * b + 0.5 * dt * dv;
          truth(p) += truth(v) * dt + dp;
          truth(v) += dv;
        }
      }
      truths.push_back(truth);
      tracker.predict(frame * dt);
      const Eigen::Vector3d pixels = *tracker.expectedPixels(truth);
      SilhouetteMeasurement m;
      m.centre_u_px = pixels(0) + options.centre_sd_px * normal(random);
      m.foot_v_px = pixels(1) + options.foot_row_sd_px * normal(random);
      m.head_v_px = pixels(2) + options.head_row_sd_px * normal(random);
      m.centre_seen = m.foot_seen = m.head_seen = true;
      tracker.correct(m);
      if (frame >= 15) {
        const GroundTrackEstimate& e = tracker.current();
        const Eigen::Vector2d error = e.position() - truth.head<2>();
        nees_sum += error.dot(e.covariance.block<2, 2>(kX, kX).ldlt().solve(error));
        ++count;
      }
    }
    const std::vector<GroundTrackEstimate> smoothed = tracker.smoothed();
    ASSERT_EQ(smoothed.size(), truths.size());
    for (size_t k = 0; k < smoothed.size(); ++k) {
      const Eigen::Vector2d error = smoothed[k].position() - truths[k].head<2>();
      nees_smoothed_sum += error.dot(smoothed[k].covariance.block<2, 2>(kX, kX).ldlt().solve(error));
      ++count_smoothed;
    }
  }
  // 3500 (partly correlated) samples of a χ²₂: the mean within about ±0.3 of 2.
  EXPECT_NEAR(nees_sum / count, 2.0, 0.35);
  EXPECT_NEAR(nees_smoothed_sum / count_smoothed, 2.0, 0.35);
}

TEST(GroundTrack, AFootRowFarFromThePredictionIsRefused) {
  const vision::Camera camera = vision::Camera::load(kRobotEyeCamera, 0.001);
  GroundTracker tracker(camera, {});
  GroundTrackVector truth;
  truth << 0, 6, 0, 0, 1.75;
  tracker.start(truth.head<2>(), 1.75, 0.0);
  for (int frame = 0; frame < 30; ++frame) {
    tracker.predict(frame / 30.0);
    const Eigen::Vector3d pixels = *tracker.expectedPixels(truth);
    SilhouetteMeasurement m;
    m.centre_u_px = pixels(0), m.foot_v_px = pixels(1), m.head_v_px = pixels(2);
    m.centre_seen = m.foot_seen = m.head_seen = true;
    if (frame == 29) m.foot_v_px += 25;  // a shadow's edge
    tracker.correct(m);
  }
  EXPECT_FALSE(tracker.current().foot_used);
  EXPECT_TRUE(tracker.current().head_used);
  EXPECT_LT((tracker.current().position() - truth.head<2>()).norm(), 0.05);
}

// The range error of the ground track on a rendered walk from robot-eye height: the person
// 6 m away walks across the view, started 0.6 m too far. Measured from one second in: a median
// of 1.20 % of the distance filtered, 1.28 % smoothed (the model's body steps wider than the
// captured people the nearer foot's offset is fitted to); the heading 8° off at the end (its
// sd 7°).
TEST(GroundTrack, FollowsARenderedWalkFromRobotEyeHeight) {
  const test::RenderedWalk rendered(3.0, 30, 4, false, kRobotEyeCamera, Eigen::Vector2d(540, 298), M_PI);
  const vision::BackgroundModel background = vision::BackgroundModel::learn(rendered.empty);
  const vision::Camera& camera = rendered.camera;
  const auto waist = [&](size_t f) { return rendered.walk.frames[f].pose.joints[body::kWaist].head<2>().eval(); };
  const Eigen::Vector2d sight = (waist(0) - camera.centre().head<2>()).normalized();
  GroundTracker tracker(camera, rendered.walk.ground);
  // Started 0.6 m too far, as a box's bottom edge from robot-eye height may put the person.
  tracker.start(waist(0) + 0.6 * sight, 1.75, 0.0);
  for (size_t f = 0; f < rendered.frames.size(); ++f) tracker.update(rendered.frames[f], background, f / 30.0);
  const std::vector<GroundTrackEstimate> filtered = tracker.filtered(), smoothed = tracker.smoothed();
  ASSERT_EQ(filtered.size(), rendered.frames.size());
  std::vector<double> filtered_errors, smoothed_errors;
  int measured = 0;
  for (size_t f = 30; f < filtered.size(); ++f) {
    const double distance = (waist(f) - camera.centre().head<2>()).norm();
    const auto range_error = [&](const GroundTrackEstimate& e) {
      return std::abs((e.position() - camera.centre().head<2>()).norm() - distance) / distance;
    };
    filtered_errors.push_back(range_error(filtered[f]));
    smoothed_errors.push_back(range_error(smoothed[f]));
    measured += filtered[f].foot_used && filtered[f].head_used;
  }
  const auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  std::printf("range error: filtered %.2f %%, smoothed %.2f %%; feet and head used in %d of %zu frames\n",
              100 * median(filtered_errors), 100 * median(smoothed_errors), measured, filtered_errors.size());
  EXPECT_LT(median(filtered_errors), 0.02);
  EXPECT_LT(median(smoothed_errors), 0.02);
  EXPECT_GT(measured, 0.9 * filtered_errors.size());
  const Eigen::Vector2d walked = waist(rendered.frames.size() - 1) - waist(rendered.frames.size() - 31);
  const double true_heading = std::atan2(walked.y(), walked.x());
  const double heading_error = std::remainder(filtered.back().headingRad() - true_heading, 2 * M_PI);
  std::printf("heading error at the end: %.1f deg (sd %.1f deg)\n", heading_error * 180 / M_PI,
              filtered.back().headingSdRad() * 180 / M_PI);
  EXPECT_LT(std::abs(heading_error), 12 * M_PI / 180);
}

TEST(GroundTrack, RefusesBadOptionsByName) {
  GroundTrackOptions options;
  options.acceleration_sd = std::nan("");
  const std::vector<std::string> problems = validate(options);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].find("ground_acceleration_sd"), std::string::npos) << problems[0];
  EXPECT_THROW(GroundTracker(vision::Camera::load(kRobotEyeCamera, 0.001), {}, options), std::invalid_argument);
}

// A start from the ground track: its position with the body's offset spread added; the walk's
// heading (spread at least kMinWalkStartHeadingSdRad) and speed when the velocity is over twice
// its spread, else no heading.
TEST(GroundTrack, AWalkStartTakesTheHeadingOnlyWhenTheVelocityTellsIt) {
  GroundTrackEstimate at;
  at.mean << 2.0, 3.0, 0.0, 1.2, 1.7;
  at.covariance = GroundTrackMatrix::Identity() * 1e-4;
  at.covariance(kX, kX) = 0.04;
  at.covariance(kVy, kVy) = 0.01;  // 0.1 m/s along the walk
  const WalkStart walking = walkStart(at, 0.06);
  EXPECT_EQ(walking.position_m, Eigen::Vector2d(2.0, 3.0));
  EXPECT_NEAR(walking.position_covariance_m2(0, 0), 0.04 + 0.0036, 1e-12);
  EXPECT_NEAR(walking.position_covariance_m2(1, 1), 1e-4 + 0.0036, 1e-12);
  ASSERT_TRUE(walking.heading_rad.has_value());
  EXPECT_NEAR(*walking.heading_rad, M_PI / 2, 1e-12);
  EXPECT_GE(walking.heading_sd_rad, kMinWalkStartHeadingSdRad);
  EXPECT_NEAR(walking.speed_kmh, 3.6 * 1.2, 1e-12);
  EXPECT_NEAR(walking.speed_sd_kmh, 3.6 * 0.1, 1e-12);
  at.covariance(kVy, kVy) = 0.49;  // 0.7 m/s: 1.2 m/s is under twice that
  const WalkStart unsure = walkStart(at, 0.06);
  EXPECT_FALSE(unsure.heading_rad.has_value());
  EXPECT_EQ(unsure.heading_sd_rad, M_PI);
}

}  // namespace
}  // namespace kneed_walker::core::person
