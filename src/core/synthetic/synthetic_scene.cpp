#include "kneed_walker/core/synthetic/synthetic_scene.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "kneed_walker/core/common/random.h"

namespace kneed_walker::core::synthetic {
namespace {

// A value in [0, 1) for a grid cell.
double cellNoise(std::int64_t i, std::int64_t j, std::uint64_t seed) {
  using common::splitMix64;
  const std::uint64_t h =
      splitMix64(splitMix64(splitMix64(seed) ^ static_cast<std::uint64_t>(i)) ^ static_cast<std::uint64_t>(j));
  return static_cast<double>(h >> 11) * 0x1.0p-53;
}

cv::Scalar scaled(const cv::Scalar& colour, double factor) {
  return cv::Scalar(colour[0] * factor, colour[1] * factor, colour[2] * factor);
}

// Fills a convex polygon given in pixels, anti-aliased, with 1/16 px precision.
void fillPolygon(cv::Mat& image, const Eigen::Vector2d* pixels, int count, const cv::Scalar& colour) {
  constexpr int kShift = 4;
  std::array<cv::Point, vision::kOutlineVertices> points;
  count = std::min(count, static_cast<int>(points.size()));
  for (int i = 0; i < count; ++i)
    points[i] = cv::Point(static_cast<int>(std::lround(pixels[i].x() * (1 << kShift))),
                          static_cast<int>(std::lround(pixels[i].y() * (1 << kShift))));
  cv::fillConvexPoly(image, points.data(), count, colour, cv::LINE_AA, kShift);
}

}  // namespace

cv::Mat texturedGround(const vision::Camera& camera, const vision::GroundPlane& ground, std::uint64_t seed,
                       double tile_m) {
  if (!(tile_m > 0)) throw std::invalid_argument("texturedGround needs tile_m > 0");
  const int width = camera.width(), height = camera.height();
  std::vector<Eigen::Vector2d> pixels;
  pixels.reserve(static_cast<size_t>(width) * height);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) pixels.emplace_back(x, y);
  const std::vector<Eigen::Vector3d> rays = camera.rays(pixels);
  const Eigen::Vector3d centre = camera.centre(), normal = ground.normal();
  const Eigen::Vector3d on_plane(ground.point_m.x(), ground.point_m.y(), 0.0);
  const cv::Vec3d paving(150, 165, 172), sky_top(230, 190, 150), sky_low(245, 225, 205);
  constexpr double kGrain_m = 0.05, kJoint_m = 0.025, kFade_m = 60.0;
  cv::Mat image(height, width, CV_8UC3);
  for (int y = 0; y < height; ++y) {
    cv::Vec3b* row = image.ptr<cv::Vec3b>(y);
    for (int x = 0; x < width; ++x) {
      const Eigen::Vector3d& ray = rays[static_cast<size_t>(y) * width + x];
      const double facing = normal.dot(ray);
      const double s = facing < 0 ? normal.dot(on_plane - centre) / facing : -1.0;
      cv::Vec3d colour;
      if (s <= 0) {  // sky
        const double up = std::clamp(ray.normalized().z(), 0.0, 1.0);
        colour = sky_low * (1 - up) + sky_top * up;
      } else {
        const Eigen::Vector3d p = centre + s * ray;
        const double u = p.x() / tile_m, v = p.y() / tile_m;
        const auto i = static_cast<std::int64_t>(std::floor(u)), j = static_cast<std::int64_t>(std::floor(v));
        double shade = 0.75 + 0.35 * cellNoise(i, j, seed);
        const double du = std::min(u - i, i + 1 - u) * tile_m, dv = std::min(v - j, j + 1 - v) * tile_m;
        if (std::min(du, dv) < kJoint_m) shade *= 0.6;
        shade *= 0.9 + 0.2 * cellNoise(static_cast<std::int64_t>(std::floor(p.x() / kGrain_m)),
                                       static_cast<std::int64_t>(std::floor(p.y() / kGrain_m)), seed + 1);
        // Far away the texture is finer than a pixel: fade it to its mean.
        const double fade = std::min(1.0, (p - centre).norm() / kFade_m);
        colour = paving * (shade * (1 - fade) + 0.86 * fade);
      }
      row[x] = cv::Vec3b(cv::saturate_cast<uchar>(colour[0]), cv::saturate_cast<uchar>(colour[1]),
                         cv::saturate_cast<uchar>(colour[2]));
    }
  }
  cv::GaussianBlur(image, image, cv::Size(3, 3), 0.7);
  return image;
}

