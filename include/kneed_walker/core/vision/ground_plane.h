// The ground the person walks on (paper §5: "roughly calibrated camera and ground plane"), in
// the world frame of the camera (metres, Z up, REP 103).
#pragma once

#include <Eigen/Core>
#include <opencv2/core/persistence.hpp>

#include <string>

namespace kneed_walker::core::vision {

// The ground: the plane through `point_m` (at Z = 0) rising at `slope_rad` along the
// direction `uphill_heading_rad` (from +X towards +Y); level when the slope is 0.
struct GroundPlane {
  Eigen::Vector2d point_m = Eigen::Vector2d::Zero();
  double slope_rad = 0;
  double uphill_heading_rad = 0;
  double height(const Eigen::Vector2d& xy_m) const;  // Z of the ground at (X, Y), m
  Eigen::Vector3d normal() const;                     // unit, upwards
};

// The ground's keys in a calibration file, beside the camera's (make_synthetic writes them):
// ground_point_mm (X, Y), ground_slope_rad, ground_uphill_heading_rad.
void writeGroundPlane(cv::FileStorage& file, const GroundPlane& ground);
// Reads them; a calibration without them means the level ground Z = 0. Throws
// std::invalid_argument naming a bad key.
GroundPlane loadGroundPlane(const std::string& path);

}  // namespace kneed_walker::core::vision
