#include "kneed_walker/core/dynamics/walker_dynamics.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

#include "kneed_walker/core/dynamics/walker_simulation.h"

namespace kneed_walker::core::dynamics {
namespace {

struct RandomStates {
  explicit RandomStates(unsigned seed) : rng(seed) {}
  Vector5 angles() {
    Vector5 q;
    for (int j = 0; j < kNumCoordinates; ++j) q[j] = angle(rng);
    return q;
  }
  Vector5 rates() {
    Vector5 v;
    for (int j = 0; j < kNumCoordinates; ++j) v[j] = rate(rng);
    return v;
  }
  std::mt19937 rng;
  std::uniform_real_distribution<double> angle{-0.9, 0.9}, rate{-3.0, 3.0};
};

const WalkerModel kPerson = scaleToPerson(BodyProportions{}, 1.75, 70);

EquationsOfMotion eomAt(const KinematicMap& map, double slope, const Vector5& q,
                        const Vector5& qdot) {
  EquationsOfMotion eom;
  equationsOfMotion(inertiaCoefficients(map), slopeGravity(kPerson.gravity, slope), q, qdot, Vector5::Zero(),
                    eom);
  return eom;
}

// ½ Σ m|v|² + ½ Σ I φ̇², from the bodies' velocities alone (not from M).
double kineticEnergy(const KinematicMap& map, const Vector5& q, const Vector5& qdot) {
  double t = 0;
  for (const BodyMap& b : map.bodies)
    t += 0.5 * b.mass * std::norm(velocity(map, b.com, q, qdot)) +
         0.5 * b.inertia * qdot[b.angle] * qdot[b.angle];
  return t;
}

TEST(WalkerDynamics, MassMatrixIsSymmetricPositiveDefiniteAndGivesKineticEnergy) {
  const KinematicMap map = kneedWalkerMap(kPerson);
  RandomStates random(1);
  for (int trial = 0; trial < 50; ++trial) {
    const Vector5 q = random.angles(), qdot = random.rates();
    const Matrix5 m = eomAt(map, 0.0, q, qdot).mass;
    EXPECT_LT((m - m.transpose()).norm(), 1e-12);
    const Eigen::SelfAdjointEigenSolver<Matrix5> eig(m);
    EXPECT_GT(eig.eigenvalues().minCoeff(), 1e-6) << "M(q) must be positive definite";
    EXPECT_NEAR(0.5 * qdot.dot(m * qdot), kineticEnergy(map, q, qdot), 1e-10);
  }
}

// F from Lagrange's equations, by finite differences of M and of the potential V:
//   F = −∂V/∂q − Ṁ q̇ + ½ ∂(q̇ᵀ M q̇)/∂q.
TEST(WalkerDynamics, GeneralisedForceSatisfiesLagrangesEquations) {
  const KinematicMap map = kneedWalkerMap(kPerson);
  const double slope = 0.07, x0 = 0.4, d = 1e-6;
  RandomStates random(2);
  auto potential = [&](const Vector5& q) {
    return mechanicalEnergy(map, kPerson.gravity, slope, q, Vector5::Zero(), x0);
  };
  for (int trial = 0; trial < 20; ++trial) {
    const Vector5 q = random.angles(), qdot = random.rates();
    const Vector5 f = eomAt(map, slope, q, qdot).force;
    const Matrix5 m_dot =
        (eomAt(map, slope, q + d * qdot, qdot).mass - eomAt(map, slope, q - d * qdot, qdot).mass) /
        (2 * d);
    Vector5 lagrange = -m_dot * qdot;
    for (int k = 0; k < kNumCoordinates; ++k) {
      Vector5 dq = Vector5::Zero();
      dq[k] = d;
      const Matrix5 m_plus = eomAt(map, slope, q + dq, qdot).mass;
      const Matrix5 m_minus = eomAt(map, slope, q - dq, qdot).mass;
      lagrange[k] += 0.5 * qdot.dot((m_plus - m_minus) * qdot) / (2 * d);
      lagrange[k] -= (potential(q + dq) - potential(q - dq)) / (2 * d);
    }
    EXPECT_LT((f - lagrange).norm(), 1e-5 * (1 + f.norm())) << "F = " << f.transpose()
                                                           << "\nLagrange = " << lagrange.transpose();
  }
}

TEST(WalkerDynamics, EnergyIsConservedWithoutTorquesLimitsOrImpacts) {
  // Eq. 4 alone (no events): RK4 over 2 s of a falling, swinging walker.
  const KinematicMap map = kneedWalkerMap(kPerson);
  const double slope = 0.05, x0 = 0.0, h = 1.25e-4;
  Vector5 q, qdot;
  q << 0.1, 0.2, 0.1, -0.3, -0.6;
  qdot << 0.5, -1.0, -1.2, 2.0, 1.0;
  auto acceleration = [&](const Vector5& at_q, const Vector5& at_qdot) {
    const EquationsOfMotion eom = eomAt(map, slope, at_q, at_qdot);
    return Vector5(eom.mass.llt().solve(eom.force));
  };
  const double e0 = mechanicalEnergy(map, kPerson.gravity, slope, q, qdot, x0);
  double max_drift = 0, max_kinetic = 0;
  for (int step = 0; step < static_cast<int>(2.0 / h); ++step) {
    const Vector5 v1 = qdot, a1 = acceleration(q, v1);
    const Vector5 v2 = qdot + 0.5 * h * a1, a2 = acceleration(q + 0.5 * h * v1, v2);
    const Vector5 v3 = qdot + 0.5 * h * a2, a3 = acceleration(q + 0.5 * h * v2, v3);
    const Vector5 v4 = qdot + h * a3, a4 = acceleration(q + h * v3, v4);
    q += (h / 6) * (v1 + 2 * v2 + 2 * v3 + v4);
    qdot += (h / 6) * (a1 + 2 * a2 + 2 * a3 + a4);
    max_drift = std::max(
        max_drift, std::abs(mechanicalEnergy(map, kPerson.gravity, slope, q, qdot, x0) - e0));
    max_kinetic = std::max(max_kinetic, kineticEnergy(map, q, qdot));
  }
  RecordProperty("relative_energy_drift", std::to_string(max_drift / std::abs(e0)));
  std::cout << "energy " << e0 << " J, max drift " << max_drift << " J (relative "
            << max_drift / std::abs(e0) << "), max kinetic energy " << max_kinetic << " J\n";
  EXPECT_GT(max_kinetic, 100.0) << "the test motion should exchange a lot of energy";
  EXPECT_LT(max_drift / std::abs(e0), 1e-6);
  EXPECT_LT(max_drift / max_kinetic, 1e-6);
}

// Turns the swing leg (thigh and shank together) until its foot touches the ground.
void touchDown(const KinematicMap& map, Vector5& q) {
  for (int iteration = 0; iteration < 50; ++iteration) {
    const double h = swingFootClearance(map, q);
    if (std::abs(h) < 1e-14) return;
    Vector5 turned = q;
    turned[kSwingThigh] += 1e-7;
    turned[kSwingShank] += 1e-7;
    const double slope = (swingFootClearance(map, turned) - h) / 1e-7;
    q[kSwingThigh] -= h / slope;
    q[kSwingShank] -= h / slope;
  }
  FAIL() << "could not put the swing foot on the ground";
}

// A random state just before a heel strike: legs about a stride apart with random rates, the
// knees on their limits by the trial's number, the swing foot turned down onto the ground.
WalkerState stateAtTouchDown(const KinematicMap& map, RandomStates& random, int trial, double stance_foot_x) {
  std::uniform_real_distribution<double> small(-0.15, 0.15);
  WalkerState s;
  s.q << small(random.rng), -0.3 + small(random.rng), -0.35 + small(random.rng), 0.3 + small(random.rng),
      0.2 + small(random.rng);
  s.qdot = random.rates();
  s.stance_foot_x = stance_foot_x;
  s.knee_on_limit = {trial % 2 == 0, trial % 3 == 0};
  if (s.knee_on_limit[0]) s.q[kStanceShank] = s.q[kStanceThigh];
  if (s.knee_on_limit[1]) s.q[kSwingShank] = s.q[kSwingThigh];
  touchDown(map, s.q);
  return s;
}

// The soles' contact points just before a strike: the landing (new) and the trailing (old) one.
struct Soles {
  Point landing, trailing;
};
Soles solesAt(const KinematicMap& map, const WalkerState& s) {
  return {position(map, map.swing_foot_centre, s.q, s.stance_foot_x) - Point(0, map.foot_radius),
          stanceFootCentre(map, s.q, s.stance_foot_x) - Point(0, map.foot_radius)};
}

// z-moment about `about` of an impulse applied at `at`, counter-clockwise.
double momentAbout(Point about, Point at, Point impulse) {
  const Point arm = at - about;
  return arm.real() * impulse.imag() - arm.imag() * impulse.real();
}

// The same for a held trailing sole's normal impulse.
double holdMoment(const Soles& soles, const HeelStrike& impact) {
  return momentAbout(soles.landing, soles.trailing, Point(0, impact.trailing_sole_impulse));
}

// Through a heel strike only the ground's impulses act. At the new contact they have no
// moment, so the angular momentum about it is conserved, but for the moment of the impulse
// on a trailing sole that the impact holds on the ground.
TEST(WalkerDynamics, HeelStrikeConservesAngularMomentumAboutTheNewContact) {
  const KinematicMap map = kneedWalkerMap(kPerson);
  RandomStates random(3);
  double worst = 0;
  int held = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const WalkerState before = stateAtTouchDown(map, random, trial, 0.2);
    const Soles soles = solesAt(map, before);
    const double h_before =
        angularMomentum(map, before.q, before.qdot, before.stance_foot_x, soles.landing);
    const HeelStrike impact = heelStrike(map, before.q, before.qdot, 0.0, before.knee_on_limit);
    ASSERT_TRUE(impact.solved) << "trial " << trial;
    held += impact.trailing_sole_held;
    const double h_expected = h_before + holdMoment(soles, impact);
    const WalkerState after = afterHeelStrike(map, before, 0.0);
    const double h_after = angularMomentum(map, after.q, after.qdot, after.stance_foot_x, soles.landing);
    worst = std::max(worst, std::abs(h_after - h_expected) / std::abs(h_before));
    // Measured 1.4e-14 worst: the impact is one linear solve, exact to rounding.
    EXPECT_NEAR(h_after, h_expected, 1e-12 * std::abs(h_before)) << "trial " << trial;
    // The new stance foot is where the swing foot was, and the legs swapped.
    EXPECT_NEAR(std::abs(stanceFootCentre(map, after.q, after.stance_foot_x) -
                         (soles.landing + Point(0, map.foot_radius))),
                0.0, 1e-12);
    EXPECT_EQ(after.q[kStanceThigh], before.q[kSwingThigh]);
    EXPECT_NE(after.stance_leg, before.stance_leg);
    // An inelastic impact never adds energy.
    EXPECT_LE(mechanicalEnergy(map, kPerson.gravity, 0, after.q, after.qdot, after.stance_foot_x),
              mechanicalEnergy(map, kPerson.gravity, 0, before.q, before.qdot,
                               before.stance_foot_x) + 1e-9);
  }
  std::cout << "angular momentum about the new contact: worst relative change " << worst
            << "; trailing sole held in " << held << " of 40 strikes\n";
  EXPECT_GT(held, 0) << "the random strikes must exercise the held trailing sole";
  EXPECT_LT(held, 40) << "... and the free one";
}

// After a heel strike the ground has only pushed on a held trailing sole, which leaves with no
// normal velocity; a free trailing sole rises; no knee on its limit moves into
// hyperextension; and a landing that needs the ground to pull is reported as not physical.
TEST(WalkerDynamics, HeelStrikeOnlyPushesLiftsTheTrailingSoleAndKeepsKneesOnTheirStops) {
  const KinematicMap map = kneedWalkerMap(kPerson);
  RandomStates random(5);
  int held = 0, pulling = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const WalkerState before = stateAtTouchDown(map, random, trial, 0.0);
    const HeelStrike impact = heelStrike(map, before.q, before.qdot, 0.0, before.knee_on_limit);
    ASSERT_TRUE(impact.solved) << "trial " << trial;
    // The trailing sole after the impact, seen from the new stance foot (it is now the swing
    // foot): along the ground's normal its sole point moves with its centre.
    const WalkerState after = afterHeelStrike(map, before, 0.0);
    const double sole_rate = velocity(map, map.swing_foot_centre, after.q, after.qdot).imag();
    EXPECT_NEAR(sole_rate, impact.trailing_sole_rate, 1e-12) << "trial " << trial;
    if (impact.trailing_sole_held) {
      ++held;
      EXPECT_GE(impact.trailing_sole_impulse, -1e-12) << "trial " << trial;
      EXPECT_NEAR(sole_rate, 0.0, 1e-12) << "trial " << trial << ": a held sole leaves the ground at rest along its normal";
    } else {
      EXPECT_GE(sole_rate, -1e-12) << "trial " << trial << ": the sole sinks";
    }
    for (int k = 0; k < kNumKnees; ++k)
      if (before.knee_on_limit[k])
        EXPECT_GE(kneeFlexionRow(k).dot(impact.qdot_after), -1e-12) << "trial " << trial << ", knee " << k;
    pulling += impact.ground_normal_impulse < 0;
    EXPECT_EQ(impact.physical(), impact.ground_normal_impulse >= -1e-12) << "trial " << trial;
  }
  std::cout << "of 200 random strikes: trailing sole held in " << held << ", pulling ground in "
            << pulling << "\n";
  EXPECT_GT(held, 0);
  EXPECT_GT(pulling, 0) << "the random strikes must exercise a pulling landing";
}

