#include "kneed_walker/core/dynamics/walker_simulation.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace kneed_walker::core::dynamics {
namespace {

// The events that can end a trial step.
enum class Event { kNone, kStanceKnee, kSwingKnee, kHeelStrike };

// Narrows a bracket [lo, hi] with g(lo) > 0 ≥ g(hi) around the root of g by the Illinois
// method (regula falsi that halves a stale end's value), until it is no wider than `width`.
template <typename Function>
void illinois(Function g, double& lo, double& hi, double g_lo, double g_hi, double width) {
  int side = 0;
  for (int i = 0; i < 200 && hi - lo > width; ++i) {
    double mid = (lo * g_hi - hi * g_lo) / (g_hi - g_lo);
    if (!(mid > lo && mid < hi)) mid = 0.5 * (lo + hi);
    const double g_mid = g(mid);
    if (g_mid > 0) {
      lo = mid;
      g_lo = g_mid;
      if (side == 1) g_hi *= 0.5;
      side = 1;
    } else {
      hi = mid;
      g_hi = g_mid;
      if (side == -1) g_lo *= 0.5;
      side = -1;
    }
    if (g_mid == 0) break;
  }
}

// The cubic Hermite interpolant of q through a step's ends (q and q̇ at both, h apart) at the
// step fraction s ∈ [0, 1], and its time derivative.
Vector5 hermitePosition(const Vector5& q0, const Vector5& qdot0, const Vector5& q1, const Vector5& qdot1,
                        double h, double s) {
  const double s2 = s * s, s3 = s2 * s;
  return (2 * s3 - 3 * s2 + 1) * q0 + ((s3 - 2 * s2 + s) * h) * qdot0 + (-2 * s3 + 3 * s2) * q1 +
         ((s3 - s2) * h) * qdot1;
}
Vector5 hermiteRate(const Vector5& q0, const Vector5& qdot0, const Vector5& q1, const Vector5& qdot1,
                    double h, double s) {
  const double s2 = s * s;
  return ((6 * s2 - 6 * s) / h) * (q0 - q1) + (3 * s2 - 4 * s + 1) * qdot0 + (3 * s2 - 2 * s) * qdot1;
}

// The step fraction in [0, 1] where g(q) crosses zero on the cubic Hermite interpolant of q
// through the step's ends: no integration needed.
template <typename EventFunction>
double interpolatedEventFraction(EventFunction g, const WalkerState& a, const WalkerState& b,
                                 double h) {
  auto at = [&](double s) { return g(hermitePosition(a.q, a.qdot, b.q, b.qdot, h, s)); };
  double lo = 0, hi = 1;
  const double g_lo = at(0), g_hi = at(1);
  if (!(g_lo > 0 && g_hi <= 0)) return 0.5;
  illinois(at, lo, hi, g_lo, g_hi, 1e-13);
  return 0.5 * (lo + hi);
}

}  // namespace

struct WalkerSimulator::Derivative {
  Vector5 qdot;
  Vector5 qddot;
  JointTorques torque_squared;
  double power;
};

WalkerSimulator::WalkerSimulator(const WalkerModel& model, const SimulationOptions& options)
    : model_(model),
      map_(kneedWalkerMap(model)),
      inertia_(inertiaCoefficients(map_)),
      options_(options) {
  if (!(options.max_step > 0 && options.max_step <= 0.2))
    throw std::invalid_argument("SimulationOptions.max_step must lie in (0, 0.2] natural time units");
  if (!(options.event_time_tolerance > 0 && options.event_time_tolerance < options.max_step))
    throw std::invalid_argument("SimulationOptions.event_time_tolerance must lie in (0, max_step)");
  if (options.max_events_per_advance < 1)
    throw std::invalid_argument("SimulationOptions.max_events_per_advance must be >= 1");
  if (!(options.max_swing_penetration >= 0))
    throw std::invalid_argument("SimulationOptions.max_swing_penetration must be >= 0 (infinity: never a fall)");
  if (!(model.gravity > 0 && model.legLength() > 0))
    throw std::invalid_argument("WalkerModel needs gravity > 0 and a positive leg length");
  natural_time_ = std::sqrt(model.legLength() / model.gravity);
}

