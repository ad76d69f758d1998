// The stochastic prior over walking (paper §3.4): the transition s_t ~ p(s_t | s_{t−1}) that
// a particle filter calls once per particle per frame.
//
//  * Per stride (from each heel strike): the mean stiffnesses κ̄_j of the stance knee, hip and
//    torso ~ N(gait value, σ̄_j²); the toe-off impulse for the coming contact ~ Exponential.
//  * Per frame: κ_j(t) ~ N(κ̄_j, σ_j²); the torque noise of eq. 11, η_j(t) = α_j η_j(t−1) +
//    s_j ε with ε Cauchy (truncated), on the knees, hip, torso and the stance leg against the ground.
//  * The rest of θ as the gait has it. The prior's table is optimised with the paper's fixed
//    values held (knee damping dK1 = dK2 = 0.05, torso rest angle φ⁰To = γ/3, torso damping
//    dTo = 1.5), so its gaits carry them; a gait of another table carries its own. The paper
//    also holds the swing knee's stiffness κK2 at 0; ours is the gait's optimum (gait::FixedControls
//    says why).
//  * Then the walker is simulated deterministically over the frame.
//
// Units: the gait table's dimensionless ones (leg length 1, body mass 1, g = 1; time in
// √(L/g)), in which the paper gives these values. All randomness comes from the caller's
// generator: the same seed gives the same particles.
#pragma once

#include <array>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "kneed_walker/core/body/body_model.h"
#include "kneed_walker/core/common/random.h"
#include "kneed_walker/core/gait/gait.h"
#include "kneed_walker/core/gait/gait_table.h"

