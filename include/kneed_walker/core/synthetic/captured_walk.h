// Real walks from motion capture (BVH), for test sequences whose motion neither the prior nor
// the gait norms made, drawn as a person unlike the tracker's body model: tapered limbs with
// arms that swing as captured, an oval head, a torso of its own breadth, clothing colours of
// a seed.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "kneed_walker/core/body/body_model.h"
#include "kneed_walker/core/vision/camera.h"

namespace kneed_walker::core::synthetic {

// A BVH file's joints in the world frame per frame: Z up, metres (BVH is Y up, here in
// `unit_m` metres per file unit). End sites are left out.
struct CapturedMotion {
  std::vector<std::string> joints;  // in the file's order
  std::vector<int> parents;         // -1 for the root
  double frame_time_s = 0;
  std::vector<std::vector<Eigen::Vector3d>> positions_m;  // [frame][joint]
  // The joint's index; throws std::invalid_argument naming the joint when there is none.
  int index(const std::string& name) const;
};

// Reads a BVH file: HIERARCHY (each joint's OFFSET and CHANNELS; position channels, when a
// joint has them, replace its offset) and MOTION; rotations in degrees, composed in the order
// their channels are listed. Throws std::invalid_argument naming the file and line.
CapturedMotion loadBvh(const std::string& path, double unit_m = 0.01);

// The captured skeleton's joints at time t (linear between frames, clamped at the ends).
std::vector<Eigen::Vector3d> jointsAt(const CapturedMotion& motion, double t_s);

// How a captured walk is placed in a scene: rotated about the vertical so that its overall
// direction of travel (first to last frame of its mid-hip) is `heading_rad`, and moved so that
// its first frame's mid-hip stands over `start_m`; the lowest point of its drawn feet (toes and
// heels, capturedHeel) over the whole walk a drawn foot's radius (CapturedFigure::foot_radius_m)
// above Z = 0.
struct CapturedPlacement {
  Eigen::Vector2d start_m = Eigen::Vector2d::Zero();
  double heading_rad = 0;
};
// The rigid motion (world from captured) that places `motion` so.
Eigen::Isometry3d placeCaptured(const CapturedMotion& motion, const CapturedPlacement& placement);

// The head's centre lies this far above the capture's Head joint (the top of the neck), along
// the neck: as the body model's head joint (0.928 of the height) for the captured people, whose
// Head joints sit about 0.84 of their height up.
constexpr double kHeadCentreAboveHeadJoint_m = 0.12;

// The REP 155 joints of a captured pose (the mapping of ../shared/data/mocap/README.md: hips
// UpperLeg_*, knees LowerLeg_*, ankles Foot_*, neck Neck, waist their hips' mean; the head the
// head's centre, kHeadCentreAboveHeadJoint_m above Head); forward along the travel direction,
// up Z. Throws std::invalid_argument naming a missing joint.
body::BodyPose capturedBodyPose(const CapturedMotion& motion, const std::vector<Eigen::Vector3d>& joints,
                                const Eigen::Vector3d& forward);

// The drawn person: sizes in metres, BGR colours.
struct CapturedFigure {
  double breadth_scale = 1.0;  // of the limbs' and torso's widths below
  double torso_half_width_m = 0.17, thigh_radius_m = 0.075, shank_radius_m = 0.05;
  double upper_arm_radius_m = 0.045, forearm_radius_m = 0.035, foot_radius_m = 0.045;
  // The heel's centre below the ankle, square to the foot's axis: the capture's ankles stand
  // 0.12 m above its toes' soles, and a foot drawn from the ankle to the toes alone walks on
  // tiptoe, its heel 7 cm in the air.
  double heel_below_ankle_m = 0.08;
  double head_radius_m = 0.11;
  cv::Scalar skin, top, bottom, shoes;
};
// The drawn heel's centre for a foot's ankle and toes joints (world, Z up): heel_below_ankle_m
// from the ankle, square to the ankle-to-toes axis in its vertical plane, downwards.
Eigen::Vector3d capturedHeel(const Eigen::Vector3d& ankle, const Eigen::Vector3d& toes, const CapturedFigure& figure);

// A figure of a seed: breadth 0.8-1.5 and colours varied.
CapturedFigure capturedFigure(std::uint64_t seed);

// Paints the person (tapered limbs and arms, torso, head), farthest part first; parts partly
// behind the camera are skipped.
void drawCapturedPerson(cv::Mat& image, const vision::Camera& camera, const CapturedMotion& motion,
                        const std::vector<Eigen::Vector3d>& joints, const CapturedFigure& figure);

}  // namespace kneed_walker::core::synthetic
