// The median and percentiles of timings, for the benchmark tools (they report medians: shared
// machines are noisy).
#pragma once

#include <algorithm>
#include <vector>

namespace kneed_walker::tools {

// The p-th percentile (0 ≤ p ≤ 100), interpolated linearly between the nearest ranks; 0 for no
// values.
inline double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double rank = std::clamp(p, 0.0, 100.0) / 100.0 * (v.size() - 1);
  const size_t below = static_cast<size_t>(rank);
  const size_t above = std::min(below + 1, v.size() - 1);
  return v[below] + (rank - below) * (v[above] - v[below]);
}

// The median (the mean of the middle two of an even count); 0 for no values.
inline double median(const std::vector<double>& v) { return percentile(v, 50); }

}  // namespace kneed_walker::tools
