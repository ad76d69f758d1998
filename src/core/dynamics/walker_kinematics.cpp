#include "kneed_walker/core/dynamics/walker_kinematics.h"

#include <cmath>

namespace kneed_walker::core::dynamics {
namespace {

constexpr double kHalfPi = 1.5707963267948966;
const Point kI(0.0, 1.0);

// Adds r · d(q_j + α) = r · (−i e^{iα}) e^{i q_j} to a point.
void addSegment(PointMap& p, int j, double r, double alpha) {
  p.w[j] += r * (-kI) * std::polar(1.0, alpha);
}

// Adds the centre of mass of a segment hanging from (or, for up = true, standing on) its
// proximal joint at angle q_j: c·d(q_j) + w·n(q_j), with n(φ) = d(φ + π/2).
void addCentreOfMass(PointMap& p, int j, const Segment& s, bool up) {
  const double sign = up ? -1.0 : 1.0;
  addSegment(p, j, sign * s.com_along, 0.0);
  addSegment(p, j, s.com_forward, kHalfPi);
}

}  // namespace

KinematicMap kneedWalkerMap(const WalkerModel& m) {
  KinematicMap map;
  map.foot_radius = m.foot_radius;
  map.shank_length = m.shank.length;
  map.rolling_coordinate = kStanceShank;
  const double foot_centre_from_knee = m.shank.length - m.foot_radius;

  // Stance leg, from the rolling foot centre C up: K1 = C − (ℓS − R) d(φS1 + e),
  // H = K1 − ℓT d(φT1).
  PointMap stance_knee;
  addSegment(stance_knee, kStanceShank, -foot_centre_from_knee, m.foot_offset_angle);
  PointMap hip = stance_knee;
  addSegment(hip, kStanceThigh, -m.thigh.length, 0.0);
  // Swing leg, down from the hip: K2 = H + ℓT d(φT2), C2 = K2 + (ℓS − R) d(φS2 + e).
  PointMap swing_knee = hip;
  addSegment(swing_knee, kSwingThigh, m.thigh.length, 0.0);
  PointMap swing_foot_centre = swing_knee;
  addSegment(swing_foot_centre, kSwingShank, foot_centre_from_knee, m.foot_offset_angle);
  PointMap shoulder = hip;
  addSegment(shoulder, kTorso, -m.torso.length, 0.0);

  auto body = [](const PointMap& proximal, int j, const Segment& s, bool up) {
    BodyMap b;
    b.com = proximal;
    addCentreOfMass(b.com, j, s, up);
    b.mass = s.mass;
    b.inertia = s.inertia();
    b.angle = j;
    return b;
  };
  map.bodies[kTorsoBody] = body(hip, kTorso, m.torso, true);
  map.bodies[kStanceThighBody] = body(hip, kStanceThigh, m.thigh, false);
  map.bodies[kStanceShankBody] = body(stance_knee, kStanceShank, m.shank, false);
  map.bodies[kSwingThighBody] = body(hip, kSwingThigh, m.thigh, false);
  map.bodies[kSwingShankBody] = body(swing_knee, kSwingShank, m.shank, false);

  map.hip = hip;
  map.stance_knee = stance_knee;
  map.swing_knee = swing_knee;
  map.swing_foot_centre = swing_foot_centre;
  map.shoulder = shoulder;
  return map;
}

Point velocity(const KinematicMap& map, const PointMap& point, const Vector5& q,
               const Vector5& qdot) {
  Point v = -map.foot_radius * qdot[map.rolling_coordinate];
  for (int j = 0; j < kNumCoordinates; ++j)
    v += kI * point.w[j] * std::polar(1.0, q[j]) * qdot[j];
  return v;
}

double swingFootClearance(const KinematicMap& map, const Vector5& q) {
  // C_y = R, so C2_y − R is the relative height of the swing foot centre.
  return relativePosition(map.swing_foot_centre, phasors(q)).imag();
}

}  // namespace kneed_walker::core::dynamics
