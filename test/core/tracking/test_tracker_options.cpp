#include "kneed_walker/core/tracking/tracker_options.h"

#include <gtest/gtest.h>

#include <limits>
#include <set>
#include <string>

namespace kneed_walker::core::tracking {
namespace {

TEST(TrackerOptions, DefaultsAreThePapersAndValid) {
  const TrackerOptions options;
  EXPECT_TRUE(validate(options).empty());
  EXPECT_EQ(options.filter.num_particles, 5000);
  EXPECT_DOUBLE_EQ(options.filter.resample_ess_fraction * options.filter.num_particles, 500.0);
  EXPECT_EQ(options.filter.resample_lag_frames, 3);
  EXPECT_DOUBLE_EQ(options.filter.resample_mixing, 0.95);
}

// True when one of the problems mentions `text`.
bool mentions(const std::vector<std::string>& problems, const std::string& text) {
  for (const auto& problem : problems)
    if (problem.find(text) != std::string::npos) return true;
  return false;
}

TEST(TrackerOptions, EachProblemNamesItsField) {
  TrackerOptions options;
  options.filter.num_threads = -2;
  options.filter.resample_mixing = 1.5;
  options.person_height_m = std::numeric_limits<double>::quiet_NaN();
  options.min_gait_speed_kmh = std::numeric_limits<double>::infinity();
  options.min_gait_step_m = -0.1;
  options.person_breadth_scale = 0.2;
  options.gait_speed_sd_kmh = std::numeric_limits<double>::quiet_NaN();
  options.gait_step_sd_m = -0.01;
  options.gait_change_persistence = 1.0;
  options.lost_likelihood_fraction = std::numeric_limits<double>::infinity();
  options.filter.initial_oversampling = 0;
  options.gait_slope_change_probability = std::numeric_limits<double>::quiet_NaN();
  const auto problems = validate(options);
  EXPECT_EQ(problems.size(), 12u);
  EXPECT_TRUE(mentions(problems, "num_threads = -2 is outside [0, 256]"));
  EXPECT_TRUE(mentions(problems, "resample_mixing = 1.5"));
  EXPECT_TRUE(mentions(problems, "person_height_m = nan"));
  EXPECT_TRUE(mentions(problems, "min_gait_speed_kmh = inf"));
  EXPECT_TRUE(mentions(problems, "min_gait_step_m = -0.1"));
  EXPECT_TRUE(mentions(problems, "person_breadth_scale = 0.2"));
  EXPECT_TRUE(mentions(problems, "gait_speed_sd_kmh = nan"));
  EXPECT_TRUE(mentions(problems, "gait_step_sd_m = -0.01"));
  EXPECT_TRUE(mentions(problems, "gait_change_persistence = 1 is outside [0, 0.95]"));
  EXPECT_TRUE(mentions(problems, "lost_likelihood_fraction = inf"));
  EXPECT_TRUE(mentions(problems, "initial_oversampling = 0 is outside [1, 1000]"));
  EXPECT_TRUE(mentions(problems, "gait_slope_change_probability = nan is outside [0, 1]"));
}

TEST(TrackerOptions, TheResamplingThresholdIsAFractionOfTheParticles) {
  TrackerOptions options;
  options.filter.resample_ess_fraction = 5;
  const auto problems = validate(options);
  EXPECT_EQ(problems.size(), 1u);
  EXPECT_TRUE(mentions(problems, "resample_ess_fraction = 5 is outside [1e-06, 1]"));
}

// The option table is the one definition of every option: each names a member of its own,
// in snake_case, and holds its default in its range.
TEST(TrackerOptions, TheTableNamesEveryOptionOnceWithItsDefaultInRange) {
  TrackerOptions defaults;
  std::set<std::string> names;
  std::set<const void*> fields;
  for (const auto& spec : trackerOptionTable()) {
    EXPECT_TRUE(names.insert(spec.name).second) << spec.name;
    EXPECT_TRUE(fields.insert(std::visit([](auto* p) -> const void* { return p; }, spec.field(defaults))).second)
        << spec.name;
    EXPECT_EQ(std::string(spec.name).find_first_not_of("abcdefghijklmnopqrstuvwxyz_0123456789"), std::string::npos);
    EXPECT_TRUE(common::inRange(spec.field(defaults), spec.min, spec.max)) << spec.name;
    EXPECT_LT(spec.min, spec.max) << spec.name;
    EXPECT_GT(std::string(spec.help).size(), 10u) << spec.name;
  }
  EXPECT_EQ(common::kebabCase("min_gait_speed_kmh"), "min-gait-speed-kmh");
}

TEST(TrackerOptions, InitialCandidatesAreBounded) {
  TrackerOptions options;
  options.filter.num_particles = 1000000;
  options.filter.initial_oversampling = 1000;
  const auto problems = validate(options);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_TRUE(mentions(problems, "initial_oversampling = 1000 times num_particles = 1000000 is 1000000000 candidates"));
  options.filter.initial_oversampling = 10;
  EXPECT_TRUE(validate(options).empty());
}

TEST(TrackerOptions, FrameGapMustExceedDefaultInterval) {
  TrackerOptions options;
  options.default_frame_interval_s = 0.5;
  options.max_frame_gap_s = 0.2;
  const auto problems = validate(options);
  EXPECT_EQ(problems.size(), 1u);
  EXPECT_TRUE(mentions(problems, "max_frame_gap_s = 0.2"));
}

}  // namespace
}  // namespace kneed_walker::core::tracking
