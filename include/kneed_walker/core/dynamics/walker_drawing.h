// Stick figures of the planar walker on an OpenCV image: for people to see what the dynamics
// do (tools/draw_walker, the gait figures). Not on any per-particle path.
#pragma once

#include <opencv2/core.hpp>

#include "kneed_walker/core/dynamics/walker_simulation.h"

namespace kneed_walker::core::dynamics {

// Where the slope frame lands in the picture: the ground is drawn tilted by the slope.
struct SideView {
  double pixels_per_unit = 200;  // image pixels per model length unit
  cv::Point2d origin_px{40, 400};  // image position of the slope-frame origin
  double ground_slope = 0;       // γ, rad, positive uphill: the ground rises to the right
  cv::Point2d toImage(Point slope_frame_point) const;
};

// Draws the ground line across the image.
void drawGround(cv::Mat& image, const SideView& view, const cv::Scalar& colour = {90, 90, 90});

// Draws the walker: torso, head, both legs (left blue, right red, as is usual in gait
// plots), round feet; `alpha` in (0, 1] fades older snapshots in a strip.
void drawWalker(cv::Mat& image, const WalkerSimulator& simulator, const WalkerState& state,
                const SideView& view, double alpha = 1.0);

// Simulates from `start` for `duration` (model time) and draws `snapshots` stick figures at
// equal intervals, older ones lighter: a stroboscopic strip. Returns the final state.
WalkerState drawStrip(cv::Mat& image, const WalkerSimulator& simulator,
                      const WalkerControls& controls, const WalkerState& start, double duration,
                      int snapshots, const SideView& view);

}  // namespace kneed_walker::core::dynamics
