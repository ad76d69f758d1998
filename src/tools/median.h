// The median of timings, for the benchmark tools (they report medians: shared machines are noisy).
#pragma once

#include <algorithm>
#include <vector>

namespace kneed_walker::tools {

// The median; 0 for no values.
inline double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace kneed_walker::tools
