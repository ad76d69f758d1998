// The Kneed Walker's kinematic map X(q) (paper §3.1; ../shared/reference/walker-model.md §2).
//
// Frame: the slope frame, x forward along the ground in the walking direction, y along the
// ground normal (up). Points are complex numbers x + i·y. Angles are absolute, from the
// ground normal, counter-clockwise positive: a segment at angle φ points (from its upper
// to its lower end) along d(φ) = (sin φ, −cos φ) = −i·e^{iφ}, so φ > 0 puts the lower end
// ahead. Knee flexion is φ_thigh − φ_shank ≥ 0.
//
// Every point of the walker is  base + Σ_j w_j · e^{i q_j}  with constant complex w_j,
// where the base is the stance foot's centre C, rolling without slip:
//   C = (x0 − R·q_stance_shank, R).
// Velocities and the convective accelerations of TMT follow from this form generically, so a
// second walker model is only another KinematicMap.
#pragma once

#include <Eigen/Core>

#include <array>
#include <complex>

#include "kneed_walker/core/common/sincos.h"
#include "kneed_walker/core/dynamics/walker_model.h"

namespace kneed_walker::core::dynamics {

// Generalised coordinates q (paper §3.1), absolute angles in rad.
enum Coordinate : int {
  kTorso = 0,
  kStanceThigh = 1,
  kStanceShank = 2,
  kSwingThigh = 3,
  kSwingShank = 4,
  kNumCoordinates = 5
};

using Vector5 = Eigen::Matrix<double, kNumCoordinates, 1>;
using Matrix5 = Eigen::Matrix<double, kNumCoordinates, kNumCoordinates>;
using Point = std::complex<double>;  // x + i·y in the slope frame, model length units

// A point rigidly attached to the chain: position relative to the base C is Σ_j w_j e^{i q_j}.
struct PointMap {
  std::array<Point, kNumCoordinates> w{};
};

// One rigid body of the TMT sum: its centre of mass, mass, inertia and which coordinate is
// its absolute angle.
struct BodyMap {
  PointMap com;
  double mass = 0;     // model mass units
  double inertia = 0;  // about the centre of mass, model mass·length²
  int angle = 0;       // index into q
};

enum Body : int {
  kTorsoBody = 0,
  kStanceThighBody,
  kStanceShankBody,
  kSwingThighBody,
  kSwingShankBody,
  kNumBodies
};

struct KinematicMap {
  std::array<BodyMap, kNumBodies> bodies;
  // Named points for contact, drawing and the 3D body model.
  PointMap hip, stance_knee, swing_knee, swing_foot_centre, shoulder;
  double foot_radius = 0;               // R: rolling radius of both feet
  double shank_length = 0;              // knee to sole along the shank, model length
  int rolling_coordinate = kStanceShank;  // the base rolls by −R per radian of this angle
};

// The Kneed Walker's map for a model (eccentric feet, torso above the hip).
KinematicMap kneedWalkerMap(const WalkerModel& model);

// Position of the stance foot centre C for foot parameter x0 (C_x when q_rolling = 0).
inline Point stanceFootCentre(const KinematicMap& map, const Vector5& q, double x0) {
  return {x0 - map.foot_radius * q[map.rolling_coordinate], map.foot_radius};
}

// e^{i q_j} for all j: computed once per state and shared by every point.
inline std::array<Point, kNumCoordinates> phasors(const Vector5& q) {
  std::array<Point, kNumCoordinates> p;
  for (int j = 0; j < kNumCoordinates; ++j) {
    double s, c;
    common::sinCos(q[j], s, c);
    p[j] = Point(c, s);
  }
  return p;
}

// Position of a point relative to the base C.
inline Point relativePosition(const PointMap& point, const std::array<Point, kNumCoordinates>& e) {
  Point r = 0;
  for (int j = 0; j < kNumCoordinates; ++j) r += point.w[j] * e[j];
  return r;
}

// Absolute position in the slope frame.
inline Point position(const KinematicMap& map, const PointMap& point, const Vector5& q, double x0) {
  return stanceFootCentre(map, q, x0) + relativePosition(point, phasors(q));
}

// Velocity of a point rigidly attached to the chain (rolling base included).
Point velocity(const KinematicMap& map, const PointMap& point, const Vector5& q,
               const Vector5& qdot);

// Swing-foot clearance h(q) = C2_y − R: the swing sole's height above the ground (contact
// when it reaches 0 while decreasing).
double swingFootClearance(const KinematicMap& map, const Vector5& q);

}  // namespace kneed_walker::core::dynamics
