#include "kneed_walker/core/dynamics/walker_dynamics.h"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>

namespace kneed_walker::core::dynamics {
namespace {

const Point kI(0.0, 1.0);

// Re(conj(a)·b) = a.x b.x + a.y b.y.
inline double dot(Point a, Point b) { return a.real() * b.real() + a.imag() * b.imag(); }
// Im(conj(a)·b) = a.x b.y − a.y b.x: the planar cross product.
inline double cross(Point a, Point b) { return a.real() * b.imag() - a.imag() * b.real(); }

// Velocity coefficients of a point: v = Σ_j V_j q̇_j, with V_j = i w_j e^{i q_j} and the
// rolling base's −R on the rolling coordinate.
inline void velocityCoefficients(const KinematicMap& map, const PointMap& p,
                                 const std::array<Point, kNumCoordinates>& e,
                                 std::array<Point, kNumCoordinates>& v) {
  for (int j = 0; j < kNumCoordinates; ++j) v[j] = kI * p.w[j] * e[j];
  v[map.rolling_coordinate] -= map.foot_radius;
}

// Solves the equality-constrained system  M x = r + Gᵀλ,  G x = c  for x (and λ), with up to
// kMaxRows constraint rows, by the Schur complement; no heap allocation.
template <int N>
struct ConstrainedSolve {
  static constexpr int kMaxRows = 5;  // the landing sole's two rows, a held sole's, two knees
  using VecN = Eigen::Matrix<double, N, 1>;
  using MatN = Eigen::Matrix<double, N, N>;
  using Rows = Eigen::Matrix<double, Eigen::Dynamic, N, 0, kMaxRows, N>;
  using VecR = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxRows, 1>;
  using MatR = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxRows, kMaxRows>;

  static void solve(const Eigen::LLT<MatN>& m_llt, const VecN& r, const Rows& g, const VecR& c,
                    VecN& x, VecR& lambda) {
    const VecN x_free = m_llt.solve(r);
    if (g.rows() == 0) {
      x = x_free;
      lambda.resize(0);
      return;
    }
    const Eigen::Matrix<double, N, Eigen::Dynamic, 0, N, kMaxRows> m_inv_gt =
        m_llt.solve(g.transpose());
    const MatR schur = g * m_inv_gt;
    lambda = schur.ldlt().solve(c - g * x_free);
    x = x_free + m_inv_gt * lambda;
  }
};

// Subsets of the knee flags to try as the active set, largest first.
template <typename Accept>
bool forEachKneeSubset(const KneeFlags& candidates, Accept accept) {
  const int n_subsets = 1 << kNumKnees;
  for (int size = kNumKnees; size >= 0; --size) {
    for (int mask = n_subsets - 1; mask >= 0; --mask) {
      int count = 0;
      bool ok = true;
      for (int k = 0; k < kNumKnees; ++k) {
        if (mask & (1 << k)) {
          ++count;
          ok = ok && candidates[k];
        }
      }
      if (!ok || count != size) continue;
      KneeFlags subset{};
      for (int k = 0; k < kNumKnees; ++k) subset[k] = (mask >> k) & 1;
      if (accept(subset)) return true;
    }
  }
  return false;
}

constexpr double kComplementarityTolerance = 1e-12;

// The flexion rows a_kᵀ of the knees in `knees`, placed at column `offset` of N columns.
template <int N>
typename ConstrainedSolve<N>::Rows kneeRows(const KneeFlags& knees, int offset = 0) {
  typename ConstrainedSolve<N>::Rows g(0, N);
  for (int k = 0; k < kNumKnees; ++k) {
    if (!knees[k]) continue;
    g.conservativeResize(g.rows() + 1, Eigen::NoChange);
    g.row(g.rows() - 1).setZero();
    g.row(g.rows() - 1).template segment<kNumCoordinates>(offset) = kneeFlexionRow(k).transpose();
  }
  return g;
}

// LDLᵀ factorisation of the 5×5 mass matrix, written out because it is the hot spot of every
// particle's step: fixed loop bounds, unrolled (GCC left the triangular loops rolled, and
// they cost a third of bench_dynamics), no pivoting (M is positive definite), no square
// roots; about 2× faster here than Eigen::LLT<Matrix5> (bench_dynamics). Only the strict
// lower triangles are written or read: zeroing the whole arrays cost two `rep stos` a call.
class MassCholesky {
 public:
  explicit MassCholesky(const Matrix5& m) {
    constexpr int n = kNumCoordinates;
#pragma GCC unroll 5
    for (int j = 0; j < n; ++j) {
      double d = m(j, j);
#pragma GCC unroll 5
      for (int k = 0; k < j; ++k) d -= ld_[j][k] * l_[j][k];  // ld_ = L·D
      inv_d_[j] = 1.0 / d;
#pragma GCC unroll 5
      for (int i = j + 1; i < n; ++i) {
        double v = m(i, j);
#pragma GCC unroll 5
        for (int k = 0; k < j; ++k) v -= ld_[i][k] * l_[j][k];
        ld_[i][j] = v;
        l_[i][j] = v * inv_d_[j];
      }
    }
  }
  // M⁻¹ b.
  Vector5 solve(const Vector5& b) const {
    constexpr int n = kNumCoordinates;
    double y[n];
#pragma GCC unroll 5
    for (int i = 0; i < n; ++i) {
      double v = b[i];
#pragma GCC unroll 5
      for (int k = 0; k < i; ++k) v -= l_[i][k] * y[k];
      y[i] = v;
    }
    Vector5 x;
#pragma GCC unroll 5
    for (int i = n - 1; i >= 0; --i) {
      double v = y[i] * inv_d_[i];
#pragma GCC unroll 5
      for (int k = i + 1; k < n; ++k) v -= l_[k][i] * x[k];
      x[i] = v;
    }
    return x;
  }

