// Periodic gaits: fixed points S(x0, θ, γ) = x0 of the stride function (paper §3.3, eq. 10),
// found by Newton's method on the stride map with a finite-difference Jacobian, and the
// linearised stride map's eigenvalues (the gait's stability: |λ| < 1 for a stable gait).
//
// Just after heel strike each knee is in one of three modes: locked on its limit (shank angle
// and rate equal the thigh's), at its limit but flexing away (angles equal, rates free), or
// bent (free). The stride map acts on the manifold these constraints define, so the search
// runs in reduced coordinates that leave out the tied shank entries (differences across a
// knee limit would otherwise straddle a knee collision or a projection).
#pragma once

#include <Eigen/Core>

#include "kneed_walker/core/dynamics/walker_simulation.h"

namespace kneed_walker::core::optimizer {

using GaitVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 2 * dynamics::kNumCoordinates, 1>;
using GaitMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 2 * dynamics::kNumCoordinates,
                                 2 * dynamics::kNumCoordinates>;

enum class KneeMode : std::uint8_t { kLocked, kAtLimit, kBent };
using KneeModes = std::array<KneeMode, dynamics::kNumKnees>;

// The knee modes of a post-heel-strike state.
KneeModes kneeModes(const dynamics::WalkerState& state);

// Reduced coordinates of a post-heel-strike state in given knee modes.
class GaitCoordinates {
 public:
  explicit GaitCoordinates(const KneeModes& modes) : modes_(modes) {}
  int size() const;
  int angles() const;  // the first angles() entries are angles, the rest rates
  GaitVector reduce(const dynamics::WalkerState& state) const;
  // A post-heel-strike state (stance foot at x0 = 0, left stance) from reduced coordinates.
  dynamics::WalkerState expand(const GaitVector& reduced) const;
  const KneeModes& modes() const { return modes_; }

 private:
  KneeModes modes_;
};

struct PeriodicGaitOptions {
  double residual_tolerance = 1e-11;  // max-norm of S(x) − x, rad and rad per model time
  int max_iterations = 40;
  double difference_step = 1e-6;      // central differences for the Jacobian
};

struct PeriodicGait {
  dynamics::WalkerState start;        // post-heel-strike state on the gait
  dynamics::StrideResult stride;      // S(start): duration, step length, speed
  double residual = 0;      // max |S(x) − x| in reduced coordinates
  int iterations = 0;
  bool converged = false;   // residual below tolerance and a completed stride
  GaitMatrix stride_jacobian;  // ∂S/∂x in reduced coordinates (the linearised stride map)
  Eigen::VectorXcd eigenvalues;  // of stride_jacobian
};

// Newton's method from `guess` (its knee modes choose the reduced coordinates).
PeriodicGait findPeriodicGait(const dynamics::WalkerSimulator& simulator, const dynamics::WalkerControls& controls,
                              const dynamics::WalkerState& guess, const PeriodicGaitOptions& options = {});

// The slope of McGeer's passive walker, rad (negative: downhill).
constexpr double kMcGeerSlope = -0.0456;

// McGeer's passive kneed walker's periodic gait down kMcGeerSlope, in dimensionless units:
// a ready-made walking motion of the bare legs (for benchmarks, pictures and physics checks).
PeriodicGait mcGeerPassiveGait();

// A dimensionless state (leg length 1, g = 1) for a walker of another size: angles unchanged,
// rates divided by the natural time √(L/g), positions times the leg length.
dynamics::WalkerState fromDimensionless(const dynamics::WalkerState& dimensionless, const dynamics::WalkerSimulator& simulator);

}  // namespace kneed_walker::core::optimizer
