// Equations of motion of the Kneed Walker (paper §3–3.2), derived by the TMT method from a
// KinematicMap (walker_kinematics.h):
//   M(q) = Tᵀ M̄ T,   F(q, q̇) = Tᵀ (f − M̄ g_conv) + τ,   M(q) q̈ = F      (paper eq. 4)
// with T = ∂X/∂q, M̄ = diag(m, m, I) per body, f the gravity forces and g_conv the convective
// accelerations (∂(T q̇)/∂q) q̇. Units are the model's (see walker_model.h).
//
// Everything here is a pure function of (map, inputs): no allocation, no state, safe to call
// from many threads at once.
#pragma once

#include <array>
#include <cmath>

#include "kneed_walker/core/dynamics/walker_kinematics.h"

namespace kneed_walker::core::dynamics {

// Spring parameters θ of the joint torques (paper eqs. 1–3). Torque units are the model's
// (N·m in SI); stiffness per rad, damping per rad/s.
struct SpringParameters {
  double stance_knee_stiffness = 0;  // κK1 (rest angle φ⁰K1 = 0)
  double stance_knee_damping = 0;    // dK1
  double swing_knee_stiffness = 0;   // κK2
  double swing_knee_rest_angle = 0;  // φ⁰K2, knee flexion, rad
  double swing_knee_damping = 0;     // dK2
  double hip_stiffness = 0;          // κH (undamped, rest angle 0)
  double torso_stiffness = 0;        // κTo
  double torso_rest_angle = 0;       // φ⁰To, absolute, rad
  double torso_damping = 0;          // dTo
};

// Additive torques besides the springs: the process noise η of paper eq. 11, held over a
// frame. stance_ankle is the stance leg's torque against the ground.
struct TorqueOffsets {
  double stance_knee = 0;
  double swing_knee = 0;
  double hip = 0;
  double torso = 0;
  double stance_ankle = 0;
};

// Everything besides the state that the motion depends on: F(q, q̇, θ, γ) and the impulse ι.
struct WalkerControls {
  SpringParameters springs;
  TorqueOffsets offsets;
  double toe_off_impulse = 0;  // ι ≥ 0, applied at heel strike along the trailing leg (eq. 5)
  double ground_slope = 0;     // γ, rad, positive uphill
};

// The four joint torques of the paper and the ground torque, model torque units.
enum Joint : int { kStanceKnee = 0, kSwingKnee, kHip, kTorsoJoint, kStanceAnkle, kNumJoints };
using JointTorques = std::array<double, kNumJoints>;

// Spring torques (eqs. 1–3) plus offsets. Knee flexion is φ_thigh − φ_shank.
JointTorques jointTorques(const WalkerControls& controls, const Vector5& q, const Vector5& qdot);

// The joint torques as generalised forces on the absolute angles. Each torque acts on the
// angle it is written in and reacts on the neighbouring segment: knees thigh/shank, hip
// stance/swing thigh, torso/stance thigh (the paper is silent on which thigh takes the
// torso's reaction: the stance thigh, which carries the torso), ankle stance shank/ground.
Vector5 generalisedForce(const JointTorques& torques);

// The TMT sums over bodies condensed into constants of the map. With the velocity
// coefficients T_bj = i w_bj e^{i q_j} (plus −R on the rolling coordinate),
//   M_jk = Re(C_jk e^{i(q_k − q_j)}) + R Im(D_j e^{i q_j}) [k = roll] + R Im(D_k e^{i q_k}) [j = roll]
//          + R² m [j = k = roll] + I_j [j = k],
//   F_j  = Σ_k q̇_k² Im(C_jk e^{i(q_k − q_j)}) + Re(conj(i D_j e^{i q_j}) g) + rolling terms,
// with C_jk = Σ_b m_b conj(w_bj) w_bk and D_j = Σ_b m_b w_bj: one complex product per
// coordinate pair, the hot path of every particle.
struct InertiaCoefficients {
  std::array<std::array<Point, kNumCoordinates>, kNumCoordinates> c{};  // C_jk (Hermitian)
  std::array<Point, kNumCoordinates> d{};                               // D_j
  std::array<double, kNumCoordinates> inertia{};  // Σ I_b of the bodies whose angle is q_j
  double total_mass = 0;
  double foot_radius = 0;
  int rolling_coordinate = kStanceShank;
};
InertiaCoefficients inertiaCoefficients(const KinematicMap& map);

// M(q) and F(q, q̇) of eq. 4 for the given applied generalised forces.
struct EquationsOfMotion {
  Matrix5 mass;   // M(q), symmetric positive definite
  Vector5 force;  // F(q, q̇, θ, γ)
};
// `gravity` is slopeGravity(g, γ): computed once per step by the caller, not per evaluation.
void equationsOfMotion(const InertiaCoefficients& inertia, const Point& gravity, const Vector5& q,
                       const Vector5& qdot, const Vector5& applied_force, EquationsOfMotion& out);
// Gravity's acceleration in the slope frame (x down the walking direction along the slope, y
// along its normal) on a slope γ (positive uphill): g (−sin γ, −cos γ).
inline Point slopeGravity(double gravity, double ground_slope) {
  return gravity * Point(-std::sin(ground_slope), -std::cos(ground_slope));
}

// Knee joint limits a_jᵀ q ≤ b_j (paper §3.2), written here as flexion_j ≥ 0 with flexion
// rows a_j = e_thigh − e_shank: index 0 the stance knee, 1 the swing knee.
constexpr int kNumKnees = 2;
using KneeFlags = std::array<bool, kNumKnees>;
Vector5 kneeFlexionRow(int knee);
inline double kneeFlexion(const Vector5& q, int knee) { return kneeFlexionRow(knee).dot(q); }

// q̈ with the knees on their limit held there by virtual torques where the free motion would
// hyperextend them (eqs. 7–8; the active set is chosen so that every virtual torque pushes
// and no free knee accelerates into its limit). `active` returns which constraints held.
Vector5 constrainedAcceleration(const EquationsOfMotion& eom, const KneeFlags& on_limit,
                                KneeFlags* active = nullptr);

// Perfectly inelastic knee-limit collision (eq. 6) for the knees in `knees`: the knees whose
// limit impulse is needed lose their flexion velocity (minimal change in the metric M(q));
// the others keep flexing away. A knee that would leave slower than `sticking_rate` (rad per
// model time) stays on its limit, which ends the endless ping-pong of two knees kicking each
// other off their limits with ever smaller rates (a resting-contact threshold).
Vector5 projectKneeVelocity(const Matrix5& mass, const Vector5& qdot, const KneeFlags& knees,
                            double sticking_rate = 0);

// Least-squares projection (in the metric M) of q onto the limits of the knees in `knees`:
// the paper's final projection that removes numerical drift.
Vector5 projectKneePosition(const Matrix5& mass, const Vector5& q, const KneeFlags& knees);

// Heel strike (paper eq. 5): the swing foot lands, perfectly inelastic and without slip, the
// old stance foot is released, the toe-off impulse ι acts at the old stance foot's contact
// point towards the hip, and knees on their limit stay there unless the impact flexes them.
// An impact that would drive the trailing sole into the ground holds it on the ground instead
// (an inelastic, frictionless contact: the sole leaves with no normal velocity; beyond the
// paper, which is silent). An impact that needs the ground to pull on the landing foot (with no slip, the
// ground's tangential impulse can ask for it) is no heel strike of this model: physical() is
// false, and the simulator makes it a fall (SimulationOptions::fall_at_pulling_landing).
// Returns q̇⁺ in the same (pre-swap) labels; swapping legs is the caller's job.
struct HeelStrike {
  Vector5 qdot_after;
  KneeFlags knees_held{};             // knees whose limit impulse was needed
  double ground_normal_impulse = 0;   // along the ground normal at the new contact, ≥ 0 physically
  bool trailing_sole_held = false;    // the impact would have driven the trailing sole into the ground
  double trailing_sole_impulse = 0;   // the ground's normal impulse on a held trailing sole, ≥ 0
  double trailing_sole_rate = 0;      // the old stance sole's velocity along the ground normal
                                      // after the impact: > 0 lifting, 0 held
  bool solved = false;                // an active set of knees and soles was found

  bool physical() const { return solved && ground_normal_impulse >= -1e-12; }
};
HeelStrike heelStrike(const KinematicMap& map, const Vector5& q, const Vector5& qdot,
                      double toe_off_impulse, const KneeFlags& knees_on_limit);

// Total mechanical energy: kinetic ½ q̇ᵀMq̇ plus gravitational potential (springs excluded:
// their effect is counted as work), model energy units.
double mechanicalEnergy(const KinematicMap& map, double gravity, double ground_slope,
                        const Vector5& q, const Vector5& qdot, double x0);

// Angular momentum of the whole walker about a fixed point, with the stance foot rolling.
double angularMomentum(const KinematicMap& map, const Vector5& q, const Vector5& qdot, double x0,
                       Point about);

}  // namespace kneed_walker::core::dynamics
