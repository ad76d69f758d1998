#include "kneed_walker/core/synthetic/norm_walk.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "kneed_walker/core/common/config_file.h"
#include "kneed_walker/core/common/random.h"
#include "kneed_walker/core/dynamics/walker_kinematics.h"

namespace kneed_walker::core::synthetic {

namespace {

constexpr double kRadiansPerDegree = M_PI / 180.0;
constexpr double kSubstepS = 0.001;  // contact changes are found to within this

struct ClassSpeed {
  const char* name;
  double dimensionless_speed;
};
constexpr std::array<ClassSpeed, 5> kClassSpeeds = {{{"Very Slow", 0.16}, {"Slow", 0.30}, {"Free", 0.43},
                                                     {"Fast", 0.57}, {"Very Fast", 0.70}}};
const char* const kTrunkTilt = "Trunk Ant/Posterior Tilt";
const char* const kPelvicTilt = "Pelvic Ant/Posterior Tilt";
const char* const kHipFlexion = "Hip Flex/Extension";
const char* const kKneeFlexion = "Knee Flex/Extension";
const char* const kHipAdduction = "Hip Ad/Abduction";
const char* const kPelvicObliquity = "Pelvic Up/Down Obliquity";

struct LegAngles {
  double thigh = 0, shank = 0, abduction = 0;  // rad: the walker's absolute angles; outwards
};
struct BodyAngles {
  double torso = 0;  // rad, the walker's (a forward lean is negative)
  std::array<LegAngles, 2> legs;  // [left, right]
};

int sideOf(dynamics::Leg leg) { return leg == dynamics::Leg::kLeft ? 0 : 1; }

// The norms' angles in the walker's terms, blended between the two speed classes around v*.
class BlendedNorms {
 public:
  // torso_lean_rad: the torso's mean forward lean in the walker's frame (from the ground's normal).
  BlendedNorms(const gait::GaitNorms& norms, double torso_lean_rad) : torso_lean_rad_(torso_lean_rad) {
    for (const ClassSpeed& c : kClassSpeeds) {
      const gait::NormSpeedClass& speed_class = norms.speedClass(c.name);
      for (const char* angle : {kTrunkTilt, kPelvicTilt, kHipFlexion, kKneeFlexion, kHipAdduction, kPelvicObliquity})
        speed_class.curve(angle);  // throws naming a missing one
      const gait::NormCurve& trunk = speed_class.curve(kTrunkTilt);
      double sum = 0;  // the cycle's mean; the last sample repeats the first
      for (std::size_t i = 0; i + 1 < trunk.mean.size(); ++i) sum += trunk.mean[i];
      classes_.push_back(&speed_class);
      trunk_means_deg_.push_back(sum / static_cast<double>(trunk.mean.size() - 1));
    }
  }

  BodyAngles at(double phase, double dimensionless_speed) const {
    std::size_t upper = 0;
    while (upper < kClassSpeeds.size() && kClassSpeeds[upper].dimensionless_speed < dimensionless_speed) ++upper;
    if (upper == 0) return ofClass(0, phase);
    if (upper == kClassSpeeds.size()) return ofClass(upper - 1, phase);
    const double v0 = kClassSpeeds[upper - 1].dimensionless_speed, v1 = kClassSpeeds[upper].dimensionless_speed;
    const double f = (dimensionless_speed - v0) / (v1 - v0);
    const BodyAngles a = ofClass(upper - 1, phase), b = ofClass(upper, phase);
    BodyAngles blended;
    blended.torso = (1 - f) * a.torso + f * b.torso;
    for (int side : {0, 1}) {
      blended.legs[side].thigh = (1 - f) * a.legs[side].thigh + f * b.legs[side].thigh;
      blended.legs[side].shank = (1 - f) * a.legs[side].shank + f * b.legs[side].shank;
      blended.legs[side].abduction = (1 - f) * a.legs[side].abduction + f * b.legs[side].abduction;
    }
    return blended;
  }

