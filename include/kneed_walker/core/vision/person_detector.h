// Finding walking people without being told where they are: the pixels the background model
// does not explain (vision/background_model.h), grouped into blobs, each kept when its box
// stands on the ground plane and is as tall as a person (paper §5 starts from a coarse initial
// state; this is where the tracker gets it when nobody gives a box).
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <optional>
#include <vector>

#include "kneed_walker/core/vision/background_model.h"
#include "kneed_walker/core/vision/camera.h"
#include "kneed_walker/core/vision/ground_plane.h"

namespace kneed_walker::core::vision {

struct PersonDetectorOptions {
  // A pixel is foreground when its squared Mahalanobis distance from the background exceeds
  // this (5 degrees of freedom: 30 leaves about 1 background pixel in 60000).
  double foreground_squared_distance = 30.0;
  int min_pixels = 150;         // smallest blob, pixels
  double min_height_m = 1.2;    // a person's standing height, m, from the box on the ground
  double max_height_m = 2.3;
  double min_fill = 0.2;        // foreground pixels over the box's area
};

struct PersonCandidate {
  cv::Rect2d box_px;                  // the blob's bounding box
  Eigen::Vector2d ground_xy_m;        // the ground point under the middle of the box's bottom edge
  double height_m = 0;                // the box's height on the ground, m
  int pixels = 0;                     // foreground pixels in the blob
};

// The ground point seen at `pixel`, on the (possibly sloped) ground plane; nullopt when the
// pixel's ray misses the ground.
std::optional<Eigen::Vector3d> groundPointOnPlane(const Camera& camera, const GroundPlane& ground,
                                                  const Eigen::Vector2d& pixel);

// The height above `foot` (a world point, m) of the point on `pixel`'s viewing ray nearest the
// vertical through `foot`: the standing height of a person whose feet are at `foot` and whose
// head is seen at `pixel`, m. 0 when the camera looks straight down.
double heightAbove(const Camera& camera, const Eigen::Vector3d& foot, const Eigen::Vector2d& pixel);

// The pixels of `roi` (inside the frame) the background does not explain: 255 where the squared
// Mahalanobis distance exceeds `foreground_squared_distance`, speckle opened away and the limbs
// closed onto the trunk. CV_8U, roi's size. Throws std::invalid_argument when the frame's size
// or type does not match the background model's.
cv::Mat foregroundMask(const BackgroundModel& background, const cv::Mat& bgr, const cv::Rect& roi,
                       double foreground_squared_distance);

// The people in a BGR frame of the camera, largest blob first. Throws std::invalid_argument
// when the frame's size or type does not match the background model's.
std::vector<PersonCandidate> findPeople(const BackgroundModel& background, const cv::Mat& bgr, const Camera& camera,
                                        const GroundPlane& ground, const PersonDetectorOptions& options = {});

}  // namespace kneed_walker::core::vision
