#include "kneed_walker/core/person/walker_finder.h"

#include <gtest/gtest.h>

#include <cmath>

namespace kneed_walker::core::person {
namespace {

// A person-sized blob whose box stands at column `u` (px) and whose feet are at `xy` (m).
vision::PersonCandidate seen(double u, const Eigen::Vector2d& xy) {
  vision::PersonCandidate person;
  person.box_px = cv::Rect2d(u, 100, 30, 90);
  person.ground_xy_m = xy;
  person.height_m = 1.7;
  person.pixels = 1500;
  return person;
}

// Someone seen heading_frames apart, moved far enough on the ground and near enough in the image,
// is found walking that way; nobody is found before the frames are apart.
TEST(WalkerFinder, FindsABlobSeenAgainHeadingFramesLaterThatMoved) {
  WalkerFinder finder(5, 0.15);
  for (int f = 0; f < 5; ++f)
    EXPECT_TRUE(finder.update({seen(100 + 2 * f, {0.05 * f, 0.03 * f})}, f).empty()) << "frame " << f;
  const std::vector<FoundWalker> found = finder.update({seen(110, {0.25, 0.15})}, 5);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_NEAR(found[0].heading_rad, std::atan2(0.15, 0.25), 1e-12);
  EXPECT_EQ(found[0].person.ground_xy_m, Eigen::Vector2d(0.25, 0.15));
}

// Standing still is not walking; a blob further than half a body in the image is someone else;
// nobody seen exactly heading_frames before is nobody found.
TEST(WalkerFinder, IgnoresTheStillTheFarAndTheUnseen) {
  WalkerFinder still(5, 0.15);
  for (int f = 0; f <= 5; ++f) EXPECT_TRUE(still.update({seen(100, {0.01 * f, 0})}, f).empty());
  WalkerFinder far(5, 0.15);
  far.update({seen(100, {0, 0})}, 0);
  for (int f = 1; f < 5; ++f) far.update({}, f);
  EXPECT_TRUE(far.update({seen(146, {1, 0})}, 5).empty());  // 46 px away: over half of 90 px
  WalkerFinder gap(5, 0.15);
  gap.update({seen(100, {0, 0})}, 0);
  gap.update({seen(100, {0.05, 0})}, 2);
  EXPECT_TRUE(gap.update({seen(104, {0.3, 0})}, 6).empty());  // nothing fed at frame 1
}

// Several walkers: nearest to a given point first; clear() forgets what was seen.
TEST(WalkerFinder, GivesTheWalkerNearestAPointFirstAndForgets) {
  WalkerFinder finder(1, 0.1);
  finder.update({seen(100, {0, 0}), seen(300, {5, 0})}, 0);
  const std::vector<FoundWalker> found = finder.update({seen(102, {0.2, 0}), seen(302, {5.2, 0})}, 1,
                                                       Eigen::Vector2d(5, 1));
  ASSERT_EQ(found.size(), 2u);
  EXPECT_EQ(found[0].person.ground_xy_m.x(), 5.2);
  finder.clear();
  EXPECT_TRUE(finder.update({seen(104, {0.4, 0})}, 2).empty());
}

}  // namespace
}  // namespace kneed_walker::core::person