namespace kneed_walker::core::prior {

// The kinematic DOFs that the walker does not fix (paper §3.4: "damped 2nd-order Markov
// processes with zero-mean Gaussian acceleration"): each value x with rate v evolves over dt as
//   v ← v e^{−c dt} + σ √dt ε,   x ← x + v dt,   ε ~ N(0, 1),
// c the damping (1/s) and σ the acceleration noise. Heading, sideways sway, hip abduction and
// rotation; `sway_restoring` also pulls the sway back towards 0 (1/s²).
struct PlacementNoise {
  double heading_damping = 2.0, heading_sigma = 0.3;      // 1/s; rad/s^1.5
  double sway_damping = 4.0, sway_sigma = 0.05;           // 1/s; m/s^1.5
  double sway_restoring = 10.0;                           // 1/s²
  double abduction_damping = 6.0, abduction_sigma = 0.3;  // 1/s; rad/s^1.5
  double rotation_damping = 6.0, rotation_sigma = 0.3;    // 1/s; rad/s^1.5
};

// The sampled stiffnesses: stance knee, hip, torso.
enum PriorStiffness : int { kPriorStanceKnee = 0, kPriorHip, kPriorTorso, kNumPriorStiffnesses };

struct PriorOptions {
  // The paper's fixed values: knee dampings, torso rest angle per slope and torso damping (in
  // the file as the flat keys knee_damping, torso_rest_per_slope, torso_damping). The walkers
  // take them from the gait; these say which values the gait table must have been optimised
  // with (requirePriorTable).
  gait::FixedControls fixed;
  // Per-stride means: N(gait value + stride_mean_offset, stride_sd²); per-frame values:
  // N(mean, frame_sd²). The paper raises the stance knee's and torso's means above the optimal
  // gaits' "to account for differences between tracked motions and optimal cyclic gaits".
  std::array<double, kNumPriorStiffnesses> stride_mean_offset{{0.3, 0.0, 0.0}};
  std::array<double, kNumPriorStiffnesses> stride_sd{{0.2, 0.005, 0.3}};
  std::array<double, kNumPriorStiffnesses> frame_sd{{0.05, 0.001, 0.05}};
  // The toe-off impulse: ι = max(0, ι* + e − impulse_scale), e ~ Exponential with mean
  // impulse_scale, ι* the gait's optimal impulse. The paper draws ι ~ Exponential(0.015)
  // outright; our optimal gaits need ≈ 0.15 on the level, and at a mean of 0.015 the walker
  // runs out of energy within a few strides, so the paper's exponential is kept as the spread
  // about the optimum (mean ι*).
  double impulse_scale = 0.015;
  // Eq. 11 per joint (stance knee, swing knee, hip, torso, stance ankle).
  dynamics::JointTorques noise_decay{{0.9, 0.9, 0.9, 0.9, 0.9}};           // α_j ∈ [0, 1]
  dynamics::JointTorques noise_scale{{0.001, 0.0002, 0.0002, 0.001, 0.0002}};  // s_j, torque units M g L
  // ε is Cauchy truncated to |ε| ≤ this: the heavy tail stays, but no single frame's torque
  // can be thousands of times its scale (untruncated, 1 frame in 300 exceeds 200 s_j).
  double noise_innovation_limit = 20.0;
  PlacementNoise placement;
};

// Every problem with the options, each naming the field.
std::vector<std::string> validate(const PriorOptions& options);

// Reads options from a YAML file such as config/prior.yaml; keys not given keep their defaults;
// unknown keys, wrong types and invalid values throw std::invalid_argument naming them.
PriorOptions loadPriorOptions(const std::string& path);

struct PlacementState {
  body::BodyPlacement value;
  double heading_rate = 0, sway_rate = 0;          // rad/s, m/s
  std::array<double, 2> abduction_rate{}, rotation_rate{};  // rad/s
};

// One step of the placement processes over dt seconds. Turning re-anchors the ground origin so
// that the point `pivot_along_m` metres along the walking direction (the stance foot) stays
// where it is: a change of heading bends the path there instead of swinging it about the origin.
void stepPlacement(PlacementState& placement, const PlacementNoise& noise, double dt_s,
                   double pivot_along_m, common::Random& random);

// One particle's full state s_t = (θ_t, η_t, x_t) (the kinematic DOFs k_t are the body
// model's placement, driven by the tracker).
struct WalkerParticle {
  dynamics::WalkerState walker;
  // The gait its strides walk around (θ, the optimal impulse ι*, γ; no torque offsets): the
  // prior's from sample(), or another set by walkGait at a heel strike (a change of speed or step).
  dynamics::WalkerControls gait;
  std::array<double, kNumPriorStiffnesses> stride_mean{};  // κ̄_j for the current stride
  std::array<double, kNumPriorStiffnesses> stiffness{};    // κ_j(t)
  dynamics::JointTorques noise{};                                    // η_j(t)
  double next_impulse = 0;                                 // ι at the coming heel strike
  std::uint32_t stride_of_means = 0;  // walker.heel_strikes when stride_mean was drawn
};

// From the particle's next stride on, its strides walk around the gait whose controls are
// `gait` (Gait::controls, ground slope set, the same slope as the particle's): the per-stride
// stiffness means and the impulse are drawn about its values, and the springs the prior does
// not sample are its. Called between a heel strike and the next transition, the stride that has
// just begun walks it.
void walkGait(WalkerParticle& particle, const dynamics::WalkerControls& gait);

// The prior walks around gaits that were optimised with its fixed controls held (optimize_gaits
// --prior-fixed, config/prior_gait_table.yaml): around gaits optimised freely, its fixed values
// perturb every stride and the walkers fall (measured with sample_prior: 45–66 % of strides
// walk on ±4.3° slopes). Throws std::invalid_argument naming the mismatch.
void requirePriorTable(const gait::GaitTable& table, const PriorOptions& options);

// The gait the prior walks around at a target of the table (speed and step length for the
// table's reference person): gait::interpolateGait, with one stride simulated for the
// stride_duration that WalkerPrior needs. Throws std::runtime_error if that stride does not
// complete (a fall), std::out_of_range for a target outside the table.
gait::Gait priorGait(const gait::GaitTable& table, const dynamics::WalkerSimulator& simulator,
                     double speed_kmh, double step_length_m, double slope_rad,
                     gait::InterpolationNote* note = nullptr);

class WalkerPrior {
 public:
  // `gait` supplies the start state and the gait sampled particles walk around (the means of
  // the stride stiffnesses, the impulse, the slope); a particle may walk another from a heel
  // strike on (walkGait). The prior keeps its own copy of the simulator (small and constant).
  WalkerPrior(const dynamics::WalkerSimulator& simulator, const gait::Gait& gait,
              const PriorOptions& options);

