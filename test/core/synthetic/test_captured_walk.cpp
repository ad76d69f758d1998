#include "kneed_walker/core/synthetic/captured_walk.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

namespace kneed_walker::core::synthetic {
namespace {

const std::string kMocap = std::string(KNEED_WALKER_SHARED_DIR) + "/data/mocap";

// A capture is read as its file says (195 frames at 30 fps) and its forward kinematics keep
// every bone's length: the thigh and the shank are rigid over the whole walk, the person stands
// on the ground (Z up, metres), and walks a few metres.
TEST(CapturedWalk, ReadsABvhWalkWithRigidBones) {
  const CapturedMotion motion = loadBvh(kMocap + "/dataset-1_walk_normal_001.bvh");
  ASSERT_EQ(motion.positions_m.size(), 195u);
  EXPECT_NEAR(motion.frame_time_s, 1.0 / 30, 1e-6);
  const int hip = motion.index("UpperLeg_L"), knee = motion.index("LowerLeg_L"), ankle = motion.index("Foot_L");
  const double thigh = (motion.positions_m[0][hip] - motion.positions_m[0][knee]).norm();
  const double shank = (motion.positions_m[0][knee] - motion.positions_m[0][ankle]).norm();
  EXPECT_NEAR(thigh, 0.40, 0.08);
  EXPECT_NEAR(shank, 0.40, 0.08);
  for (const auto& frame : motion.positions_m) {
    EXPECT_NEAR((frame[hip] - frame[knee]).norm(), thigh, 1e-3);
    EXPECT_NEAR((frame[knee] - frame[ankle]).norm(), shank, 1e-3);
    EXPECT_GT(frame[motion.index("Head")].z(), frame[hip].z() + 0.3) << "the head above the hips: Z is up";
  }
  const Eigen::Vector3d travel = motion.positions_m.back()[hip] - motion.positions_m.front()[hip];
  EXPECT_GT(travel.head<2>().norm(), 2.0);
  EXPECT_LT(std::abs(travel.z()), 0.1);
  EXPECT_THROW(motion.index("Tail"), std::invalid_argument);
}

// Placed at a start and heading, the walk's first mid-hip stands over the start, it travels
// along the heading, and its lowest toe or heel is a foot's radius above the ground; the truth's
// joints are the mapped ones, the head's centre above the neck.
TEST(CapturedWalk, IsPlacedWhereAskedAndMappedToTheBodysJoints) {
  const CapturedMotion motion = loadBvh(kMocap + "/dataset-1_walk_normal_001.bvh");
  const Eigen::Isometry3d place = placeCaptured(motion, {Eigen::Vector2d(3, -2), 1.0});
  const Eigen::Vector3d forward(std::cos(1.0), std::sin(1.0), 0);
  const std::vector<Eigen::Vector3d> first = [&] {
    std::vector<Eigen::Vector3d> p = jointsAt(motion, 0);
    for (auto& q : p) q = place * q;
    return p;
  }();
  const body::BodyPose pose = capturedBodyPose(motion, first, forward);
  EXPECT_LT((pose.joints[body::kWaist].head<2>() - Eigen::Vector2d(3, -2)).norm(), 1e-9);
  const double duration = motion.frame_time_s * (motion.positions_m.size() - 1);
  std::vector<Eigen::Vector3d> last = jointsAt(motion, duration);
  for (auto& q : last) q = place * q;
  const body::BodyPose end = capturedBodyPose(motion, last, forward);
  const Eigen::Vector2d travel = (end.joints[body::kWaist] - pose.joints[body::kWaist]).head<2>();
  EXPECT_NEAR(std::atan2(travel.y(), travel.x()), 1.0, 1e-9);
  // The drawn feet: the lowest toe or heel of the walk a foot's radius up. Each foot stands on
  // its heel as on its toes (a flat foot, not tiptoe): at the frames where its ankle is lowest
  // (mid-stance) its heel is within 2 cm of the walk's lowest.
  const CapturedFigure figure;
  double lowest = 1e9;
  for (const char* side : {"_L", "_R"}) {
    const int ankle = motion.index(std::string("Foot") + side), toes = motion.index(std::string("Toes") + side);
    for (size_t f = 0; f < motion.positions_m.size(); ++f) {
      const std::vector<Eigen::Vector3d>& p = motion.positions_m[f];
      lowest = std::min({lowest, (place * p[toes]).z(), (place * capturedHeel(p[ankle], p[toes], figure)).z()});
    }
  }
  EXPECT_NEAR(lowest, figure.foot_radius_m, 1e-9);
  for (const char* side : {"_L", "_R"}) {
    const int ankle = motion.index(std::string("Foot") + side), toes = motion.index(std::string("Toes") + side);
    size_t stance = 0;
    for (size_t f = 0; f < motion.positions_m.size(); ++f)
      if (motion.positions_m[f][ankle].z() < motion.positions_m[stance][ankle].z()) stance = f;
    const std::vector<Eigen::Vector3d>& p = motion.positions_m[stance];
    EXPECT_LT((place * capturedHeel(p[ankle], p[toes], figure)).z() - lowest, 0.02) << side;
    EXPECT_GT((place * p[ankle]).z() - lowest, 0.05) << side << ": the ankle stands above the heel";
  }
  EXPECT_EQ(pose.joints[body::kLeftKnee], first[motion.index("LowerLeg_L")]);
  EXPECT_NEAR((pose.joints[body::kHead] - first[motion.index("Head")]).norm(), kHeadCentreAboveHeadJoint_m, 1e-9);
  EXPECT_GT(pose.joints[body::kHead].z(), first[motion.index("Head")].z());
  // Halfway between two frames, the joints lie halfway.
  const std::vector<Eigen::Vector3d> half = jointsAt(motion, 0.5 * motion.frame_time_s);
  EXPECT_LT((half[0] - 0.5 * (motion.positions_m[0][0] + motion.positions_m[1][0])).norm(), 1e-12);
}

// Figures of different seeds differ in breadth (within 0.8-1.5) and colours; the same seed
// gives the same figure.
TEST(CapturedWalk, FiguresVaryWithTheirSeed) {
  const CapturedFigure a = capturedFigure(1), b = capturedFigure(2), again = capturedFigure(1);
  EXPECT_EQ(a.breadth_scale, again.breadth_scale);
  EXPECT_EQ(a.top, again.top);
  EXPECT_NE(a.breadth_scale, b.breadth_scale);
  EXPECT_NE(a.top, b.top);
  for (std::uint64_t seed = 0; seed < 50; ++seed) {
    const double breadth = capturedFigure(seed).breadth_scale;
    EXPECT_GE(breadth, 0.8);
    EXPECT_LE(breadth, 1.5);
  }
}

// A malformed file is refused naming the file and the line.
TEST(CapturedWalk, RefusesAMalformedFileNamingTheLine) {
  const std::string path = ::testing::TempDir() + "/kneed_walker_bad.bvh";
  std::ofstream(path) << "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 3 Xposition Wrotation Zrotation\n}\n";
  try {
    loadBvh(path);
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("kneed_walker_bad.bvh:5: unknown channel Wrotation"), std::string::npos)
        << e.what();
  }
  std::ofstream(path) << "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 1 Xposition\n}\nMOTION\nFrames: 2\n"
                         "Frame Time: 0.1\n1\n";
  try {
    loadBvh(path);
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("the file ends early"), std::string::npos) << e.what();
  }
  std::remove(path.c_str());
  EXPECT_THROW(loadBvh(kMocap + "/missing.bvh"), std::invalid_argument);
}

}  // namespace
}  // namespace kneed_walker::core::synthetic
