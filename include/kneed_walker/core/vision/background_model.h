// The background model of paper §4 ("Likelihood"): at each pixel the mean of the measurement
// z = (blue, green, red, ∂I/∂x, ∂I/∂y) (grey levels; I the grey image) and its 5×5 covariance,
// learned from a set of frames of the static camera, robustly: the person may be in them.
//
// Learning: per pixel and channel the median and the MAD over the frames; a frame's value is
// an outlier when any channel lies more than `outlier_mads` robust SDs from the median (a person
// passing); mean and covariance come from the inliers. Every variance is floored
// (colour_floor, gradient_floor), so that a flat or noise-free region is not infinitely sure.
#pragma once

#include <opencv2/core.hpp>

#include <vector>

namespace kneed_walker::core::vision {

constexpr int kMeasurementChannels = 5;  // B, G, R, ∂I/∂x, ∂I/∂y

// The measurements of one frame: CV_32FC(5), the image's size.
cv::Mat measurements(const cv::Mat& bgr_image);
// The measurements of the region `roi` (inside the image) of a frame, equal to those of the whole
// frame there: computed on the region and the margin its filters reach, not on the whole frame.
cv::Mat measurements(const cv::Mat& bgr_image, const cv::Rect& roi);

struct BackgroundOptions {
  double colour_floor = 4.0;    // SD floor of each colour channel, grey levels
  double gradient_floor = 3.0;  // SD floor of each gradient component, grey levels per pixel
  double outlier_mads = 3.0;    // a sample further than this many robust SDs is an outlier
};

class BackgroundModel {
 public:
  BackgroundModel() = default;
  // From BGR 8-bit frames of one size (at least 1; 10–30 spread over a sequence are usual).
  // Throws std::invalid_argument for no frames, mixed sizes or types. Measures the frames 32
  // rows at a time (per thread), not whole: 20 B a pixel of each frame held, for those rows only.
  static BackgroundModel learn(const std::vector<cv::Mat>& frames, const BackgroundOptions& options = {});

  // log N(z; μ, Σ) of the measurements (from measurements()) of the image region `roi`, given
  // roi-sized, into the CV_32F `log_density` of roi's size.
  void logDensity(const cv::Mat& roi_measurements, const cv::Rect& roi, cv::Mat& log_density) const;
  // The squared Mahalanobis distance (z − μ)ᵀ Σ⁻¹ (z − μ) of the same, into the CV_32F
  // `squared_distance` (5 degrees of freedom: about 15 or less on the background 99 % of the time).
  void squaredDistance(const cv::Mat& roi_measurements, const cv::Rect& roi, cv::Mat& squared_distance) const;

  cv::Size size() const { return mean_.size(); }
  bool empty() const { return mean_.empty(); }
  const cv::Mat& mean() const { return mean_; }  // CV_32FC(5)

 private:
  cv::Mat mean_;          // CV_32FC(5)
  cv::Mat whitening_;     // CV_32FC(15): the lower triangle of L⁻¹, Σ = L Lᵀ, row by row
  cv::Mat log_normaliser_;  // CV_32F: −½ log((2π)⁵ |Σ|)
};

}  // namespace kneed_walker::core::vision