WalkerSimulator::Derivative WalkerSimulator::derivative(const WalkerControls& controls, const Point& gravity,
                                                        const Vector5& q, const Vector5& qdot,
                                                        const KneeFlags& on_limit) const {
  const JointTorques torques = jointTorques(controls, q, qdot);
  const Vector5 applied = generalisedForce(torques);
  EquationsOfMotion eom;
  equationsOfMotion(inertia_, gravity, q, qdot, applied, eom);
  Derivative d;
  d.qdot = qdot;
  d.qddot = constrainedAcceleration(eom, on_limit);  // eqs. 4, 7, 8
  for (int j = 0; j < kNumJoints; ++j) d.torque_squared[j] = torques[j] * torques[j];
  d.power = applied.dot(qdot);
  return d;
}

void WalkerSimulator::rk4(const WalkerControls& controls, const WalkerState& from, double h,
                          WalkerState& to, TorqueIntegrals* integrals) const {
  const KneeFlags& lim = from.knee_on_limit;
  const Point g = slopeGravity(model_.gravity, controls.ground_slope);  // once for the four stages
  const Derivative k1 = derivative(controls, g, from.q, from.qdot, lim);
  const Derivative k2 =
      derivative(controls, g, from.q + 0.5 * h * k1.qdot, from.qdot + 0.5 * h * k1.qddot, lim);
  const Derivative k3 =
      derivative(controls, g, from.q + 0.5 * h * k2.qdot, from.qdot + 0.5 * h * k2.qddot, lim);
  const Derivative k4 = derivative(controls, g, from.q + h * k3.qdot, from.qdot + h * k3.qddot, lim);
  to = from;
  to.q = from.q + (h / 6) * (k1.qdot + 2 * k2.qdot + 2 * k3.qdot + k4.qdot);
  to.qdot = from.qdot + (h / 6) * (k1.qddot + 2 * k2.qddot + 2 * k3.qddot + k4.qddot);
  to.time_in_stride = from.time_in_stride + h;
  if (integrals) {
    for (int j = 0; j < kNumJoints; ++j)
      integrals->squared[j] += (h / 6) * (k1.torque_squared[j] + 2 * k2.torque_squared[j] +
                                          2 * k3.torque_squared[j] + k4.torque_squared[j]);
    integrals->work += (h / 6) * (k1.power + 2 * k2.power + 2 * k3.power + k4.power);
  }
}

void WalkerSimulator::applyKneeLimit(WalkerState& state, int knee) const {
  // Eq. 6, then the least-squares projection onto the boundary.
  state.knee_on_limit[knee] = true;
  EquationsOfMotion eom;
  equationsOfMotion(inertia_, slopeGravity(model_.gravity, 0.0), state.q, state.qdot, Vector5::Zero(), eom);
  state.qdot = projectKneeVelocity(eom.mass, state.qdot, state.knee_on_limit,
                                   options_.knee_sticking_rate / natural_time_);
  state.q = projectKneePosition(eom.mass, state.q, state.knee_on_limit);
}

WalkerState afterHeelStrike(const KinematicMap& map, const WalkerState& before,
                            double toe_off_impulse, HeelStrike* impact_out) {
  const HeelStrike impact =
      heelStrike(map, before.q, before.qdot, toe_off_impulse, before.knee_on_limit);
  if (impact_out) *impact_out = impact;
  const Point new_foot = position(map, map.swing_foot_centre, before.q, before.stance_foot_x);
  // Swap stance and swing labels (the torso keeps its index).
  auto swap = [](const Vector5& v) {
    Vector5 s;
    s << v[kTorso], v[kSwingThigh], v[kSwingShank], v[kStanceThigh], v[kStanceShank];
    return s;
  };
  WalkerState after = before;
  after.q = swap(before.q);
  after.qdot = swap(impact.qdot_after);
  after.stance_foot_x = new_foot.real() + map.foot_radius * after.q[map.rolling_coordinate];
  // A knee stays on its limit only if the impact left it there (zero flexion rate); a knee
  // that the impact sets flexing is free from now on.
  for (int k = 0; k < kNumKnees; ++k) {
    const int swapped = 1 - k;
    after.knee_on_limit[swapped] =
        before.knee_on_limit[k] && kneeFlexionRow(k).dot(impact.qdot_after) <= 1e-12;
  }
  after.stance_leg = otherLeg(before.stance_leg);
  after.time_in_stride = 0;
  ++after.heel_strikes;
  return after;
}