 private:
  BodyAngles ofClass(std::size_t k, double phase) const {
    const gait::NormSpeedClass& c = *classes_[k];
    const double pelvic_tilt_deg = c.curve(kPelvicTilt).meanAt(phase);
    BodyAngles a;
    a.torso = -(torso_lean_rad_ + kRadiansPerDegree * (c.curve(kTrunkTilt).meanAt(phase) - trunk_means_deg_[k]));
    for (int side : {0, 1}) {
      const double leg_phase = phase + 0.5 * side;
      LegAngles& leg = a.legs[side];
      leg.thigh = kRadiansPerDegree * (c.curve(kHipFlexion).meanAt(leg_phase) - pelvic_tilt_deg);
      leg.shank = leg.thigh - kRadiansPerDegree * c.curve(kKneeFlexion).meanAt(leg_phase);
      // From the vertical: the pelvis is level in the body model, so its obliquity goes to the leg.
      leg.abduction = kRadiansPerDegree * (c.curve(kPelvicObliquity).meanAt(leg_phase) -
                                           c.curve(kHipAdduction).meanAt(leg_phase));
    }
    return a;
  }

  double torso_lean_rad_;
  std::vector<const gait::NormSpeedClass*> classes_;
  std::vector<double> trunk_means_deg_;
};

dynamics::Vector5 coordinates(const BodyAngles& a, dynamics::Leg stance) {
  const LegAngles& on = a.legs[sideOf(stance)];
  const LegAngles& off = a.legs[1 - sideOf(stance)];
  dynamics::Vector5 q;
  q << a.torso, on.thigh, on.shank, off.thigh, off.shank;
  return q;
}

// The hip's height above the ground (model lengths) when the stance leg of q carries it.
double hipHeight(const dynamics::KinematicMap& map, const dynamics::Vector5& q) {
  return map.foot_radius + dynamics::relativePosition(map.hip, dynamics::phasors(q)).imag();
}

// The walker's contact: which leg stands, where, and since when. The stance leg is the one that
// holds the hip higher; contact passes to the leading leg when it does (a heel strike), its
// foot centre becoming the rolling base where it is.
struct Contact {
  dynamics::Leg stance = dynamics::Leg::kLeft;
  double stance_foot_x = 0;  // x0, model lengths
  std::uint32_t heel_strikes = 0;

  void start(const dynamics::KinematicMap& map, const BodyAngles& a) {
    const bool left = hipHeight(map, coordinates(a, dynamics::Leg::kLeft)) >=
                      hipHeight(map, coordinates(a, dynamics::Leg::kRight));
    stance = left ? dynamics::Leg::kLeft : dynamics::Leg::kRight;
    stance_foot_x = 0;
  }

