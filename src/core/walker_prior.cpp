#include "kneed_walker/core/walker_prior.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace kneed_walker {

std::vector<std::string> validate(const PriorOptions& o) {
  std::vector<std::string> problems;
  auto nonNegative = [&](const std::string& name, double v) {
    if (!(std::isfinite(v) && v >= 0)) problems.push_back(name + " = " + std::to_string(v) + " must be >= 0");
  };
  nonNegative("knee_damping", o.knee_damping);
  nonNegative("swing_knee_stiffness", o.swing_knee_stiffness);
  nonNegative("torso_damping", o.torso_damping);
  nonNegative("impulse_scale", o.impulse_scale);
  if (!std::isfinite(o.torso_rest_per_slope)) problems.push_back("torso_rest_per_slope must be finite");
  for (int i = 0; i < kNumPriorStiffnesses; ++i) {
    nonNegative("stride_sd[" + std::to_string(i) + "]", o.stride_sd[i]);
    nonNegative("frame_sd[" + std::to_string(i) + "]", o.frame_sd[i]);
  }
  for (int j = 0; j < kNumJoints; ++j) {
    if (!(o.noise_decay[j] >= 0 && o.noise_decay[j] <= 1))
      problems.push_back("noise_decay[" + std::to_string(j) + "] = " + std::to_string(o.noise_decay[j]) +
                         " must lie in [0, 1]");
    nonNegative("noise_scale[" + std::to_string(j) + "]", o.noise_scale[j]);
  }
  return problems;
}

WalkerPrior::WalkerPrior(const WalkerSimulator& simulator, const OptimalGait& gait,
                         const PriorOptions& options)
    : sim_(simulator), gait_(gait), options_(options) {
  const auto problems = validate(options);
  if (!problems.empty()) throw std::invalid_argument("PriorOptions: " + problems.front());
  if (!(gait.stride.duration > 0)) throw std::invalid_argument("WalkerPrior needs a simulated gait");
  gait_stiffness_ = {gait.controls.springs.stance_knee_stiffness,
                     gait.controls.springs.hip_stiffness, gait.controls.springs.torso_stiffness};
}

void WalkerPrior::newStride(WalkerParticle& p, Random& random) const {
  for (int i = 0; i < kNumPriorStiffnesses; ++i) {
    std::normal_distribution<double> mean(gait_stiffness_[i], options_.stride_sd[i]);
    p.stride_mean[i] = std::max(0.0, mean(random));
  }
  std::exponential_distribution<double> impulse(1.0 / std::max(options_.impulse_scale, 1e-12));
  p.next_impulse = options_.impulse_scale > 0 ? impulse(random) : 0.0;
  p.stride_of_means = p.walker.heel_strikes;
}

WalkerParticle WalkerPrior::sample(double phase, Random& random) const {
  WalkerParticle p;
  p.walker = gait_.start;
  newStride(p, random);
  p.stiffness = p.stride_mean;
  sim_.advance(controls(p), p.walker, std::clamp(phase, 0.0, 1.0) * gait_.stride.duration);
  p.stride_of_means = p.walker.heel_strikes;
  return p;
}

WalkerControls WalkerPrior::controls(const WalkerParticle& p) const {
  WalkerControls c;
  const double slope = gait_.target.slope;
  c.ground_slope = slope;
  c.springs.stance_knee_stiffness = p.stiffness[kPriorStanceKnee];
  c.springs.stance_knee_damping = options_.knee_damping;
  c.springs.swing_knee_stiffness = options_.swing_knee_stiffness;
  c.springs.swing_knee_rest_angle = gait_.controls.springs.swing_knee_rest_angle;
  c.springs.swing_knee_damping = options_.knee_damping;
  c.springs.hip_stiffness = p.stiffness[kPriorHip];
  c.springs.torso_stiffness = p.stiffness[kPriorTorso];
  c.springs.torso_rest_angle = options_.torso_rest_per_slope * slope;
  c.springs.torso_damping = options_.torso_damping;
  c.offsets.stance_knee = p.noise[kStanceKnee];
  c.offsets.swing_knee = p.noise[kSwingKnee];
  c.offsets.hip = p.noise[kHip];
  c.offsets.torso = p.noise[kTorsoJoint];
  c.offsets.stance_ankle = p.noise[kStanceAnkle];
  c.toe_off_impulse = p.next_impulse;
  return c;
}

AdvanceReport WalkerPrior::transition(WalkerParticle& p, double dt, Random& random) const {
  if (p.walker.heel_strikes != p.stride_of_means) newStride(p, random);
  for (int i = 0; i < kNumPriorStiffnesses; ++i) {
    std::normal_distribution<double> value(p.stride_mean[i], options_.frame_sd[i]);
    p.stiffness[i] = std::max(0.0, value(random));
  }
  std::cauchy_distribution<double> cauchy(0.0, 1.0);
  for (int j = 0; j < kNumJoints; ++j)  // eq. 11
    p.noise[j] = options_.noise_decay[j] * p.noise[j] + options_.noise_scale[j] * cauchy(random);
  return sim_.advance(controls(p), p.walker, dt);
}

void stepPlacement(PlacementState& p, const PlacementNoise& n, double dt, double pivot_along_m,
                   Random& random) {
  std::normal_distribution<double> normal(0.0, 1.0);
  const double root_dt = std::sqrt(dt);
  auto step = [&](double& value, double& rate, double damping, double sigma, double restoring) {
    rate = rate * std::exp(-damping * dt) - restoring * value * dt + sigma * root_dt * normal(random);
    value += rate * dt;
  };
  const double old_heading = p.value.heading_rad;
  step(p.value.heading_rad, p.heading_rate, n.heading_damping, n.heading_sigma, 0.0);
  step(p.value.sway_m, p.sway_rate, n.sway_damping, n.sway_sigma, n.sway_restoring);
  for (int side = 0; side < 2; ++side) {
    step(p.value.hip_abduction_rad[side], p.abduction_rate[side], n.abduction_damping,
         n.abduction_sigma, 0.0);
    step(p.value.hip_rotation_rad[side], p.rotation_rate[side], n.rotation_damping,
         n.rotation_sigma, 0.0);
  }
  // Keep the pivot (origin + pivot_along · heading direction) fixed through the turn.
  const Eigen::Vector2d before(std::cos(old_heading), std::sin(old_heading));
  const Eigen::Vector2d after(std::cos(p.value.heading_rad), std::sin(p.value.heading_rad));
  p.value.ground_origin_m += pivot_along_m * (before - after);
}

}  // namespace kneed_walker
