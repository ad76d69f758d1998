#include "kneed_walker/core/common/sincos.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace kneed_walker::core::common {
namespace {

TEST(SinCos, AgreesWithTheCLibraryToAFewUlp) {
  std::mt19937 rng(5);
  double worst_small = 0, worst_large = 0;
  for (double range : {1.0, 4.0, 100.0, 1e4}) {
    std::uniform_real_distribution<double> angle(-range, range);
    for (int i = 0; i < 200000; ++i) {
      const double x = angle(rng);
      double s, c;
      sinCos(x, s, c);
      const double error = std::max(std::abs(s - std::sin(x)), std::abs(c - std::cos(x)));
      (range <= 4.0 ? worst_small : worst_large) = std::max(range <= 4.0 ? worst_small : worst_large, error);
    }
  }
  std::cout << "max |error|: " << worst_small << " for |x| <= 4, " << worst_large
            << " for |x| <= 1e4\n";
  EXPECT_LT(worst_small, 4e-16);
  EXPECT_LT(worst_large, 1e-14);
}

TEST(SinCos, ExactAtQuadrantBoundariesAndZero) {
  double s, c;
  sinCos(0.0, s, c);
  EXPECT_EQ(s, 0.0);
  EXPECT_EQ(c, 1.0);
  for (int k = -8; k <= 8; ++k) {
    const double x = k * M_PI / 2;
    sinCos(x, s, c);
    EXPECT_NEAR(s, std::sin(x), 1e-15) << x;
    EXPECT_NEAR(c, std::cos(x), 1e-15) << x;
  }
}

}  // namespace
}  // namespace kneed_walker::core::common
