#include "kneed_walker/core/optimizer/periodic_gait.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
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

// The eigenvalue nearest to `expected`, and how far it is.
double distanceToNearest(const Eigen::VectorXcd& eigenvalues, std::complex<double> expected) {
  double nearest = 1e9;
  for (int i = 0; i < eigenvalues.size(); ++i)
    nearest = std::min(nearest, std::abs(eigenvalues[i] - expected));
  return nearest;
}

// McGeer's passive kneed walker (his legs and shank frame, the torso reduced to his hip mass)
// down 0.0456 rad: a periodic gait exists as a fixed point of the stride map, and it is his
// stable cycle (McGeer, "Passive walking with knees", ICRA 1990, Table 1 and Fig. 2).
TEST(PeriodicGait, McGeersPassiveWalkerWalksHisStableCycle) {
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

  // McGeer's Table 1: −0.001, 0.073 and 0.447∠±0.947 rad, each within 5 % of the largest
  // (0.447), and his Fig. 2's period of about 2.7 √(L/g) within 5 %.
  const double spectral_radius = 0.447;
  const std::complex<double> table1[] = {-0.001, 0.073, std::polar(0.447, 0.947),
                                         std::polar(0.447, -0.947)};
  for (const std::complex<double> expected : table1)
    EXPECT_LT(distanceToNearest(gait.eigenvalues, expected), 0.05 * spectral_radius)
        << "McGeer's eigenvalue " << expected;
  EXPECT_NEAR(gait.stride.duration, 2.7, 0.05 * 2.7);
  // Every other eigenvalue is inside the unit circle but the torso's two (below): stable.
  int outside = 0;
  for (int i = 0; i < gait.eigenvalues.size(); ++i)
    outside += std::abs(gait.eigenvalues[i]) > 1 - 1e-5;
  EXPECT_EQ(outside, 2);

  // The figures the README quotes for McGeer's walker as modelled here, near what is measured
  // (step 0.6862 L, period 2.6549, eigenvalues 0.0670 and 0.2701 ± 0.3732i = 0.461∠±0.944):
  // a change of the model's geometry or dynamics moves them; it must be deliberate, and the
  // README updated.
  EXPECT_NEAR(gait.stride.step_length, 0.6862, 0.001);
  EXPECT_NEAR(gait.stride.duration, 2.6549, 0.002);
  for (const std::complex<double> expected :
       {std::complex<double>(0.0670), {0.2701, 0.3732}, {0.2701, -0.3732}})
    EXPECT_LT(distanceToNearest(gait.eigenvalues, expected), 0.002) << "eigenvalue " << expected;
  // The torso is decoupled (its centre of mass is at the hip): its angle and rate are neutral
  // directions of the stride map, so two eigenvalues are 1.
  int unit = 0;
  for (int i = 0; i < gait.eigenvalues.size(); ++i)
    unit += std::abs(gait.eigenvalues[i] - 1.0) < 1e-5;
  EXPECT_EQ(unit, 2);
}

}  // namespace
}  // namespace kneed_walker::core::optimizer
