// The one random generator type of the project: every stochastic function takes one from its
// caller, so that the same seed gives the same result (seeded and injectable randomness).
#pragma once

#include <random>

namespace kneed_walker::core::common {

using Random = std::mt19937_64;

}  // namespace kneed_walker::core::common
