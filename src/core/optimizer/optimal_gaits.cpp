#include "kneed_walker/core/optimizer/optimal_gaits.h"

#include <nlopt.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace kneed_walker::core::optimizer {
namespace {

// The optimisation variables: θ and ι in the order of gait::Control, then x0 in reduced
// coordinates.
constexpr int kNumControlVariables = gait::kNumControls;

// Bounds of the controls, dimensionless (torque unit M g L, time unit √(L/g)). The torso
// spring must hold the torso up against gravity (its gravity torque about the hip is about
// 0.23 φ), so κTo ≥ 0.5 and dTo ≥ 0.1; its rest angle stays within ±0.15 rad of the vertical (the paper's
// prior leans it γ/3 into the slope), else the optimum turns the torso spring into a constant hip motor
// with the torso leaning far forward.
constexpr double kControlLower[kNumControlVariables] = {0, 0, 0, 0, 0, 0, 0.5, -0.15, 0.1, 0};
constexpr double kControlUpper[kNumControlVariables] = {30, 5, 5, 1.5, 5, 30, 50, 0.15, 20, 0.5};
constexpr double kAngleBound = 1.3;  // rad, |q| of x0
constexpr double kRateBound = 6.0;   // per natural time unit, |q̇| of x0

// The problem as NLopt sees it. Objective and constraints at one x come from one stride, and
// their gradients from one sweep of central differences, cached for both callbacks.
class GaitProblem {
 public:
  GaitProblem(const dynamics::WalkerSimulator& simulator, const gait::GaitTarget& target,
              const GaitCoordinates& coordinates, const GaitOptimizerOptions& options)
      : sim_(simulator),
        target_(target),
        coordinates_(coordinates),
        options_(options),
        n_(kNumControlVariables + coordinates.size()),
        m_(coordinates.size() + 2) {
    // c_ holds the m_ equalities of eq. 10, then the inequalities: the landing impulse, and the
    // swing's clearance and its knee's flexion if bounded.
    if (std::isfinite(options.min_passing_clearance)) clearance_row_ = m_ + inequalities_++;
    if (std::isfinite(options.max_swing_knee_flexion)) flexion_row_ = m_ + inequalities_++;
    lower_.assign(n_, 0);
    upper_.assign(n_, 0);
    for (int i = 0; i < kNumControlVariables; ++i) {
      lower_[i] = kControlLower[i];
      upper_[i] = kControlUpper[i];
    }
    // The torso's rest angle is bounded about the vertical, not the slope's normal: an upright
    // torso is at −γ in the walker's slope frame.
    lower_[gait::kTorsoRestAngle] -= target.slope;
    upper_[gait::kTorsoRestAngle] -= target.slope;
    if (options.fixed) {
      dynamics::WalkerControls zero;
      zero.ground_slope = target.slope;
      const gait::ControlVector held =
          gait::toControlVector(gait::withFixedControls(zero, *options.fixed));
      for (int i = 0; i < kNumControlVariables; ++i)
        if (gait::isFixed(static_cast<gait::Control>(i))) lower_[i] = upper_[i] = held[i];
    }
    const int angles = coordinates.angles();
    for (int i = kNumControlVariables; i < n_; ++i) {
      const bool angle = i - kNumControlVariables < angles;
      lower_[i] = angle ? -kAngleBound : -kRateBound;
      upper_[i] = angle ? kAngleBound : kRateBound;
    }
  }

  int variables() const { return n_; }
  int equalityConstraints() const { return m_; }
  int inequalityConstraints() const { return inequalities_; }
  const std::vector<double>& lower() const { return lower_; }
  const std::vector<double>& upper() const { return upper_; }
  int evaluations() const { return evaluations_; }

  std::vector<double> pack(const gait::Gait& gait) const {
    std::vector<double> x(n_);
    const gait::ControlVector controls = gait::toControlVector(gait.controls);
    std::copy(controls.begin(), controls.end(), x.begin());
    const GaitVector r = coordinates_.reduce(gait.start);
    for (int i = 0; i < r.size(); ++i) x[kNumControlVariables + i] = r[i];
    for (int i = 0; i < n_; ++i) x[i] = std::clamp(x[i], lower_[i], upper_[i]);
    return x;
  }

