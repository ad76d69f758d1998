#include "kneed_walker/core/vision/body_projection.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>

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

// The walker's rolling foot is an arc: with the drawn foot rigid with the shank, a tilted stance
// shank puts its heel or toe into the ground. Stood on the ground, over a stride the feet stay on
// or above it, and the stance foot stands on it.
TEST(BodyProjection, FeetStoodOnTheGroundAreNotInIt) {
  const Scene scene;
  dynamics::WalkerSimulator sim = scene.sim;
  dynamics::WalkerState s = optimizer::fromDimensionless(optimizer::mcGeerPassiveGait().start, sim);
  dynamics::WalkerControls passive;
  passive.ground_slope = optimizer::kMcGeerSlope;
  body::BodyPlacement placement;
  placement.heading_rad = 0.3;
  double deepest_m = std::numeric_limits<double>::infinity(), stance_highest_m = 0;
  for (int step = 0; step < 60; ++step) {
    sim.advance(passive, s, 0.02);
    placement.hip_abduction_rad = {0.05 * std::sin(0.3 * step), -0.04};
    const body::BodyPose pose = body::bodyPose(sim.map(), s, passive.ground_slope, placement, scene.shape);
    PartAxes axes = partAxes(pose, scene.shape);
    standFeetOnGround(pose, scene.shape, axes);
    const int stance = s.stance_leg == dynamics::Leg::kLeft ? 0 : 1;
    for (int side = 0; side < 2; ++side) {
      const int foot = body::kLeftFootPart + side;
      const PartFrame frame = partFrame(pose, axes, foot);
      const body::PartShape& part = scene.shape.parts[foot];
      double lowest_m = std::numeric_limits<double>::infinity();
      for (int k = 0; k < 72; ++k) {  // each end's rim, sampled
        const double t = 2 * M_PI * k / 72;
        for (const bool proximal : {true, false}) {
          const Eigen::Vector3d point = (proximal ? axes.proximal[foot] : axes.distal[foot]) +
                                        0.5 * std::cos(t) * (proximal ? part.proximal_width_m : part.distal_width_m) * frame.across +
                                        0.5 * std::sin(t) * (proximal ? part.proximal_depth_m : part.distal_depth_m) * frame.depth;
          lowest_m = std::min(lowest_m, (point - pose.ground_point_m).dot(pose.up));
        }
      }
      deepest_m = std::min(deepest_m, lowest_m);
      if (side == stance) stance_highest_m = std::max(stance_highest_m, lowest_m);
    }
  }
  std::cout << "drawn feet: lowest " << deepest_m * 1e3 << " mm above the ground; the stance foot at most "
            << stance_highest_m * 1e3 << " mm above it\n";
  EXPECT_GT(deepest_m, -1e-4);
  EXPECT_LT(stance_highest_m, 0.02);
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

// How far a point lies outside a convex outline, pixels (0 inside).
double distanceOutside(const PartOutline& outline, const Eigen::Vector2d& p) {
  if (inside(outline, p)) return 0;
  double nearest = std::numeric_limits<double>::infinity();
  for (int i = 0; i < outline.size; ++i) {
    const Eigen::Vector2d a = outline.hull[i], b = outline.hull[(i + 1) % outline.size];
    const double t = std::clamp((p - a).dot(b - a) / std::max((b - a).squaredNorm(), 1e-300), 0.0, 1.0);
    nearest = std::min(nearest, (a + t * (b - a) - p).norm());
  }
  return nearest;
}

double area(const PartOutline& outline) {
  double twice = 0;
  for (int i = 0; i < outline.size; ++i) twice += cross(Eigen::Vector2d::Zero(), outline.hull[i], outline.hull[(i + 1) % outline.size]);
  return 0.5 * std::abs(twice);
}

// The likelihood's outlines (each end ellipse mapped by the camera's derivative at its centre)
// against the exact perspective image (projectBodyPartsExactly, as the synthetic sequences are
// drawn), for the person where the PETS camera sees the image centre (23 m away) and
// placed 4 m in front of the camera. Both are polygons inscribed in the parts' true outlines,
// with vertices in different places, so they differ by up to a chord's sagitta.
TEST(BodyProjection, OutlinesMatchTheExactPerspectiveImage) {
  for (const double distance_m : {0.0, 4.0}) {
    Scene scene;
    if (distance_m > 0) {  // the waist moved onto the optical axis, distance_m from the camera
      const Eigen::Vector3d target = scene.camera.centre() + distance_m * scene.camera.rotation().row(2).transpose();
      const Eigen::Vector3d shift = target - scene.pose.joints[body::kWaist];
      for (auto& joint : scene.pose.joints) joint += shift;
      for (auto& foot : scene.pose.foot_centres) foot += shift;
    }
    BodyOutlines fast, exact;
    projectBodyParts(scene.camera, scene.pose, scene.shape, fast);
    projectBodyPartsExactly(scene.camera, scene.pose, scene.shape, partAxes(scene.pose, scene.shape), exact);
    double worst_px = 0, worst_area = 0, worst_end_px = 0, height_px = 0;
    for (int p = 0; p < body::kNumBodyParts; ++p) {
      ASSERT_TRUE(fast[p].visible && exact[p].visible);
      for (int i = 0; i < exact[p].size; ++i) worst_px = std::max(worst_px, distanceOutside(fast[p], exact[p].hull[i]));
      for (int i = 0; i < fast[p].size; ++i) worst_px = std::max(worst_px, distanceOutside(exact[p], fast[p].hull[i]));
      worst_area = std::max(worst_area, std::abs(area(fast[p]) / area(exact[p]) - 1));
      for (int end = 0; end < 2; ++end) worst_end_px = std::max(worst_end_px, (fast[p].ends_px[end] - exact[p].ends_px[end]).norm());
      EXPECT_EQ(fast[p].depth_m, exact[p].depth_m);
    }
    for (const auto& outline : exact)
      for (int i = 0; i < outline.size; ++i) height_px = std::max(height_px, outline.hull[i].y() - exact[body::kHeadPart].hull[0].y());
    std::cout << (distance_m > 0 ? "4 m away" : "at the image centre") << ": waist at depth "
              << scene.camera.depth(scene.pose.joints[body::kWaist]) << " m, body about " << height_px
              << " px tall; vertices at most " << worst_px << " px outside the other outline, areas differ by at most "
              << 100 * worst_area << " %, end centres by " << worst_end_px << " px\n";
    EXPECT_LT(worst_px, distance_m > 0 ? 6.0 : 1.0);
    EXPECT_LT(worst_area, 0.1);
    EXPECT_LT(worst_end_px, distance_m > 0 ? 2.0 : 0.2);
  }
}

TEST(BodyProjection, PartsBehindTheCameraAreInvisible) {
  Scene scene;
  const Eigen::Vector3d behind = scene.camera.centre() - 3.0 * scene.camera.rotation().row(2).transpose();
  const Eigen::Vector3d shift = behind - scene.pose.joints[body::kWaist];
  for (auto& joint : scene.pose.joints) joint += shift;
  for (auto& foot : scene.pose.foot_centres) foot += shift;
  BodyOutlines outlines, exact;
  projectBodyParts(scene.camera, scene.pose, scene.shape, outlines);
  projectBodyPartsExactly(scene.camera, scene.pose, scene.shape, partAxes(scene.pose, scene.shape), exact);
  for (const BodyOutlines* o : {&outlines, &exact}) {
    EXPECT_FALSE((*o)[body::kTorsoPart].visible);
    EXPECT_EQ((*o)[body::kTorsoPart].size, 0);
  }
}

}  // namespace
}  // namespace kneed_walker::core::vision
