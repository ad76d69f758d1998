#include "kneed_walker/core/tracking/particle_filter.h"

namespace kneed_walker::core::tracking {

std::uint64_t mixSeed(std::uint64_t seed, std::uint64_t frame, std::uint64_t pass, std::uint64_t chunk) {
  auto mix = [](std::uint64_t x) {
    x += 0x9e3779b97f4a7c15ULL;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
  };
  return mix(mix(mix(mix(seed) ^ frame) ^ pass) ^ chunk);
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