WalkerSimulator::Geometry WalkerSimulator::geometry(const Vector5& q) const {
  const auto e = phasors(q);
  const Point swing_foot = relativePosition(map_.swing_foot_centre, e);
  return {swing_foot.imag(), swing_foot.real(),
          relativePosition(map_.hip, e).imag() + map_.foot_radius};
}

bool WalkerSimulator::hasFallen(const WalkerState& s, const Geometry& g) const {
  if (!s.q.allFinite() || !s.qdot.allFinite()) return true;
  return g.hip_height < options_.min_hip_height * model_.legLength() ||
         g.swing_clearance < -options_.max_swing_penetration * model_.legLength() ||
         s.time_in_stride > options_.max_stride_duration * natural_time_;
}

AdvanceReport WalkerSimulator::advance(const WalkerControls& controls, WalkerState& state,
                                       double duration, TorqueIntegrals* integrals) const {
  return run(controls, state, duration, false, integrals);
}

namespace {

// q and q̇ `done` model time into a step (its cubic Hermite interpolant).
void stepPose(const StepInProgress& step, double done, Vector5& q, Vector5& qdot) {
  const double h = step.duration, s = done / h;
  q = hermitePosition(step.start_q, step.start_qdot, step.end_q, step.end_qdot, h, s);
  qdot = hermiteRate(step.start_q, step.start_qdot, step.end_q, step.end_qdot, h, s);
  // Between ends that keep a knee within its limit, the interpolant may pass it by a few µrad
  // (a free knee grazing the limit): the knee is shown on its limit there.
  if (kneeFlexion(q, 0) < 0) q[kStanceShank] = q[kStanceThigh];
  if (kneeFlexion(q, 1) < 0) q[kSwingShank] = q[kSwingThigh];
}

}  // namespace

void WalkerSimulator::interpolateStep(WalkerState& state, double done) {
  state.step.done = done;
  stepPose(state.step, done, state.q, state.qdot);
  state.time_in_stride = state.step.start_time_in_stride + done;
}

bool WalkerSimulator::isIntegratorState(const WalkerState& state) {
  const StepInProgress& step = state.step;
  if (!step.valid) return false;
  if (step.duration == 0) return state.q == step.end_q && state.qdot == step.end_qdot;
  Vector5 q, qdot;
  stepPose(step, step.done, q, qdot);
  return state.q == q && state.qdot == qdot;
}

