// Optical flow at the points of a coarse grid (paper §4): OpenCV's DIS flow between the previous
// and the current frame, and at each grid point an approximate estimator covariance Σ from the
// local 2×2 gradient tensor, Σ = σ² (w T + ε I)⁻¹ + σ_min² I (T the window's mean tensor, w its
// pixel count): large along an edge and in flat regions, small at corners.
//
// Grid points lie at image coordinates that are multiples of grid_step_px, so that a particle's
// visible rows and columns find them without search.
#pragma once

#include <opencv2/core.hpp>

#include <algorithm>
#include <vector>

namespace kneed_walker::core::vision {

struct FlowOptions {
  int grid_step_px = 6;         // grid spacing, px
  int window_px = 7;            // side of the gradient tensor's window, px
  double noise_sd = 2.0;        // σ: intensity noise, grey levels
  double flat_epsilon = 0.16;   // ε: regularises flat regions (their flow SD is σ/√ε px)
  double min_sd_px = 0.3;       // σ_min: DIS's own error floor, px
};

// One grid point: the measured motion v (from the previous frame to this one, px), A = ½ Σ⁻¹,
// and log(1 + e₀²), e₀² = vᵀ A v, the Student-t's term at u = 0 (the static background).
struct FlowPoint {
  float vx = 0, vy = 0;
  float a00 = 0, a01 = 0, a11 = 0;
  float log1p_background = 0;
};

class FlowField {
 public:
  // Flow inside `roi` of the current frame (8-bit grey images of one size). A region narrower
  // or lower than kMinSidePx (the particles near an image edge, or off it) has no flow: DIS
  // refuses images under 12 px, and its 8 px patches need two to a side.
  static constexpr int kMinSidePx = 16;
  void compute(const cv::Mat& previous_grey, const cv::Mat& grey, const cv::Rect& roi,
               const FlowOptions& options);
  bool empty() const { return points_.empty(); }
  int step() const { return step_; }
  // The grid points of image row y (a multiple of step()) at columns [x0, x1): x0 rounded up to
  // a multiple of step(), the first point, and how many; count 0 when none. By look-up tables,
  // not divisions: it runs per visible part row on the grid, per particle (its three integer
  // divisions were most of the flow term's time).
  struct RowPoints {
    int first_x = 0, count = 0;
    const FlowPoint* first = nullptr;
  };
  RowPoints rowPoints(int y, int x0, int x1) const {
    RowPoints r;
    const int row = y - roi_.y;
    if (row < 0 || row >= roi_.height || grid_row_at_[row] < 0) return r;
    const int i0 = grid_column_at_[std::clamp(x0 - roi_.x, 0, roi_.width)];
    const int i1 = grid_column_at_[std::clamp(x1 - roi_.x, 0, roi_.width)];
    if (i0 >= i1) return r;
    r.first_x = (i0 + first_column_) * step_;
    r.count = i1 - i0;
    r.first = &points_[static_cast<size_t>(grid_row_at_[row]) * columns_ + i0];
    return r;
  }
  // e² = (v − u)ᵀ A (v − u) of eq. 13 at a grid point, for a predicted motion u (px). Inline:
  // it runs per grid point per particle.
  static float squaredError(const FlowPoint& p, float ux, float uy) {
    const float dx = p.vx - ux, dy = p.vy - uy;
    return p.a00 * dx * dx + 2 * p.a01 * dx * dy + p.a11 * dy * dy;
  }

 private:
  std::vector<FlowPoint> points_;
  int step_ = 1, first_column_ = 0, first_row_ = 0, columns_ = 0, rows_ = 0;
  cv::Rect roi_;
  std::vector<int> grid_column_at_;  // at x − roi.x (0 to roi.width): the first grid column at or right of x
  std::vector<int> grid_row_at_;     // at y − roi.y: y's grid row, −1 if y is not a multiple of step()
};

}  // namespace kneed_walker::core::vision
