#include "kneed_walker/core/body/body_model.h"

#include <Eigen/Geometry>

#include <cmath>

namespace kneed_walker::core::body {
namespace {

constexpr int kLeft = 0, kRight = 1;

}  // namespace

const char* jointName(BodyJoint joint) {
  static const char* const kNames[kNumBodyJoints] = {
      "waist", "neck", "head", "l_hip", "r_hip", "l_knee", "r_knee", "l_ankle", "r_ankle"};
  return kNames[joint];
}

const char* partName(BodyPart part) {
  static const char* const kNames[kNumBodyParts] = {"torso",   "head",    "l_thigh", "r_thigh",
                                                    "l_shank", "r_shank", "l_foot",  "r_foot"};
  return kNames[part];
}

BodyShape BodyShape::forHeight(double h) {
  BodyShape shape;
  shape.hip_width_m = 0.100 * h;     // hip joint centres (inferred; hip breadth is 0.191 H)
  shape.ankle_height_m = 0.039 * h;  // Drillis & Contini
  shape.neck_length_m = 0.110 * h;   // shoulder line (0.818 H) to the head's centre
  shape.foot_length_m = 0.152 * h;   // Drillis & Contini
  // {proximal width, depth, distal width, depth} as fractions of height.
  auto part = [h](double pw, double pd, double dw, double dd) {
    return PartShape{pw * h, pd * h, dw * h, dd * h};
  };
  shape.parts[kTorsoPart] = part(0.19, 0.12, 0.21, 0.13);  // hips to shoulder line
  shape.parts[kHeadPart] = part(0.09, 0.11, 0.09, 0.11);
  shape.parts[kLeftThighPart] = shape.parts[kRightThighPart] = part(0.09, 0.10, 0.06, 0.06);
  shape.parts[kLeftShankPart] = shape.parts[kRightShankPart] = part(0.06, 0.065, 0.04, 0.04);
  shape.parts[kLeftFootPart] = shape.parts[kRightFootPart] = part(0.05, 0.05, 0.055, 0.025);
  return shape;
}

BodyPose bodyPose(const dynamics::KinematicMap& map, const dynamics::WalkerState& state, double ground_slope,
                  const BodyPlacement& placement, const BodyShape& shape,
                  double metres_per_model_length) {
  BodyPose pose;
  // The slope frame in the world: forward along the ground, up along its normal.
  const double c = std::cos(placement.heading_rad), s = std::sin(placement.heading_rad);
  const Eigen::Vector3d heading(c, s, 0), vertical(0, 0, 1);
  pose.forward = std::cos(ground_slope) * heading + std::sin(ground_slope) * vertical;
  pose.up = -std::sin(ground_slope) * heading + std::cos(ground_slope) * vertical;
  pose.left = Eigen::Vector3d(-s, c, 0);
  const Eigen::Vector3d origin = Eigen::Vector3d(placement.ground_origin_m.x(),
                                                 placement.ground_origin_m.y(), 0) +
                                 placement.sway_m * pose.left;
  // Walker points are in model lengths; `vector` and `world` return metres.
  const double scale = metres_per_model_length;
  auto vector = [&](dynamics::Point p) {
    return Eigen::Vector3d(scale * (p.real() * pose.forward + p.imag() * pose.up));
  };
  auto world = [&](dynamics::Point p, double lateral) {
    return Eigen::Vector3d(origin + vector(p) + lateral * pose.left);
  };

  const auto e = dynamics::phasors(state.q);
  const dynamics::Point base = dynamics::stanceFootCentre(map, state.q, state.stance_foot_x);
  auto at = [&](const dynamics::PointMap& p) { return base + dynamics::relativePosition(p, e); };
  const dynamics::Point hip = at(map.hip), shoulder = at(map.shoulder);
  const dynamics::Point down_torso(std::sin(state.q[dynamics::kTorso]), -std::cos(state.q[dynamics::kTorso]));  // d(φTo)

  pose.joints[kWaist] = world(hip, 0);
  pose.joints[kNeck] = world(shoulder, 0);
  pose.joints[kHead] = world(shoulder - (shape.neck_length_m / scale) * down_torso, 0);

  // Legs: the stance leg is the walker's stance leg; each hangs from its hip joint.
  const int stance = state.stance_leg == dynamics::Leg::kLeft ? kLeft : kRight;
  const double ankle_from_knee = map.shank_length - shape.ankle_height_m / scale;
  for (int side : {kLeft, kRight}) {
    const bool is_stance = side == stance;
    const dynamics::Point knee = at(is_stance ? map.stance_knee : map.swing_knee);
    const dynamics::Point foot = is_stance ? base : at(map.swing_foot_centre);
    const double shank_angle = state.q[is_stance ? dynamics::kStanceShank : dynamics::kSwingShank];
    const dynamics::Point ankle = knee + ankle_from_knee * dynamics::Point(std::sin(shank_angle), -std::cos(shank_angle));
    const double outward = side == kLeft ? 1.0 : -1.0;
    const Eigen::Vector3d hip_joint = world(hip, 0.5 * outward * shape.hip_width_m);
    Eigen::Vector3d thigh = vector(knee - hip), shank = vector(ankle - knee),
                    to_foot = vector(foot - knee);
    // Hip rotation turns the shank about the thigh; abduction turns the leg outwards about the
    // forward axis.
    const Eigen::AngleAxisd rotation(outward * placement.hip_rotation_rad[side], thigh.normalized());
    shank = rotation * shank;
    to_foot = rotation * to_foot;
    const Eigen::AngleAxisd abduction(outward * placement.hip_abduction_rad[side], pose.forward);
    thigh = abduction * thigh;
    shank = abduction * shank;
    to_foot = abduction * to_foot;
    const int hip_joint_index = side == kLeft ? kLeftHip : kRightHip;
    pose.joints[hip_joint_index] = hip_joint;
    pose.joints[hip_joint_index + 2] = hip_joint + thigh;          // knee
    pose.joints[hip_joint_index + 4] = hip_joint + thigh + shank;  // ankle
    pose.foot_centres[side] = hip_joint + thigh + to_foot;
  }
  // The stance foot rests on the ground as the walker's does: a turned-out stance leg is
  // shorter in the sagittal plane, which lowers the body rather than lifting the foot.
  const double lift = (pose.foot_centres[stance] - world(base, 0)).dot(pose.up);
  const Eigen::Vector3d down = -lift * pose.up;
  for (Eigen::Vector3d& joint : pose.joints) joint += down;
  for (Eigen::Vector3d& foot : pose.foot_centres) foot += down;
  pose.ground_point_m = origin;  // the slope frame's origin lies on the ground (y = 0)
  return pose;
}

FootGeometry FootGeometry::of(const dynamics::BodyProportions& proportions, double height_m) {
  const double leg_m = proportions.leg_length_per_height * height_m;
  FootGeometry foot;
  foot.centre_from_knee_m = (proportions.shank.length - proportions.foot_radius) * leg_m;
  foot.radius_m = proportions.foot_radius * leg_m;
  foot.offset_angle_rad = proportions.foot_offset_angle;
  foot.ankle_height_m = BodyShape::forHeight(height_m).ankle_height_m;
  return foot;
}

RollingFoot rollingFoot(const Eigen::Vector3d& knee_m, const Eigen::Vector3d& ankle_m, const Eigen::Vector3d& forward,
                        const Eigen::Vector3d& up, const FootGeometry& foot) {
  // In the leg's plane the foot centre is along d(φ + e) = cos e·d(φ) + sin e·n(φ), n(φ) the
  // in-plane normal on the forward side; turning the leg out about `forward` keeps `forward`
  // in that plane, so n is `forward` made orthogonal to the shank.
  const Eigen::Vector3d shank = (ankle_m - knee_m).normalized();
  const Eigen::Vector3d normal = (forward - forward.dot(shank) * shank).normalized();
  RollingFoot result;
  result.centre_m = knee_m + foot.centre_from_knee_m *
                                 (std::cos(foot.offset_angle_rad) * shank + std::sin(foot.offset_angle_rad) * normal);
  result.roll_rad = std::atan2(shank.dot(forward), -shank.dot(up));
  return result;
}

double torsoLeanRad(const Eigen::Vector3d& waist_m, const Eigen::Vector3d& neck_m, const Eigen::Vector3d& heading) {
  const Eigen::Vector3d torso = neck_m - waist_m;
  return std::atan2(torso.dot(heading), torso.z());
}

double kneeFlexionRad(const Eigen::Vector3d& hip_m, const Eigen::Vector3d& knee_m, const Eigen::Vector3d& ankle_m) {
  const Eigen::Vector3d thigh = knee_m - hip_m, shank = ankle_m - knee_m;
  return std::atan2(thigh.cross(shank).norm(), thigh.dot(shank));
}

}  // namespace kneed_walker::core::body
