#include "kneed_walker/ros/conversions.h"

#include <gtest/gtest.h>
#include <sensor_msgs/image_encodings.h>

#include <limits>

namespace kneed_walker {
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

}  // namespace
}  // namespace kneed_walker