  // The stride from x: controls and start state.
  dynamics::StrideResult simulate(const double* x, dynamics::WalkerControls& controls, dynamics::WalkerState& start) const {
    gait::ControlVector vector;
    std::copy(x, x + kNumControlVariables, vector.begin());
    controls = gait::fromControlVector(vector, target_.slope);
    GaitVector r(coordinates_.size());
    for (int i = 0; i < r.size(); ++i) r[i] = x[kNumControlVariables + i];
    start = coordinates_.expand(r);
    ++evaluations_;
    return sim_.stride(controls, start);
  }

  // Objective and constraints at x (no gradients): eq. 10's equalities S(x0) − x0, V − v,
  // L − ℓ in c[0, m_), then the inequalities (≤ 0): the landing's min_landing_impulse − impulse
  // in c[m_] and, if bounded, the swing's min_passing_clearance − passing clearance and its
  // knee's flexion − max_swing_knee_flexion after it.
  double evaluate(const double* x, double* c) const {
    dynamics::WalkerControls controls;
    dynamics::WalkerState start;
    const dynamics::StrideResult stride = simulate(x, controls, start);
    if (!stride.completed) {
      // A fall: no periodic gait here. Large, finite values keep SLSQP's line search away.
      for (int i = 0; i < m_ + inequalities_; ++i) c[i] = 10.0;
      return 1e3;
    }
    const GaitVector end = coordinates_.reduce(stride.end);
    for (int i = 0; i < end.size(); ++i) c[i] = end[i] - x[kNumControlVariables + i];
    c[m_ - 2] = stride.speed - target_.speed;
    c[m_ - 1] = stride.step_length - target_.step_length;
    c[m_] = options_.min_landing_impulse - stride.landing_impulse;
    // A swing that never reaches the stance foot (+inf) clears it; capped to keep the
    // differences finite.
    if (clearance_row_ >= 0)
      c[clearance_row_] = options_.min_passing_clearance - std::min(stride.integrals.passing_clearance, 1.0);
    if (flexion_row_ >= 0)
      c[flexion_row_] = stride.integrals.max_swing_knee_flexion - options_.max_swing_knee_flexion;
    return gaitEffort(stride, controls.toe_off_impulse, options_.weights);
  }

  double objective(const double* x, double* grad) {
    refresh(x, grad != nullptr);
    if (grad) std::copy(grad_f_.begin(), grad_f_.end(), grad);
    return f_;
  }

  void equalityValues(const double* x, double* c, double* grad) {
    refresh(x, grad != nullptr);
    std::copy(c_.begin(), c_.begin() + m_, c);
    if (grad) std::copy(grad_c_.begin(), grad_c_.begin() + static_cast<size_t>(m_) * n_, grad);
  }

  void inequalityValues(const double* x, double* c, double* grad) {
    refresh(x, grad != nullptr);
    std::copy(c_.begin() + m_, c_.end(), c);
    if (grad) std::copy(grad_c_.begin() + static_cast<size_t>(m_) * n_, grad_c_.end(), grad);
  }

 private:
  void refresh(const double* x, bool need_gradient) {
    const bool same = !x_.empty() && std::equal(x_.begin(), x_.end(), x);
    if (!same) {
      x_.assign(x, x + n_);
      c_.assign(m_ + inequalities_, 0);
      f_ = evaluate(x, c_.data());
      has_gradient_ = false;
    }
    if (!need_gradient || has_gradient_) return;
    grad_f_.assign(n_, 0);
    grad_c_.assign(static_cast<size_t>(m_ + inequalities_) * n_, 0);
    std::vector<double> probe = x_, c_plus(m_ + inequalities_), c_minus(m_ + inequalities_);
    for (int j = 0; j < n_; ++j) {
      // Central differences, one-sided at a bound (ι ≥ 0 must stay ≥ 0).
      const double h = options_.difference_step * std::max(1.0, std::abs(x_[j]));
      const double up = std::min(x_[j] + h, upper_[j]);
      const double down = std::max(x_[j] - h, lower_[j]);
      if (up <= down) continue;  // a fixed control: its gradient entries stay 0
      probe[j] = up;
      const double f_plus = evaluate(probe.data(), c_plus.data());
      probe[j] = down;
      const double f_minus = evaluate(probe.data(), c_minus.data());
      probe[j] = x_[j];
      const double width = up - down;
      grad_f_[j] = (f_plus - f_minus) / width;
      for (int i = 0; i < m_ + inequalities_; ++i)
        grad_c_[static_cast<size_t>(i) * n_ + j] = (c_plus[i] - c_minus[i]) / width;
    }
    has_gradient_ = true;
  }

