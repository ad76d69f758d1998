// The prior over the whole 3D body (paper §3.4): the walker's transition (walker_prior.h), the
// damped Markov processes of the body's other DOFs (heading, sway, hip abduction and rotation),
// and the stance foot held where it rolls: what the placement processes would make it slide
// moves the body over the foot instead. One frame of a synthetic walk and one particle's
// transition in the tracker are both BodyPrior::transition.
//
// Lengths in metres for a person of the given height (the walker is the gait table's
// dimensionless one, scaled by the leg length L); times in seconds.
#pragma once

#include <Eigen/Core>

#include <optional>

#include "kneed_walker/core/body/body_model.h"
#include "kneed_walker/core/prior/walker_prior.h"

namespace kneed_walker::core::prior {

struct BodyParticle {
  WalkerParticle walker;        // dimensionless
  PlacementState placement;     // SI
  Eigen::Vector3d stance_foot_m = Eigen::Vector3d::Zero();  // the stance foot's centre at the last pose
};

class BodyPrior {
 public:
  // `gravity` (m/s²) sets the walker's natural time √(L/g). The body walks on ground of the
  // gait's slope, or of `ground_slope_rad` if given: a ground steeper or flatter than any gait of
  // the table (the prior's has none uphill beyond 4.3°). Then the walker's motion is turned into
  // that ground's frame, a kinematic stand-in for the gait there: the legs keep their angles to
  // the ground's normal (the feet stay on it) and the torso its angle to its rest, which the
  // prior's torso_rest_per_slope sets at the ground's slope (so a steeper climb leans it more).
  // The turn is by the slope of the gait each particle walks (WalkerParticle::gait), which may
  // be another slope's than this prior's own gait (a tracker's particles on level and hill gaits).
  BodyPrior(const WalkerPrior& walker_prior, double person_height_m, double leg_length_per_height,
            double gravity, std::optional<double> ground_slope_rad = std::nullopt);

  // A particle at `phase` ∈ [0, 1) of the gait's stride with fresh samples, walking along
  // `heading_rad` with its stance foot's centre above `stance_foot_xy_m`; `pose` receives its
  // body pose. Draws the walker's samples first, as WalkerPrior::sample (`start` as there). The
  // gait's strides start on the left leg; `stance_leg` relabels the legs (the walker is
  // symmetric: the other leg's stance is the same motion half a gait cycle on).
  BodyParticle sample(double phase, const Eigen::Vector2d& stance_foot_xy_m, double heading_rad,
                      common::Random& random, body::BodyPose& pose,
                      std::optional<dynamics::Leg> stance_leg = std::nullopt,
                      WalkerPrior::Start start = WalkerPrior::Start::kFromStrike) const;

  // s_t ~ p(s_t | s_{t−1}) over dt_s seconds; `pose` receives the body pose at t. Returns what the
  // walker did (a fall freezes it).
  dynamics::AdvanceReport transition(BodyParticle& particle, double dt_s, common::Random& random,
                                     body::BodyPose& pose) const;

  body::BodyPose pose(const BodyParticle& particle) const;

  const WalkerPrior& walkerPrior() const { return walker_prior_; }
  const body::BodyShape& shape() const { return shape_; }
  double legLengthM() const { return leg_length_m_; }
  double naturalTimeS() const { return natural_time_s_; }  // √(L/g): one unit of the walker's time, s
  double slopeRad() const { return walker_prior_.gait().target.slope; }  // the gait's
  double groundSlopeRad() const { return ground_slope_rad_; }            // the body's ground's

 private:
  WalkerPrior walker_prior_;
  body::BodyShape shape_;
  double ground_slope_rad_;
  double torso_rest_per_slope_;  // the prior's: the torso's rest angle per rad of slope
  double leg_length_m_, natural_time_s_, along_xy_m_, foot_radius_m_;
};

}  // namespace kneed_walker::core::prior
