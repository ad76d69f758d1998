#include "kneed_walker/core/optimizer/periodic_gait.h"

#include <Eigen/Eigenvalues>
#include <Eigen/QR>

#include <cmath>
#include <limits>

namespace kneed_walker::core::optimizer {
namespace {

// The shank and thigh coordinates of knee k.
constexpr int kShankOf[dynamics::kNumKnees] = {dynamics::kStanceShank, dynamics::kSwingShank};
constexpr int kThighOf[dynamics::kNumKnees] = {dynamics::kStanceThigh, dynamics::kSwingThigh};

// Whether coordinate j's angle (or rate) is tied to its thigh's in these modes.
bool angleTied(const KneeModes& modes, int j) {
  for (int k = 0; k < dynamics::kNumKnees; ++k)
    if (modes[k] != KneeMode::kBent && kShankOf[k] == j) return true;
  return false;
}
bool rateTied(const KneeModes& modes, int j) {
  for (int k = 0; k < dynamics::kNumKnees; ++k)
    if (modes[k] == KneeMode::kLocked && kShankOf[k] == j) return true;
  return false;
}

}  // namespace

KneeModes kneeModes(const dynamics::WalkerState& state) {
  KneeModes modes;
  for (int k = 0; k < dynamics::kNumKnees; ++k) {
    if (state.knee_on_limit[k])
      modes[k] = KneeMode::kLocked;
    else if (dynamics::kneeFlexion(state.q, k) <= 1e-12)
      modes[k] = KneeMode::kAtLimit;
    else
      modes[k] = KneeMode::kBent;
  }
  return modes;
}

int GaitCoordinates::angles() const {
  int n = 0;
  for (int j = 0; j < dynamics::kNumCoordinates; ++j) n += !angleTied(modes_, j);
  return n;
}

int GaitCoordinates::size() const {
  int n = angles();
  for (int j = 0; j < dynamics::kNumCoordinates; ++j) n += !rateTied(modes_, j);
  return n;
}

GaitVector GaitCoordinates::reduce(const dynamics::WalkerState& state) const {
  GaitVector r(size());
  int i = 0;
  for (int j = 0; j < dynamics::kNumCoordinates; ++j)
    if (!angleTied(modes_, j)) r[i++] = state.q[j];
  for (int j = 0; j < dynamics::kNumCoordinates; ++j)
    if (!rateTied(modes_, j)) r[i++] = state.qdot[j];
  return r;
}

dynamics::WalkerState GaitCoordinates::expand(const GaitVector& r) const {
  dynamics::WalkerState s;
  int i = 0;
  for (int j = 0; j < dynamics::kNumCoordinates; ++j)
    if (!angleTied(modes_, j)) s.q[j] = r[i++];
  for (int j = 0; j < dynamics::kNumCoordinates; ++j)
    if (!rateTied(modes_, j)) s.qdot[j] = r[i++];
  for (int k = 0; k < dynamics::kNumKnees; ++k) {
    if (modes_[k] == KneeMode::kBent) continue;
    s.q[kShankOf[k]] = s.q[kThighOf[k]];
    if (modes_[k] == KneeMode::kLocked) s.qdot[kShankOf[k]] = s.qdot[kThighOf[k]];
    s.knee_on_limit[k] = modes_[k] == KneeMode::kLocked;
  }
  return s;
}

PeriodicGait findPeriodicGait(const dynamics::WalkerSimulator& simulator, const dynamics::WalkerControls& controls,
                              const dynamics::WalkerState& guess, const PeriodicGaitOptions& options) {
  const GaitCoordinates coordinates(kneeModes(guess));
  const int n = coordinates.size();
  PeriodicGait gait;
  GaitVector x = coordinates.reduce(guess);

  // Residual S(x) − x; a stride that falls has none. (Near a gait whose knee barely leaves
  // its limit, a difference probe may end with another knee pattern; the probe still counts,
  // and the solution itself must end with the start's pattern to converge.)
  auto residual = [&](const GaitVector& at, dynamics::StrideResult* stride_out) -> GaitVector {
    const dynamics::StrideResult stride = simulator.stride(controls, coordinates.expand(at));
    if (stride_out) *stride_out = stride;
    GaitVector r = coordinates.reduce(stride.end) - at;
    if (!stride.completed) r.setConstant(std::numeric_limits<double>::quiet_NaN());
    return r;
  };

  auto jacobianAt = [&](const GaitVector& at) {
    GaitMatrix j(n, n);
    for (int c = 0; c < n; ++c) {
      GaitVector plus = at, minus = at;
      plus[c] += options.difference_step;
      minus[c] -= options.difference_step;
      j.col(c) = (residual(plus, nullptr) - residual(minus, nullptr)) / (2 * options.difference_step);
    }
    return j;  // ∂(S(x) − x)/∂x
  };

  dynamics::StrideResult stride;
  GaitVector r = residual(x, &stride);
  for (gait.iterations = 0; gait.iterations < options.max_iterations; ++gait.iterations) {
    if (!r.allFinite() || r.lpNorm<Eigen::Infinity>() < options.residual_tolerance) break;
    const GaitMatrix j = jacobianAt(x);
    if (!j.allFinite()) break;
    // Least squares: the stride map may have neutral directions (a decoupled torso).
    const GaitVector step = j.completeOrthogonalDecomposition().solve(-r);
    // Backtrack until the residual decreases.
    double scale = 1.0;
    GaitVector candidate;
    GaitVector candidate_r;
    dynamics::StrideResult candidate_stride;
    for (int attempt = 0; attempt < 12; ++attempt, scale *= 0.5) {
      candidate = x + scale * step;
      candidate_r = residual(candidate, &candidate_stride);
      if (candidate_r.allFinite() &&
          candidate_r.lpNorm<Eigen::Infinity>() < r.lpNorm<Eigen::Infinity>())
        break;
    }
    if (!candidate_r.allFinite()) break;
    x = candidate;
    r = candidate_r;
    stride = candidate_stride;
  }

  gait.start = coordinates.expand(x);
  gait.stride = stride;
  gait.residual = r.allFinite() ? r.lpNorm<Eigen::Infinity>() : std::numeric_limits<double>::infinity();
  gait.converged = stride.completed && gait.residual < options.residual_tolerance &&
                   kneeModes(stride.end) == coordinates.modes();
  if (r.allFinite()) {
    gait.stride_jacobian = jacobianAt(x) + GaitMatrix::Identity(n, n);
    gait.eigenvalues = gait.stride_jacobian.eigenvalues();
  }
  return gait;
}

PeriodicGait mcGeerPassiveGait() {
  const dynamics::WalkerSimulator simulator(dynamics::mcGeerPassiveWalker());
  dynamics::WalkerControls passive;
  passive.ground_slope = kMcGeerSlope;
  dynamics::WalkerState guess;
  guess.q << 0, 0.27, 0.27, -0.44, -0.44;
  guess.qdot << 0, -0.355, -0.355, 0.065, -0.625;
  guess.knee_on_limit = {true, false};
  return findPeriodicGait(simulator, passive, guess);
}

dynamics::WalkerState fromDimensionless(const dynamics::WalkerState& s, const dynamics::WalkerSimulator& simulator) {
  dynamics::WalkerState scaled = s;
  scaled.qdot = s.qdot / simulator.naturalTime();
  scaled.stance_foot_x = s.stance_foot_x * simulator.model().legLength();
  scaled.time_in_stride = s.time_in_stride * simulator.naturalTime();
  return scaled;
}

}  // namespace kneed_walker::core::optimizer
