#include "kneed_walker/core/prior/walker_prior.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "kneed_walker/core/common/config_file.h"
#include "kneed_walker/core/common/parallel.h"

namespace kneed_walker::core::prior {

std::vector<std::string> validate(const PriorOptions& o) {
  std::vector<std::string> problems;
  auto nonNegative = [&](const std::string& name, double v) {
    if (!(std::isfinite(v) && v >= 0)) problems.push_back(name + " = " + std::to_string(v) + " must be >= 0");
  };
  nonNegative("knee_damping", o.fixed.knee_damping);
  nonNegative("torso_damping", o.fixed.torso_damping);
  nonNegative("impulse_scale", o.impulse_scale);
  if (!(o.noise_innovation_limit > 0)) problems.push_back("noise_innovation_limit must be > 0");
  if (!std::isfinite(o.fixed.torso_rest_per_slope)) problems.push_back("torso_rest_per_slope must be finite");
  for (int i = 0; i < kNumPriorStiffnesses; ++i) {
    nonNegative("stride_mean_offset[" + std::to_string(i) + "]", o.stride_mean_offset[i]);
    nonNegative("stride_sd[" + std::to_string(i) + "]", o.stride_sd[i]);
    nonNegative("frame_sd[" + std::to_string(i) + "]", o.frame_sd[i]);
  }
  const PlacementNoise& pl = o.placement;
  for (const auto& [name, value] :
       {std::pair<const char*, double>{"heading_damping", pl.heading_damping},
        {"heading_sigma", pl.heading_sigma}, {"sway_damping", pl.sway_damping},
        {"sway_sigma", pl.sway_sigma}, {"sway_restoring", pl.sway_restoring},
        {"abduction_damping", pl.abduction_damping}, {"abduction_sigma", pl.abduction_sigma},
        {"rotation_damping", pl.rotation_damping}, {"rotation_sigma", pl.rotation_sigma}})
    nonNegative(name, value);
  for (int j = 0; j < dynamics::kNumJoints; ++j) {
    if (!(o.noise_decay[j] >= 0 && o.noise_decay[j] <= 1))
      problems.push_back("noise_decay[" + std::to_string(j) + "] = " + std::to_string(o.noise_decay[j]) +
                         " must lie in [0, 1]");
    nonNegative("noise_scale[" + std::to_string(j) + "]", o.noise_scale[j]);
  }
  return problems;
}

PriorOptions loadPriorOptions(const std::string& path) {
  common::ConfigFile file(path, "prior parameters");
  PriorOptions o;
  file.read("knee_damping", o.fixed.knee_damping);
  file.read("torso_rest_per_slope", o.fixed.torso_rest_per_slope);
  file.read("torso_damping", o.fixed.torso_damping);
  file.read("stride_mean_offset", o.stride_mean_offset);
  file.read("stride_sd", o.stride_sd);
  file.read("frame_sd", o.frame_sd);
  file.read("impulse_scale", o.impulse_scale);
  file.read("noise_decay", o.noise_decay);
  file.read("noise_scale", o.noise_scale);
  file.read("noise_innovation_limit", o.noise_innovation_limit);
  PlacementNoise& pl = o.placement;
  file.read("heading_damping", pl.heading_damping);
  file.read("heading_sigma", pl.heading_sigma);
  file.read("sway_damping", pl.sway_damping);
  file.read("sway_sigma", pl.sway_sigma);
  file.read("sway_restoring", pl.sway_restoring);
  file.read("abduction_damping", pl.abduction_damping);
  file.read("abduction_sigma", pl.abduction_sigma);
  file.read("rotation_damping", pl.rotation_damping);
  file.read("rotation_sigma", pl.rotation_sigma);
  file.finish(validate(o));
  return o;
}

void requirePriorTable(const gait::GaitTable& table, const PriorOptions& o) {
  if (!table.fixed)
    throw std::invalid_argument(
        "the prior needs a gait table optimised with its fixed controls (optimize_gaits "
        "--prior-fixed, as config/prior_gait_table.yaml); this one optimised them freely");
  const gait::FixedControls& f = *table.fixed;
  const gait::FixedControls& p = o.fixed;
  auto differs = [](double a, double b) { return std::abs(a - b) > 1e-9 * (1 + std::abs(b)); };
  std::ostringstream message;
  if (differs(f.knee_damping, p.knee_damping))
    message << "knee_damping " << p.knee_damping << " (table: " << f.knee_damping << ") ";
  if (differs(f.torso_rest_per_slope, p.torso_rest_per_slope))
    message << "torso_rest_per_slope " << p.torso_rest_per_slope << " (table: " << f.torso_rest_per_slope << ") ";
  if (differs(f.torso_damping, p.torso_damping))
    message << "torso_damping " << p.torso_damping << " (table: " << f.torso_damping << ") ";
  if (!message.str().empty())
    throw std::invalid_argument("the prior's fixed controls differ from those the gait table was optimised with: " +
                                message.str() + "(re-run optimize_gaits --prior-fixed with them)");
}

gait::Gait priorGait(const gait::GaitTable& table, const dynamics::WalkerSimulator& simulator,
                     double speed_kmh, double step_length_m, double slope_rad, gait::InterpolationNote* note) {
  gait::Gait gait = gait::interpolateGait(table, speed_kmh, step_length_m, slope_rad, note);
  const dynamics::StrideResult stride = simulator.stride(gait.controls, gait.start);
  if (!stride.completed) {
    std::ostringstream message;
    message << "the gait interpolated at " << speed_kmh << " km/h, " << step_length_m << " m steps, slope "
            << slope_rad << " rad does not complete a stride";
    throw std::runtime_error(message.str());
  }
  gait.stride_duration = stride.duration;
  return gait;
}

void walkGait(WalkerParticle& p, const dynamics::WalkerControls& gait) { p.gait = gait; }

WalkerPrior::WalkerPrior(const dynamics::WalkerSimulator& simulator, const gait::Gait& gait,
                         const PriorOptions& options)
    : sim_(simulator), gait_(gait), options_(options) {
  const auto problems = validate(options);
  common::throwIfInvalid("PriorOptions", problems);
  if (!(gait.stride_duration > 0)) throw std::invalid_argument("WalkerPrior needs a simulated gait");
  WalkerParticle on_cycle;
  walkGait(on_cycle, gait_.controls);
  cycle_[0] = gait_.start;
  for (int k = 1; k < kCycleStates; ++k) {
    cycle_[k] = cycle_[k - 1];
    sim_.advance(on_cycle.gait, cycle_[k], gait_.stride_duration / kCycleStates);
  }
}

void WalkerPrior::newStride(WalkerParticle& p, common::Random& random) const {
  const dynamics::SpringParameters& gait = p.gait.springs;
  const std::array<double, kNumPriorStiffnesses> gait_stiffness{
      {gait.stance_knee_stiffness, gait.hip_stiffness, gait.torso_stiffness}};
  for (int i = 0; i < kNumPriorStiffnesses; ++i) {
    std::normal_distribution<double> mean(gait_stiffness[i] + options_.stride_mean_offset[i],
                                          options_.stride_sd[i]);
    p.stride_mean[i] = std::max(0.0, mean(random));
  }
  // The impulse's exponential spread about the gait's optimal impulse (see PriorOptions).
  double spread = 0.0;
  if (options_.impulse_scale > 0) {
    std::exponential_distribution<double> exponential(1.0 / options_.impulse_scale);
    spread = exponential(random) - options_.impulse_scale;
  }
  p.next_impulse = std::max(0.0, p.gait.toe_off_impulse + spread);
  p.stride_of_means = p.walker.heel_strikes;
}

WalkerParticle WalkerPrior::sample(double phase, common::Random& random, Start start) const {
  phase = std::clamp(phase, 0.0, 1.0);
  const int k = start == Start::kFromCycle ? std::min(kCycleStates - 1, static_cast<int>(phase * kCycleStates)) : 0;
  WalkerParticle p;
  p.walker = cycle_[k];  // cycle_[0] is the stride's start
  walkGait(p, gait_.controls);
  newStride(p, random);
  p.stiffness = p.stride_mean;
  sim_.advance(controls(p), p.walker, (phase - static_cast<double>(k) / kCycleStates) * gait_.stride_duration);
  p.stride_of_means = p.walker.heel_strikes;
  return p;
}

dynamics::WalkerControls WalkerPrior::controls(const WalkerParticle& p) const {
  // The particle's gait's own dampings, swing knee spring and torso rest angle (the fixed
  // values for a table optimised with them held, and its optimal swing knee stiffness); the
  // sampled stiffnesses and the noise of eq. 11.
  dynamics::WalkerControls c = p.gait;
  c.springs.stance_knee_stiffness = p.stiffness[kPriorStanceKnee];
  c.springs.hip_stiffness = p.stiffness[kPriorHip];
  c.springs.torso_stiffness = p.stiffness[kPriorTorso];
  c.offsets.stance_knee = p.noise[dynamics::kStanceKnee];
  c.offsets.swing_knee = p.noise[dynamics::kSwingKnee];
  c.offsets.hip = p.noise[dynamics::kHip];
  c.offsets.torso = p.noise[dynamics::kTorsoJoint];
  c.offsets.stance_ankle = p.noise[dynamics::kStanceAnkle];
  c.toe_off_impulse = p.next_impulse;
  return c;
}

dynamics::AdvanceReport WalkerPrior::transition(WalkerParticle& p, double dt, common::Random& random) const {
  if (p.walker.heel_strikes != p.stride_of_means) newStride(p, random);
  for (int i = 0; i < kNumPriorStiffnesses; ++i) {
    std::normal_distribution<double> value(p.stride_mean[i], options_.frame_sd[i]);
    p.stiffness[i] = std::max(0.0, value(random));
  }
  // Truncated Cauchy by its inverse CDF: ε = tan(u), u uniform in ±atan(limit).
  const double u_limit = std::atan(options_.noise_innovation_limit);
  std::uniform_real_distribution<double> angle(-u_limit, u_limit);
  for (int j = 0; j < dynamics::kNumJoints; ++j)  // eq. 11
    p.noise[j] = options_.noise_decay[j] * p.noise[j] + options_.noise_scale[j] * std::tan(angle(random));
  return sim_.advance(controls(p), p.walker, dt);
}

WalkingFraction sampleStrides(const std::vector<WalkerPrior>& stride_priors, int strides,
                              int strides_per_chain, double dt, common::Random& random) {
  if (stride_priors.empty() || strides < 1 || strides_per_chain < 1 || !(dt > 0))
    throw std::invalid_argument("sampleStrides needs a prior, strides >= 1, strides_per_chain >= 1, dt > 0");
  const int last = static_cast<int>(stride_priors.size()) - 1;
  WalkingFraction count;
  while (count.walked + count.fell < strides) {
    WalkerParticle particle = stride_priors.front().sample(0.0, random);
    int in_chain = 0;
    bool fell = false;
    while (in_chain < strides_per_chain && count.walked + count.fell < strides) {
      const WalkerPrior& prior = stride_priors[std::min(in_chain, last)];
      const dynamics::AdvanceReport report = prior.transition(particle, dt, random);
      count.walked += report.heel_strikes;
      count.pulling += report.pulling_heel_strikes;
      in_chain += report.heel_strikes;
      if (report.heel_strikes > 0) walkGait(particle, stride_priors[std::min(in_chain, last)].gait().controls);
      if (report.fell) {
        ++count.fell;
        fell = true;
        break;
      }
    }
    if (fell)
      ++count.chains_fell;
    else if (in_chain >= strides_per_chain)
      ++count.chains_walked;
  }
  return count;
}

std::vector<std::optional<WalkingFraction>> tableWalkingFractions(const gait::GaitTable& table,
                                                                 const dynamics::WalkerSimulator& simulator,
                                                                 const PriorOptions& options, int strides,
                                                                 int strides_per_chain, double dt,
                                                                 std::uint64_t seed, int threads) {
  std::vector<std::optional<WalkingFraction>> fractions(table.entries.size());
  common::parallelFor(static_cast<int>(table.entries.size()), threads, [&](int begin, int end) {
    for (int i = begin; i < end; ++i) {
      if (!table.entries[i].feasible) continue;
      const std::vector<WalkerPrior> prior{WalkerPrior(simulator, table.entries[i].gait, options)};
      common::Random random(seed * 1000003u + static_cast<std::uint64_t>(i));
      fractions[i] = sampleStrides(prior, strides, strides_per_chain, dt, random);
    }
  }, 1);
  return fractions;
}

void stepPlacement(PlacementState& p, const PlacementNoise& n, double dt, double pivot_along_m,
                   common::Random& random) {
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

}  // namespace kneed_walker::core::prior