  const dynamics::WalkerSimulator& sim_;
  gait::GaitTarget target_;
  GaitCoordinates coordinates_;
  GaitOptimizerOptions options_;
  int n_, m_, inequalities_ = 1;
  int clearance_row_ = -1, flexion_row_ = -1;  // rows of c_, -1 when unbounded
  std::vector<double> lower_, upper_;
  mutable int evaluations_ = 0;
  std::vector<double> x_, c_, grad_f_, grad_c_;
  double f_ = 0;
  bool has_gradient_ = false;
};

double objectiveCallback(unsigned, const double* x, double* grad, void* data) {
  return static_cast<GaitProblem*>(data)->objective(x, grad);
}

void equalityCallback(unsigned, double* result, unsigned, const double* x, double* grad,
                      void* data) {
  static_cast<GaitProblem*>(data)->equalityValues(x, result, grad);
}

void inequalityCallback(unsigned, double* result, unsigned, const double* x, double* grad,
                        void* data) {
  static_cast<GaitProblem*>(data)->inequalityValues(x, result, grad);
}

}  // namespace

double gaitEffort(const dynamics::StrideResult& stride, double toe_off_impulse, const EffortWeights& w) {
  const dynamics::JointTorques& sq = stride.integrals.squared;
  const double torques = w.stance_knee * sq[dynamics::kStanceKnee] + w.swing_knee * sq[dynamics::kSwingKnee] +
                         w.hip * sq[dynamics::kHip] + w.torso * sq[dynamics::kTorsoJoint];
  return w.impulse * std::pow(toe_off_impulse, w.impulse_exponent) +
         (w.torque_unit_scale * torques + w.scuff * stride.integrals.scuff) /
             std::max(stride.duration, 1e-9);
}

namespace {

// The stride function the optimiser sees: a landing on a pulling ground and a swing foot
// through the ground are simulated through (not falls), so that the landing constraint's value
// goes on smoothly below zero and the scuff penalty and the clearance bound see the whole dip;
// feasible() refuses a pulling landing and a swing through the ground that the runtime's
// simulator calls a fall.
dynamics::WalkerSimulator optimiserSimulator(const dynamics::BodyProportions& proportions,
                                             const GaitOptimizerOptions& options) {
  dynamics::SimulationOptions simulation = options.simulation;
  simulation.fall_at_pulling_landing = false;
  simulation.max_swing_penetration = std::numeric_limits<double>::infinity();
  return dynamics::WalkerSimulator(dynamics::dimensionlessWalker(proportions), simulation);
}

// Fills in the figures of a gait whose stride has been simulated from its start; `runtime`
// simulates it again as the prior does (options.simulation unchanged).
void measure(OptimalGait& gait, const dynamics::WalkerSimulator& runtime, const GaitOptimizerOptions& options) {
  gait.walks_at_runtime = runtime.stride(gait.controls, gait.start).completed;
  gait.clears_the_ground = gait.stride.integrals.passing_clearance >= options.min_passing_clearance - 1e-6;
  gait.knee_within_bound = gait.stride.integrals.max_swing_knee_flexion <= options.max_swing_knee_flexion + 1e-6;
  const gait::GaitTarget& target = gait.target;
  gait.effort = gaitEffort(gait.stride, gait.controls.toe_off_impulse, options.weights);
  gait.periodicity_residual =
      std::max((gait.stride.end.q - gait.start.q).lpNorm<Eigen::Infinity>(),
               (gait.stride.end.qdot - gait.start.qdot).lpNorm<Eigen::Infinity>());
  if (!gait.stride.completed || kneeModes(gait.stride.end) != kneeModes(gait.start))
    gait.periodicity_residual = std::numeric_limits<double>::infinity();
  gait.speed_error = std::abs(gait.stride.speed - target.speed) / target.speed;
  gait.step_length_error = std::abs(gait.stride.step_length - target.step_length) / target.step_length;
  gait.stride_duration = gait.stride.duration;
}

// One SLSQP solve in the knee modes of `start`, then a Newton polish of x0.
OptimalGait optimizeInPattern(const dynamics::WalkerSimulator& sim, const dynamics::WalkerSimulator& runtime,
                              const gait::GaitTarget& target,
                              const gait::Gait& start, const GaitOptimizerOptions& options) {
  const GaitCoordinates coordinates(kneeModes(start.start));
  GaitProblem problem(sim, target, coordinates, options);

  nlopt::opt solver(nlopt::LD_SLSQP, static_cast<unsigned>(problem.variables()));
  solver.set_lower_bounds(problem.lower());
  solver.set_upper_bounds(problem.upper());
  solver.set_min_objective(objectiveCallback, &problem);
  solver.add_equality_mconstraint(
      equalityCallback, &problem,
      std::vector<double>(problem.equalityConstraints(), options.constraint_tolerance));
  solver.add_inequality_mconstraint(inequalityCallback, &problem,
                                    std::vector<double>(problem.inequalityConstraints(), options.constraint_tolerance));
  solver.set_xtol_rel(options.relative_tolerance);
  solver.set_maxeval(options.max_iterations);

  std::vector<double> x = problem.pack(start);
  double effort = 0;
  OptimalGait result;
  try {
    result.nlopt_result = solver.optimize(x, effort);
  } catch (const nlopt::roundoff_limited&) {
    result.nlopt_result = nlopt::ROUNDOFF_LIMITED;
  } catch (const std::runtime_error&) {
    result.nlopt_result = nlopt::FAILURE;
  }

  result.target = target;
  result.stride = problem.simulate(x.data(), result.controls, result.start);
  // SLSQP stops on its step tolerance with the constraints met to about 1e-6; Newton on the
  // stride map at the optimised controls makes x0 periodic to rounding (changing V and L by
  // about as much).
  PeriodicGait polished = findPeriodicGait(sim, result.controls, result.start);
  if (!polished.converged && polished.residual < 1e-6) {
    // Periodic, but its knees end in other modes than x0 was given in (a knee that leaves its
    // limit at zero rate is locked): start again from the end of the stride.
    dynamics::WalkerState from_end = polished.stride.end;
    from_end.stance_foot_x = 0;
    polished = findPeriodicGait(sim, result.controls, from_end);
  }
  if (polished.converged) {
    result.start = polished.start;
    result.stride = polished.stride;
  }
  measure(result, runtime, options);
  result.evaluations = problem.evaluations();
  return result;
}

}  // namespace

