// Walks driven by measured joint angles, not by the prior: the mean curves of the Schwartz 2008
// gait norms (gait_norms.h) pose the tracker's body model frame by frame, so that the tracker
// is tested on motions its own prior did not generate (issue 10's non-prior sequences).
//
// How a body is walked by the norms (all of it kinematic; no dynamics, no noise):
// - Angles. At left-leg cycle phase p, the left leg takes the norms at p, the right leg at
//   p + 0.5. Thigh from the vertical = hip flexion − pelvic tilt; shank = thigh − knee flexion
//   (the walker's absolute angles, walker_kinematics.h). The body model's pelvis stays level, so
//   the leg's angle out from the vertical is the pelvis's obliquity on its side minus the hip's
//   adduction (BodyPlacement::hip_abduction_rad; ±3° at free speed). The torso leans forward by
//   `torso_lean_rad` plus the norms' trunk tilt minus its cycle mean (the study's trunk angle
//   has an offset from its marker set that is not a lean). Ankle and hip rotation are not in
//   the body model and are left out.
// - Speed. The norms' five speed classes are blended linearly by dimensionless speed
//   v* = v / √(g L) between nominal class speeds (the middles of the study's speed bins as we
//   read them: 0.16, 0.30, 0.43, 0.57, 0.70; outside them the end class). The step length
//   follows from the angles and the leg lengths; the cadence is the speed over the stride.
//   The speed may change linearly in time (a walk that slows down).
// - Ground contact. The stance leg is the one that holds the hip higher: the other foot is on
//   or above the ground. The stance foot rolls without slipping (the walker's rolling foot)
//   and stays where it is put: contact passes to the leading foot when its leg would hold the
//   hip higher (a heel strike), where that foot is.
// - Slope. On a hill (`slope_rad`, positive uphill along the heading) the legs keep their level
//   angles to the ground's normal, so the whole leg motion turns with the ground (a hip that
//   flexes about as much more at contact as the grade, as people do uphill); the torso keeps its
//   lean from the vertical and leans a third of the slope more into it, as the prior's rest
//   angle does (prior.yaml's torso_rest_per_slope, the paper's pictures). Contact and rolling
//   are the walker's, in the slope's frame, so the feet stay on the sloped ground.
// The frames are the body model's poses (body_model.h) of these walker states, for a person of
// the given height with the walker's proportions: the same joints the tracker estimates.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

#include "kneed_walker/core/dynamics/walker_model.h"
#include "kneed_walker/core/gait/gait_norms.h"
#include "kneed_walker/core/synthetic/synthetic_walk.h"

namespace kneed_walker::core::synthetic {

struct NormWalkOptions {
  double start_speed_kmh = 4.5;  // speed at the first frame
  double end_speed_kmh = 4.5;    // speed at the last frame; between them it changes linearly in time
  double heading_rad = 0.0;      // walking direction in the world XY plane
  double slope_rad = 0.0;        // ground slope along the walk, positive uphill
  Eigen::Vector2d start_m = Eigen::Vector2d::Zero();  // world XY of the first stance foot
  double duration_s = 3.0;
  double fps = 10.0;
  double person_height_m = 1.75;
  double torso_lean_rad = 0.05;  // mean forward lean of the torso
  std::uint64_t seed = 1;        // chooses the cycle phase of the first frame
};

// Every problem with the options, each naming the field.
std::vector<std::string> validate(const NormWalkOptions& options);

// The nominal dimensionless speed of a norms speed class ("Very Slow" ... "Very Fast"); throws
// std::out_of_range for another name.
double nominalDimensionlessSpeed(const std::string& speed_class);

// Walks the person by the norms for options.duration_s on the ground of options.slope_rad. The result's `gait`
// and `attempts` are those of prior walks and stay empty. Throws std::invalid_argument for bad
// options, std::out_of_range when the norms lack a class or an angle it needs.
SyntheticWalk synthesizeNormWalk(const gait::GaitNorms& norms, const dynamics::BodyProportions& proportions,
                                 const NormWalkOptions& options, double gravity_mps2 = 9.81);

// The stride (two steps) of a norm walk at dimensionless speed v*, in leg lengths.
double normStrideLength(const gait::GaitNorms& norms, const dynamics::BodyProportions& proportions,
                        double dimensionless_speed);

}  // namespace kneed_walker::core::synthetic
