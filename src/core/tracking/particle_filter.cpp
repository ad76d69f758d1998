#include "kneed_walker/core/tracking/particle_filter.h"

namespace kneed_walker::core::tracking {

std::uint64_t mixSeed(std::uint64_t seed, std::uint64_t frame, std::uint64_t pass, std::uint64_t chunk) {
  using common::splitMix64;
  return splitMix64(splitMix64(splitMix64(splitMix64(seed) ^ frame) ^ pass) ^ chunk);
}

double logSumExp(const std::vector<double>& x) {
  double top = -std::numeric_limits<double>::infinity();
  for (double v : x) top = std::max(top, v);
  if (!std::isfinite(top)) return top;
  double sum = 0;
  for (double v : x) sum += std::exp(v - top);
  return top + std::log(sum);
}

}  // namespace kneed_walker::core::tracking
