#include "kneed_walker/core/vision/person_detector.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "rendered_walk.h"

namespace kneed_walker::core::vision {
namespace {

const test::RenderedWalk& scene() {
  static const test::RenderedWalk walk(1.0, 10, 7);
  return walk;
}

TEST(PersonDetector, FindsTheWalkerStandingOnTheGroundAtHerHeight) {
  const test::RenderedWalk& s = scene();
  const BackgroundModel background = BackgroundModel::learn(s.empty);
  for (size_t f = 0; f < s.frames.size(); f += 3) {
    const std::vector<PersonCandidate> people = findPeople(background, s.frames[f], s.camera, s.walk.ground);
    ASSERT_EQ(people.size(), 1u) << "frame " << f;
    const auto& joints = s.walk.frames[f].pose.joints;
    const Eigen::Vector2d feet = 0.5 * (joints[body::kLeftAnkle] + joints[body::kRightAnkle]).head<2>();
    EXPECT_LT((people[0].ground_xy_m - feet).norm(), 0.3) << "frame " << f;
    EXPECT_NEAR(people[0].height_m, 1.75, 0.25) << "frame " << f;
  }
}

TEST(PersonDetector, FindsNobodyInTheEmptyScene) {
  const test::RenderedWalk& s = scene();
  const BackgroundModel background = BackgroundModel::learn({s.empty.begin(), s.empty.begin() + 6});
  for (size_t f = 6; f < s.empty.size(); ++f)
    EXPECT_TRUE(findPeople(background, s.empty[f], s.camera, s.walk.ground).empty()) << "empty frame " << f;
}

TEST(PersonDetector, IgnoresABlobTooSmallToBeAPerson) {
  const test::RenderedWalk& s = scene();
  const BackgroundModel background = BackgroundModel::learn(s.empty);
  cv::Mat frame = s.empty[0].clone();
  cv::rectangle(frame, cv::Rect(300, 400, 30, 30), cv::Scalar(0, 0, 255), cv::FILLED);  // a ball, 900 px
  EXPECT_TRUE(findPeople(background, frame, s.camera, s.walk.ground).empty());
}

TEST(PersonDetector, RefusesAFrameOfAnotherSize) {
  const test::RenderedWalk& s = scene();
  const BackgroundModel background = BackgroundModel::learn(s.empty);
  EXPECT_THROW(findPeople(background, cv::Mat(100, 100, CV_8UC3), s.camera, s.walk.ground), std::invalid_argument);
}

}  // namespace
}  // namespace kneed_walker::core::vision
