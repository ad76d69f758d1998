// Simulating the Kneed Walker (paper §3.2): fixed-step RK4 on eq. 4 with the knee limits of
// eqs. 6–8 and the heel strikes of eq. 5 handled as localised events.
//
// The simulator is constant after construction (model, kinematic map, options) and every
// method is const and allocation-free, so one simulator serves all particles on all threads;
// the per-particle state is WalkerState (MuJoCo's model/data split).
#pragma once

#include <cstdint>
#include <limits>

#include "kneed_walker/core/dynamics/walker_dynamics.h"

namespace kneed_walker::core::dynamics {

enum class Leg : std::uint8_t { kLeft = 0, kRight = 1 };
inline Leg otherLeg(Leg leg) { return leg == Leg::kLeft ? Leg::kRight : Leg::kLeft; }

// The integrator's RK4 step that a state lies inside (see WalkerSimulator::advance): its two
// ends, which are the integrator's own states, and how far into it the state is.
struct StepInProgress {
  Vector5 start_q = Vector5::Zero(), start_qdot = Vector5::Zero();  // at the step's start
  Vector5 end_q = Vector5::Zero(), end_qdot = Vector5::Zero();      // at its end: the next grid point, or an event
  double start_time_in_stride = 0;  // model time
  double duration = 0;              // model time from start to end; 0: the state is the end itself
  double done = 0;                  // model time from the start to the state, in [0, duration)
  std::uint8_t event_at_end = 0;    // the event that the end reaches (applied when the state gets there); 0: none
  bool valid = false;               // false: the state is not the integrator's (made or changed outside it)
};

// The dynamics state x = (q, q̇) of one walker plus what the events need.
struct WalkerState {
  Vector5 q = Vector5::Zero();     // rad: torso, stance thigh, stance shank, swing thigh, swing shank
  Vector5 qdot = Vector5::Zero();  // rad/s (model time)
  double stance_foot_x = 0;        // x0: stance foot centre C_x = x0 − R·q[kStanceShank], model length
  KneeFlags knee_on_limit{};       // [stance, swing]: knee on its extension limit
  Leg stance_leg = Leg::kLeft;
  double time_in_stride = 0;       // since the last heel strike, model time
  std::uint32_t heel_strikes = 0;  // since the state was made
  bool fallen = false;             // fell (or diverged): the state is frozen
  StepInProgress step;             // the integrator's, so that a split advance() continues it
};

// The heel-strike transition: the impact of eq. 5 (heelStrike, returned in `impact` if given),
// then stance and swing labels swapped, the new stance foot's x0 set, the knee flags swapped,
// the stride clock reset.
WalkerState afterHeelStrike(const KinematicMap& map, const WalkerState& before,
                            double toe_off_impulse, HeelStrike* impact = nullptr);

// Integrals accumulated while simulating, for the gait objective (eq. 9) and energy checks.
struct TorqueIntegrals {
  JointTorques squared{};  // ∫ τ_j² dt per joint (stance knee, swing knee, hip, torso, ankle)
  double work = 0;         // ∫ Q_applied · q̇ dt: work of all applied joint torques
  // ∫ max(0, clearance_margin − h)² dt while the swing foot passes the stance foot, h the
  // swing sole's height: how far the swing foot scuffs (the dynamics ignore scuffing, as in
  // McGeer's walkers; the gait optimisation must not).
  double scuff = 0;
  // The lowest swing-sole height while the swing foot passes the stance foot (within the
  // passing window), at the integrator's step ends, model length; +inf if it never passed.
  // Negative: the sole went through the ground, which the dynamics ignore.
  double passing_clearance = std::numeric_limits<double>::infinity();
  // The swing knee's largest flexion over the stride, at the integrator's step ends, rad.
  double max_swing_knee_flexion = 0;
};

// Step and event settings, in units of the model's natural time √(L/g) (0.31 s for a
// 1.75 m adult) so that they suit any body size.
struct SimulationOptions {
  double max_step = 0.02;             // RK4 step, natural time units, (0, 0.2]
  double event_time_tolerance = 1e-12;  // events are localised within this, natural time units
  double max_stride_duration = 6.0;   // a longer stride counts as a fall, natural time units
  double min_hip_height = 0.5;        // a hip lower than this × leg length is a fall
  double knee_sticking_rate = 1e-3;   // a knee leaving its limit slower stays on it, rad per natural time
  double passing_window = 0.15;       // the swing foot passes the stance foot within ± this × leg length
  double clearance_margin = 0.01;     // swing-sole height below which passing counts as scuffing, × leg length
  // More events than this in one advance() (knee limits chattering ever faster: a Zeno
  // sequence that some noisy particle states reach) freeze the walker as fallen.
  int max_events_per_advance = 200;
  // A heel strike whose landing would need the ground to pull (HeelStrike::physical() false:
  // the toe-off impulse has launched the body, and stopping the landing foot without slip
  // would hold it down) is a fall: the foot would slide or the walker fly, which this model
  // of walking has no phase for. The walker is frozen as it touches. The gait optimiser turns
  // this off, to see its landing constraint go on smoothly below zero.
  bool fall_at_pulling_landing = true;
  // A swing sole deeper below the ground than this × leg length is a fall. The dynamics ignore
  // a swing foot that scuffs while passing (McGeer's walkers do), and a foot that went under
  // the ground there never strikes it (a heel strike is a crossing from above): it would walk on
  // through the ground, as far as 0.4 m below it, and such a walker is no walking person. The
  // shipped gaits dip at most 0.024 L passing the stance foot.
  // The gait optimiser turns this off (infinity), to keep its stride function smooth, and then
  // checks its optima with it on (OptimalGait::walks_at_runtime).
  double max_swing_penetration = 0.03;
};

struct AdvanceReport {
  int heel_strikes = 0;
  // Heel strikes whose landing needed the ground to pull (HeelStrike::physical() false): a
  // fall (fell is set), unless SimulationOptions::fall_at_pulling_landing is off, when they
  // are simulated as any other and counted.
  int pulling_heel_strikes = 0;
  // The ground's normal impulse at the last heel strike's new contact (HeelStrike::
  // ground_normal_impulse), model momentum units; 0 if there was none.
  double last_landing_impulse = 0;
  int knee_limit_events = 0;
  bool fell = false;
  double elapsed = 0;  // model time actually simulated (less than asked at a stop or a fall)
};

struct StrideResult {
  WalkerState end;           // after the heel strike, legs swapped: S(x0, θ, γ)
  double duration = 0;       // model time
  double step_length = 0;    // hip displacement along the ground, model length
  double speed = 0;          // step_length / duration
  bool completed = false;    // false: fell before the next heel strike (or at it, see below)
  bool pulling_heel_strike = false;  // the heel strike needed the ground to pull: a fall (see AdvanceReport)
  double landing_impulse = 0;        // the ground's normal impulse at that heel strike, M √(gL)
  TorqueIntegrals integrals;
};

class WalkerSimulator {
 public:
  explicit WalkerSimulator(const WalkerModel& model, const SimulationOptions& options = {});

