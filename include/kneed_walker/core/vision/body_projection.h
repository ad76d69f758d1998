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
// The feet lifted onto the ground (BodyPose::ground_point_m) where they reach below it, as a
// person's stand on the floor: the synthetic sequences draw them so. The walker's foot rolls on
// an arc and partAxes keeps the drawn foot rigid with the shank, so at contact its heel or toe
// reaches up to 4 cm into the ground; the likelihood keeps that shape (it tracks the captured
// walks better).
void standFeetOnGround(const body::BodyPose& pose, const body::BodyShape& shape, PartAxes& axes);

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

// A part's outline in the image: a convex polygon around the images of its two end ellipses.
constexpr int kOutlineVertices = 16;
struct PartOutline {
  std::array<Eigen::Vector2d, kOutlineVertices> hull;  // first `size` points, in order (cross products ≥ 0)
  int size = 0;
  bool visible = false;
  std::array<Eigen::Vector2d, 2> ends_px;  // image of the proximal and distal centres
  double depth_m = 0;                      // camera depth of the axis' midpoint: nearer parts occlude
};
using BodyOutlines = std::array<PartOutline, body::kNumBodyParts>;

// Projects all parts for the likelihood (per particle: no allocation). Each end ellipse is
// mapped by the camera's derivative at its centre (exact to first order in the ellipse's size
// over its depth; against projectBodyPartsExactly the vertices lie within 0.37 px at 23 m and
// 2.8 px at 4 m, test_body_projection), so its image is an ellipse; the outline is the two
// ellipses' support points in kOutlineVertices image directions
// evenly spread, which lie in order on their convex hull. A part is invisible when any point of
// either end ellipse is behind the camera.
void projectBodyParts(const Camera& camera, const body::BodyPose& pose, const body::BodyShape& shape,
                      BodyOutlines& outlines);

// The exact perspective image, for drawing the synthetic sequences' truth and for testing the
// approximation above: the convex hull of each end ellipse's kOutlineSamples surface points,
// every one projected through the full camera model. `axes`: the parts' (partAxes, with the
// feet stood on the ground for a synthetic sequence).
constexpr int kOutlineSamples = 8;
static_assert(2 * kOutlineSamples <= kOutlineVertices, "the hull must fit an outline");
void projectBodyPartsExactly(const Camera& camera, const body::BodyPose& pose, const body::BodyShape& shape,
                             const PartAxes& axes, BodyOutlines& outlines);

}  // namespace kneed_walker::core::vision
