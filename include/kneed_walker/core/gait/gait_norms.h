// Measured gait norms: mean ± 1 SD joint angles over the gait cycle at five walking speeds, as
// Schwartz, Rozumalski & Trost publish them (J. Biomech. 2008; ../shared/data/gait/
// Schwartz2008_Joint_Rotations.csv, CC BY-SA 4.0). compare_gait_norms compares table gaits with
// them; synthetic/norm_walk.h walks a body by them (test sequences the prior did not make).
//
// The cycle runs from one foot's contact (0) to its next contact (1); angles in degrees, in the
// study's conventions (flexion, anterior tilt and adduction positive).
#pragma once

#include <map>
#include <string>
#include <vector>

namespace kneed_walker::core::gait {

// One angle over the cycle: samples at `cycle` (fractions, increasing, from 0 to 1).
struct NormCurve {
  std::vector<double> cycle, low, mean, high;  // degrees: mean − 1 SD, mean, mean + 1 SD
  // The mean at `phase` (any real: the cycle repeats), linearly interpolated.
  double meanAt(double phase) const;
};

// The curves of one speed class ("Very Slow", "Slow", "Free", "Fast", "Very Fast"), by the
// angle's name in the file ("Knee Flex/Extension", ...).
struct NormSpeedClass {
  std::string name;
  std::map<std::string, NormCurve> curves;
  const NormCurve& curve(const std::string& angle) const;  // throws std::out_of_range naming it
};

struct GaitNorms {
  std::string source;  // the file read
  std::vector<NormSpeedClass> classes;  // in the file's order: slowest first
  const NormSpeedClass& speedClass(const std::string& name) const;  // throws std::out_of_range naming it
};

// Reads the joint-rotations CSV: a header row of speed classes (each over three columns,
// −1sd, mean, +1sd), a sub-header, then rows `angle name, % cycle, values...`. Throws
// std::runtime_error naming the file and the row for an unreadable file, a malformed number, a
// curve whose cycle does not run from 0 to 1 in increasing order, or rows of unequal length.
GaitNorms loadGaitNorms(const std::string& path);

}  // namespace kneed_walker::core::gait