  // Returns whether contact passed to the other leg.
  bool update(const dynamics::KinematicMap& map, const BodyAngles& a) {
    const dynamics::Vector5 q = coordinates(a, stance);
    const dynamics::Vector5 q_other = coordinates(a, dynamics::otherLeg(stance));
    if (!(q[dynamics::kSwingThigh] > q[dynamics::kStanceThigh] && hipHeight(map, q_other) > hipHeight(map, q)))
      return false;
    const dynamics::Point foot = dynamics::position(map, map.swing_foot_centre, q, stance_foot_x);
    stance = dynamics::otherLeg(stance);
    stance_foot_x = foot.real() + map.foot_radius * q_other[map.rolling_coordinate];
    ++heel_strikes;
    return true;
  }
};

dynamics::KinematicMap normWalkerMap(const dynamics::BodyProportions& proportions) {
  return dynamics::kneedWalkerMap(dynamics::dimensionlessWalker(proportions));
}

double strideLength(const dynamics::KinematicMap& map, const BlendedNorms& blended, double dimensionless_speed) {
  // Two cycles from phase 0; the hip's advance over the second is the stride.
  constexpr int kStepsPerCycle = 2000;
  Contact contact;
  contact.start(map, blended.at(0.0, dimensionless_speed));
  double hip_x_after_one = 0;
  for (int i = 1; i <= 2 * kStepsPerCycle; ++i) {
    const BodyAngles a = blended.at(static_cast<double>(i) / kStepsPerCycle, dimensionless_speed);
    contact.update(map, a);
    if (i % kStepsPerCycle == 0) {
      const double hip_x = dynamics::position(map, map.hip, coordinates(a, contact.stance), contact.stance_foot_x).real();
      if (i == 2 * kStepsPerCycle) return hip_x - hip_x_after_one;
      hip_x_after_one = hip_x;
    }
  }
  return 0;  // not reached
}

}  // namespace

std::vector<std::string> validate(const NormWalkOptions& o) {
  std::vector<std::string> problems;
  auto number = [](double v) {
    std::ostringstream text;
    text << v;
    return text.str();
  };
  auto within = [&](const char* name, double v, double low, double high) {
    if (!(std::isfinite(v) && v >= low && v <= high))
      problems.push_back(std::string(name) + " must lie in [" + number(low) + ", " + number(high) + "]");
  };
  within("start_speed_kmh", o.start_speed_kmh, 0.5, 10.0);
  within("end_speed_kmh", o.end_speed_kmh, 0.5, 10.0);
  within("duration_s", o.duration_s, 0.01, 3600.0);
  within("fps", o.fps, 1.0, 1000.0);
  within("person_height_m", o.person_height_m, 1.0, 2.3);
  within("torso_lean_rad", o.torso_lean_rad, -0.5, 0.5);
  within("slope_rad", o.slope_rad, -0.2, 0.2);
  if (!std::isfinite(o.heading_rad)) problems.push_back("heading_rad must be finite");
  if (!o.start_m.allFinite()) problems.push_back("start_m must be finite");
  if (std::isfinite(o.duration_s * o.fps) && o.duration_s * o.fps > 100000)
    problems.push_back("duration_s * fps must be at most 100000 frames");
  return problems;
}

double nominalDimensionlessSpeed(const std::string& speed_class) {
  for (const ClassSpeed& c : kClassSpeeds)
    if (speed_class == c.name) return c.dimensionless_speed;
  throw std::out_of_range("no gait-norms speed class '" + speed_class + "'");
}

double normStrideLength(const gait::GaitNorms& norms, const dynamics::BodyProportions& proportions,
                        double dimensionless_speed) {
  return strideLength(normWalkerMap(proportions), BlendedNorms(norms, 0.0), dimensionless_speed);
}

SyntheticWalk synthesizeNormWalk(const gait::GaitNorms& norms, const dynamics::BodyProportions& proportions,
                                 const NormWalkOptions& o, double gravity_mps2) {
  common::throwIfInvalid("norm walk", validate(o));
  const dynamics::KinematicMap map = normWalkerMap(proportions);
  // The torso's lean from the vertical, plus a third of the slope into it: from the ground's
  // normal, the slope and a third (the vertical is at -slope in the walker's frame).
  constexpr double kTorsoLeanPerSlope = 4.0 / 3.0;
  const BlendedNorms blended(norms, o.torso_lean_rad + kTorsoLeanPerSlope * o.slope_rad);
  const body::BodyShape shape = body::BodyShape::forHeight(o.person_height_m);

  SyntheticWalk walk;
  const double leg_m = proportions.leg_length_per_height * o.person_height_m;
  walk.leg_length_m = leg_m;
  const double natural_time_s = std::sqrt(leg_m / gravity_mps2);
  const double froude_speed_mps = std::sqrt(gravity_mps2 * leg_m);  // v* = v / √(g L)
  auto speed_mps = [&](double t_s) {
    const double f = std::clamp(t_s / o.duration_s, 0.0, 1.0);
    return ((1 - f) * o.start_speed_kmh + f * o.end_speed_kmh) / 3.6;
  };
  // The stride length at the walk's speeds, tabulated every 0.01 of v* and interpolated.
  const double v_low = std::min(o.start_speed_kmh, o.end_speed_kmh) / 3.6 / froude_speed_mps;
  const double v_high = std::max(o.start_speed_kmh, o.end_speed_kmh) / 3.6 / froude_speed_mps;
  const int strides = 1 + static_cast<int>(std::ceil((v_high - v_low) / 0.01));
  std::vector<double> stride_table(strides + 1);
  for (int k = 0; k <= strides; ++k)
    stride_table[k] = strideLength(map, blended, v_low + k * (v_high - v_low) / strides);
  auto stride_m = [&](double v_star) {
    const double x = v_high > v_low ? (v_star - v_low) / (v_high - v_low) * strides : 0.0;
    const int k = std::clamp(static_cast<int>(x), 0, std::max(0, strides - 1));
    const double f = std::clamp(x - k, 0.0, 1.0);
    return leg_m * (strides > 0 ? (1 - f) * stride_table[k] + f * stride_table[k + 1] : stride_table[0]);
  };

  common::Random random(o.seed);
  double phase = std::uniform_real_distribution<double>(0.0, 1.0)(random);
  BodyAngles angles = blended.at(phase, speed_mps(0) / froude_speed_mps);
  Contact contact;
  contact.start(map, angles);

  dynamics::WalkerState walker;
  body::BodyPlacement placement;
  placement.heading_rad = o.heading_rad;
  const Eigen::Vector2d heading(std::cos(o.heading_rad), std::sin(o.heading_rad));
  auto pose_now = [&]() {
    walker.q = coordinates(angles, contact.stance);
    walker.stance_leg = contact.stance;
    walker.stance_foot_x = contact.stance_foot_x;
    walker.heel_strikes = contact.heel_strikes;
    for (int side : {0, 1}) placement.hip_abduction_rad[side] = angles.legs[side].abduction;
    return body::bodyPose(map, walker, o.slope_rad, placement, shape, leg_m);
  };
  const dynamics::Point first_foot = dynamics::stanceFootCentre(map, coordinates(angles, contact.stance), 0.0);
  placement.ground_origin_m = o.start_m - leg_m * first_foot.real() * std::cos(o.slope_rad) * heading;
  body::BodyPose pose = pose_now();
  placement.ground_origin_m += o.start_m - pose.foot_centres[sideOf(contact.stance)].head<2>();  // abduction moved it
  pose = pose_now();
  // The walker's frame stands on the ground through its origin; later the origin moves only
  // across the walk (abduction), where the ground is level, so it stays on it.
  walk.ground = vision::GroundPlane{placement.ground_origin_m, o.slope_rad, o.heading_rad};
  Eigen::Vector3d stance_foot_m = pose.foot_centres[sideOf(contact.stance)];

  const int frame_count = static_cast<int>(std::floor(o.duration_s * o.fps)) + 1;
  const int substeps = std::max(1, static_cast<int>(std::ceil(1.0 / (o.fps * kSubstepS))));
  const double substep_s = 1.0 / (o.fps * substeps);
  double stride_start_s = 0;
  walk.frames.reserve(frame_count);
  for (int i = 0; i < frame_count; ++i) {
    BodyAngles before = angles;
    for (int k = 0; i > 0 && k < substeps; ++k) {
      const double t_s = (i - 1) * (1.0 / o.fps) + (k + 0.5) * substep_s;
      const double v_star = speed_mps(t_s) / froude_speed_mps;
      phase += substep_s * speed_mps(t_s) / stride_m(v_star);
      before = angles;
      const double stance_shank_before = coordinates(angles, contact.stance)[dynamics::kStanceShank];
      const body::BodyPose previous = pose;
      angles = blended.at(phase, v_star);
      const bool struck = contact.update(map, angles);
      pose = pose_now();
      // Pin the stance foot: it rolls without slipping (its centre moves by −R Δθ along the
      // walk) and the hip's abduction moves the body over it, not it.
      const int side = sideOf(contact.stance);
      Eigen::Vector3d pinned;
      if (struck) {
        pinned = previous.foot_centres[side];  // the leading foot lands where it was
        stride_start_s = (i - 1) * (1.0 / o.fps) + (k + 1) * substep_s;
      } else {
        const double turn = walker.q[dynamics::kStanceShank] - stance_shank_before;
        pinned = stance_foot_m - leg_m * map.foot_radius * turn * pose.forward;
      }
      placement.ground_origin_m += (pinned - pose.foot_centres[side]).head<2>();
      pose = pose_now();
      stance_foot_m = pose.foot_centres[side];
    }
    SyntheticFrame frame;
    frame.time_s = i / o.fps;
    frame.pose = pose;
    frame.placement = placement;
    frame.walker = walker;
    // Rates from the last substep, in the walker's natural time (as the prior's states).
    frame.walker.qdot = i > 0 ? dynamics::Vector5((walker.q - coordinates(before, contact.stance)) *
                                                  (natural_time_s / substep_s))
                              : dynamics::Vector5::Zero();
    frame.walker.time_in_stride = (frame.time_s - stride_start_s) / natural_time_s;
    walk.frames.push_back(frame);
  }
  return walk;
}

}  // namespace kneed_walker::core::synthetic