OptimalGait optimizeGait(const dynamics::BodyProportions& proportions, const gait::GaitTarget& target,
                         const gait::Gait& start, const GaitOptimizerOptions& options) {
  const dynamics::WalkerSimulator sim = optimiserSimulator(proportions, options);
  const dynamics::WalkerSimulator runtime(dynamics::dimensionlessWalker(proportions), options.simulation);
  OptimalGait result = optimizeInPattern(sim, runtime, target, start, options);
  // Which knees stay locked through heel strike is a property of the gait (a stance knee that
  // flexes right at contact is not locked): when the solution ends in other knee modes than it
  // started in, solve again in those.
  if (!result.feasible() && result.stride.completed &&
      kneeModes(result.stride.end) != kneeModes(result.start)) {
    gait::Gait restart = result;
    restart.start = result.stride.end;
    restart.start.stance_foot_x = 0;
    OptimalGait again = optimizeInPattern(sim, runtime, target, restart, options);
    again.evaluations += result.evaluations;
    if (again.feasible() || again.periodicity_residual < result.periodicity_residual)
      result = again;
  }
  return result;
}

OptimalGait initialGaitGuess() {
  const PeriodicGait passive = mcGeerPassiveGait();
  OptimalGait guess;
  guess.start = passive.start;
  guess.start.q[dynamics::kTorso] = 0;
  guess.start.qdot[dynamics::kTorso] = 0;
  guess.controls.springs.torso_stiffness = 3.0;
  guess.controls.springs.torso_damping = 1.0;
  guess.controls.ground_slope = kMcGeerSlope;
  guess.target = {passive.stride.speed, passive.stride.step_length, kMcGeerSlope};
  guess.stride = passive.stride;
  guess.stride_duration = passive.stride.duration;
  return guess;
}

