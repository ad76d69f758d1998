#include "kneed_walker/core/vision/optical_flow.h"

#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include <cmath>
#include <stdexcept>

namespace kneed_walker::core::vision {

void FlowField::compute(const cv::Mat& previous_grey, const cv::Mat& grey, const cv::Rect& roi,
                        const FlowOptions& o) {
  if (grey.type() != CV_8UC1 || previous_grey.type() != CV_8UC1 || grey.size() != previous_grey.size())
    throw std::invalid_argument("optical flow needs two 8-bit grey images of one size");
  if (roi.width < kMinSidePx || roi.height < kMinSidePx) {
    *this = FlowField();  // no flow, as before a first frame
    return;
  }
  step_ = o.grid_step_px;
  first_column_ = (roi.x + step_ - 1) / step_;
  first_row_ = (roi.y + step_ - 1) / step_;
  columns_ = std::max(0, (roi.x + roi.width - 1) / step_ - first_column_ + 1);
  rows_ = std::max(0, (roi.y + roi.height - 1) / step_ - first_row_ + 1);
  points_.assign(static_cast<size_t>(columns_) * rows_, FlowPoint{});
  roi_ = roi;
  grid_column_at_.resize(roi.width + 1);
  for (int c = 0; c <= roi.width; ++c)  // ⌈x / step⌉ for x ≥ 0, as a grid column index
    grid_column_at_[c] = std::clamp((roi.x + c + step_ - 1) / step_ - first_column_, 0, columns_);
  grid_row_at_.resize(roi.height);
  for (int r = 0; r < roi.height; ++r) grid_row_at_[r] = (roi.y + r) % step_ == 0 ? (roi.y + r) / step_ - first_row_ : -1;
  if (points_.empty()) return;

  // Flow from the current frame back to the previous one, at the current frame's pixels:
  // grey(x) ≈ previous(x + f(x)), so the motion from the previous frame is v = −f.
  cv::Mat flow;
  cv::Ptr<cv::DISOpticalFlow> dis = cv::DISOpticalFlow::create(cv::DISOpticalFlow::PRESET_FAST);
  dis->calc(grey(roi).clone(), previous_grey(roi).clone(), flow);  // DIS needs continuous images

  cv::Mat g, gx, gy, xx, xy, yy;
  grey(roi).convertTo(g, CV_32F);
  cv::Sobel(g, gx, CV_32F, 1, 0, 1, 0.5);
  cv::Sobel(g, gy, CV_32F, 0, 1, 1, 0.5);
  const cv::Size window(o.window_px, o.window_px);
  cv::boxFilter(gx.mul(gx), xx, CV_32F, window);
  cv::boxFilter(gx.mul(gy), xy, CV_32F, window);
  cv::boxFilter(gy.mul(gy), yy, CV_32F, window);
  const double w = o.window_px * o.window_px, sigma2 = o.noise_sd * o.noise_sd;
  const double floor2 = o.min_sd_px * o.min_sd_px;
  for (int j = 0; j < rows_; ++j)
    for (int i = 0; i < columns_; ++i) {
      const int x = (first_column_ + i) * step_ - roi.x, y = (first_row_ + j) * step_ - roi.y;
      FlowPoint& p = points_[static_cast<size_t>(j) * columns_ + i];
      const cv::Vec2f f = flow.at<cv::Vec2f>(y, x);
      p.vx = -f[0];
      p.vy = -f[1];
      // Σ = σ² (w T + ε I)⁻¹ + σ_min² I, then A = ½ Σ⁻¹.
      const double t00 = w * xx.at<float>(y, x) + o.flat_epsilon, t01 = w * xy.at<float>(y, x),
                   t11 = w * yy.at<float>(y, x) + o.flat_epsilon;
      const double det_t = t00 * t11 - t01 * t01;
      const double s00 = sigma2 * t11 / det_t + floor2, s01 = -sigma2 * t01 / det_t,
                   s11 = sigma2 * t00 / det_t + floor2;
      const double det_s = s00 * s11 - s01 * s01;
      p.a00 = static_cast<float>(0.5 * s11 / det_s);
      p.a01 = static_cast<float>(-0.5 * s01 / det_s);
      p.a11 = static_cast<float>(0.5 * s00 / det_s);
      p.log1p_background = std::log1p(p.a00 * p.vx * p.vx + 2 * p.a01 * p.vx * p.vy + p.a11 * p.vy * p.vy);
    }
}

}  // namespace kneed_walker::core::vision
