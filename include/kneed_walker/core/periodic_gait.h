// Periodic gaits: fixed points S(x0, θ, γ) = x0 of the stride function (paper §3.3, eq. 10),
// found by Newton's method on the stride map with a finite-difference Jacobian, and the
// linearised stride map's eigenvalues (the gait's stability: |λ| < 1 for a stable gait).
//
// A knee that is on its limit just after heel strike has shank angle = thigh angle and the
// same rates, so the stride map acts on the manifold of those constraints: the search runs in
// the reduced coordinates that leave out each locked knee's shank angle and rate (differences
// across the knee-lock would otherwise straddle an inelastic knee collision).
#pragma once

#include <Eigen/Core>

#include "kneed_walker/core/walker_simulation.h"

namespace kneed_walker {

using GaitVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 2 * kNumCoordinates, 1>;
using GaitMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 2 * kNumCoordinates,
                                 2 * kNumCoordinates>;

// Reduced coordinates of a post-heel-strike state: q and q̇ without the shank entries of the
// knees locked in `locked`.
class GaitCoordinates {
 public:
  explicit GaitCoordinates(const KneeFlags& locked) : locked_(locked) {}
  int size() const;
  GaitVector reduce(const WalkerState& state) const;
  // A post-heel-strike state (stance foot at x0 = 0, left stance) from reduced coordinates.
  WalkerState expand(const GaitVector& reduced) const;
  const KneeFlags& locked() const { return locked_; }

 private:
  KneeFlags locked_;
};

struct PeriodicGaitOptions {
  double residual_tolerance = 1e-11;  // max-norm of S(x) − x, rad and rad per model time
  int max_iterations = 40;
  double difference_step = 1e-6;      // central differences for the Jacobian
};

struct PeriodicGait {
  WalkerState start;        // post-heel-strike state on the gait
  StrideResult stride;      // S(start): duration, step length, speed
  double residual = 0;      // max |S(x) − x| in reduced coordinates
  int iterations = 0;
  bool converged = false;   // residual below tolerance and a completed stride
  GaitMatrix stride_jacobian;  // ∂S/∂x in reduced coordinates (the linearised stride map)
  Eigen::VectorXcd eigenvalues;  // of stride_jacobian
};

// Newton's method from `guess` (its knee flags choose the reduced coordinates).
PeriodicGait findPeriodicGait(const WalkerSimulator& simulator, const WalkerControls& controls,
                              const WalkerState& guess, const PeriodicGaitOptions& options = {});

// The slope of McGeer's passive walker, rad (negative: downhill).
constexpr double kMcGeerSlope = -0.0456;

// McGeer's passive kneed walker's periodic gait down kMcGeerSlope, in dimensionless units:
// a ready-made walking motion (for benchmarks and pictures) until optimal gaits exist.
PeriodicGait mcGeerPassiveGait();

// A dimensionless state (leg length 1, g = 1) for a walker of another size: angles unchanged,
// rates divided by the natural time √(L/g), positions times the leg length.
WalkerState fromDimensionless(const WalkerState& dimensionless, const WalkerSimulator& simulator);

}  // namespace kneed_walker
