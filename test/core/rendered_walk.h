// A synthetic walk rendered in memory for the core's vision and tracking tests: a person
// walking across the PETS camera's view over a textured ground, with sensor noise, and
// noisy frames of the empty scene to learn the background from; optionally a second person in
// other clothes walking the other way further off.
#pragma once

#include <opencv2/core.hpp>

#include <optional>
#include <string>
#include <vector>

#include "kneed_walker/core/synthetic/synthetic_scene.h"
#include "kneed_walker/core/vision/likelihood.h"
#include "shipped_config.h"

namespace kneed_walker::core::test {

struct RenderedWalk {
  vision::Camera camera;
  synthetic::SyntheticWalk walk;
  std::optional<synthetic::SyntheticWalk> second;  // the second person's walk
  body::BodyShape shape = body::BodyShape::forHeight(1.75);
  std::vector<cv::Mat> frames;  // BGR, one per walk frame
  std::vector<cv::Mat> empty;   // the scene without the person, 8 noisy frames

  // By default through the PETS camera; or through another calibration, walking from
  // `start_px` (the ground there) in `heading_rad`.
  RenderedWalk(double duration_s, double fps, std::uint64_t seed, bool two_people = false,
               const std::string& camera_path = std::string(KNEED_WALKER_SHARED_DIR) +
                                                "/data/pets2009/View_001_camera.yml",
               const Eigen::Vector2d& start_px = {560, 470}, double heading_rad = 2.1)
      : camera(vision::Camera::load(camera_path, 0.001)) {
    const gait::GaitTable table = gait::loadGaitTable(configFile("prior_gait_table.yaml"), shippedWalkerModel());
    const prior::PriorOptions prior = prior::loadPriorOptions(configFile("prior.yaml"));
    synthetic::SyntheticWalkOptions o;
    o.start_m = camera.groundPoint(start_px)->head<2>();
    o.heading_rad = heading_rad;
    o.duration_s = duration_s;
    o.fps = fps;
    o.seed = seed;
    walk = synthetic::synthesizeWalk(table, prior, o);
    if (two_people) {
      o.start_m = camera.groundPoint({200, 330})->head<2>();
      o.heading_rad = 2.1 + M_PI;
      o.seed = seed + 1;
      second = synthetic::synthesizeWalk(table, prior, o);
    }
    const cv::Mat ground = synthetic::texturedGround(camera, walk.ground, 5);
    for (int i = 0; i < 8; ++i) {
      empty.push_back(ground.clone());
      synthetic::addSensorNoise(empty.back(), 3.0, 100 + i);
    }
    synthetic::PersonAppearance other;
    other.shirt = {60, 140, 50};
    other.trousers = {130, 120, 110};
    for (size_t f = 0; f < walk.frames.size(); ++f) {
      frames.push_back(ground.clone());
      // The farther person first.
      const body::BodyPose& first = walk.frames[f].pose;
      const bool second_behind = second && f < second->frames.size() &&
                                 camera.depth(second->frames[f].pose.joints[body::kWaist]) >
                                     camera.depth(first.joints[body::kWaist]);
      if (second_behind) synthetic::drawPerson(frames.back(), camera, second->frames[f].pose, shape, other);
      synthetic::drawPerson(frames.back(), camera, first, shape, synthetic::PersonAppearance{});
      if (second && f < second->frames.size() && !second_behind)
        synthetic::drawPerson(frames.back(), camera, second->frames[f].pose, shape, other);
      synthetic::addSensorNoise(frames.back(), 3.0, 200 + f);
    }
  }

  // The person's appearance as the tracker learns it, from the true pose's part outlines in
  // `frame`.
  vision::AppearanceModel appearanceAt(int frame) const {
    vision::BodyOutlines outlines;
    vision::projectBodyParts(camera, walk.frames[frame].pose, shape, outlines);
    std::array<std::vector<cv::Vec3b>, vision::kNumPartKinds> samples;
    vision::RowSpans spans;
    for (int p = 0; p < body::kNumBodyParts; ++p) {
      vision::rasterize(outlines[p], spans);
      for (int k = 0; k < spans.rows; ++k)
        for (int x = spans.left[k]; x < spans.right[k]; ++x)
          samples[vision::partKind(static_cast<body::BodyPart>(p))].push_back(
              frames[frame].at<cv::Vec3b>(spans.first_row + k, x));
    }
    return vision::AppearanceModel::learn(samples);
  }
};

}  // namespace kneed_walker::core::test
