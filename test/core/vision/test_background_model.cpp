#include "kneed_walker/core/vision/background_model.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <vector>

namespace kneed_walker::core::vision {
namespace {

cv::Mat texturedScene(cv::Size size, int seed) {
  cv::Mat scene(size, CV_8UC3);
  cv::RNG random(seed);
  random.fill(scene, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(scene, scene, cv::Size(5, 5), 1.5);  // gradients of every size
  return scene;
}

TEST(BackgroundModel, ARegionsMeasurementsAreTheWholeFramesThere) {
  const cv::Mat frame = texturedScene(cv::Size(131, 97), 1);
  const cv::Mat whole = measurements(frame);
  ASSERT_EQ(whole.type(), CV_32FC(kMeasurementChannels));
  for (const cv::Rect roi : {cv::Rect(0, 0, 131, 97), cv::Rect(0, 0, 131, 32), cv::Rect(0, 32, 131, 32),
                             cv::Rect(0, 96, 131, 1), cv::Rect(40, 30, 17, 23), cv::Rect(130, 0, 1, 97),
                             cv::Rect(1, 1, 2, 2)}) {
    const cv::Mat region = measurements(frame, roi);
    ASSERT_EQ(region.size(), roi.size());
    EXPECT_EQ(cv::norm(region, whole(roi), cv::NORM_INF), 0.0) << roi;
  }
  EXPECT_THROW(measurements(frame, cv::Rect(120, 0, 20, 10)), std::invalid_argument);
  EXPECT_THROW(measurements(frame, cv::Rect(0, 0, 0, 10)), std::invalid_argument);
}

// learn() measures the frames a band of rows at a time: every row, those at the bands' edges
// included, must get the whole frame's measurements. Blocks crossing the frames (outliers at the
// pixels they cover, in one frame each) must not show beyond the reach of their edges' gradients.
TEST(BackgroundModel, LearnsEveryRowAsTheWholeFrameMeasuresIt) {
  const cv::Mat scene = texturedScene(cv::Size(80, 150), 2);
  std::vector<cv::Mat> frames;
  cv::Mat touched(scene.size(), CV_8U, cv::Scalar(0));
  for (int i = 0; i < 9; ++i) {
    cv::Mat frame = scene.clone();
    const cv::Rect block(8 * i, 16 * i, 10, 12);
    cv::rectangle(frame, block, cv::Scalar(255, 0, 255), cv::FILLED);
    cv::rectangle(touched, cv::Rect(block.x - 3, block.y - 3, block.width + 6, block.height + 6), 255, cv::FILLED);
    frames.push_back(frame);
  }
  const BackgroundModel model = BackgroundModel::learn(frames);
  const cv::Mat expected = measurements(scene);
  ASSERT_EQ(model.mean().size(), expected.size());
  cv::Mat difference;
  cv::absdiff(model.mean(), expected, difference);
  difference = difference.reshape(1, scene.rows * scene.cols);
  cv::Mat untouched = touched.reshape(1, scene.rows * scene.cols) == 0;
  double worst = 0;
  for (int i = 0; i < difference.rows; ++i)
    if (untouched.at<uchar>(i)) worst = std::max(worst, cv::norm(difference.row(i), cv::NORM_INF));
  EXPECT_LT(worst, 1e-3);
  EXPECT_GT(cv::countNonZero(untouched), scene.rows * scene.cols / 2);
}

}  // namespace
}  // namespace kneed_walker::core::vision
