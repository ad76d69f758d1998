#include "kneed_walker/core/optimizer/periodic_gait.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

namespace kneed_walker::core::optimizer {
namespace {

TEST(PeriodicGait, ReducedCoordinatesRoundTripInEachKneeMode) {
  dynamics::WalkerState s;
  s.q << 0.1, 0.2, 0.2, -0.3, -0.3;
  s.qdot << 0.0, -1.0, -1.0, 0.4, 0.9;
  s.knee_on_limit = {true, false};
  const KneeModes modes = kneeModes(s);
  EXPECT_EQ(modes[0], KneeMode::kLocked);
  EXPECT_EQ(modes[1], KneeMode::kAtLimit) << "straight swing knee flexing away";
  const GaitCoordinates coordinates(modes);
  EXPECT_EQ(coordinates.size(), 7);
  EXPECT_EQ(coordinates.angles(), 3);
  dynamics::WalkerState back = coordinates.expand(coordinates.reduce(s));
  EXPECT_EQ(back.q, s.q);
  EXPECT_EQ(back.qdot, s.qdot);
  EXPECT_EQ(back.knee_on_limit, s.knee_on_limit);

  s.q[dynamics::kSwingShank] = -0.5;  // a bent swing knee is free
  const GaitCoordinates bent(kneeModes(s));
  EXPECT_EQ(bent.size(), 8);
  back = bent.expand(bent.reduce(s));
  EXPECT_EQ(back.q, s.q);
  EXPECT_EQ(back.qdot, s.qdot);
}

// McGeer's passive kneed walker (torso reduced to a hip mass) down 0.0456 rad: a periodic
// gait exists as a fixed point of the stride map.
TEST(PeriodicGait, McGeersPassiveWalkerHasAPeriodicGait) {
  const dynamics::WalkerSimulator sim(dynamics::mcGeerPassiveWalker());
  dynamics::WalkerControls passive;
  passive.ground_slope = -0.0456;
  dynamics::WalkerState guess;  // a rough post-heel-strike state, dimensionless
  guess.q << 0, 0.25, 0.25, -0.45, -0.45;
  guess.qdot << 0, -0.35, -0.35, 0.0, 0.0;
  guess.knee_on_limit = {true, false};  // the trailing knee flexes right after heel strike
  const PeriodicGait gait = findPeriodicGait(sim, passive, guess);
  ASSERT_TRUE(gait.converged) << "residual " << gait.residual;
  EXPECT_LT(gait.residual, 1e-9);

  // It really repeats: one more stride from the full state returns to it.
  const dynamics::StrideResult again = sim.stride(passive, gait.start);
  EXPECT_LT((again.end.q - gait.start.q).lpNorm<Eigen::Infinity>(), 1e-9);
  EXPECT_LT((again.end.qdot - gait.start.qdot).lpNorm<Eigen::Infinity>(), 1e-9);

  std::cout << "McGeer passive gait down 0.0456 rad: step length " << gait.stride.step_length
            << " L, period " << gait.stride.duration << " sqrt(L/g), speed " << gait.stride.speed
            << " sqrt(gL), residual " << gait.residual << " after " << gait.iterations
            << " Newton steps\n  start q = " << gait.start.q.transpose()
            << "\n  start qdot = " << gait.start.qdot.transpose()
            << "\n  eigenvalues of the linearised stride map: " << gait.eigenvalues.transpose()
            << "\n";
  RecordProperty("step_length_L", std::to_string(gait.stride.step_length));
  RecordProperty("period_natural", std::to_string(gait.stride.duration));
  // The figures the README quotes for McGeer's walker as modelled here (mcGeerPassiveWalker):
  // step 0.6968 L, period 2.9607 √(L/g), and the flip eigenvalue
  // −1.381 that makes the cycle unstable, with 0.169 and −0.047. A change of the model's
  // geometry or dynamics moves them: it must be deliberate, and the README updated.
  EXPECT_NEAR(gait.stride.step_length, 0.6968, 0.001);
  EXPECT_NEAR(gait.stride.duration, 2.9607, 0.002);
  for (const double expected : {-1.381, 0.169, -0.047}) {
    double nearest = 1e9;
    for (int i = 0; i < gait.eigenvalues.size(); ++i)
      nearest = std::min(nearest, std::abs(gait.eigenvalues[i] - expected));
    EXPECT_LT(nearest, 0.002) << "eigenvalue " << expected;
  }
  // The torso is decoupled (its centre of mass is at the hip): its angle and rate are neutral
  // directions of the stride map, so two eigenvalues are 1.
  int unit = 0;
  for (int i = 0; i < gait.eigenvalues.size(); ++i)
    unit += std::abs(gait.eigenvalues[i] - 1.0) < 1e-5;
  EXPECT_EQ(unit, 2);
}

}  // namespace
}  // namespace kneed_walker::core::optimizer
