// The one random generator type of the project: every stochastic function takes one from its
// caller, so that the same seed gives the same result (seeded and injectable randomness).
#pragma once

#include <cstdint>
#include <random>

namespace kneed_walker::core::common {

using Random = std::mt19937_64;

// SplitMix64's finaliser: a fixed, platform-independent hash of a 64-bit integer (seeds of
// particle chunks, procedural textures).
inline std::uint64_t splitMix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

}  // namespace kneed_walker::core::common
