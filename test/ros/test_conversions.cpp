#include "kneed_walker/ros/conversions.h"
#include "kneed_walker/core/vision/body_projection.h"

#include <gtest/gtest.h>
#include <sensor_msgs/image_encodings.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <tuple>
#include <vector>

namespace kneed_walker::ros_glue {
namespace {

// A consistent 4x3 bgr8 frame with a calibrated camera.
struct Frame {
  Frame() {
    image.header.frame_id = "camera_optical";
    image.header.stamp = ros::Time(1.5);
    image.width = 4;
    image.height = 3;
    image.encoding = sensor_msgs::image_encodings::BGR8;
    image.step = 12;
    image.data.assign(36, 0);
    info.header = image.header;
    info.width = 4;
    info.height = 3;
    info.K = {100, 0, 2, 0, 100, 1.5, 0, 0, 1};
    info.distortion_model = "plumb_bob";
    info.D = {0, 0, 0, 0, 0};
  }
  sensor_msgs::Image image;
  sensor_msgs::CameraInfo info;
};

TEST(FrameProblem, ConsistentFrameIsAccepted) {
  Frame f;
  EXPECT_EQ(frameProblem(f.image, f.info), "");
  f.info.D.clear();
  f.info.distortion_model.clear();
  EXPECT_EQ(frameProblem(f.image, f.info), "") << "no distortion given is a pinhole camera";
}

// Every encoding the README lists is accepted at its own pixel size, and a plumb_bob camera
// with 4 or 5 coefficients and a rational_polynomial one with 8; other counts are refused.
TEST(FrameProblem, EveryListedEncodingAndDistortionModelIsAccepted) {
  for (const auto& [encoding, bytes] : {std::pair{"mono8", 1}, {"bgr8", 3}, {"rgb8", 3}, {"bgra8", 4}, {"rgba8", 4}}) {
    Frame f;
    f.image.encoding = encoding;
    f.image.step = 4 * bytes;
    f.image.data.assign(3 * f.image.step, 0);
    EXPECT_EQ(frameProblem(f.image, f.info), "") << encoding;
  }
  for (const auto& [model, count, accepted] :
       {std::tuple{"plumb_bob", 4, true}, {"plumb_bob", 5, true}, {"plumb_bob", 3, false}, {"plumb_bob", 8, false},
        {"rational_polynomial", 8, true}, {"rational_polynomial", 5, false}}) {
    Frame f;
    f.info.distortion_model = model;
    f.info.D.assign(count, 0.0);
    EXPECT_EQ(frameProblem(f.image, f.info).empty(), accepted) << model << " with " << count << " coefficients: "
                                                                << frameProblem(f.image, f.info);
  }
}

TEST(FrameProblem, EachDefectIsNamed) {
  struct Case {
    const char* expected;
    void (*spoil)(Frame&);
  };
  const Case cases[] = {
      {"image is empty", [](Frame& f) { f.image.width = 0; }},
      {"encoding '32FC1'", [](Frame& f) { f.image.encoding = "32FC1"; }},
      {"step 6 is shorter", [](Frame& f) { f.image.step = 6; f.image.data.resize(18); }},
      {"holds 35 bytes", [](Frame& f) { f.image.data.resize(35); }},
      {"camera_info is for 640x480", [](Frame& f) { f.info.width = 640; f.info.height = 480; }},
      {"no valid focal length", [](Frame& f) { f.info.K[0] = 0; }},
      {"no valid focal length",
       [](Frame& f) { f.info.K[4] = std::numeric_limits<double>::quiet_NaN(); }},
      {"model 'fisheye'", [](Frame& f) { f.info.distortion_model = "fisheye"; }},
      {"no frame_id", [](Frame& f) { f.image.header.frame_id.clear(); }},
      {"no stamp (0)", [](Frame& f) { f.image.header.stamp = ros::Time(); }},
      {"larger than the 64 megapixels", [](Frame& f) { f.image.width = f.image.height = 9000; }},
  };
  for (const Case& c : cases) {
    Frame f;
    c.spoil(f);
    const std::string problem = frameProblem(f.image, f.info);
    EXPECT_NE(problem.find(c.expected), std::string::npos)
        << "expected '" << c.expected << "', got '" << problem << "'";
  }
}

// A core camera survives CameraInfo + pose and back: every pixel lands where it did.
TEST(CameraConversion, RoundTripKeepsProjection) {
  Eigen::Matrix3d k;
  k << 1100, 0, 290, 0, 1140, 258, 0, 0, 1;
  const Eigen::Matrix3d r =
      (Eigen::AngleAxisd(2.1, Eigen::Vector3d::UnitX()) * Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()))
          .toRotationMatrix();
  for (const std::vector<double>& d : {std::vector<double>{-0.15, 0.05, 0.001, 0.004, 0.0},
                                       std::vector<double>{-0.2, 0.05, 0.001, -0.002, 0.01, 0.02, -0.01, 0.003}}) {
    const core::vision::Camera camera(k, d, r, Eigen::Vector3d(1.9, -2.4, 34.4), 768, 576);
    const sensor_msgs::CameraInfo info = toCameraInfo(camera, "camera_optical");
    EXPECT_EQ(info.distortion_model, d.size() == 8 ? "rational_polynomial" : "plumb_bob");
    EXPECT_EQ(info.header.frame_id, "camera_optical");
    EXPECT_EQ(info.P[3], 0.0);
    EXPECT_EQ(frameProblem(Frame().image, info).find("size"), std::string::npos);
    const geometry_msgs::TransformStamped pose = cameraPose(camera, "world", "camera_optical");
    EXPECT_EQ(pose.header.frame_id, "world");
    EXPECT_EQ(pose.child_frame_id, "camera_optical");
    const core::vision::Camera back = toCamera(info, pose);
    for (const Eigen::Vector3d& point : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(3, -2, 1.5),
                                         Eigen::Vector3d(-4, 5, 0.2)}) {
      const auto a = camera.project(point), b = back.project(point);
      ASSERT_EQ(a.has_value(), b.has_value());
      if (a) EXPECT_LT((*a - *b).norm(), 1e-9);
    }
  }
}

