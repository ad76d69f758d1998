#include "kneed_walker/ros/conversions.h"

#include <gtest/gtest.h>
#include <sensor_msgs/image_encodings.h>

#include <Eigen/Geometry>

#include <limits>
#include <stdexcept>
#include <vector>

namespace kneed_walker::ros_glue {
namespace {

// A consistent 4x3 bgr8 frame with a calibrated camera.
struct Frame {
  Frame() {
    image.header.frame_id = "camera_optical";
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

}  // namespace
}  // namespace kneed_walker::ros_glue
