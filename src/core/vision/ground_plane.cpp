#include "kneed_walker/core/vision/ground_plane.h"

#include <cmath>

namespace kneed_walker::core::vision {

double GroundPlane::height(const Eigen::Vector2d& xy_m) const {
  const Eigen::Vector2d uphill(std::cos(uphill_heading_rad), std::sin(uphill_heading_rad));
  return std::tan(slope_rad) * uphill.dot(xy_m - point_m);
}

Eigen::Vector3d GroundPlane::normal() const {
  const Eigen::Vector3d uphill(std::cos(uphill_heading_rad), std::sin(uphill_heading_rad), 0);
  return -std::sin(slope_rad) * uphill + std::cos(slope_rad) * Eigen::Vector3d::UnitZ();
}

}  // namespace kneed_walker::core::vision