AdvanceReport WalkerSimulator::run(const WalkerControls& controls, WalkerState& state,
                                   double duration, bool stop_at_heel_strike,
                                   TorqueIntegrals* integrals) const {
  AdvanceReport report;
  if (state.fallen) {
    report.fell = true;
    return report;
  }
  const double max_step = options_.max_step * natural_time_;
  const double tolerance = options_.event_time_tolerance * natural_time_;

  // Event functions, positive before the event: the flexion of a free knee, and the
  // swing-sole clearance. A heel strike needs the swing foot ahead of the stance foot; a foot
  // that scuffs the ground while passing is ignored, as in McGeer's walkers.
  auto eventValue = [&](Event event, const Vector5& q) {
    switch (event) {
      case Event::kStanceKnee: return kneeFlexion(q, 0);
      case Event::kSwingKnee: return kneeFlexion(q, 1);
      case Event::kHeelStrike: return swingFootClearance(map_, q);
      case Event::kNone: break;
    }
    return 1.0;
  };

  // The scuff integrand at a pose (see TorqueIntegrals::scuff).
  const double window = options_.passing_window * model_.legLength();
  const double margin = options_.clearance_margin * model_.legLength();
  auto scuffing = [&](const Geometry& g) {
    if (std::abs(g.swing_foot_ahead) >= window) return 0.0;
    const double below = margin - g.swing_clearance;
    return below > 0 ? below * below : 0.0;
  };

  // The event at the state (reached by a step); true if the walker fell at it.
  auto applyEvent = [&](Event event) {
    if (event == Event::kHeelStrike) {
      HeelStrike impact;
      const WalkerState after = afterHeelStrike(map_, state, controls.toe_off_impulse, &impact);
      report.last_landing_impulse = impact.ground_normal_impulse;
      if (!impact.physical()) {
        ++report.pulling_heel_strikes;
        if (options_.fall_at_pulling_landing) {
          state.fallen = true;
          report.fell = true;
          return true;
        }
      }
      state = after;
      ++report.heel_strikes;
    } else {
      applyKneeLimit(state, event == Event::kStanceKnee ? 0 : 1);
      ++report.knee_limit_events;
    }
    return false;
  };
  // After a step or an event, at a grid point: knees leaving their limits, falls, the stop at a
  // heel strike. True if run() is to return.
  Geometry at_state;
  auto settle = [&](const Geometry& at) {
    at_state = at;
    // A knee held on its limit leaves it when the motion flexes it again.
    for (int k = 0; k < kNumKnees; ++k)
      if (state.knee_on_limit[k] && kneeFlexion(state.q, k) > 1e-12) state.knee_on_limit[k] = false;
    if (hasFallen(state, at_state) ||
        report.heel_strikes + report.knee_limit_events > options_.max_events_per_advance) {
      state.fallen = true;
      report.fell = true;
      return true;
    }
    return stop_at_heel_strike && report.heel_strikes > 0;
  };
  // The state at a grid point, as the integrator leaves it.
  auto onGrid = [&]() {
    state.step = StepInProgress{};
    state.step.end_q = state.q;
    state.step.end_qdot = state.qdot;
    state.step.valid = true;
    return report;
  };
  // The step from the state to `end` (h model time; up to `event`, if any) taken whole; the
  // state is put `done` into it.
  auto keepStep = [&](const WalkerState& end, double h, Event event, double done) {
    StepInProgress step;
    step.start_q = state.q;
    step.start_qdot = state.qdot;
    step.end_q = end.q;
    step.end_qdot = end.qdot;
    step.start_time_in_stride = state.time_in_stride;
    step.duration = h;
    step.event_at_end = static_cast<std::uint8_t>(event);
    step.valid = true;
    state.step = step;
    interpolateStep(state, done);
    report.elapsed = duration;
    return report;
  };

  if (!isIntegratorState(state)) {
    state.step = StepInProgress{};
    // A state from outside (a perturbed particle, a hand-made guess) may sit beyond a knee
    // limit or move into it while flagged as on it: put it on the limit first (eq. 6 +
    // projection).
    for (int k = 0; k < kNumKnees; ++k) {
      const bool beyond = kneeFlexion(state.q, k) < 0;
      const bool into = state.knee_on_limit[k] && kneeFlexionRow(k).dot(state.qdot) < 0;
      if (beyond || into) applyKneeLimit(state, k);
    }
    at_state = geometry(state.q);
  } else if (state.step.duration > 0) {
    // Inside a step taken before: move within it, or go on from its end.
    const StepInProgress step = state.step;
    const double left = step.duration - step.done;
    if (duration < left) {
      interpolateStep(state, step.done + duration);
      report.elapsed = duration;
      return report;
    }
    state.q = step.end_q;
    state.qdot = step.end_qdot;
    state.time_in_stride = step.start_time_in_stride + step.duration;
    state.step = StepInProgress{};
    report.elapsed = left;
    const Event event = static_cast<Event>(step.event_at_end);
    if (event != Event::kNone && applyEvent(event)) return report;
    if (settle(geometry(state.q))) return state.fallen ? report : onGrid();
  } else {
    at_state = geometry(state.q);
  }

  WalkerState trial;
  while (duration - report.elapsed > tolerance) {  // a rounding sliver left over is no step
    const double h = max_step;  // whole steps: the grid does not depend on `duration`
    TorqueIntegrals step_integrals;
    rk4(controls, state, h, trial, integrals ? &step_integrals : nullptr);
    const Geometry at_trial = geometry(trial.q);

    const std::array<bool, 3> triggered = {
        !state.knee_on_limit[0] && kneeFlexion(trial.q, 0) < 0,
        !state.knee_on_limit[1] && kneeFlexion(trial.q, 1) < 0,
        at_state.swing_clearance > 0 && at_trial.swing_clearance <= 0 &&
            at_trial.swing_foot_ahead > 0};
    const bool any_event = triggered[0] || triggered[1] || triggered[2];

    if (!any_event) {
      if (integrals) {
        for (int j = 0; j < kNumJoints; ++j) integrals->squared[j] += step_integrals.squared[j];
        integrals->work += step_integrals.work;
        integrals->scuff += h * 0.5 * (scuffing(at_state) + scuffing(at_trial));  // trapezoid
        if (std::abs(at_trial.swing_foot_ahead) < window)
          integrals->passing_clearance = std::min(integrals->passing_clearance, at_trial.swing_clearance);
        integrals->max_swing_knee_flexion = std::max(integrals->max_swing_knee_flexion, kneeFlexion(trial.q, 1));
      }
      if (report.elapsed + h > duration) {  // the step ends after the time asked
        if (hasFallen(trial, at_trial)) {     // a fall is a fall as soon as it is seen
          state = trial;
          state.fallen = true;
          report.fell = true;
          report.elapsed = duration;
          return report;
        }
        return keepStep(trial, h, Event::kNone, duration - report.elapsed);
      }
      state = trial;
      report.elapsed += h;
      if (settle(at_trial)) return state.fallen ? report : onGrid();
    } else {
      // Localise the earliest event by the Illinois method on the step fraction.
      Event first = Event::kNone;
      double first_fraction = 2.0;
      const Event events[3] = {Event::kStanceKnee, Event::kSwingKnee, Event::kHeelStrike};
      for (int i = 0; i < 3; ++i) {
        if (!triggered[i]) continue;
        const Event event = events[i];
        double lo = 0, hi = 1;
        double g_lo = eventValue(event, state.q), g_hi = eventValue(event, trial.q);
        WalkerState probe;
        // Start from the root on the cubic Hermite interpolant of q through both ends of the
        // step (accurate to O(h⁴), no integration), then bracket it tightly with a second
        // probe just beyond, on the side where the root lies.
        auto probeAt = [&](double at) {
          rk4(controls, state, at * h, probe, nullptr);
          const double g = eventValue(event, probe.q);
          if (g > 0) {
            lo = at;
            g_lo = g;
          } else {
            hi = at;
            g_hi = g;
          }
        };
        const double guess = interpolatedEventFraction(
            [&](const Vector5& q) { return eventValue(event, q); }, state, trial, h);
        if (guess > lo && guess < hi) {
          probeAt(guess);
          constexpr double kBracket = 1e-6;  // ≫ the interpolant's error in the step fraction
          const double beyond = lo == guess ? guess + kBracket : guess - kBracket;
          if (beyond > lo && beyond < hi) probeAt(beyond);
        }
        illinois(
            [&](double at) {
              rk4(controls, state, at * h, probe, nullptr);
              return eventValue(event, probe.q);
            },
            lo, hi, g_lo, g_hi, tolerance / h);
        if (hi < first_fraction) {
          first_fraction = hi;
          first = event;
        }
      }
      const double h_event = first_fraction * h;
      if (report.elapsed + h_event > duration) {  // the event comes after the time asked
        WalkerState at_event;
        rk4(controls, state, h_event, at_event, integrals);
        return keepStep(at_event, h_event, first, duration - report.elapsed);
      }
      rk4(controls, state, h_event, state, integrals);
      report.elapsed += h_event;
      if (applyEvent(first)) return report;
      if (settle(geometry(state.q))) return state.fallen ? report : onGrid();
    }
  }
  return onGrid();
}

StrideResult WalkerSimulator::stride(const WalkerControls& controls,
                                     const WalkerState& start) const {
  StrideResult result;
  result.end = start;
  result.end.time_in_stride = 0;
  result.end.step = StepInProgress{};  // a stride starts at a grid point
  const double hip_start = pointPosition(map_.hip, result.end).real();
  const double limit = options_.max_stride_duration * natural_time_;
  const AdvanceReport report = run(controls, result.end, limit * 1.01, true, &result.integrals);
  result.completed = report.heel_strikes > 0 && !report.fell;
  result.pulling_heel_strike = report.pulling_heel_strikes > 0;
  result.landing_impulse = report.last_landing_impulse;
  result.duration = report.elapsed;
  result.step_length = pointPosition(map_.hip, result.end).real() - hip_start;
  result.speed = result.duration > 0 ? result.step_length / result.duration : 0;
  return result;
}

double WalkerSimulator::mechanicalEnergy(const WalkerControls& controls,
                                         const WalkerState& state) const {
  return dynamics::mechanicalEnergy(map_, model_.gravity, controls.ground_slope, state.q,
                                        state.qdot, state.stance_foot_x);
}

}  // namespace kneed_walker::core::dynamics
