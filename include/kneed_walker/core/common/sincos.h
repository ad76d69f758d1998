// sin and cos of one angle together, for the per-particle hot path (every evaluation of the
// walker's equations of motion needs e^{i q_j} of all five angles).
//
// Written here because it must be faster than the C library's sincos, which costs about 18 ns
// per call on this project's machines and was a quarter of the dynamics' time
// (bench_dynamics). Method: Cody–Waite reduction by multiples of π/2, then the minimax
// polynomial kernels of fdlibm's __kernel_sin / __kernel_cos (Sun Microsystems, freely
// distributable), accurate to about 1 ulp on |r| ≤ π/4. Valid for |x| < 1e5 rad; test_sincos
// checks it against std::sin / std::cos.
#pragma once

#include <cmath>

namespace kneed_walker::core::common {

inline void sinCos(double x, double& sin_x, double& cos_x) {
  constexpr double kTwoOverPi = 6.36619772367581382433e-01;
  constexpr double kPiOver2Hi = 1.57079632673412561417e+00;  // first 33 bits of π/2
  constexpr double kPiOver2Lo = 6.07710050650619224932e-11;  // π/2 − kPiOver2Hi
  // k = nearbyint(x · 2/π) by the 1.5·2⁵² trick: adding it leaves no fraction bits, so the
  // sum is rounded to the nearest integer (ties to even, the default mode, as nearbyint),
  // exactly, for |x · 2/π| < 2⁵¹. Without SSE4.1's roundsd, std::nearbyint is a call into
  // libm, five per evaluation of the equations of motion.
  constexpr double kRoundingShift = 6755399441055744.0;  // 1.5 · 2⁵²
  const double k = (x * kTwoOverPi + kRoundingShift) - kRoundingShift;
  const double r = (x - k * kPiOver2Hi) - k * kPiOver2Lo;  // |r| ≤ π/4
  const double z = r * r;
  const double s = r + r * z * (-1.66666666666666324348e-01 +
                                z * (8.33333333332248946124e-03 +
                                     z * (-1.98412698298579493134e-04 +
                                          z * (2.75573137070700676789e-06 +
                                               z * (-2.50507602534068634195e-08 +
                                                    z * 1.58969099521155010221e-10)))));
  const double c = 1.0 - 0.5 * z +
                   z * z * (4.16666666666666019037e-02 +
                            z * (-1.38888888888741095749e-03 +
                                 z * (2.48015872894767294178e-05 +
                                      z * (-2.75573143513906633035e-07 +
                                           z * (2.08757232129817482790e-09 +
                                                z * -1.13596475577881948265e-11)))));
  // Quadrant: x = r + k π/2.
  switch (static_cast<long>(k) & 3) {
    case 0: sin_x = s; cos_x = c; break;
    case 1: sin_x = c; cos_x = -s; break;
    case 2: sin_x = -s; cos_x = -c; break;
    default: sin_x = -c; cos_x = s; break;
  }
}

}  // namespace kneed_walker::core::common