TEST(CameraConversion, NonUnitQuaternionIsRefused) {
  geometry_msgs::TransformStamped pose;
  pose.transform.rotation.w = 0.5;
  sensor_msgs::CameraInfo info = Frame().info;
  EXPECT_THROW(toCamera(info, pose), std::invalid_argument);
}

// The walker state message carries the MAP walker as the estimate gives it, in SI: angles,
// rates, the stride clock and every spring field (the nodelet once left the springs at 0).
TEST(WalkerStateConversion, CarriesTheStateAndEverySpring) {
  core::tracking::TrackEstimate e;
  e.walker.q << 0.1, 0.2, 0.3, 0.4, 0.5;
  e.walker.qdot << 1, 2, 3, 4, 5;
  e.walker.stance_leg = core::dynamics::Leg::kRight;
  e.walker.time_in_stride = 0.25;
  e.walker.heel_strikes = 7;
  e.gait_slope_rad = 0.05;
  e.springs = {11, 12, 13, 0.14, 15, 16, 17, -0.18, 19};
  e.toe_off_impulse_ns = 20;
  std_msgs::Header header;
  header.frame_id = "world";
  const WalkerState m = toWalkerState(e, header);
  EXPECT_EQ(m.stance_leg, WalkerState::RIGHT);
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(m.q[i], e.walker.q[i]);
    EXPECT_EQ(m.qdot[i], e.walker.qdot[i]);
  }
  EXPECT_EQ(m.ground_slope, 0.05);
  EXPECT_EQ(m.time_in_stride, 0.25);
  EXPECT_EQ(m.stride_count, 7u);
  const std::vector<double> springs = {m.stance_knee_stiffness, m.stance_knee_damping, m.swing_knee_stiffness,
                                       m.swing_knee_rest_angle, m.swing_knee_damping, m.hip_stiffness,
                                       m.torso_stiffness, m.torso_rest_angle, m.torso_damping};
  EXPECT_EQ(springs, (std::vector<double>{11, 12, 13, 0.14, 15, 16, 17, -0.18, 19}));
  EXPECT_EQ(m.toe_off_impulse, 20);
}