// With a toe-off impulse ι (eq. 5), the angular momentum about the new contact changes by
// exactly the moment of ι applied at the old contact, along the trailing leg towards the hip:
// the ground's impulse at the new contact and the knees' limit impulses have no moment there
// (a held trailing sole's impulse has, and is counted).
// (With the impulse's moment the wrong way round, the change has the wrong sign: issue 15.)
TEST(WalkerDynamics, ToeOffImpulseChangesAngularMomentumByItsMoment) {
  const KinematicMap map = kneedWalkerMap(kPerson);
  RandomStates random(3);  // the states of the test above
  std::mt19937 pushes(9);
  std::uniform_real_distribution<double> push(5.0, 40.0);  // N·s
  double worst = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const WalkerState before = stateAtTouchDown(map, random, trial, -0.1);
    const Soles soles = solesAt(map, before);
    const Point hip = position(map, map.hip, before.q, before.stance_foot_x);
    const double iota = push(pushes);
    const Point impulse = iota * (hip - soles.trailing) / std::abs(hip - soles.trailing);
    const double moment = momentAbout(soles.landing, soles.trailing, impulse);
    const WalkerState without = afterHeelStrike(map, before, 0.0), with = afterHeelStrike(map, before, iota);
    const double expected = moment + holdMoment(soles, heelStrike(map, before.q, before.qdot, iota, before.knee_on_limit)) -
                            holdMoment(soles, heelStrike(map, before.q, before.qdot, 0.0, before.knee_on_limit));
    const double change = angularMomentum(map, with.q, with.qdot, with.stance_foot_x, soles.landing) -
                          angularMomentum(map, without.q, without.qdot, without.stance_foot_x, soles.landing);
    EXPECT_NEAR(change, expected, 1e-11 * std::abs(moment)) << "trial " << trial << ", ι = " << iota << " N s";  // measured 1.7e-13
    worst = std::max(worst, std::abs(change - expected) / std::abs(moment));
  }
  std::cout << "toe-off impulse's moment about the new contact: worst relative error " << worst << "\n";
}

