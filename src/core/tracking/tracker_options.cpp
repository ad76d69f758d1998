#include "kneed_walker/core/tracking/tracker_options.h"

#include <cmath>
#include <sstream>

namespace kneed_walker::core::tracking {

using common::OptionField;

const common::OptionTable<TrackerOptions>& trackerOptionTable() {
  using O = TrackerOptions;
  static const common::OptionTable<TrackerOptions> table{
      {"num_particles", [](O& o) -> OptionField { return &o.filter.num_particles; }, 1, 1e6, "",
       "particles per person (the paper: 5000)"},
      {"resample_ess_fraction", [](O& o) -> OptionField { return &o.filter.resample_ess_fraction; }, 1e-6, 1, "",
       "resample when the effective sample size falls below this fraction of the particles (the paper: 0.1)"},
      {"resample_lag_frames", [](O& o) -> OptionField { return &o.filter.resample_lag_frames; }, 0, 30, "frames",
       "Δs: resample from time t − Δs (paper §4)"},
      {"resample_mixing", [](O& o) -> OptionField { return &o.filter.resample_mixing; }, 0, 1, "",
       "γ: weight of the time-t weights in the resampling mixture (paper §4)"},
      {"initial_oversampling", [](O& o) -> OptionField { return &o.filter.initial_oversampling; }, 1, 1000, "",
       "a track's first frame weighs this many times num_particles candidates and keeps num_particles"},
      {"num_threads", [](O& o) -> OptionField { return &o.filter.num_threads; }, 0, 256, "",
       "worker threads for the per-particle work; 0: all cores"},
      {"seed", [](O& o) -> OptionField { return &o.filter.seed; }, 0, 1.8446744073709552e19, "",
       "random seed: the same input and seed give the same output"},
      {"person_height_m", [](O& o) -> OptionField { return &o.person_height_m; }, kMinPersonHeightM, kMaxPersonHeightM, "m",
       "the person's standing height (not given: each person's is measured by their ground track)"},
      {"person_mass_kg", [](O& o) -> OptionField { return &o.person_mass_kg; }, 20, 250, "kg", "the person's mass"},
      {"person_breadth_scale", [](O& o) -> OptionField { return &o.person_breadth_scale; }, 0.5, 3, "",
       "the projected torso and thighs this many times as broad as the body model's (a coat, arms)"},
      {"ground_slope_rad", [](O& o) -> OptionField { return &o.ground_slope_rad; }, -0.2, 0.2, "rad",
       "ground slope along the walk, positive uphill (0 with a calibration file: the file gives the ground)"},
      {"min_gait_speed_kmh", [](O& o) -> OptionField { return &o.min_gait_speed_kmh; }, 0, 20, "km/h",
       "the slowest of the gait table's gaits the particles may walk (1.5 with min_gait_step_m 0.3: strolling)"},
      {"min_gait_step_m", [](O& o) -> OptionField { return &o.min_gait_step_m; }, 0, 3, "m",
       "the shortest step of the gait table's gaits the particles may walk"},
      {"gait_speed_sd_kmh", [](O& o) -> OptionField { return &o.gait_speed_sd_kmh; }, 0, 5, "km/h",
       "speed changes: a particle's target speed steps by N(0, this²) at each heel strike"},
      {"gait_step_sd_m", [](O& o) -> OptionField { return &o.gait_step_sd_m; }, 0, 0.5, "m",
       "step changes: a particle's target step length steps by N(0, this²) at each heel strike"},
      {"gait_change_persistence", [](O& o) -> OptionField { return &o.gait_change_persistence; }, 0, 0.95, "",
       "this fraction of a target's last step is carried into its next (0.8 for people who keep slowing)"},
      {"gait_slope_change_probability", [](O& o) -> OptionField { return &o.gait_slope_change_probability; }, 0, 1,
       "", "on a hill: the chance per heel strike that a particle's gait moves to a neighbouring slope's"},
      {"lost_likelihood_fraction", [](O& o) -> OptionField { return &o.lost_likelihood_fraction; }, 0, 1, "",
       "a track is lost after 3 frames whose best log-likelihood ratio is below this fraction of its recent "
       "median (0: below 0)"},
      {"ground_track_sd_m", [](O& o) -> OptionField { return &o.ground_track_sd_m; }, 0, 10, "m",
       "each particle's waist is also weighed against the person's ground track, with its covariance plus this "
       "spread (0: not held to it)"},
      {"ground_track_velocity_sd_mps", [](O& o) -> OptionField { return &o.ground_track_velocity_sd_mps; }, 0, 10,
       "m/s", "... and its walk's velocity against the track's, with its covariance plus this spread (0: not held)"},
      {"default_frame_interval_s", [](O& o) -> OptionField { return &o.default_frame_interval_s; }, 1e-4, 1, "s",
       "the frame interval when stamps are unusable"},
      {"max_frame_gap_s", [](O& o) -> OptionField { return &o.max_frame_gap_s; }, 1e-4, 60, "s",
       "a larger gap between stamps starts the track again"},
  };
  return table;
}

std::vector<std::string> validate(const TrackerOptions& o) {
  std::vector<std::string> problems = common::rangeProblems(o, trackerOptionTable());
  // Each candidate is weighed and its weight held (16 bytes): their number is bounded too.
  const FilterOptions& f = o.filter;
  if (f.num_particles >= 1 && f.initial_oversampling >= 1 &&
      static_cast<long long>(f.num_particles) * f.initial_oversampling > kMaxInitialCandidates) {
    std::ostringstream message;
    message << "initial_oversampling = " << f.initial_oversampling << " times num_particles = " << f.num_particles
            << " is " << static_cast<long long>(f.num_particles) * f.initial_oversampling
            << " candidates at a track's first frame, above " << kMaxInitialCandidates << ": lower either";
    problems.push_back(message.str());
  }
  if (!(std::isfinite(o.frame_budget_fraction) && o.frame_budget_fraction >= 0 && o.frame_budget_fraction <= 1))
    problems.push_back("frame_budget_fraction = " + std::to_string(o.frame_budget_fraction) + " is outside [0, 1]");
  // (A num_particles below 1 is named by the table's range already.)
  if (o.frame_budget_fraction > 0 && f.num_particles >= 1 && !(o.min_particles >= 1 && o.min_particles <= f.num_particles))
    problems.push_back("min_particles = " + std::to_string(o.min_particles) + " is outside [1, num_particles = " +
                       std::to_string(f.num_particles) + "]");
  if (o.max_frame_gap_s < o.default_frame_interval_s)
    problems.push_back("max_frame_gap_s = " + std::to_string(o.max_frame_gap_s) +
                       " is below default_frame_interval_s = " + std::to_string(o.default_frame_interval_s));
  return problems;
}

}  // namespace kneed_walker::core::tracking