// The markers: the skeleton, the joints and the body's parts as the likelihood sees them, each
// part a closed tapered elliptical cylinder around its axis, no wider than its shape.
TEST(MarkerConversion, DrawsTheSkeletonAndEveryPartAsItsCylinder) {
  core::tracking::TrackEstimate e;
  const core::body::BodyShape shape = core::body::BodyShape::forHeight(1.75);
  e.pose.forward = Eigen::Vector3d(0, 1, 0);
  e.pose.up = Eigen::Vector3d(0, 0, 1);
  e.pose.left = Eigen::Vector3d(-1, 0, 0);
  const double z[core::body::kNumBodyJoints] = {0.93, 1.43, 1.63, 0.93, 0.93, 0.48, 0.48, 0.07, 0.07};
  for (int j = 0; j < core::body::kNumBodyJoints; ++j) {
    const double x = j == core::body::kLeftHip || j == core::body::kLeftKnee || j == core::body::kLeftAnkle ? -0.09
                     : j == core::body::kRightHip || j == core::body::kRightKnee || j == core::body::kRightAnkle ? 0.09 : 0.0;
    e.pose.joints[j] = Eigen::Vector3d(x, 0.02 * j, z[j]);
  }
  std_msgs::Header header;
  header.frame_id = "world";
  const visualization_msgs::MarkerArray m = toMarkers(e, header, "1", 1.0, shape);
  ASSERT_EQ(m.markers.size(), 3u);
  EXPECT_EQ(m.markers[0].type, visualization_msgs::Marker::LINE_LIST);
  EXPECT_EQ(m.markers[1].points.size(), static_cast<size_t>(core::body::kNumBodyJoints));
  const visualization_msgs::Marker& parts = m.markers[2];
  EXPECT_EQ(parts.type, visualization_msgs::Marker::TRIANGLE_LIST);
  const size_t per_part = 4 * kPartMeshSides * 3;  // side (2 triangles a side) and two end caps
  ASSERT_EQ(parts.points.size(), core::body::kNumBodyParts * per_part);
  ASSERT_EQ(parts.colors.size(), parts.points.size());
  const core::vision::PartAxes axes = core::vision::partAxes(e.pose, shape);
  for (int p = 0; p < core::body::kNumBodyParts; ++p) {
    const Eigen::Vector3d a = axes.proximal[p], axis = (axes.distal[p] - a).normalized();
    const core::body::PartShape& s = shape.parts[p];
    const double widest = 0.5 * std::max({s.proximal_width_m, s.proximal_depth_m, s.distal_width_m, s.distal_depth_m});
    double farthest = 0;
    for (size_t k = p * per_part; k < (p + 1) * per_part; ++k) {
      const Eigen::Vector3d v(parts.points[k].x, parts.points[k].y, parts.points[k].z);
      const double along = (v - a).dot(axis);
      EXPECT_GE(along, -1e-12);
      EXPECT_LE(along, (axes.distal[p] - a).norm() + 1e-12);
      farthest = std::max(farthest, (v - a - along * axis).norm());
    }
    EXPECT_LE(farthest, widest + 1e-12) << core::body::partName(core::body::BodyPart(p));
    EXPECT_GE(farthest, 0.5 * std::min(s.proximal_width_m, s.distal_width_m) - 1e-12) << core::body::partName(core::body::BodyPart(p));
  }
}

// The smoothed pose's tf frames: body_<id>_smoothed at the mid-hip turned to the walking
// direction, each joint under it (REP 155 names with the suffix) where the pose has it.
TEST(TransformConversion, APoseGivesSuffixedFramesAtItsJoints) {
  core::body::BodyPose pose;
  for (int j = 0; j < core::body::kNumBodyJoints; ++j) pose.joints[j] = Eigen::Vector3d(1.0 + 0.1 * j, 2.0, 0.05 * j);
  const double heading = 0.7;
  std_msgs::Header header;
  header.frame_id = "world";
  header.stamp = ros::Time(5.0);
  const std::vector<geometry_msgs::TransformStamped> transforms = toTransforms(pose, heading, header, "1_smoothed");
  ASSERT_EQ(transforms.size(), static_cast<size_t>(core::body::kNumBodyJoints));
  EXPECT_EQ(transforms[0].child_frame_id, "body_1_smoothed");
  EXPECT_EQ(transforms[0].header.frame_id, "world");
  const Eigen::Vector3d& waist = pose.joints[core::body::kWaist];
  EXPECT_NEAR(transforms[0].transform.translation.x, waist.x(), 1e-12);
  for (size_t i = 1; i < transforms.size(); ++i) {
    const geometry_msgs::TransformStamped& t = transforms[i];
    EXPECT_EQ(t.header.frame_id, "body_1_smoothed");
    EXPECT_EQ(t.header.stamp, header.stamp);
    EXPECT_NE(t.child_frame_id.find("_1_smoothed"), std::string::npos) << t.child_frame_id;
    int j = 0;
    while (std::string(core::body::jointName(core::body::BodyJoint(j))) + "_1_smoothed" != t.child_frame_id) ++j;
    // Back to the world: the body frame's yaw, then the mid-hip.
    const Eigen::Vector3d offset(t.transform.translation.x, t.transform.translation.y, t.transform.translation.z);
    const Eigen::Vector3d world = waist + Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()) * offset;
    EXPECT_NEAR((world - pose.joints[j]).norm(), 0.0, 1e-12) << t.child_frame_id;
  }
}

