// A synthetic walk rendered in memory for the core's vision and tracking tests: a person
// walking across the PETS camera's view over a textured ground, with sensor noise, and
// noisy frames of the empty scene to learn the background from.
#pragma once

#include <opencv2/core.hpp>

#include <string>
#include <vector>

#include "kneed_walker/core/synthetic/synthetic_scene.h"
#include "shipped_config.h"

namespace kneed_walker::core::test {

struct RenderedWalk {
  vision::Camera camera =
      vision::Camera::load(std::string(KNEED_WALKER_SHARED_DIR) + "/data/pets2009/View_001_camera.yml", 0.001);
  synthetic::SyntheticWalk walk;
  body::BodyShape shape = body::BodyShape::forHeight(1.75);
  std::vector<cv::Mat> frames;  // BGR, one per walk frame
  std::vector<cv::Mat> empty;   // the scene without the person, 8 noisy frames

  RenderedWalk(double duration_s, double fps, std::uint64_t seed) {
    synthetic::SyntheticWalkOptions o;
    o.start_m = camera.groundPoint({560, 470})->head<2>();
    o.heading_rad = 2.1;
    o.duration_s = duration_s;
    o.fps = fps;
    o.seed = seed;
    walk = synthetic::synthesizeWalk(gait::loadGaitTable(configFile("prior_gait_table.yaml"), shippedWalkerModel()),
                                     prior::loadPriorOptions(configFile("prior.yaml")), o);
    const cv::Mat ground = synthetic::texturedGround(camera, walk.ground, 5);
    for (int i = 0; i < 8; ++i) {
      empty.push_back(ground.clone());
      synthetic::addSensorNoise(empty.back(), 3.0, 100 + i);
    }
    for (size_t f = 0; f < walk.frames.size(); ++f) {
      frames.push_back(ground.clone());
      synthetic::drawPerson(frames.back(), camera, walk.frames[f].pose, shape, synthetic::PersonAppearance{});
      synthetic::addSensorNoise(frames.back(), 3.0, 200 + f);
    }
  }
};

}  // namespace kneed_walker::core::test
