#include "kneed_walker/core/dynamics/walker_drawing.h"

#include <opencv2/imgproc.hpp>

#include <cmath>

namespace kneed_walker::core::dynamics {
namespace {

const cv::Scalar kLeftColour(200, 90, 30);   // BGR: blue
const cv::Scalar kRightColour(40, 40, 210);  // red
const cv::Scalar kTrunkColour(40, 40, 40);

cv::Scalar faded(const cv::Scalar& colour, double alpha) {
  return colour * alpha + cv::Scalar(255, 255, 255) * (1 - alpha);
}

}  // namespace

cv::Point2d SideView::toImage(Point p) const {
  // Rotate the slope frame into the world (x right, y up), then flip y for the image.
  const double c = std::cos(ground_slope), s = std::sin(ground_slope);
  const double x = c * p.real() - s * p.imag(), y = s * p.real() + c * p.imag();
  return {origin_px.x + pixels_per_unit * x, origin_px.y - pixels_per_unit * y};
}

void drawGround(cv::Mat& image, const SideView& view, const cv::Scalar& colour) {
  const double half_width = 2.0 * image.cols / view.pixels_per_unit;
  cv::line(image, view.toImage({-half_width, 0}), view.toImage({half_width, 0}), colour, 2,
           cv::LINE_AA);
}

void drawWalker(cv::Mat& image, const WalkerSimulator& sim, const WalkerState& state,
                const SideView& view, double alpha) {
  const KinematicMap& map = sim.map();
  const int thickness = std::max(2, static_cast<int>(std::lround(view.pixels_per_unit * 0.02)));
  auto at = [&](const PointMap& p) { return view.toImage(sim.pointPosition(p, state)); };
  auto line = [&](cv::Point2d a, cv::Point2d b, const cv::Scalar& colour) {
    cv::line(image, a, b, faded(colour, alpha), thickness, cv::LINE_AA);
  };
  const bool left_stance = state.stance_leg == Leg::kLeft;
  const cv::Scalar stance_colour = left_stance ? kLeftColour : kRightColour;
  const cv::Scalar swing_colour = left_stance ? kRightColour : kLeftColour;

  const Point stance_foot = stanceFootCentre(map, state.q, state.stance_foot_x);
  const Point swing_foot = sim.pointPosition(map.swing_foot_centre, state);
  const cv::Point2d hip = at(map.hip), shoulder = at(map.shoulder);
  const double foot_radius_px = map.foot_radius * view.pixels_per_unit;

  // Feet: the lower arc of each foot circle, turned with its shank.
  auto foot = [&](Point centre, double shank_angle, const cv::Scalar& colour) {
    const double degrees = -(shank_angle + sim.model().foot_offset_angle + view.ground_slope) *
                           180.0 / M_PI;
    cv::ellipse(image, view.toImage(centre), cv::Size2d(foot_radius_px, foot_radius_px), degrees,
                50, 130, faded(colour, alpha), thickness, cv::LINE_AA);
  };
  // Each shank along its own axis down to the foot's level, then the foot's offset e to the
  // foot centre (drawn to the foot centre directly, a straight knee would look bent by e).
  const double shank_to_foot = sim.model().shank.length - map.foot_radius;
  auto leg = [&](const PointMap& knee_map, Point foot_centre, double shank_angle,
                 const cv::Scalar& colour) {
    const Point knee = sim.pointPosition(knee_map, state);
    const Point shank_end = knee + shank_to_foot * Point(std::sin(shank_angle), -std::cos(shank_angle));
    line(hip, view.toImage(knee), colour);
    line(view.toImage(knee), view.toImage(shank_end), colour);
    line(view.toImage(shank_end), view.toImage(foot_centre), colour);
    foot(foot_centre, shank_angle, colour);
  };
  leg(map.swing_knee, swing_foot, state.q[kSwingShank], swing_colour);
  leg(map.stance_knee, stance_foot, state.q[kStanceShank], stance_colour);
  line(hip, shoulder, kTrunkColour);
  const double head_radius = 0.12 * sim.model().legLength() * view.pixels_per_unit;
  const cv::Point2d neck_to_head = (shoulder - hip) * (head_radius / cv::norm(shoulder - hip));
  cv::circle(image, shoulder + neck_to_head, static_cast<int>(head_radius),
             faded(kTrunkColour, alpha), thickness, cv::LINE_AA);
}

WalkerState drawStrip(cv::Mat& image, const WalkerSimulator& sim, const WalkerControls& controls,
                      const WalkerState& start, double duration, int snapshots,
                      const SideView& view) {
  WalkerState state = start;
  const double interval = duration / std::max(1, snapshots - 1);
  for (int k = 0; k < snapshots && !state.fallen; ++k) {
    drawWalker(image, sim, state, view, 0.35 + 0.65 * k / std::max(1, snapshots - 1));
    if (k + 1 < snapshots) sim.advance(controls, state, interval);
  }
  return state;
}

}  // namespace kneed_walker::core::dynamics
