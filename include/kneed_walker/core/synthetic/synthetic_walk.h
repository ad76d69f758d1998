// Synthetic walks with ground truth: a person walking by the stochastic prior (paper §3.4)
// around a table gait, as a 3D body pose per frame in the world frame (metres, Z up). The
// synthetic sequences that test the tracker are made from these (synthetic_scene.h renders
// them; `rosrun kneed_walker make_synthetic` writes bag, CSV, calibration and video).
//
// The walk is deterministic for a seed: the prior's samples, the placement processes and the
// choice of phase all come from one generator seeded with it.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "kneed_walker/core/body/body_model.h"
#include "kneed_walker/core/gait/gait_table.h"
#include "kneed_walker/core/prior/walker_prior.h"
#include "kneed_walker/core/vision/ground_plane.h"

namespace kneed_walker::core::synthetic {

struct SyntheticWalkOptions {
  double speed_kmh = 4.5;        // mean walking speed (at the start, with a speed change)
  double step_length_m = 0.7;    // mean step length (at the start, with a step change)
  // A change of speed and/or step length (issue 13: a person slowing from 7 to 3 km/h): the
  // gait at the last frame; between, the gait changes linearly in time, taking over at each
  // heel strike. Unset: as at the start.
  std::optional<double> end_speed_kmh, end_step_length_m;
  double slope_rad = 0.0;        // ground slope along the walk, positive uphill
  double heading_rad = 0.0;      // initial walking direction in the world XY plane
  Eigen::Vector2d start_m = Eigen::Vector2d::Zero();  // world XY of the first stance foot
  double duration_s = 3.0;       // length of the sequence
  double fps = 10.0;             // frames per second
  double person_height_m = 1.75;
  std::uint64_t seed = 1;
  int max_attempts = 50;         // prior samples tried until one walks the whole duration
};

// Every problem with the options, each naming the field.
std::vector<std::string> validate(const SyntheticWalkOptions& options);

struct SyntheticFrame {
  double time_s = 0;  // since the first frame
  body::BodyPose pose;      // world frame, metres
  body::BodyPlacement placement;
  dynamics::WalkerState walker;  // dimensionless, as the prior's
};

struct SyntheticWalk {
  gait::Gait gait;        // the table gait the prior walked around first (dimensionless)
  double leg_length_m = 0;
  vision::GroundPlane ground;
  int attempts = 0;       // prior samples drawn (a sample that fell is discarded)
  std::string gait_note;  // "" or what the interpolation did at holes in the table
  std::vector<SyntheticFrame> frames;
};

// Walks the person by the prior for options.duration_s. Speed and step length are the
// person's; they scale to the table's reference person by Froude similarity. With an end speed
// or step, each stride from a heel strike walks around the gait of that moment of the change.
// On a slope the heading is held (the ground is one plane rising along it); on the level it
// wanders by the placement processes. Throws std::invalid_argument for bad options,
// std::out_of_range for a gait outside the table, std::runtime_error when no sample walks the
// whole duration.
SyntheticWalk synthesizeWalk(const gait::GaitTable& table, const prior::PriorOptions& prior,
                             const SyntheticWalkOptions& options);

}  // namespace kneed_walker::core::synthetic
