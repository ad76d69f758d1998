// Rendering synthetic frames: a background (a real scene without people, or a textured ground
// plane), the person's body parts (body_projection.h) painted far to near, an optional
// occluder crossing in front, and sensor noise. All of it is deterministic for a seed.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <cstdint>
#include <string>

#include "kneed_walker/core/synthetic/synthetic_walk.h"
#include "kneed_walker/core/vision/body_projection.h"
#include "kneed_walker/core/vision/camera.h"
#include "kneed_walker/core/vision/ground_plane.h"

namespace kneed_walker::core::synthetic {

// A paved ground plane seen by the camera (square tiles of `tile_m`, each its own shade, with
// joints between them and fine grain), and a sky above the horizon. BGR, 8 bit, the camera's
// image size.
cv::Mat texturedGround(const vision::Camera& camera, const vision::GroundPlane& ground, std::uint64_t seed,
                       double tile_m = 0.6);

// Colours of the person's clothes, BGR.
struct PersonAppearance {
  cv::Scalar skin{120, 150, 200};
  cv::Scalar shirt{150, 60, 40};
  cv::Scalar trousers{60, 50, 45};
  cv::Scalar shoes{30, 30, 30};
};

// Paints the body parts, farthest from the camera first; the limbs on the side away from the
// camera are shaded darker. Parts partly behind the camera are skipped.
void drawPerson(cv::Mat& image, const vision::Camera& camera, const body::BodyPose& pose, const body::BodyShape& shape,
                const PersonAppearance& appearance);

// A board standing on the ground that slides along the ground, its face to the camera: a
// stand-in for a pedestrian or a passing object that hides the person for a while.
struct Occluder {
  Eigen::Vector3d base_start_m = Eigen::Vector3d::Zero();  // centre of its bottom edge at t = 0
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  double width_m = 0.8, height_m = 2.0;
  cv::Scalar colour{70, 110, 150};
};

// An occluder that crosses the camera's line of sight to `target_m` at time `cross_time_s`,
// `in_front_m` nearer the camera than the target (along the ground), at `speed_mps`, moving
// against `walking_direction` (the person's, world XY) so that the two pass each other.
Occluder crossingOccluder(const vision::Camera& camera, const Eigen::Vector3d& target_m,
                          double cross_time_s, const Eigen::Vector2d& walking_direction,
                          double in_front_m = 1.5, double speed_mps = 1.2);

void drawOccluder(cv::Mat& image, const vision::Camera& camera, const Occluder& occluder, double time_s);

// Adds zero-mean Gaussian noise of `sigma` grey levels to every channel, seeded.
void addSensorNoise(cv::Mat& image, double sigma, std::uint64_t seed);

}  // namespace kneed_walker::core::synthetic
