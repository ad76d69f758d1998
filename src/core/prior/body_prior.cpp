#include "kneed_walker/core/prior/body_prior.h"

#include <cmath>
#include <stdexcept>

namespace kneed_walker::core::prior {

BodyPrior::BodyPrior(const WalkerPrior& walker_prior, double person_height_m, double leg_length_per_height,
                     double gravity, std::optional<double> ground_slope_rad)
    : walker_prior_(walker_prior),
      shape_(body::BodyShape::forHeight(person_height_m)),
      ground_slope_rad_(ground_slope_rad.value_or(walker_prior.gait().target.slope)),
      torso_rest_per_slope_(walker_prior.options().fixed.torso_rest_per_slope),
      leg_length_m_(leg_length_per_height * person_height_m),
      natural_time_s_(std::sqrt(leg_length_m_ / gravity)),
      along_xy_m_(leg_length_m_ * std::cos(ground_slope_rad_)),
      foot_radius_m_(walker_prior.simulator().model().foot_radius * leg_length_m_) {
  if (!std::isfinite(ground_slope_rad_)) throw std::invalid_argument("the body prior's ground slope must be finite");
}

body::BodyPose BodyPrior::pose(const BodyParticle& p) const {
  // The torso's rest is torso_rest_per_slope × slope from the ground's normal: the rest at the
  // ground's slope less the rest at the slope of the gait the particle walks.
  const double torso_turn_rad = torso_rest_per_slope_ * (ground_slope_rad_ - p.walker.gait.ground_slope);
  if (torso_turn_rad == 0)
    return body::bodyPose(walker_prior_.simulator().map(), p.walker.walker, ground_slope_rad_, p.placement.value,
                          shape_, leg_length_m_);
  dynamics::WalkerState turned = p.walker.walker;
  turned.q[dynamics::kTorso] += torso_turn_rad;
  return body::bodyPose(walker_prior_.simulator().map(), turned, ground_slope_rad_, p.placement.value, shape_,
                        leg_length_m_);
}

BodyParticle BodyPrior::sample(double phase, const Eigen::Vector2d& stance_foot_xy_m, double heading_rad,
                               common::Random& random, body::BodyPose& pose,
                               std::optional<dynamics::Leg> stance_leg, WalkerPrior::Start start) const {
  BodyParticle p;
  p.walker = walker_prior_.sample(phase, random, start);
  if (stance_leg) p.walker.walker.stance_leg = *stance_leg;
  p.placement.value.heading_rad = heading_rad;
  const Eigen::Vector2d heading(std::cos(heading_rad), std::sin(heading_rad));
  const dynamics::Point foot = dynamics::stanceFootCentre(walker_prior_.simulator().map(), p.walker.walker.q,
                                                          p.walker.walker.stance_foot_x);
  p.placement.value.ground_origin_m = stance_foot_xy_m - along_xy_m_ * foot.real() * heading;
  pose = this->pose(p);
  p.stance_foot_m = pose.foot_centres[p.walker.walker.stance_leg == dynamics::Leg::kLeft ? 0 : 1];
  return p;
}

dynamics::AdvanceReport BodyPrior::transition(BodyParticle& p, double dt_s, common::Random& random,
                                              body::BodyPose& pose) const {
  const double stance_shank_before = p.walker.walker.q[dynamics::kStanceShank];
  const std::uint32_t strikes_before = p.walker.walker.heel_strikes;
  const dynamics::AdvanceReport report = walker_prior_.transition(p.walker, dt_s / natural_time_s_, random);
  const dynamics::WalkerState& walker = p.walker.walker;
  const dynamics::Point stance =
      dynamics::stanceFootCentre(walker_prior_.simulator().map(), walker.q, walker.stance_foot_x);
  stepPlacement(p.placement, walker_prior_.options().placement, dt_s, along_xy_m_ * stance.real(), random);
  pose = this->pose(p);
  const int side = walker.stance_leg == dynamics::Leg::kLeft ? 0 : 1;
  if (walker.heel_strikes == strikes_before) {
    // The stance foot rolls without slipping (its centre moves by −R Δθ along the walk).
    const double turn = walker.q[dynamics::kStanceShank] - stance_shank_before;
    const Eigen::Vector3d rolled_to = p.stance_foot_m - foot_radius_m_ * turn * pose.forward;
    p.placement.value.ground_origin_m += (rolled_to - pose.foot_centres[side]).head<2>();
    pose = this->pose(p);
  }
  p.stance_foot_m = pose.foot_centres[side];
  return report;
}

}  // namespace kneed_walker::core::prior