// The ground track's message carries its state and full covariance in the world frame, and its
// markers draw the position's 2-sd ellipse along the covariance's long axis.
TEST(GroundTrackConversion, CarriesTheStateAndCovarianceAndDrawsTheSpread) {
  core::person::GroundTrackEstimate track;
  track.mean << 1.5, 6.0, -1.2, 0.4, 1.72;
  track.measured = true;
  Eigen::Matrix<double, 5, 5> a = Eigen::Matrix<double, 5, 5>::Identity();
  a(0, 1) = 0.3, a(2, 3) = -0.2, a(4, 0) = 0.1;
  track.covariance = 0.01 * a * a.transpose();
  track.covariance(1, 1) += 0.08;  // long along y, the line of sight
  std_msgs::Header header;
  header.frame_id = "world";
  header.stamp = ros::Time(7.25);
  const GroundTrack message = toGroundTrack(track, header, "2", 0.05);
  EXPECT_EQ(message.header.frame_id, "world");
  EXPECT_EQ(message.header.stamp, header.stamp);
  EXPECT_EQ(message.body_id, "2");
  EXPECT_TRUE(message.measured);
  EXPECT_DOUBLE_EQ(message.position.x, 1.5);
  EXPECT_DOUBLE_EQ(message.position.y, 6.0);
  EXPECT_DOUBLE_EQ(message.position.z, 0.05);
  EXPECT_DOUBLE_EQ(message.velocity.x, -1.2);
  EXPECT_DOUBLE_EQ(message.velocity.y, 0.4);
  EXPECT_DOUBLE_EQ(message.velocity.z, 0.0);
  EXPECT_DOUBLE_EQ(message.stature, 1.72);
  for (int r = 0; r < 5; ++r)
    for (int c = 0; c < 5; ++c) EXPECT_DOUBLE_EQ(message.covariance[5 * r + c], track.covariance(r, c)) << r << "," << c;

  const visualization_msgs::MarkerArray markers = toGroundTrackMarkers(message, 1.0);
  ASSERT_EQ(markers.markers.size(), 3u);
  const visualization_msgs::Marker& spread = markers.markers[0];
  EXPECT_EQ(spread.ns, "ground_track_2");
  EXPECT_EQ(spread.header.frame_id, "world");
  Eigen::Matrix2d position_covariance = track.covariance.topLeftCorner<2, 2>();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> axes(position_covariance);
  EXPECT_NEAR(spread.scale.x, 4 * std::sqrt(axes.eigenvalues()(1)), 1e-9);
  EXPECT_NEAR(spread.scale.y, 4 * std::sqrt(axes.eigenvalues()(0)), 1e-9);
  // The cylinder's x axis (its yaw) along the long axis, which is nearly the line of sight (y).
  const double yaw = 2 * std::atan2(spread.pose.orientation.z, spread.pose.orientation.w);
  EXPECT_GT(std::abs(std::sin(yaw)), 0.95);
  const visualization_msgs::Marker& velocity = markers.markers[1];
  ASSERT_EQ(velocity.points.size(), 2u);
  EXPECT_NEAR(velocity.points[1].x - velocity.points[0].x, -1.2, 1e-12);
  EXPECT_NEAR(velocity.points[1].y - velocity.points[0].y, 0.4, 1e-12);
  const visualization_msgs::Marker& stature = markers.markers[2];
  ASSERT_EQ(stature.points.size(), 2u);
  EXPECT_NEAR(stature.points[1].z - stature.points[0].z, 1.72, 1e-12);
}

}  // namespace
}  // namespace kneed_walker::ros_glue
