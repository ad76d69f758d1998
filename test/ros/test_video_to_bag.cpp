// video_to_bag (issue 12): a video and its calibration become a bag a camera driver would have
// recorded: the frames themselves, stamped at the asked rate, with the calibration's camera in
// camera_info and on a latched /tf_static.
#include <gtest/gtest.h>
#include <opencv2/videoio.hpp>
#include <cv_bridge/cv_bridge.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2_msgs/TFMessage.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "kneed_walker/ros/conversions.h"

namespace kneed_walker::ros_glue {
namespace {

const std::string kShared = KNEED_WALKER_SHARED_DIR;
const std::string kVideo = kShared + "/data/pets2009/vtest.avi";
const std::string kCalibration = kShared + "/data/pets2009/View_001_camera.yml";

// video_to_bag on the PETS video with `options`, into the temporary directory's `name`.
struct BagRun {
  std::string out, command;
};
BagRun petsToBag(const std::string& name, const std::string& options) {
  BagRun run;
  run.out = (std::filesystem::temp_directory_path() / name).string();
  run.command = std::string(KNEED_WALKER_VIDEO_TO_BAG) + " --video " + kVideo + " --camera " + kCalibration + " --out " +
                run.out + " " + options + " > /dev/null";
  return run;
}

TEST(VideoToBag, WritesTheFramesAtTheAskedRateWithTheCalibratedCamera) {
  const BagRun run = petsToBag("kneed_walker_video_to_bag_test.bag", "--first-frame 600 --frames 10 --fps 7");
  ASSERT_EQ(std::system(run.command.c_str()), 0) << run.command;
  const std::string& out = run.out;

  std::vector<sensor_msgs::Image::ConstPtr> images;
  std::vector<sensor_msgs::CameraInfo::ConstPtr> infos;
  std::vector<tf2_msgs::TFMessage::ConstPtr> tf_static;
  bool latched = false;
  {
    rosbag::Bag bag(out, rosbag::bagmode::Read);
    for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
      if (auto image = m.instantiate<sensor_msgs::Image>()) images.push_back(image);
      if (auto info = m.instantiate<sensor_msgs::CameraInfo>()) infos.push_back(info);
      if (auto tf = m.instantiate<tf2_msgs::TFMessage>()) {
        tf_static.push_back(tf);
        latched = m.getConnectionHeader() && m.getConnectionHeader()->count("latching") &&
                  m.getConnectionHeader()->at("latching") == "1";
      }
    }
  }
  std::filesystem::remove(out);
  ASSERT_EQ(images.size(), 10u);
  ASSERT_EQ(infos.size(), 10u);
  ASSERT_EQ(tf_static.size(), 1u);
  EXPECT_TRUE(latched) << "/tf_static is not on a latched connection";
  // The frames are the video's own, 1/7 s apart.
  cv::VideoCapture capture(kVideo);
  cv::Mat frame;
  for (int skipped = 0; skipped <= 600; ++skipped) ASSERT_TRUE(capture.read(frame));
  const cv::Mat first = cv_bridge::toCvCopy(images[0], "bgr8")->image;
  EXPECT_EQ(cv::norm(first, frame, cv::NORM_INF), 0.0) << "the first image is not the video's frame 600";
  for (size_t i = 0; i < images.size(); ++i) {
    EXPECT_NEAR((images[i]->header.stamp - images[0]->header.stamp).toSec(), i / 7.0, 1e-6);
    EXPECT_EQ(infos[i]->header.stamp, images[i]->header.stamp);
    EXPECT_EQ(frameProblem(*images[i], *infos[i]), "");
  }
  // The camera from camera_info and /tf_static projects as the calibration file's.
  const core::vision::Camera file_camera = core::vision::Camera::load(kCalibration, 0.001);
  const core::vision::Camera bag_camera = toCamera(*infos[0], tf_static[0]->transforms.at(0));
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(-15, -14, 1.7), Eigen::Vector3d(5, -20, 0.5)}) {
    const auto a = file_camera.project(p), b = bag_camera.project(p);
    ASSERT_TRUE(a && b);
    EXPECT_LT((*a - *b).norm(), 1e-6);
  }
}

// Without --fps the frames are stamped at the video's own rate (the PETS AVI says 10 frames a
// second), never at a rate of the tool's.
TEST(VideoToBag, StampsAtTheVideosRateByDefault) {
  const BagRun run = petsToBag("kneed_walker_video_to_bag_rate.bag", "--frames 3");
  ASSERT_EQ(std::system(run.command.c_str()), 0) << run.command;
  const std::string& out = run.out;
  std::vector<double> stamps;
  {
    rosbag::Bag bag(out, rosbag::bagmode::Read);
    for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery("/camera/image_raw")))
      stamps.push_back(m.instantiate<sensor_msgs::Image>()->header.stamp.toSec());
  }
  std::filesystem::remove(out);
  ASSERT_EQ(stamps.size(), 3u);
  EXPECT_NEAR(stamps[1] - stamps[0], 1.0 / cv::VideoCapture(kVideo).get(cv::CAP_PROP_FPS), 1e-6);
  EXPECT_NEAR(stamps[2] - stamps[1], 0.1, 1e-6);
}

}  // namespace
}  // namespace kneed_walker::ros_glue
