#include "kneed_walker/core/tracking/tracker_options.h"

#include <cmath>
#include <sstream>

namespace kneed_walker::core::tracking {
namespace {

// Appends "name = value is outside [lo, hi] (meaning)" when value is not inside the range.
template <typename T>
void checkRange(std::vector<std::string>& problems, const char* name, T value, T lo, T hi,
                const char* meaning) {
  const bool finite = std::isfinite(static_cast<double>(value));
  if (finite && value >= lo && value <= hi) return;
  std::ostringstream message;
  message << name << " = " << value << " is outside [" << lo << ", " << hi << "] ("
          << meaning << ")";
  problems.push_back(message.str());
}

}  // namespace

std::vector<std::string> validate(const TrackerOptions& o) {
  std::vector<std::string> problems;
  checkRange(problems, "num_particles", o.num_particles, 1, 1000000, "particle count");
  if (o.num_particles >= 1)  // a bad particle count is reported by itself, not as this range's end
    checkRange(problems, "resample_ess_threshold", o.resample_ess_threshold, 1e-9,
               static_cast<double>(o.num_particles),
               "effective sample size below which to resample; at most num_particles: lower it, or leave it "
               "out for num_particles / 10");
  checkRange(problems, "resample_lag_frames", o.resample_lag_frames, 0, 30,
             "frames back to resample from (paper's Δs)");
  checkRange(problems, "resample_mixing", o.resample_mixing, 0.0, 1.0,
             "weight of the current-time weights in the resampling proposal, the paper's gamma");
  checkRange(problems, "initial_oversampling", o.initial_oversampling, 1, 1000,
             "candidates per particle drawn and weighed at a track's first frame");
  // The candidates are held at once: their number is bounded too.
  if (o.num_particles >= 1 && o.initial_oversampling >= 1 &&
      static_cast<long long>(o.num_particles) * o.initial_oversampling > kMaxInitialCandidates) {
    std::ostringstream message;
    message << "initial_oversampling = " << o.initial_oversampling << " times num_particles = " << o.num_particles
            << " is " << static_cast<long long>(o.num_particles) * o.initial_oversampling
            << " candidates at a track's first frame, above " << kMaxInitialCandidates << ": lower either";
    problems.push_back(message.str());
  }
  checkRange(problems, "num_threads", o.num_threads, 0, 256, "worker threads; 0 = all cores");
  checkRange(problems, "person_height_m", o.person_height_m, 1.0, 2.3, "standing height, m");
  checkRange(problems, "person_mass_kg", o.person_mass_kg, 20.0, 250.0, "body mass, kg");
  checkRange(problems, "ground_slope_rad", o.ground_slope_rad, -0.2, 0.2,
             "ground slope, rad, positive uphill");
  checkRange(problems, "min_gait_speed_kmh", o.min_gait_speed_kmh, 0.0, 20.0,
             "slowest gait of the table the particles may walk, km/h");
  checkRange(problems, "gait_speed_sd_kmh", o.gait_speed_sd_kmh, 0.0, 5.0,
             "spread of a particle's target speed's step at a heel strike, km/h");
  checkRange(problems, "gait_step_sd_m", o.gait_step_sd_m, 0.0, 0.5,
             "spread of a particle's target step length's step at a heel strike, m");
  checkRange(problems, "gait_change_persistence", o.gait_change_persistence, 0.0, 0.95,
             "fraction of a target's last step carried into its next at a heel strike");
  checkRange(problems, "gait_slope_change_probability", o.gait_slope_change_probability, 0.0, 1.0,
             "chance per heel strike that a particle's gait moves to a neighbouring slope's on a hill");
  if (o.hill_gaits != HillGaits::kNearest && o.hill_gaits != HillGaits::kLevelToNearest)
    problems.push_back("hill_gaits = " + std::to_string(static_cast<int>(o.hill_gaits)) +
                       " is not a HillGaits value (nearest or level_to_nearest)");
  checkRange(problems, "person_breadth_scale", o.person_breadth_scale, 0.5, 3.0,
             "factor on the torso's and thighs' breadth");
  checkRange(problems, "lost_likelihood_fraction", o.lost_likelihood_fraction, 0.0, 1.0,
             "fraction of the recent median log-likelihood ratio below which frames count towards a lost track");
  checkRange(problems, "min_gait_step_m", o.min_gait_step_m, 0.0, 3.0,
             "shortest step of the table's gaits the particles may walk, m");
  checkRange(problems, "default_frame_interval_s", o.default_frame_interval_s, 1e-4, 1.0,
             "frame interval used when stamps are unusable, s");
  checkRange(problems, "max_frame_gap_s", o.max_frame_gap_s, o.default_frame_interval_s, 60.0,
             "stamp gap that reinitialises the tracker, s; at least default_frame_interval_s");
  return problems;
}

}  // namespace kneed_walker::core::tracking
