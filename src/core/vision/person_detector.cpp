#include "kneed_walker/core/vision/person_detector.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <stdexcept>

namespace kneed_walker::core::vision {

std::optional<Eigen::Vector3d> groundPointOnPlane(const Camera& camera, const GroundPlane& ground,
                                                  const Eigen::Vector2d& pixel) {
  // Fixed-point iteration on the plane's height under the point (exact for level ground).
  double height = 0;
  std::optional<Eigen::Vector3d> point;
  for (int i = 0; i < 5; ++i) {
    point = camera.groundPoint(pixel, height);
    if (!point) return std::nullopt;
    height = ground.height(point->head<2>());
  }
  return point;
}

double heightAbove(const Camera& camera, const Eigen::Vector3d& foot, const Eigen::Vector2d& pixel) {
  const Eigen::Vector3d ray = camera.rays({pixel}).front().normalized();
  const Eigen::Vector3d centre = camera.centre();
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  // Closest points of the lines centre + s·ray and foot + h·up.
  const Eigen::Vector3d w = centre - foot;
  const double b = ray.dot(up), d = ray.dot(w), e = up.dot(w);
  const double denominator = 1 - b * b;
  if (denominator < 1e-9) return 0;  // looking straight down: no height
  return (e - b * d) / denominator;
}

cv::Mat foregroundMask(const BackgroundModel& background, const cv::Mat& bgr, const cv::Rect& roi,
                       double foreground_squared_distance) {
  if (bgr.type() != CV_8UC3 || bgr.size() != background.size())
    throw std::invalid_argument("foregroundMask: the frame is not a BGR 8-bit image of the background's size");
  cv::Mat squared;
  background.squaredDistance(measurements(bgr, roi), roi, squared);
  cv::Mat mask = squared > foreground_squared_distance;
  // Speckle out, then the limbs and the trunk joined into one blob.
  cv::morphologyEx(mask, mask, cv::MORPH_OPEN, cv::getStructuringElement(cv::MORPH_RECT, {3, 3}));
  cv::morphologyEx(mask, mask, cv::MORPH_CLOSE, cv::getStructuringElement(cv::MORPH_ELLIPSE, {9, 9}));
  return mask;
}

std::vector<PersonCandidate> findPeople(const BackgroundModel& background, const cv::Mat& bgr, const Camera& camera,
                                        const GroundPlane& ground, const PersonDetectorOptions& options) {
  if (bgr.type() != CV_8UC3 || bgr.size() != background.size())
    throw std::invalid_argument("findPeople: the frame is not a BGR 8-bit image of the background's size");
  const cv::Mat mask =
      foregroundMask(background, bgr, cv::Rect(cv::Point(), bgr.size()), options.foreground_squared_distance);
  cv::Mat labels, stats, centroids;
  const int count = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);
  std::vector<PersonCandidate> people;
  for (int label = 1; label < count; ++label) {
    const int pixels = stats.at<int>(label, cv::CC_STAT_AREA);
    if (pixels < options.min_pixels) continue;
    const cv::Rect2d box(stats.at<int>(label, cv::CC_STAT_LEFT), stats.at<int>(label, cv::CC_STAT_TOP),
                         stats.at<int>(label, cv::CC_STAT_WIDTH), stats.at<int>(label, cv::CC_STAT_HEIGHT));
    if (pixels < options.min_fill * box.area()) continue;
    const auto foot = groundPointOnPlane(camera, ground, {box.x + 0.5 * box.width, box.y + box.height});
    if (!foot) continue;
    const double height = heightAbove(camera, *foot, {box.x + 0.5 * box.width, box.y});
    if (height < options.min_height_m || height > options.max_height_m) continue;
    people.push_back({box, foot->head<2>(), height, pixels});
  }
  std::sort(people.begin(), people.end(), [](const auto& a, const auto& b) { return a.pixels > b.pixels; });
  return people;
}

}  // namespace kneed_walker::core::vision
