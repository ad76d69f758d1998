// Efficient cyclic gaits (paper §3.3): minimise the effort of eq. 9
//   E(x0, θ, γ) = β_ι ι^α + Σ_j (β_j / T) ∫₀ᵀ τ_j² dt
// over the spring parameters θ, the toe-off impulse ι and the post-heel-strike state x0,
// subject to eq. 10: S(x0, θ, γ) = x0, V = v, L = ℓ. Solved with NLopt's SLSQP with
// finite-difference gradients. Everything is in dimensionless units (leg length 1, body
// mass 1, g = 1), in which the paper's weights are given; a gait scales to any person by
// Froude similarity (speed × √(gL), step length × L, time × √(L/g)).
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "kneed_walker/core/gait/gait.h"
#include "kneed_walker/core/gait/gait_table.h"
#include "kneed_walker/core/optimizer/periodic_gait.h"

namespace kneed_walker::core::optimizer {

// The paper's weights of eq. 9.
//
// The paper does not say in which units eq. 9 is evaluated, and the units matter: torques and
// the impulse scale differently (τ by M g L, ι by M √(gL), and ι enters as ι^1.5). Read in SI
// units for the reference person (70 kg, L = 0.9275 m), the torque terms weigh
// (M g L)² / (M √(gL))^1.5 = 132.3 times more against the impulse than read in dimensionless
// units. That reading reproduces the paper's findings far better (a passive swing knee on the
// level, a stiffer stance knee uphill, the torso leaning back downhill; the dimensionless
// reading stiffens the swing knee and props the torso forward), so the torque terms carry
// torque_unit_scale.
struct EffortWeights {
  double impulse = 0.62;         // β_ι
  double impulse_exponent = 1.5;  // α
  double stance_knee = 0.3;      // β_K1
  double swing_knee = 0.007;     // β_K2
  double hip = 0.007;            // β_H
  double torso = 0.034;          // β_To
  double torque_unit_scale = 132.3;  // weight of the torque terms against the impulse term
  // Penalty on a swing foot passing lower than SimulationOptions::clearance_margin (per unit
  // of TorqueIntegrals::scuff / T): not in the paper, whose walker presumably cleared the
  // ground; without it the cheapest swing is a straight leg through the ground. The prior's
  // table is solved with it alone; the free table with GaitOptimizerOptions::
  // min_passing_clearance as well, the hard constraint (issue 13), under which the penalty is 0.
  double scuff = 1e5;
};

// Effort E of eq. 9 for a simulated stride and its impulse.
double gaitEffort(const dynamics::StrideResult& stride, double toe_off_impulse, const EffortWeights& weights);

// One optimised gait: the controls and the start of its periodic stride (the runtime's
// gait::Gait), its simulated stride, and how well the constraints hold.
struct OptimalGait : gait::Gait {
  dynamics::StrideResult stride;  // S(x0, θ, γ); its duration is stride_duration
  double effort = 0;         // E of eq. 9
  double periodicity_residual = 0;  // max |S(x0) − x0| over the full state
  double speed_error = 0;           // relative |V − v| / v
  double step_length_error = 0;     // relative |L − ℓ| / ℓ
  int nlopt_result = 0;             // nlopt::result code of the last solve
  int evaluations = 0;              // strides simulated
  // The stride also completes with GaitOptimizerOptions::simulation as given, as the prior and
  // the tracker simulate it: the optimiser's own stride function lets the swing sole pass
  // through the ground (to stay smooth), theirs calls a sole deeper than
  // SimulationOptions::max_swing_penetration a fall (11 gaits of the ±10° tables, 0.015–0.045 L
  // below the ground as they pass the stance foot, were feasible without this).
  bool walks_at_runtime = false;
  // The swing sole passes the stance foot at least GaitOptimizerOptions::min_passing_clearance
  // above the ground (within 1e-6 L: SLSQP meets an active bound to its tolerance); always
  // true when that bound is off.
  bool clears_the_ground = false;
  // The swing knee flexes at most GaitOptimizerOptions::max_swing_knee_flexion (within 1e-6
  // rad); always true when that bound is off.
  bool knee_within_bound = false;
  // Periodic, on target, landing on a ground that pushes (HeelStrike::physical()), clearing the
  // ground as it swings, within the knee's bound, and walked by the runtime's simulator.
  bool feasible() const {
    return stride.completed && !stride.pulling_heel_strike && periodicity_residual < 1e-6 &&
           speed_error < 0.01 && step_length_error < 0.01 && clears_the_ground && knee_within_bound &&
           walks_at_runtime;
  }
};

struct GaitOptimizerOptions {
  EffortWeights weights;
  // Controls held at the prior's fixed values instead of optimised (paper §3.4): gaits that
  // the prior's walkers can follow (the prior's table). Empty: all optimised.
  std::optional<gait::FixedControls> fixed;
  int max_iterations = 1000;        // SLSQP objective evaluations
  double constraint_tolerance = 1e-9;
  double relative_tolerance = 1e-7;  // on the variables
  double difference_step = 1e-6;     // central finite differences
  // The ground's normal impulse at the heel strike must be at least this, M √(gL) (an
  // inequality beside eq. 10; the median landing of the unconstrained gaits is about 0.14).
  // Zero would be the physical limit; the margin keeps strides near the optimum, as noisy
  // particles take, from landing on a pulling ground.
  double min_landing_impulse = 0.01;
  // When finite, the swing sole's lowest height while the foot passes the stance foot
  // (TorqueIntegrals::passing_clearance) must be at least this, L: a second inequality beside
  // eq. 10 (issue 13), so that an optimum clears the ground instead of scraping. Not in the
  // paper. The shipped free table is solved with 0.01 (gait::GaitTable::swing_bounds records
  // it). From an optimum that swings a nearly straight leg (as under the soft scuff penalty
  // alone) the bound lifts the foot only to about the ground: the table was grown from a seed
  // gait whose swing knee is already bent at heel strike.
  double min_passing_clearance = -std::numeric_limits<double>::infinity();
  // When finite, the swing knee's largest flexion over the stride
  // (TorqueIntegrals::max_swing_knee_flexion) must be at most this, rad: a third inequality.
  // The walker's knee has no flexion stop, and under the clearance bound 10 of the 53 level
  // optima of the paper's grid fold the swing knee past 90 degrees (people's peak is about 60,
  // Schwartz 2008); at 1.31 rad (75 degrees) none does. Not in the paper. Off by default.
  double max_swing_knee_flexion = std::numeric_limits<double>::infinity();
  dynamics::SimulationOptions simulation;      // of the stride function
};

// Optimises the gait for `target`, starting from `start` (its controls and state; typically a
// neighbouring solution). The knee modes of start.start (kneeModes) choose the reduced
// coordinates of x0; a solution that ends in other modes is solved again in those.
OptimalGait optimizeGait(const dynamics::BodyProportions& proportions, const gait::GaitTarget& target,
                         const gait::Gait& start, const GaitOptimizerOptions& options = {});

// A start for optimizeGait: McGeer's passive gait as the state, a stiff damped torso spring
// to hold the torso up, no other torque.
OptimalGait initialGaitGuess();

// A first optimal gait for `target` by continuation from McGeer's passive gait: the torso's
// centre of mass is raised from the hip to its place in `proportions`, then the target moves
// from the passive gait's to `target`, each step warm-started from the last; a continuation
// that dead-ends is tried again with half and then double the first step count. The result's
// feasible() says whether one succeeded.
OptimalGait seedGait(const dynamics::BodyProportions& proportions, const gait::GaitTarget& target,
                     const GaitOptimizerOptions& options = {}, int target_steps = 8);

// A gait (a stored table entry, say) simulated for one stride and measured as optimizeGait
// measures its results: feasible() says whether it meets eq. 10 and lands on a pushing ground
// with this simulator.
OptimalGait simulatedGait(const dynamics::BodyProportions& proportions, const gait::Gait& gait,
                          const GaitOptimizerOptions& options = {});

// The gait table's record of an optimised gait.
gait::GaitTableEntry tableEntry(const OptimalGait& gait);

}  // namespace kneed_walker::core::optimizer
