// The body's parts (tapered elliptical cylinders of BodyShape, paper §4) placed on a BodyPose
// and projected into the image as convex outlines, one polygon per part: the image regions the
// likelihood reads.
//
// Each part runs from a proximal to a distal centre point; its width axis lies across the
// body (along BodyPose::left, made square to the part) and its depth axis square to both.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>

#include "kneed_walker/core/body/body_model.h"
#include "kneed_walker/core/vision/camera.h"

namespace kneed_walker::core::vision {

// The proximal and distal centre points of every part in the world, metres.
struct PartAxes {
  std::array<Eigen::Vector3d, body::kNumBodyParts> proximal, distal;
};
PartAxes partAxes(const body::BodyPose& pose, const body::BodyShape& shape);

// A part's unit axes: along it (proximal to distal), across the body (BodyPose::left made square
// to it) and its depth axis square to both. A point of the part's surface at an end with centre
// c, half width a and half depth b is c + a cos θ · across + b sin θ · depth.
struct PartFrame {
  Eigen::Vector3d along, across, depth;
};
// Inline: the per-particle projection computes it for every part.
inline PartFrame partFrame(const body::BodyPose& pose, const PartAxes& axes, int part) {
  PartFrame frame;
  frame.along = (axes.distal[part] - axes.proximal[part]).normalized();
  frame.across = (pose.left - pose.left.dot(frame.along) * frame.along).normalized();
  frame.depth = frame.along.cross(frame.across);
  return frame;
}

// A part's outline in the image: the convex hull of its two end ellipses, sampled at
// kOutlineSamples points each. `visible` is false when any point is behind the camera.
constexpr int kOutlineSamples = 8;
struct PartOutline {
  std::array<Eigen::Vector2d, 2 * kOutlineSamples> hull;  // first `size` points, in order
  int size = 0;
  bool visible = false;
  std::array<Eigen::Vector2d, 2> ends_px;  // image of the proximal and distal centres (mean of each end's samples)
  double depth_m = 0;                      // camera depth of the axis' midpoint: nearer parts occlude
};
using BodyOutlines = std::array<PartOutline, body::kNumBodyParts>;

// Projects all parts; no allocation (fixed-size arrays), for the per-particle path.
void projectBodyParts(const Camera& camera, const body::BodyPose& pose, const body::BodyShape& shape,
                      BodyOutlines& outlines);

}  // namespace kneed_walker::core::vision