namespace {

double mix(double from, double to, double a) { return (1 - a) * from + a * to; }  // exact at 0 and 1

dynamics::Segment blend(const dynamics::Segment& from, const dynamics::Segment& to, double a) {
  return {mix(from.mass, to.mass, a), mix(from.length, to.length, a),
          mix(from.com_along, to.com_along, a), mix(from.com_forward, to.com_forward, a),
          mix(from.radius_of_gyration, to.radius_of_gyration, a)};
}

// The proportions a of the way from one set to another (a ∈ [0, 1]); the masses still add
// up to 1.
dynamics::BodyProportions blend(const dynamics::BodyProportions& from, const dynamics::BodyProportions& to,
                                double a) {
  dynamics::BodyProportions p;
  p.leg_length_per_height = mix(from.leg_length_per_height, to.leg_length_per_height, a);
  p.torso = blend(from.torso, to.torso, a);
  p.thigh = blend(from.thigh, to.thigh, a);
  p.shank = blend(from.shank, to.shank, a);
  p.foot_radius = mix(from.foot_radius, to.foot_radius, a);
  p.foot_offset_angle = mix(from.foot_offset_angle, to.foot_offset_angle, a);
  return p;
}

OptimalGait continueFromPassiveGait(const dynamics::BodyProportions& proportions, const gait::GaitTarget& target,
                                    const GaitOptimizerOptions& options, int target_steps) {
  // Adaptive continuation on a homotopy parameter a ∈ [0, 1]: a failed step is retried at half
  // the size from the last feasible gait, a successful one lets the next grow.
  auto follow = [&](OptimalGait gait, auto solveAt) {
    double reached = 0, step = 1.0 / target_steps;
    while (reached < 1 && step > 1.0 / 512) {
      const double next = std::min(1.0, reached + step);
      const OptimalGait candidate = solveAt(next, gait);
      if (candidate.feasible()) {
        gait = candidate;
        reached = next;
        step *= 1.5;
      } else {
        step *= 0.5;
        if (step <= 1.0 / 512) return candidate;  // give up: report the failure
      }
    }
    return gait;
  };
  OptimalGait gait = initialGaitGuess();
  const dynamics::BodyProportions mcgeer = dynamics::mcGeerProportions();
  gait = follow(gait, [&](double a, const OptimalGait& from) {
    // From McGeer's walker (hip mass, his shank) to the person's proportions (the torso
    // raised to its place, the shank's centre of mass moved).
    return optimizeGait(blend(mcgeer, proportions, a), from.target, from, options);
  });
  if (!gait.feasible()) return gait;
  const gait::GaitTarget start = gait.target;
  return follow(gait, [&](double a, const OptimalGait& from) {
    const gait::GaitTarget between{start.speed + a * (target.speed - start.speed),
                             start.step_length + a * (target.step_length - start.step_length),
                             start.slope + a * (target.slope - start.slope)};
    return optimizeGait(proportions, between, from, options);
  });
}

}  // namespace

OptimalGait seedGait(const dynamics::BodyProportions& proportions, const gait::GaitTarget& target,
                     const GaitOptimizerOptions& options, int target_steps) {
  // A continuation can dead-end on a gait from which no step reaches on; the path taken
  // depends on the first step size, so try half and double it before giving up.
  OptimalGait gait;
  for (const int steps : {target_steps, std::max(1, target_steps / 2), 2 * target_steps}) {
    gait = continueFromPassiveGait(proportions, target, options, steps);
    if (gait.feasible()) break;
  }
  return gait;
}

OptimalGait simulatedGait(const dynamics::BodyProportions& proportions, const gait::Gait& gait,
                          const GaitOptimizerOptions& options) {
  const dynamics::WalkerSimulator sim = optimiserSimulator(proportions, options);
  const dynamics::WalkerSimulator runtime(dynamics::dimensionlessWalker(proportions), options.simulation);
  OptimalGait result;
  static_cast<gait::Gait&>(result) = gait;
  result.stride = sim.stride(gait.controls, gait.start);
  measure(result, runtime, options);
  return result;
}

gait::GaitTableEntry tableEntry(const OptimalGait& gait) {
  gait::GaitTableEntry entry;
  entry.solved = true;
  entry.feasible = gait.feasible();
  entry.gait = gait;
  // A stride that fell or diverged has no speed or step length (NaN after a divergence): it
  // is recorded as 0, and its effort, if not finite, as infinite, so that the table stays
  // readable (a failed point is solved again with --retry-failed).
  entry.quality.speed = gait.stride.completed && std::isfinite(gait.stride.speed) ? gait.stride.speed : 0.0;
  entry.quality.step_length =
      gait.stride.completed && std::isfinite(gait.stride.step_length) ? gait.stride.step_length : 0.0;
  entry.quality.effort = std::isfinite(gait.effort) ? gait.effort : std::numeric_limits<double>::infinity();
  entry.quality.periodicity_residual = gait.periodicity_residual;
  entry.quality.solver_status = gait.nlopt_result;
  entry.quality.evaluations = gait.evaluations;
  return entry;
}

}  // namespace kneed_walker::core::optimizer

