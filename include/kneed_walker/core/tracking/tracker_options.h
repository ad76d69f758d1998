// Options of the tracker (paper §4 and §5), one plain struct validated in one place.
//
// The nodelet fills this from its private ROS parameters, the offline tools from their
// command lines, both through trackerOptionTable(); both refuse to start when validate()
// reports a problem. Defaults are the paper's settings where the paper gives them.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "kneed_walker/core/common/option_table.h"
#include "kneed_walker/core/tracking/particle_filter.h"

namespace kneed_walker::core::tracking {

// The heights of people the tracker's body model is made for, m.
constexpr double kMinPersonHeightM = 1.0, kMaxPersonHeightM = 2.3;

struct TrackerOptions {
  // The particle filter (paper §4, "Inference"), run once per track.
  FilterOptions filter;

  // Person and scene priors (paper §5: "initial state specified coarsely").
  double person_height_m = 1.75;  // standing height H, [kMinPersonHeightM, kMaxPersonHeightM]
  double person_mass_kg = 70.0;   // body mass M
  double ground_slope_rad = 0.0;  // γ, positive uphill
  // On a hill the particles walk the gaits of the table's slope nearest the ground's that has
  // gaits and of every slope between it and the level, turned onto the ground (BodyPrior): how a
  // person walks a hill lies between their level walk turned onto it and the hill's optimal gait,
  // and the prior's gaits uphill beyond 2° fall in a chain of strides. The filter weighs which
  // fits; at each heel strike a particle's gait moves to a neighbouring slope's with this
  // probability (half up, half down). On level ground only the level's gaits are walked.
  double gait_slope_change_probability = 0.3;
  // The prior table's gaits the particles may walk around: those at least this fast and with
  // steps at least this long (the table's axes, for its reference person). The defaults are the
  // paper's grid (3–7 km/h, 0.5–1.0 m); the shipped tables add slow walks on short steps (down
  // to 1.5 km/h, 0.3 m), which people strolling or pausing need and which brisk walks track
  // worse with.
  double min_gait_speed_kmh = 3.0;
  double min_gait_step_m = 0.5;
  // Speed changes inside a track: each particle walks around a target gait (speed, step length)
  // of its own, which takes a random step at each of its heel strikes, N(0, sd²) in each, the new
  // stride walking the table's gait there (interpolated). A step that leaves the gaits the
  // particles may walk is not taken. 0 and 0: each particle keeps the gait it started on.
  double gait_speed_sd_kmh = 0.6;
  double gait_step_sd_m = 0.05;
  // Persistent speed changes: a target's step at a heel strike is this times its last step plus
  // the N(0, sd²) above, so that a particle that has begun to slow keeps slowing. It tracks a
  // person who keeps slowing better and steady walks worse, so it is off by default.
  double gait_change_persistence = 0.0;
  // The projected torso's and thighs' breadth (width and depth) times this: a person in a coat,
  // or with arms swinging beside the torso, which the body model does not have, is broader than
  // its bare torso (Winter's proportions).
  double person_breadth_scale = 1.0;
  // A track is lost after 3 frames whose MAP log-likelihood ratio is below 0 or, when this is
  // above 0, below this fraction of the ratio's median over the last 20 frames
  // (TrackLossDetector): a body drifting off the person is then lost sooner, and a session
  // starts again from where it was.
  double lost_likelihood_fraction = 0.0;
  // Each particle is also weighed by its waist on the ground against the person's ground track
  // (person/ground_track.h), when the tracker is given one: a Student-t (4 degrees of freedom) of
  // their distance, with the track's covariance plus this spread (the waist's sway about the
  // track and the track's offsets), m. From a low camera the image likelihood barely feels
  // depth; the feet's row does. 0: not held.
  double ground_track_sd_m = 0.05;
  // ... and by its walk's velocity (its target speed along its heading) against the track's,
  // with the track's velocity covariance plus this spread, m/s. 0: not held.
  double ground_track_velocity_sd_mps = 0.15;

  // Online (the nodelet): each frame's work fits into this fraction of the frame interval (from
  // the stamps): at every resampling the particle count becomes what the measured cost per
  // particle (resampling's re-propagation included, on average) allows, within
  // [min_particles, filter.num_particles], as amcl adapts its count. 0: always num_particles,
  // whatever the time (the offline tools: the same input and seed give the same output). Not
  // in trackerOptionTable(): the nodelet's own parameters set them.
  double frame_budget_fraction = 0.0;
  int min_particles = 500;

  // Frames whose stamp gap is not usable (first frame, equal or backwards stamps) are
  // advanced by this interval; gaps above max_frame_gap_s reinitialise the tracker.
  double default_frame_interval_s = 0.1;
  double max_frame_gap_s = 1.0;
};

// Every option people set (the filter's included): name, range, unit, help.
const common::OptionTable<TrackerOptions>& trackerOptionTable();

// Every problem with the options, each naming the option and its allowed range; empty when
// the options are usable.
std::vector<std::string> validate(const TrackerOptions& options);

}  // namespace kneed_walker::core::tracking