  const WalkerModel& model() const { return model_; }
  const KinematicMap& map() const { return map_; }
  double naturalTime() const { return natural_time_; }  // √(L/g), model time units

  // Advances the state by `duration` model time; any number of heel strikes and knee-limit
  // events are handled inside. Torque integrals are added to `integrals` if given.
  //
  // The RK4 steps lie on a grid that starts at the last event (heel strike or knee limit):
  // whole steps of max_step, however the time is split into advance() calls, so that a stride
  // advanced frame by frame is the same, bit for bit, as the stride advanced at once (a gait
  // that repeats under stride() repeats in the tracker's frames). An advance() that ends inside
  // a step takes the whole step (or the part up to an event, which is then applied when the
  // state gets there) and keeps it in state.step; q and q̇ are then the step's cubic Hermite
  // interpolant at the time asked (O(h⁴)), and the next advance() goes on from the step's end.
  // Its torque integrals hold whole steps. A state whose q or q̇ was changed since is taken
  // as new: its knees are first put on their limits if beyond or moving into them.
  AdvanceReport advance(const WalkerControls& controls, WalkerState& state, double duration,
                        TorqueIntegrals* integrals = nullptr) const;

  // The stride function S(x0, θ, γ) of §3.3: from `start` to the first heel strike.
  StrideResult stride(const WalkerControls& controls, const WalkerState& start) const;

  // Absolute position of a walker point (map().hip, ...) in the slope frame.
  Point pointPosition(const PointMap& point, const WalkerState& state) const {
    return position(map_, point, state.q, state.stance_foot_x);
  }
  // Kinetic plus gravitational energy (springs' effect is work; see TorqueIntegrals).
  double mechanicalEnergy(const WalkerControls& controls, const WalkerState& state) const;

 private:
  struct Derivative;
  Derivative derivative(const WalkerControls& controls, const Point& gravity, const Vector5& q, const Vector5& qdot,
                        const KneeFlags& on_limit) const;
  void rk4(const WalkerControls& controls, const WalkerState& from, double h, WalkerState& to,
           TorqueIntegrals* integrals) const;
  AdvanceReport run(const WalkerControls& controls, WalkerState& state, double duration,
                    bool stop_at_heel_strike, TorqueIntegrals* integrals) const;
  void applyKneeLimit(WalkerState& state, int knee) const;
  // Puts a state inside its step at `done` model time from the step's start (the Hermite
  // interpolant), or at the step's end itself.
  static void interpolateStep(WalkerState& state, double done);
  // Whether the state is still the integrator's: q and q̇ as the integrator left them.
  static bool isIntegratorState(const WalkerState& state);
  // What the event and fall checks need of a pose, from one set of phasors.
  struct Geometry {
    double swing_clearance;   // swing sole height above the ground
    double swing_foot_ahead;  // swing foot centre ahead of the stance foot centre
    double hip_height;
  };
  Geometry geometry(const Vector5& q) const;
  bool hasFallen(const WalkerState& state, const Geometry& geometry) const;

  WalkerModel model_;
  KinematicMap map_;
  InertiaCoefficients inertia_;
  SimulationOptions options_;
  double natural_time_;
};

}  // namespace kneed_walker::core::dynamics