void drawPerson(cv::Mat& image, const vision::Camera& camera, const body::BodyPose& pose, const body::BodyShape& shape,
                const PersonAppearance& appearance) {
  // A person's feet stand on the floor, not in it.
  vision::PartAxes axes = vision::partAxes(pose, shape);
  vision::standFeetOnGround(pose, shape, axes);
  vision::BodyOutlines outlines;
  vision::projectBodyPartsExactly(camera, pose, shape, axes, outlines);
  const Eigen::Vector3d eye = camera.centre();
  std::array<int, body::kNumBodyParts> order;
  std::array<double, body::kNumBodyParts> distance;
  for (int p = 0; p < body::kNumBodyParts; ++p) {
    order[p] = p;
    distance[p] = (0.5 * (axes.proximal[p] + axes.distal[p]) - eye).norm();
  }
  std::sort(order.begin(), order.end(), [&](int a, int b) { return distance[a] > distance[b]; });
  const bool left_far = (pose.joints[body::kLeftHip] - eye).norm() > (pose.joints[body::kRightHip] - eye).norm();
  for (int p : order) {
    const vision::PartOutline& outline = outlines[p];
    if (!outline.visible || outline.size < 3) continue;
    cv::Scalar colour;
    switch (p) {
      case body::kTorsoPart: colour = appearance.shirt; break;
      case body::kHeadPart: colour = appearance.skin; break;
      case body::kLeftFootPart: case body::kRightFootPart: colour = appearance.shoes; break;
      default: colour = appearance.trousers;
    }
    const bool left_part = p == body::kLeftThighPart || p == body::kLeftShankPart || p == body::kLeftFootPart;
    const bool right_part = p == body::kRightThighPart || p == body::kRightShankPart || p == body::kRightFootPart;
    if ((left_part && left_far) || (right_part && !left_far)) colour = scaled(colour, 0.8);
    fillPolygon(image, outline.hull.data(), outline.size, colour);
  }
}

Occluder crossingOccluder(const vision::Camera& camera, const Eigen::Vector3d& target_m,
                          double cross_time_s, const Eigen::Vector2d& walking_direction,
                          double in_front_m, double speed_mps) {
  const Eigen::Vector3d foot(camera.centre().x(), camera.centre().y(), 0.0);
  const Eigen::Vector3d target(target_m.x(), target_m.y(), 0.0);
  const Eigen::Vector3d crossing = target - in_front_m * (target - foot).normalized();
  Eigen::Vector3d across(-(target - foot).y(), (target - foot).x(), 0.0);
  if (across.norm() < 1e-9) throw std::invalid_argument("crossingOccluder: target under the camera");
  across.normalize();
  if (across.head<2>().dot(walking_direction) > 0) across = -across;
  Occluder occluder;
  occluder.velocity_mps = speed_mps * across;
  occluder.base_start_m = crossing - cross_time_s * occluder.velocity_mps;
  return occluder;
}

void drawOccluder(cv::Mat& image, const vision::Camera& camera, const Occluder& occluder, double time_s) {
  const Eigen::Vector3d base = occluder.base_start_m + time_s * occluder.velocity_mps;
  Eigen::Vector3d side(-(camera.centre() - base).y(), (camera.centre() - base).x(), 0.0);
  if (side.norm() < 1e-9) return;
  side = 0.5 * occluder.width_m * side.normalized();
  // Horizontal bands of two shades, so that the board has texture.
  constexpr int kBands = 6;
  for (int band = 0; band < kBands; ++band) {
    const Eigen::Vector3d low = base + occluder.height_m * band / kBands * Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d high = base + occluder.height_m * (band + 1) / kBands * Eigen::Vector3d::UnitZ();
    const std::array<Eigen::Vector3d, 4> corners{low - side, low + side, high + side, high - side};
    std::array<Eigen::Vector2d, 4> pixels;
    bool visible = true;
    for (int i = 0; i < 4 && visible; ++i) {
      const auto pixel = camera.project(corners[i]);
      visible = pixel.has_value();
      if (visible) pixels[i] = *pixel;
    }
    if (visible) fillPolygon(image, pixels.data(), 4, scaled(occluder.colour, band % 2 ? 0.8 : 1.0));
  }
}

void addSensorNoise(cv::Mat& image, double sigma, std::uint64_t seed) {
  if (!(sigma > 0)) return;
  cv::RNG rng(seed);
  cv::Mat noise(image.size(), CV_32FC(image.channels()));
  rng.fill(noise, cv::RNG::NORMAL, 0.0, sigma);
  cv::Mat sum;
  image.convertTo(sum, CV_32F);
  sum += noise;
  sum.convertTo(image, image.type());
}

}  // namespace kneed_walker::core::synthetic