 private:
  double l_[kNumCoordinates][kNumCoordinates];   // unit lower triangle L (below the diagonal)
  double ld_[kNumCoordinates][kNumCoordinates];  // L·D, below the diagonal
  double inv_d_[kNumCoordinates];                // 1 / D
};

// aᵀ v for a knee's flexion row a = e_thigh − e_shank.
inline double flexionOf(const Vector5& v, int knee) {
  return knee == 0 ? v[kStanceThigh] - v[kStanceShank] : v[kSwingThigh] - v[kSwingShank];
}

}  // namespace

JointTorques jointTorques(const WalkerControls& c, const Vector5& q, const Vector5& qdot) {
  const SpringParameters& s = c.springs;
  JointTorques t;
  // Eq. 1, stance knee with rest flexion 0, and swing knee.
  t[kStanceKnee] = -s.stance_knee_stiffness * (q[kStanceThigh] - q[kStanceShank]) -
                   s.stance_knee_damping * (qdot[kStanceThigh] - qdot[kStanceShank]) +
                   c.offsets.stance_knee;
  t[kSwingKnee] =
      -s.swing_knee_stiffness * (q[kSwingThigh] - q[kSwingShank] - s.swing_knee_rest_angle) -
      s.swing_knee_damping * (qdot[kSwingThigh] - qdot[kSwingShank]) + c.offsets.swing_knee;
  // Eq. 2: undamped hip spring between the thighs, rest angle 0.
  t[kHip] = -s.hip_stiffness * (q[kStanceThigh] - q[kSwingThigh]) + c.offsets.hip;
  // Eq. 3: torso spring and damper on the torso's absolute angle.
  t[kTorsoJoint] = -s.torso_stiffness * (q[kTorso] - s.torso_rest_angle) -
                   s.torso_damping * qdot[kTorso] + c.offsets.torso;
  t[kStanceAnkle] = c.offsets.stance_ankle;
  return t;
}

Vector5 generalisedForce(const JointTorques& t) {
  Vector5 f = Vector5::Zero();
  f[kStanceThigh] += t[kStanceKnee];
  f[kStanceShank] -= t[kStanceKnee];
  f[kSwingThigh] += t[kSwingKnee];
  f[kSwingShank] -= t[kSwingKnee];
  f[kStanceThigh] += t[kHip];
  f[kSwingThigh] -= t[kHip];
  f[kTorso] += t[kTorsoJoint];
  f[kStanceThigh] -= t[kTorsoJoint];
  f[kStanceShank] += t[kStanceAnkle];
  return f;
}

InertiaCoefficients inertiaCoefficients(const KinematicMap& map) {
  InertiaCoefficients k;
  for (const BodyMap& body : map.bodies) {
    for (int i = 0; i < kNumCoordinates; ++i) {
      k.d[i] += body.mass * body.com.w[i];
      for (int j = 0; j < kNumCoordinates; ++j)
        k.c[i][j] += body.mass * std::conj(body.com.w[i]) * body.com.w[j];
    }
    k.inertia[body.angle] += body.inertia;
    k.total_mass += body.mass;
  }
  k.foot_radius = map.foot_radius;
  k.rolling_coordinate = map.rolling_coordinate;
  return k;
}

void equationsOfMotion(const InertiaCoefficients& k, const Point& g_vec, const Vector5& q,
                       const Vector5& qdot, const Vector5& applied_force, EquationsOfMotion& out) {
  const auto e = phasors(q);
  const int roll = k.rolling_coordinate;
  const double r = k.foot_radius;
  Matrix5& m = out.mass;
  Vector5& f = out.force;
  f = applied_force;
  std::array<double, kNumCoordinates> rate_sq;
  for (int j = 0; j < kNumCoordinates; ++j) rate_sq[j] = qdot[j] * qdot[j];
  for (int j = 0; j < kNumCoordinates; ++j) {
    // Diagonal: C_jj is real; its convective term Im(C_jj) q̇_j² vanishes.
    m(j, j) = k.c[j][j].real() + k.inertia[j];
    for (int l = j + 1; l < kNumCoordinates; ++l) {
      // P_jl = C_jl e^{i(q_l − q_j)}; P_lj = conj(P_jl).
      const Point p = k.c[j][l] * (e[l] * std::conj(e[j]));
      m(j, l) = m(l, j) = p.real();
      f[j] += rate_sq[l] * p.imag();
      f[l] -= rate_sq[j] * p.imag();
    }
    const Point de = k.d[j] * e[j];
    f[j] += dot(kI * de, g_vec);  // gravity: Σ_b m_b T_bj · g
  }
  // Rolling base: T_b,roll gains −R for every body.
  for (int j = 0; j < kNumCoordinates; ++j) {
    const Point de = k.d[j] * e[j];
    m(j, roll) += r * de.imag();
    m(roll, j) += r * de.imag();
    f[roll] -= r * rate_sq[j] * de.real();  // −R Σ_b m_b Re(−conv_b)
  }
  m(roll, roll) += r * r * k.total_mass;
  f[roll] -= r * g_vec.real() * k.total_mass;
}

Vector5 kneeFlexionRow(int knee) {
  Vector5 a = Vector5::Zero();
  const int thigh = knee == 0 ? kStanceThigh : kSwingThigh;
  const int shank = knee == 0 ? kStanceShank : kSwingShank;
  a[thigh] = 1.0;
  a[shank] = -1.0;
  return a;
}

Vector5 constrainedAcceleration(const EquationsOfMotion& eom, const KneeFlags& on_limit,
                                KneeFlags* active) {
  const MassCholesky chol(eom.mass);
  const Vector5 free_acc = chol.solve(eom.force);
  if (!on_limit[0] && !on_limit[1]) {
    if (active) *active = {false, false};
    return free_acc;
  }
  // u_k = M⁻¹ a_k for the knees on their limit; with virtual torques τ_k a_k,
  // q̈ = q̈_free + Σ τ_k u_k (eq. 8).
  std::array<Vector5, kNumKnees> u;
  for (int k = 0; k < kNumKnees; ++k)
    if (on_limit[k]) u[k] = chol.solve(kneeFlexionRow(k));
  Vector5 result = free_acc;
  KneeFlags chosen{};
  forEachKneeSubset(on_limit, [&](const KneeFlags& subset) {
    // Schur complement S τ = −Aᵀ q̈_free with S_kl = a_kᵀ M⁻¹ a_l, solved in closed form
    // (1×1 or 2×2, symmetric positive definite).
    double tau[kNumKnees] = {0, 0};
    if (subset[0] && subset[1]) {
      const double s00 = flexionOf(u[0], 0), s01 = flexionOf(u[1], 0), s11 = flexionOf(u[1], 1);
      const double r0 = -flexionOf(free_acc, 0), r1 = -flexionOf(free_acc, 1);
      const double det = s00 * s11 - s01 * s01;
      tau[0] = (s11 * r0 - s01 * r1) / det;
      tau[1] = (s00 * r1 - s01 * r0) / det;
    } else {
      for (int k = 0; k < kNumKnees; ++k)
        if (subset[k]) tau[k] = -flexionOf(free_acc, k) / flexionOf(u[k], k);
    }
    Vector5 acc = free_acc;
    for (int k = 0; k < kNumKnees; ++k)
      if (subset[k]) acc += tau[k] * u[k];
    for (int k = 0; k < kNumKnees; ++k) {
      if (subset[k] && tau[k] < -kComplementarityTolerance) return false;  // would pull
      if (!subset[k] && on_limit[k] && flexionOf(acc, k) < -kComplementarityTolerance)
        return false;  // a free knee on its limit would hyperextend
    }
    result = acc;
    chosen = subset;
    return true;
  });
  if (active) *active = chosen;
  return result;
}

Vector5 projectKneeVelocity(const Matrix5& mass, const Vector5& qdot, const KneeFlags& knees,
                            double sticking_rate) {
  // Eq. 6 for the knees whose limit impulse is needed: [M −A; Aᵀ 0][q̇⁺; λ] = [M q̇⁻; 0] with
  // λ ≥ 0 (the kneecap pushes), and every other listed knee leaving at sticking_rate or more.
  // When no set qualifies (a knee would leave, but too slowly), all listed knees are held.
  using Solve = ConstrainedSolve<kNumCoordinates>;
  const Eigen::LLT<Matrix5> llt(mass);
  const Vector5 momentum = mass * qdot;
  Vector5 result = qdot;
  const double leave_rate = std::max(sticking_rate, -kComplementarityTolerance);
  const bool found = forEachKneeSubset(knees, [&](const KneeFlags& subset) {
    const Solve::Rows g = kneeRows<kNumCoordinates>(subset);
    Vector5 candidate;
    Solve::VecR lambda;
    Solve::solve(llt, momentum, g, Solve::VecR::Zero(g.rows()), candidate, lambda);
    int row = 0;
    for (int k = 0; k < kNumKnees; ++k) {
      if (subset[k] && lambda[row++] < -kComplementarityTolerance) return false;
      if (!subset[k] && knees[k] && kneeFlexionRow(k).dot(candidate) < leave_rate) return false;
    }
    result = candidate;
    return true;
  });
  if (!found) {
    const Solve::Rows g = kneeRows<kNumCoordinates>(knees);
    Solve::VecR lambda;
    Solve::solve(llt, momentum, g, Solve::VecR::Zero(g.rows()), result, lambda);
  }
  return result;
}

Vector5 projectKneePosition(const Matrix5& mass, const Vector5& q, const KneeFlags& knees) {
  using Solve = ConstrainedSolve<kNumCoordinates>;
  const Solve::Rows g = kneeRows<kNumCoordinates>(knees);
  // min ½ ΔqᵀMΔq subject to a_kᵀ(q + Δq) = 0.
  const Eigen::LLT<Matrix5> llt(mass);
  Vector5 delta;
  Solve::VecR lambda;
  Solve::solve(llt, Vector5::Zero(), g, -(g * q), delta, lambda);
  return q + delta;
}

HeelStrike heelStrike(const KinematicMap& map, const Vector5& q, const Vector5& qdot,
                      double toe_off_impulse, const KneeFlags& knees_on_limit) {
  // Floating-base coordinates z = (C_x, C_y, q): the old stance foot centre is set free so
  // that its contact can be released and the new one imposed (walker-model.md §2).
  constexpr int kN = kNumCoordinates + 2;
  using Solve = ConstrainedSolve<kN>;
  using VecN = Solve::VecN;
  const auto e = phasors(q);

  Solve::MatN m = Solve::MatN::Zero();
  for (const BodyMap& body : map.bodies) {
    std::array<Point, kN> v;
    v[0] = 1.0;
    v[1] = kI;
    for (int j = 0; j < kNumCoordinates; ++j) v[2 + j] = kI * body.com.w[j] * e[j];
    for (int a = 0; a < kN; ++a)
      for (int b = a; b < kN; ++b) m(a, b) += body.mass * dot(v[a], v[b]);
    m(2 + body.angle, 2 + body.angle) += body.inertia;
  }
  m.template triangularView<Eigen::StrictlyLower>() = m.transpose();

  VecN z_dot;
  z_dot << -map.foot_radius * qdot[map.rolling_coordinate], 0.0, qdot;

  // Toe-off impulse ι at the old stance foot's contact point P1 = C − iR, towards the hip.
  VecN momentum = m * z_dot;
  if (toe_off_impulse != 0) {
    const Point to_hip = relativePosition(map.hip, e) + kI * map.foot_radius;
    const Point u = to_hip / std::abs(to_hip);
    // Velocity of P1 (on the rigid stance foot): v_C + R q̇_S1 along x.
    momentum[0] += toe_off_impulse * u.real();
    momentum[1] += toe_off_impulse * u.imag();
    momentum[2 + map.rolling_coordinate] += toe_off_impulse * u.real() * map.foot_radius;
  }

  // New contact: the swing sole point P2 = C2 − iR, velocity v_C2 + R q̇_S2 along x, must stop.
  Solve::Rows contact(2, kN);
  contact.setZero();
  contact(0, 0) = 1.0;
  contact(1, 1) = 1.0;
  for (int j = 0; j < kNumCoordinates; ++j) {
    const Point vj = kI * map.swing_foot_centre.w[j] * e[j];
    contact(0, 2 + j) = vj.real();
    contact(1, 2 + j) = vj.imag();
  }
  contact(0, 2 + kSwingShank) += map.foot_radius;
  // The old stance sole's normal velocity v_Cy: held at 0 when the impact would drive the sole
  // into the ground. The hold is frictionless (the normal row alone), so that with the knees
  // the active set is a linear complementarity problem with a positive definite matrix, which
  // always has one solution; with no slip at both soles some impacts have none.
  Solve::Rows trailing(1, kN);
  trailing.setZero();
  trailing(0, 1) = 1.0;

  // The active set by enumeration: the trailing sole free (it must then rise) or held (the
  // ground must then push it), each with the knee subsets (a held knee's impulse ≥ 0, a free
  // one must not hyperextend).
  const Eigen::LLT<Solve::MatN> llt(m);
  HeelStrike result{};
  VecN z_after = z_dot;
  for (const bool hold : {false, true}) {
    const int sole_rows = hold ? 3 : 2;
    const bool found = forEachKneeSubset(knees_on_limit, [&](const KneeFlags& subset) {
      const Solve::Rows knee_rows = kneeRows<kN>(subset, 2);
      Solve::Rows g(sole_rows + knee_rows.rows(), kN);
      if (hold)
        g << contact, trailing, knee_rows;
      else
        g << contact, knee_rows;
      VecN z;
      Solve::VecR lambda;
      Solve::solve(llt, momentum, g, Solve::VecR::Zero(g.rows()), z, lambda);
      if (hold ? lambda[2] < -kComplementarityTolerance : z[1] < -kComplementarityTolerance)
        return false;
      int row = sole_rows;
      for (int k = 0; k < kNumKnees; ++k) {
        const double flexion_rate = kneeFlexionRow(k).dot(z.tail<kNumCoordinates>());
        if (subset[k] && lambda[row++] < -kComplementarityTolerance) return false;
        if (!subset[k] && knees_on_limit[k] && flexion_rate < -kComplementarityTolerance)
          return false;
      }
      z_after = z;
      result.knees_held = subset;
      result.ground_normal_impulse = lambda[1];
      result.trailing_sole_held = hold;
      result.trailing_sole_impulse = hold ? lambda[2] : 0.0;
      result.trailing_sole_rate = z[1];  // v_Cy: the released sole moves with its centre along y
      result.solved = true;
      return true;
    });
    if (found) break;
  }
  result.qdot_after = z_after.tail<kNumCoordinates>();
  return result;
}

double mechanicalEnergy(const KinematicMap& map, double gravity, double ground_slope,
                        const Vector5& q, const Vector5& qdot, double x0) {
  const auto e = phasors(q);
  const Point base = stanceFootCentre(map, q, x0);
  double energy = 0;
  for (const BodyMap& body : map.bodies) {
    const Point p = base + relativePosition(body.com, e);
    const Point v = velocity(map, body.com, q, qdot);
    energy += 0.5 * body.mass * std::norm(v) + 0.5 * body.inertia * qdot[body.angle] * qdot[body.angle];
    energy += body.mass * gravity *
              (std::sin(ground_slope) * p.real() + std::cos(ground_slope) * p.imag());
  }
  return energy;
}

double angularMomentum(const KinematicMap& map, const Vector5& q, const Vector5& qdot, double x0,
                       Point about) {
  const auto e = phasors(q);
  const Point base = stanceFootCentre(map, q, x0);
  double h = 0;
  for (const BodyMap& body : map.bodies) {
    const Point p = base + relativePosition(body.com, e);
    h += body.mass * cross(p - about, velocity(map, body.com, q, qdot)) +
         body.inertia * qdot[body.angle];
  }
  return h;
}

}  // namespace kneed_walker::core::dynamics