TEST(WalkerDynamics, ToeOffImpulsePushesAlongTheTrailingLeg) {
  const KinematicMap map = kneedWalkerMap(kPerson);
  WalkerState before;
  before.q << 0.0, -0.3, -0.3, 0.3, 0.3;
  before.qdot << 0.0, -1.0, -1.0, 0.5, 0.5;
  before.knee_on_limit = {true, true};
  const WalkerState without = afterHeelStrike(map, before, 0.0);
  const WalkerState with = afterHeelStrike(map, before, 20.0);  // N·s
  auto energy = [&](const WalkerState& s) {
    return mechanicalEnergy(map, kPerson.gravity, 0, s.q, s.qdot, s.stance_foot_x);
  };
  // The push adds energy and makes the new stance leg rotate forward faster.
  EXPECT_GT(energy(with), energy(without));
  EXPECT_LT(with.qdot[kStanceThigh], without.qdot[kStanceThigh]);
  EXPECT_GT(heelStrike(map, before.q, before.qdot, 0.0, {true, true}).ground_normal_impulse, 0.0)
      << "the ground pushes up on the landing foot";
}

TEST(WalkerDynamics, KneeLimitCollisionRemovesOnlyHyperextendingVelocity) {
  const KinematicMap map = kneedWalkerMap(kPerson);
  Vector5 q;
  q << 0.0, 0.2, 0.2, -0.3, -0.3;
  const Matrix5 m = eomAt(map, 0, q, Vector5::Zero()).mass;
  Vector5 qdot;
  qdot << 0.3, -1.0, -0.5, 1.0, 2.0;  // both knees moving into hyperextension
  const double stance_rate = kneeFlexionRow(0).dot(qdot), swing_rate = kneeFlexionRow(1).dot(qdot);
  ASSERT_LT(stance_rate, 0);
  ASSERT_LT(swing_rate, 0);
  const Vector5 after = projectKneeVelocity(m, qdot, {true, true});
  EXPECT_NEAR(kneeFlexionRow(0).dot(after), 0.0, 1e-12);
  EXPECT_NEAR(kneeFlexionRow(1).dot(after), 0.0, 1e-12);
  EXPECT_LT(after.dot(m * after), qdot.dot(m * qdot)) << "eq. 6 dissipates energy";

  // A knee already leaving its limit is not held back.
  Vector5 leaving = qdot;
  leaving[kSwingShank] = -2.0;  // swing knee flexing
  ASSERT_GT(kneeFlexionRow(1).dot(leaving), 0);
  const Vector5 released = projectKneeVelocity(m, leaving, {true, true});
  EXPECT_NEAR(kneeFlexionRow(0).dot(released), 0.0, 1e-12);
  const double leaving_rate = kneeFlexionRow(1).dot(released);
  EXPECT_GT(leaving_rate, 0.0);

  // The resting-contact threshold: a knee that would leave slower than the sticking rate stays
  // on its limit; one that leaves faster is released as before.
  const Vector5 stuck = projectKneeVelocity(m, leaving, {true, true}, 2 * leaving_rate);
  EXPECT_NEAR(kneeFlexionRow(0).dot(stuck), 0.0, 1e-12);
  EXPECT_NEAR(kneeFlexionRow(1).dot(stuck), 0.0, 1e-12) << "a knee leaving slower than the threshold is held";
  const Vector5 free = projectKneeVelocity(m, leaving, {true, true}, 0.5 * leaving_rate);
  EXPECT_NEAR((free - released).lpNorm<Eigen::Infinity>(), 0.0, 1e-12) << "a knee leaving faster is released";
}

TEST(WalkerDynamics, VirtualTorquesHoldOnlyKneesThatWouldHyperextend) {
  const KinematicMap map = kneedWalkerMap(kPerson);
  Vector5 q;
  q << 0.0, 0.15, 0.15, -0.2, -0.2;
  const Vector5 still = Vector5::Zero();
  for (double push : {-300.0, 300.0}) {
    EquationsOfMotion eom;
    JointTorques t{};
    t[kStanceKnee] = push;  // positive flexes the knee, negative hyperextends it
    equationsOfMotion(inertiaCoefficients(map), slopeGravity(kPerson.gravity, 0), q, still, generalisedForce(t),
                      eom);
    KneeFlags active;
    const Vector5 acc = constrainedAcceleration(eom, {true, false}, &active);
    if (push < 0) {
      EXPECT_TRUE(active[0]);
      EXPECT_NEAR(kneeFlexionRow(0).dot(acc), 0.0, 1e-9) << "eq. 8 keeps aᵀq̈ = 0";
    } else {
      EXPECT_FALSE(active[0]);
      EXPECT_GT(kneeFlexionRow(0).dot(acc), 0.0) << "a flexing knee leaves its limit";
    }
  }
}

}  // namespace
}  // namespace kneed_walker::core::dynamics
