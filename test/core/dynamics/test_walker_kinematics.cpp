#include "kneed_walker/core/dynamics/walker_kinematics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace kneed_walker::core::dynamics {
namespace {

TEST(WalkerKinematics, StandingStraightPutsTheHipAtLegHeight) {
  const WalkerModel m = scaleToPerson(BodyProportions{}, 1.75, 70);
  const KinematicMap map = kneedWalkerMap(m);
  const Vector5 q = Vector5::Zero();
  const double e = m.foot_offset_angle, r = m.foot_radius;
  const Point hip = position(map, map.hip, q, 0.3);
  EXPECT_NEAR(hip.imag(), r + (m.shank.length - r) * std::cos(e) + m.thigh.length, 1e-12);
  EXPECT_NEAR(hip.real(), 0.3 - (m.shank.length - r) * std::sin(e), 1e-12)
      << "the foot centre is turned ahead of the knee by e";
  const Point shoulder = position(map, map.shoulder, q, 0.3);
  EXPECT_NEAR(shoulder.imag() - hip.imag(), m.torso.length, 1e-12);
}

TEST(WalkerKinematics, SymmetricStanceWithRoundFeetTouchesWithBothFeet) {
  WalkerModel m = mcGeerPassiveWalker();
  m.foot_offset_angle = 0;  // with e = 0 the mirrored pose is exactly symmetric
  const KinematicMap map = kneedWalkerMap(m);
  Vector5 q;
  q << 0.1, 0.3, 0.3, -0.3, -0.3;
  EXPECT_NEAR(swingFootClearance(map, q), 0.0, 1e-12);
  q[kSwingShank] = -0.5;  // bend the swing knee: the foot lifts
  EXPECT_GT(swingFootClearance(map, q), 0.01);
}

TEST(WalkerKinematics, VelocityIsTheDerivativeOfPositionIncludingRolling) {
  const KinematicMap map = kneedWalkerMap(scaleToPerson(BodyProportions{}, 1.6, 55));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(-0.8, 0.8), rate(-3, 3);
  const double dt = 1e-6;
  for (int trial = 0; trial < 20; ++trial) {
    Vector5 q, qdot;
    for (int j = 0; j < kNumCoordinates; ++j) {
      q[j] = angle(rng);
      qdot[j] = rate(rng);
    }
    for (const PointMap* p : {&map.hip, &map.swing_foot_centre, &map.bodies[kTorsoBody].com,
                              &map.bodies[kStanceShankBody].com}) {
      const Point numeric =
          (position(map, *p, q + dt * qdot, 0.0) - position(map, *p, q - dt * qdot, 0.0)) /
          (2 * dt);
      EXPECT_NEAR(std::abs(velocity(map, *p, q, qdot) - numeric), 0.0, 1e-7);
    }
  }
}

}  // namespace
}  // namespace kneed_walker::core::dynamics
