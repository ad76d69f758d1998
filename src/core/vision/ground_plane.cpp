#include "kneed_walker/core/vision/ground_plane.h"

#include <cmath>

#include "kneed_walker/core/common/config_file.h"

namespace kneed_walker::core::vision {

double GroundPlane::height(const Eigen::Vector2d& xy_m) const {
  const Eigen::Vector2d uphill(std::cos(uphill_heading_rad), std::sin(uphill_heading_rad));
  return std::tan(slope_rad) * uphill.dot(xy_m - point_m);
}

Eigen::Vector3d GroundPlane::normal() const {
  const Eigen::Vector3d uphill(std::cos(uphill_heading_rad), std::sin(uphill_heading_rad), 0);
  return -std::sin(slope_rad) * uphill + std::cos(slope_rad) * Eigen::Vector3d::UnitZ();
}

void writeGroundPlane(cv::FileStorage& file, const GroundPlane& ground) {
  file << "ground_point_mm" << std::vector<double>{1000 * ground.point_m.x(), 1000 * ground.point_m.y()}
       << "ground_slope_rad" << ground.slope_rad << "ground_uphill_heading_rad" << ground.uphill_heading_rad;
}

GroundPlane loadGroundPlane(const std::string& path) {
  common::ConfigFile file(path, "ground plane");
  GroundPlane ground;
  std::array<double, 2> point_mm{0, 0};
  file.read("ground_point_mm", point_mm);
  file.read("ground_slope_rad", ground.slope_rad);
  file.read("ground_uphill_heading_rad", ground.uphill_heading_rad);
  ground.point_m = Eigen::Vector2d(point_mm[0], point_mm[1]) / 1000;
  std::vector<std::string> problems;
  if (!(std::abs(ground.slope_rad) < 0.5)) problems.push_back("ground_slope_rad must lie in (-0.5, 0.5)");
  file.finish(problems, true);  // the rest of the file is the camera's
  return ground;
}

}  // namespace kneed_walker::core::vision
