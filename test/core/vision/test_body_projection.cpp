#include "kneed_walker/core/vision/body_projection.h"

#include <gtest/gtest.h>

#include "kneed_walker/core/optimizer/periodic_gait.h"

namespace kneed_walker::core::vision {
namespace {

const std::string kPets = std::string(KNEED_WALKER_SHARED_DIR) + "/data/pets2009";

// A 1.75 m person walking McGeer's passive gait, placed where the PETS camera sees the
// ground at the image centre, walking across the view.
struct Scene {
  Scene()
      : camera(Camera::load(kPets + "/View_001_camera.yml", 0.001)),
        sim(dynamics::scaleToPerson(dynamics::mcGeerProportions(), 1.75, 70)),
        shape(body::BodyShape::forHeight(1.75)) {
    dynamics::WalkerState s = optimizer::fromDimensionless(optimizer::mcGeerPassiveGait().start, sim);
    dynamics::WalkerControls passive;
    passive.ground_slope = optimizer::kMcGeerSlope;
    sim.advance(passive, s, 0.4);
    const Eigen::Vector3d ground = *camera.groundPoint({384, 288});
    body::BodyPlacement placement;
    placement.ground_origin_m = ground.head<2>();
    placement.heading_rad = 0.3;
    pose = body::bodyPose(sim.map(), s, 0.0, placement, shape);
  }
  Camera camera;
  dynamics::WalkerSimulator sim;
  body::BodyShape shape;
  body::BodyPose pose;
};

double cross(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

bool inside(const PartOutline& outline, const Eigen::Vector2d& p) {
  for (int i = 0; i < outline.size; ++i)
    if (cross(outline.hull[i], outline.hull[(i + 1) % outline.size], p) < -1e-9) return false;
  return true;
}

TEST(BodyProjection, PartsAreNamedAndRunBetweenTheirJoints) {
  EXPECT_STREQ(body::partName(body::kTorsoPart), "torso");
  EXPECT_STREQ(body::partName(body::kRightFootPart), "r_foot");
  const Scene scene;
  const PartAxes axes = partAxes(scene.pose, scene.shape);
  EXPECT_EQ(axes.proximal[body::kLeftThighPart], scene.pose.joints[body::kLeftHip]);
  EXPECT_EQ(axes.distal[body::kRightShankPart], scene.pose.joints[body::kRightAnkle]);
  for (int side = 0; side < 2; ++side) {
    const Eigen::Vector3d foot = axes.distal[body::kLeftFootPart + side] - axes.proximal[body::kLeftFootPart + side];
    EXPECT_NEAR(foot.norm(), scene.shape.foot_length_m, 1e-12);
    EXPECT_GT(foot.dot(scene.pose.forward), 0.5 * foot.norm()) << "feet point forward";
  }
}

TEST(BodyProjection, OutlinesAreConvexAndCoverTheirAxes) {
  const Scene scene;
  BodyOutlines outlines;
  projectBodyParts(scene.camera, scene.pose, scene.shape, outlines);
  const PartAxes axes = partAxes(scene.pose, scene.shape);
  for (int p = 0; p < body::kNumBodyParts; ++p) {
    const PartOutline& o = outlines[p];
    ASSERT_TRUE(o.visible) << body::partName(static_cast<body::BodyPart>(p));
    ASSERT_GE(o.size, 4);
    for (int i = 0; i < o.size; ++i)
      EXPECT_GE(cross(o.hull[i], o.hull[(i + 1) % o.size], o.hull[(i + 2) % o.size]), -1e-9)
          << "not convex: " << body::partName(static_cast<body::BodyPart>(p));
    for (const auto* end : {&axes.proximal[p], &axes.distal[p]})
      EXPECT_TRUE(inside(o, *scene.camera.project(*end))) << body::partName(static_cast<body::BodyPart>(p));
  }
}

TEST(BodyProjection, TorsoWidthInPixelsFollowsThePinholeModel) {
  const Scene scene;
  BodyOutlines outlines;
  projectBodyParts(scene.camera, scene.pose, scene.shape, outlines);
  // The torso's widest extent in the image against f · width / depth at its middle (the
  // image-centre distortion is small; the camera looks at it obliquely, hence a loose bound).
  const Eigen::Vector3d middle = 0.5 * (scene.pose.joints[body::kWaist] + scene.pose.joints[body::kNeck]);
  const double depth = (scene.camera.rotation() * middle + scene.camera.translation()).z();
  const double expected_px = scene.camera.intrinsics()(0, 0) *
                             scene.shape.parts[body::kTorsoPart].proximal_width_m / depth;
  double min_x = 1e9, max_x = -1e9;
  for (int i = 0; i < outlines[body::kTorsoPart].size; ++i) {
    min_x = std::min(min_x, outlines[body::kTorsoPart].hull[i].x());
    max_x = std::max(max_x, outlines[body::kTorsoPart].hull[i].x());
  }
  std::cout << "torso outline " << max_x - min_x << " px wide; one cross-section " << expected_px
            << " px\n";
  EXPECT_GT(max_x - min_x, 0.7 * expected_px);
  EXPECT_LT(max_x - min_x, 3.0 * expected_px);
}

TEST(BodyProjection, PartsBehindTheCameraAreInvisible) {
  Scene scene;
  const Eigen::Vector3d behind = scene.camera.centre() - 3.0 * scene.camera.rotation().row(2).transpose();
  const Eigen::Vector3d shift = behind - scene.pose.joints[body::kWaist];
  for (auto& joint : scene.pose.joints) joint += shift;
  for (auto& foot : scene.pose.foot_centres) foot += shift;
  BodyOutlines outlines;
  projectBodyParts(scene.camera, scene.pose, scene.shape, outlines);
  EXPECT_FALSE(outlines[body::kTorsoPart].visible);
  EXPECT_EQ(outlines[body::kTorsoPart].size, 0);
}

}  // namespace
}  // namespace kneed_walker::core::vision