  // A particle on the gait's periodic stride at `phase` ∈ [0, 1) of it, with fresh samples.
  // kFromStrike: the walker simulated from the stride's start with those samples (up to a
  // whole stride: the tracker's 5000 × 32 initial candidates took 11.6 s so). kFromCycle: from the gait's own cycle, tabulated at construction
  // (kCycleStates states), the tabulated state at or before `phase` simulated with the samples
  // over the rest (at most 1/kCycleStates of a stride, a few µs), for the tracker's initial
  // search, which draws tens of thousands.
  enum class Start { kFromStrike, kFromCycle };
  static constexpr int kCycleStates = 64;
  WalkerParticle sample(double phase, common::Random& random, Start start = Start::kFromStrike) const;

  // s_t ~ p(s_t | s_{t−1}) over dt (natural time units): samples, then simulates, around the
  // particle's gait.
  dynamics::AdvanceReport transition(WalkerParticle& particle, double dt, common::Random& random) const;

  // The controls a particle's walker runs with.
  dynamics::WalkerControls controls(const WalkerParticle& particle) const;

  const gait::Gait& gait() const { return gait_; }
  const dynamics::WalkerSimulator& simulator() const { return sim_; }
  const PriorOptions& options() const { return options_; }

 private:
  void newStride(WalkerParticle& particle, common::Random& random) const;

  dynamics::WalkerSimulator sim_;
  gait::Gait gait_;
  PriorOptions options_;
  std::array<dynamics::WalkerState, kCycleStates> cycle_;  // the gait's stride at phases k / kCycleStates
};

// How often the prior's sampled strides keep walking. Each chain starts on the first prior's
// gait just after a heel strike with fresh samples and runs the transition frame by frame (dt,
// natural time) until `strides_per_chain` strides have ended in a heel strike or one in a fall;
// chains are sampled until `strides` strides have ended either way. A chain's k-th stride (from
// 0) walks around the gait of `stride_priors[min(k, size − 1)]`: one prior walks one gait
// throughout, one per stride walks a change of speed, the new gait taking over at the heel
// strike (walkGait) as in the tracker's gait changes.
struct WalkingFraction {
  int walked = 0;  // strides that ended in a heel strike
  int fell = 0;    // strides that ended in a fall
  int pulling = 0;  // of the falls, those at a landing that needed the ground to pull (AdvanceReport)
  int chains_walked = 0, chains_fell = 0;  // whole chains (one cut short by `strides` is neither)
  double fraction() const { return walked + fell > 0 ? double(walked) / (walked + fell) : 0.0; }
  double chainFraction() const {
    return chains_walked + chains_fell > 0 ? double(chains_walked) / (chains_walked + chains_fell) : 0.0;
  }
};
WalkingFraction sampleStrides(const std::vector<WalkerPrior>& stride_priors, int strides,
                              int strides_per_chain, double dt, common::Random& random);

// sampleStrides on every feasible gait of a table, each with a prior of its own and a generator
// seeded by `seed` and the gait's index (the same figures on any number of threads); an entry
// per grid point, nullopt where there is no feasible gait. Issue 13's
// "usable by the prior" counts the grid points whose gait keeps walking.
std::vector<std::optional<WalkingFraction>> tableWalkingFractions(const gait::GaitTable& table,
                                                                 const dynamics::WalkerSimulator& simulator,
                                                                 const PriorOptions& options, int strides,
                                                                 int strides_per_chain, double dt,
                                                                 std::uint64_t seed, int threads);

}  // namespace kneed_walker::core::prior
