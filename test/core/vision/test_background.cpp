#include "kneed_walker/core/vision/background.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <cstdio>

namespace kneed_walker::core::vision {
namespace {

TEST(Background, MedianRemovesMovingThings) {
  const std::string path = ::testing::TempDir() + "/kneed_walker_median_test.avi";
  const cv::Mat scene(120, 160, CV_8UC3, cv::Scalar(40, 120, 200));
  {
    cv::VideoWriter video(path, cv::CAP_OPENCV_MJPEG, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10,
                          scene.size());
    ASSERT_TRUE(video.isOpened());
    for (int i = 0; i < 20; ++i) {
      cv::Mat frame = scene.clone();
      cv::rectangle(frame, cv::Rect(8 * i, 40, 20, 40), cv::Scalar(255, 255, 255), cv::FILLED);
      video.write(frame);
    }
  }
  const cv::Mat median = medianBackground(path, 20);
  EXPECT_LT(cv::norm(median, scene, cv::NORM_INF), 12.0) << "only JPEG's error is left";
  EXPECT_THROW(medianBackground(path + ".missing", 5), std::runtime_error);
  std::remove(path.c_str());
}

}  // namespace
}  // namespace kneed_walker::core::vision
