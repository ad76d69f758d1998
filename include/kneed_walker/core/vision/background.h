// The scene without the person (paper §4, "Likelihood": the background model is learned from
// frames of a static camera): images of the background from a video.
#pragma once

#include <opencv2/core.hpp>

#include <string>

namespace kneed_walker::core::vision {

// The per-pixel median of `samples` frames spread evenly over a video from a static camera:
// the scene without the people who walk through it. Throws std::runtime_error naming the file
// when it cannot be read.
cv::Mat medianBackground(const std::string& video_path, int samples);

}  // namespace kneed_walker::core::vision
