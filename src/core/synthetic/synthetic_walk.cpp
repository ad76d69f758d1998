#include "kneed_walker/core/synthetic/synthetic_walk.h"

#include "kneed_walker/core/common/config_file.h"
#include "kneed_walker/core/prior/body_prior.h"

#include <algorithm>
#include <cmath>
#include <set>
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
  if (o.end_speed_kmh) positive("end_speed_kmh", *o.end_speed_kmh);
  if (o.end_step_length_m) positive("end_step_length_m", *o.end_step_length_m);
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
  const double speed_scale = std::sqrt(reference_leg_m / leg_length_m);
  const double end_speed_kmh = o.end_speed_kmh.value_or(o.speed_kmh);
  const double end_step_m = o.end_step_length_m.value_or(o.step_length_m);
  const bool changing = end_speed_kmh != o.speed_kmh || end_step_m != o.step_length_m;
  const dynamics::WalkerSimulator sim(dynamics::dimensionlessWalker(table.body));
  prior::PriorOptions options = prior_options;
  if (o.slope_rad != 0) options.placement.heading_sigma = 0;  // the slope is one plane
  std::set<std::string> notes;  // of the gaits walked: the start's, then the sample's strides'
  // The gait at fraction f ∈ [0, 1] of the walk's change of speed and step.
  auto gaitAt = [&](double f) {
    gait::InterpolationNote note;
    gait::Gait gait;
    try {
      gait = prior::priorGait(table, sim, ((1 - f) * o.speed_kmh + f * end_speed_kmh) * speed_scale,
                              ((1 - f) * o.step_length_m + f * end_step_m) * reference_leg_m / leg_length_m,
                              o.slope_rad, &note);
    } catch (const std::runtime_error& e) {
      throw std::runtime_error(std::string("synthetic walk: ") + e.what());
    }
    if (!note.exact()) notes.insert(note.describe(table.grid));
    return gait;
  };
  if (changing) {  // the change's end inside the table, said in its own terms before any walking
    try {
      gaitAt(1.0);
    } catch (const std::out_of_range& e) {
      std::ostringstream message;
      message << "synthetic walk: end_speed_kmh = " << end_speed_kmh << ", end_step_length_m = " << end_step_m
              << ": " << e.what();
      throw std::out_of_range(message.str());
    }
    notes.clear();
  }
  walk.gait = gaitAt(0.0);
  const prior::BodyPrior prior(prior::WalkerPrior(sim, walk.gait, options), o.person_height_m,
                               table.grid.leg_length_per_height, table.grid.gravity);
  const std::set<std::string> start_notes = notes;
  const double frame_s = 1.0 / o.fps;
  const int frame_count = static_cast<int>(std::floor(o.duration_s * o.fps)) + 1;

  common::Random random(o.seed);
  std::uniform_real_distribution<double> phase(0.0, 1.0);
  double longest_s = 0;  // walked before falling, over the samples
  for (walk.attempts = 1; walk.attempts <= o.max_attempts; ++walk.attempts) {
    SyntheticFrame frame;
    notes = start_notes;
    prior::BodyParticle particle = prior.sample(phase(random), o.start_m, o.heading_rad, random, frame.pose);
    walk.ground = vision::GroundPlane{particle.placement.value.ground_origin_m, o.slope_rad, o.heading_rad};
    walk.frames.clear();
    walk.frames.reserve(frame_count);
    bool fell = false;
    for (int i = 0; i < frame_count && !fell; ++i) {
      if (i > 0) {
        const std::uint32_t strikes = particle.walker.walker.heel_strikes;
        fell = prior.transition(particle, frame_s, random, frame.pose).fell;
        if (changing && particle.walker.walker.heel_strikes != strikes)  // the next stride's gait
          prior::walkGait(particle.walker, gaitAt(std::min(1.0, i * frame_s / o.duration_s)).controls);
      }
      if (fell) longest_s = std::max(longest_s, (i - 1) * frame_s);
      frame.time_s = i * frame_s;
      frame.walker = particle.walker.walker;
      frame.placement = particle.placement.value;
      walk.frames.push_back(frame);
    }
    if (!fell) {
      for (const std::string& note : notes) walk.gait_note += (walk.gait_note.empty() ? "" : "; ") + note;
      return walk;
    }
  }
  std::ostringstream message;
  message << "synthetic walk: all " << o.max_attempts << " samples of the prior fell within the " << o.duration_s
          << " s asked (the longest walked " << longest_s
          << " s): a chain of sampled strides falls sooner or later (at the default gait most within about 16 s), "
             "so make shorter walks, or walk nearer a table gait, or with less prior noise";
  throw std::runtime_error(message.str());
}

}  // namespace kneed_walker::core::synthetic
