// The 3D kinematic body model conditioned on the planar walker (paper §3.4): the walker fixes
// the sagittal motion (hip and knee flexion, torso pitch, progression along the ground); the
// other degrees of freedom (heading, position, sideways sway, hip abduction and rotation) come
// from BodyPlacement, which the prior drives as damped 2nd-order Markov processes. Joints are
// named as in REP 155. The walker's rolling foot is rigid with its shank, so the ankle hinge
// adds no joint position here; it belongs to the body shapes of the likelihood.
//
// World frame: metres, Z up (REP 103), as the camera's. The walker's slope frame (x along the
// ground in the walking direction, y along the ground normal) is placed at `ground_origin` and
// turned to `heading`; the ground rises by the slope along the heading.
#pragma once

#include <Eigen/Core>

#include <array>
#include <string>

#include "kneed_walker/core/dynamics/walker_simulation.h"

namespace kneed_walker::core::body {

// REP 155 joint names (without the body id suffix).
enum BodyJoint : int {
  kWaist = 0,  // mid-hip: the body root
  kNeck,
  kHead,
  kLeftHip,
  kRightHip,
  kLeftKnee,
  kRightKnee,
  kLeftAnkle,
  kRightAnkle,
  kNumBodyJoints
};
const char* jointName(BodyJoint joint);  // "waist", "neck", "head", "l_hip", ...

// The body's volume for the image likelihood: tapered elliptical cylinders, one per part.
enum BodyPart : int {
  kTorsoPart = 0,
  kHeadPart,
  kLeftThighPart,
  kRightThighPart,
  kLeftShankPart,
  kRightShankPart,
  kLeftFootPart,
  kRightFootPart,
  kNumBodyParts
};
const char* partName(BodyPart part);  // "torso", "head", "l_thigh", ...

// A part's cross-sections at its proximal and distal ends: ellipses with one axis across the
// body (width) and one square to it (depth), tapering linearly between the ends.
struct PartShape {
  double proximal_width_m = 0, proximal_depth_m = 0;
  double distal_width_m = 0, distal_depth_m = 0;
};

// Body dimensions that the planar walker does not have, from a person's height (Drillis &
// Contini's proportions, in Winter's Biomechanics and Motor Control of Human Movement; part
// breadths inferred from Winter's anthropometry, as the paper set its sizes by hand).
struct BodyShape {
  double hip_width_m = 0;     // between the hip joints
  double ankle_height_m = 0;  // ankle above the sole
  double neck_length_m = 0;   // shoulder line to the head's centre
  double foot_length_m = 0;   // heel to toe
  std::array<PartShape, kNumBodyParts> parts;
  static BodyShape forHeight(double height_m);
};

// The kinematic degrees of freedom beyond the walker's. Per-leg arrays are [left, right].
struct BodyPlacement {
  Eigen::Vector2d ground_origin_m = Eigen::Vector2d::Zero();  // world (X, Y) of the slope-frame origin
  double heading_rad = 0;      // walking direction in the world XY plane, from +X towards +Y
  double sway_m = 0;           // sideways offset of the whole body (to its left)
  std::array<double, 2> hip_abduction_rad{};  // leg turned outwards about the forward axis
  std::array<double, 2> hip_rotation_rad{};   // about the thigh (turns the bent knee's shank)
};

struct BodyPose {
  std::array<Eigen::Vector3d, kNumBodyJoints> joints;  // world, metres
  std::array<Eigen::Vector3d, 2> foot_centres;         // centres of the rolling feet [left, right]
  Eigen::Vector3d forward;  // unit walking direction along the ground
  Eigen::Vector3d up;       // unit ground normal
  Eigen::Vector3d left;     // unit lateral direction, up × forward
  // A point of the ground the stance foot rolls on (the plane through it square to `up`): the
  // synthetic sequences draw the feet standing on it (vision::standFeetOnGround).
  Eigen::Vector3d ground_point_m = Eigen::Vector3d::Zero();
};

// The 3D pose of a walker state. The stance foot rests on the ground: when the stance leg is
// turned out (abduction, or rotation with a bent knee) the body is lowered to keep it there.
// `ground_slope` is the walker's γ (positive uphill).
// `map` is the walker's (WalkerSimulator::map()); `metres_per_model_length` converts its lengths: 1 for a walker in SI units
// (scaleToPerson), the person's leg length L for a dimensionless one (the gait table's).
BodyPose bodyPose(const dynamics::KinematicMap& map, const dynamics::WalkerState& state,
                  double ground_slope, const BodyPlacement& placement, const BodyShape& shape,
                  double metres_per_model_length = 1.0);

// A leg's rolling foot recovered from its knee and ankle, as a pose CSV gives them (the inverse
// of bodyPose's leg, for measuring contact: evaluate's foot skate and ground penetration).
// The foot's centre lies (ℓS − R)·L from the knee, turned from the shank's axis by the foot's
// offset angle e towards `forward` (walker_kinematics.h); `roll_rad` is the shank's angle from
// the ground normal, the angle the foot has rolled through. Exact for a leg turned out
// (abduction); with hip rotation of a bent knee, approximate.
struct FootGeometry {
  double centre_from_knee_m = 0;  // (ℓS − R)·L
  double radius_m = 0;            // R·L
  double offset_angle_rad = 0;    // e
  double ankle_height_m = 0;      // the ankle above the sole, BodyShape's
  static FootGeometry of(const dynamics::BodyProportions& proportions, double height_m);
};
struct RollingFoot {
  Eigen::Vector3d centre_m = Eigen::Vector3d::Zero();
  double roll_rad = 0;
};
// `forward` and `up` are the pose's unit walking direction along the ground and ground normal.
RollingFoot rollingFoot(const Eigen::Vector3d& knee_m, const Eigen::Vector3d& ankle_m, const Eigen::Vector3d& forward,
                        const Eigen::Vector3d& up, const FootGeometry& foot);

// Sagittal posture read back from a pose's joints (evaluate's torso lean and knee bend at
// contact, the paper's Fig. 5 findings). The torso's forward lean from the vertical (world Z),
// positive towards `heading` (the horizontal unit walking direction): the waist-to-neck line's
// angle; for a body in the walker's plane, −φTo − γ (walker angles are measured from the slope's
// normal, counter-clockwise).
double torsoLeanRad(const Eigen::Vector3d& waist_m, const Eigen::Vector3d& neck_m, const Eigen::Vector3d& heading);
// A knee's flexion: the angle between the thigh (hip to knee) and the shank (knee to ankle), 0
// when straight; for a body in the walker's plane, |φthigh − φshank|.
double kneeFlexionRad(const Eigen::Vector3d& hip_m, const Eigen::Vector3d& knee_m, const Eigen::Vector3d& ankle_m);

}  // namespace kneed_walker::core::body
