#include "kneed_walker/core/vision/background.h"

#include <opencv2/videoio.hpp>

#include <algorithm>
#include <stdexcept>
#include <vector>

namespace kneed_walker::core::vision {

cv::Mat medianBackground(const std::string& video_path, int samples) {
  if (samples < 1) throw std::invalid_argument("medianBackground needs samples >= 1");
  cv::VideoCapture video(video_path);
  if (!video.isOpened()) throw std::runtime_error(video_path + ": cannot open the video");
  // Decode in order and keep only the sampled frames (a whole video would not fit in memory).
  const int n = static_cast<int>(video.get(cv::CAP_PROP_FRAME_COUNT));
  if (n <= 0) throw std::runtime_error(video_path + ": the video has no frame count");
  const int count = std::min(samples, n);
  std::vector<cv::Mat> frames;
  cv::Mat frame;
  for (int index = 0; static_cast<int>(frames.size()) < count && video.read(frame); ++index) {
    const int next = count == 1 ? 0 : static_cast<int>(static_cast<long>(frames.size()) * (n - 1) / (count - 1));
    if (index == next) frames.push_back(frame.clone());
  }
  if (frames.empty()) throw std::runtime_error(video_path + ": the video has no frames");
  cv::Mat median(frames[0].size(), frames[0].type());
  const int used = static_cast<int>(frames.size());
  std::vector<uchar> values(used);
  const int width = frames[0].cols * frames[0].channels();
  for (int y = 0; y < median.rows; ++y) {
    uchar* out = median.ptr<uchar>(y);
    for (int x = 0; x < width; ++x) {
      for (int k = 0; k < used; ++k) values[k] = frames[k].ptr<uchar>(y)[x];
      std::nth_element(values.begin(), values.begin() + used / 2, values.end());
      out[x] = values[used / 2];
    }
  }
  return median;
}

}  // namespace kneed_walker::core::vision
