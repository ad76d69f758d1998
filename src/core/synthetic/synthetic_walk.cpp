#include "kneed_walker/core/synthetic/synthetic_walk.h"

#include "kneed_walker/core/common/config_file.h"
#include "kneed_walker/core/prior/body_prior.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace kneed_walker::core::synthetic {

std::vector<std::string> validate(const SyntheticWalkOptions& o) {
  std::vector<std::string> problems;
  auto positive = [&](const char* name, double v) {
    if (!(std::isfinite(v) && v > 0)) problems.push_back(std::string(name) + " must be > 0");
  };
  positive("speed_kmh", o.speed_kmh);
  positive("step_length_m", o.step_length_m);
  positive("duration_s", o.duration_s);
  positive("fps", o.fps);
  if (!(o.person_height_m >= 1.0 && o.person_height_m <= 2.3))
    problems.push_back("person_height_m must lie in [1.0, 2.3]");
  if (!(std::abs(o.slope_rad) <= 0.2)) problems.push_back("slope_rad must lie in [-0.2, 0.2]");
  if (!std::isfinite(o.heading_rad)) problems.push_back("heading_rad must be finite");
  if (!o.start_m.allFinite()) problems.push_back("start_m must be finite");
  if (o.max_attempts < 1) problems.push_back("max_attempts must be >= 1");
  if (o.duration_s * o.fps > 100000) problems.push_back("duration_s * fps must be at most 100000 frames");
  return problems;
}

SyntheticWalk synthesizeWalk(const gait::GaitTable& table, const prior::PriorOptions& prior_options,
                             const SyntheticWalkOptions& o) {
  const auto problems = validate(o);
  common::throwIfInvalid("synthetic walk", problems);

  prior::requirePriorTable(table, prior_options);
  SyntheticWalk walk;
  const double leg_length_m = table.grid.leg_length_per_height * o.person_height_m;
  walk.leg_length_m = leg_length_m;
  // Froude similarity: the same dimensionless gait for the table's reference person.
  const double reference_leg_m = table.grid.referenceLegLength();
  const double speed_ref_kmh = o.speed_kmh * std::sqrt(reference_leg_m / leg_length_m);
  const double step_ref_m = o.step_length_m * reference_leg_m / leg_length_m;
  const dynamics::WalkerSimulator sim(dynamics::dimensionlessWalker(table.body));
  gait::InterpolationNote note;
  walk.gait = gait::interpolateGait(table, speed_ref_kmh, step_ref_m, o.slope_rad, &note);
  walk.gait_note = note.describe(table.grid);
  const dynamics::StrideResult stride = sim.stride(walk.gait.controls, walk.gait.start);
  if (!stride.completed)
    throw std::runtime_error("synthetic walk: the interpolated gait does not complete a stride");
  walk.gait.stride_duration = stride.duration;

  prior::PriorOptions options = prior_options;
  if (o.slope_rad != 0) options.placement.heading_sigma = 0;  // the slope is one plane
  const prior::BodyPrior prior(prior::WalkerPrior(sim, walk.gait, options), o.person_height_m,
                               table.grid.leg_length_per_height, table.grid.gravity);
  const double frame_s = 1.0 / o.fps;
  const int frame_count = static_cast<int>(std::floor(o.duration_s * o.fps)) + 1;

  common::Random random(o.seed);
  std::uniform_real_distribution<double> phase(0.0, 1.0);
  double longest_s = 0;  // walked before falling, over the samples
  for (walk.attempts = 1; walk.attempts <= o.max_attempts; ++walk.attempts) {
    SyntheticFrame frame;
    prior::BodyParticle particle = prior.sample(phase(random), o.start_m, o.heading_rad, random, frame.pose);
    walk.ground = vision::GroundPlane{particle.placement.value.ground_origin_m, o.slope_rad, o.heading_rad};
    walk.frames.clear();
    walk.frames.reserve(frame_count);
    bool fell = false;
    for (int i = 0; i < frame_count && !fell; ++i) {
      if (i > 0) fell = prior.transition(particle, frame_s, random, frame.pose).fell;
      if (fell) longest_s = std::max(longest_s, (i - 1) * frame_s);
      frame.time_s = i * frame_s;
      frame.walker = particle.walker.walker;
      frame.placement = particle.placement.value;
      walk.frames.push_back(frame);
    }
    if (!fell) return walk;
  }
  std::ostringstream message;
  message << "synthetic walk: all " << o.max_attempts << " samples of the prior fell within the " << o.duration_s
          << " s asked (the longest walked " << longest_s
          << " s): a chain of sampled strides falls sooner or later (at the default gait most within about 16 s), "
             "so make shorter walks, or walk nearer a table gait, or with less prior noise";
  throw std::runtime_error(message.str());
}

}  // namespace kneed_walker::core::synthetic
