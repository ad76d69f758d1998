// Options of the tracker (paper §4 and §5), one plain struct validated in one place.
//
// The nodelet fills this from its private ROS parameters, the offline tools from their
// command lines; both refuse to start when validate() reports a problem. Defaults are the
// paper's settings where the paper gives them.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace kneed_walker::core::tracking {

// The most candidates a track's first frame may draw (TrackerOptions::initial_oversampling).
constexpr long long kMaxInitialCandidates = 10'000'000;

// Which slopes' gaits a tracker's particles walk on a hill (TrackerOptions::hill_gaits).
enum class HillGaits {
  kNearest,         // the table's slope nearest the ground's that has gaits
  kLevelToNearest,  // that slope's and every slope's between it and the level
};

struct TrackerOptions {
  // Particle filter (paper §4, "Inference"; §5 uses 5000 particles, threshold 500).
  int num_particles = 5000;               // N, count, [1, 1000000]
  double resample_ess_threshold = 500.0;  // resample when N_eff falls below this, (0, N]
  int resample_lag_frames = 3;            // Δs: resample from time t − Δs, frames, [0, 30]
  double resample_mixing = 0.95;          // γ: weight of the time-t weights in the resampling proposal, [0, 1]
  // A track's first frame (and each restart's) draws and weighs this many times N candidates
  // from the initial guess and keeps N (ParticleFilter: systematic resampling). The guess is
  // coarse (position ± 0.25 m, heading, phase and gait unknown): N particles drawn from it put
  // none near the person, and the filter locks onto a nearby wrong walk that it cannot leave
  // (on level_fast, seed 3, the truth scored above the best particle on 30 of 31 frames, by up to
  // 23 log units). Measured on the synthetic sequences (README "The tracker"). [1, 1000], and
  // num_particles × initial_oversampling ≤ kMaxInitialCandidates (they are held at once).
  int initial_oversampling = 32;

  // Execution.
  int num_threads = 0;        // worker threads for the per-particle work; 0 = all cores
  std::uint64_t seed = 1;     // random seed: the same input and seed give the same output

  // Person and scene priors (paper §5: "initial state specified coarsely").
  double person_height_m = 1.75;  // standing height H, m, [1.0, 2.3]
  double person_mass_kg = 70.0;   // body mass M, kg, [20, 250]
  double ground_slope_rad = 0.0;  // γ, rad, |γ| ≤ 0.2 (≈ 11.5°); positive = uphill
  // On a hill, the particles walk the gaits of the table's slope nearest the ground's, or those
  // and the gaits of every slope between it and the level, turned onto the ground (BodyPrior):
  // how a person walks a hill lies somewhere between their level walk turned onto it and the
  // hill's optimal gait, and the prior's gaits uphill beyond 2° fall in a chain of strides
  // (issue 13). The filter weighs which fits; at each heel strike a particle's gait moves to a
  // neighbouring slope's with gait_slope_change_probability (half up, half down). On level
  // ground both are the level's gaits. Measured on the hill sequences (README "Synthetic
  // sequences with ground truth", 2000 particles, seeds 1-12): the 10° climb driven by the norms
  // 57 mm mean joint error against 201 on the nearest slope's gaits alone, the prior-made hills
  // the same within the seeds' spread.
  HillGaits hill_gaits = HillGaits::kLevelToNearest;
  double gait_slope_change_probability = 0.3;  // per heel strike, [0, 1]
  // The prior table's gaits the particles may walk around: those at least this fast and with
  // steps at least this long (the table's axes, for its reference person). The defaults are the
  // paper's grid (3–7 km/h, 0.5–1.0 m); the shipped tables add slow walks on short steps (down
  // to 1.5 km/h, 0.3 m), which real people strolling or pausing need (PETS 2009: the demo uses
  // 1.5 km/h and 0.3 m) and which the synthetic walks (3.5–6.5 km/h) track worse with (README
  // "The tracker").
  double min_gait_speed_kmh = 3.0;  // km/h, [0, 20]
  double min_gait_step_m = 0.5;     // m, [0, 3]
  // Speed changes inside a track: each particle walks around a target gait (speed, step length)
  // of its own, which takes a random step at each of its heel strikes, N(0, sd²) in each, the new
  // stride walking the table's gait there (interpolated). A step that leaves the gaits the
  // particles may walk is not taken. 0 and 0: each particle keeps the gait it started on.
  double gait_speed_sd_kmh = 0.6;  // the person's km/h per heel strike, [0, 5]
  double gait_step_sd_m = 0.05;    // the person's m per heel strike, [0, 0.5]
  // Persistent speed changes: a target's step at a heel strike is this times its last step plus
  // the N(0, sd²) above, so that a particle that has begun to slow keeps slowing (a person
  // slowing from 6.5 to 3.5 km/h changes speed by about −0.4 km/h at every heel strike, in the
  // same direction). It tracks such a walk better and steady walks worse (README "The tracker":
  // norms_slowing 114 mm mean joint error at 0.8 against 164, occluded 53 against 37), so it is
  // off by default: for footage of people who change speed. 0: independent steps. [0, 0.95]
  double gait_change_persistence = 0.0;
  // The projected torso's and thighs' breadth (width and depth) times this: a person in a coat,
  // or with arms swinging beside the torso, which the body model does not have, is broader than
  // its bare torso (Winter's proportions). [0.5, 3]
  double person_breadth_scale = 1.0;
  // A track is lost after 3 frames whose MAP log-likelihood ratio is below 0 or, when this is
  // above 0, below this fraction of the ratio's median over the last 20 frames
  // (TrackLossDetector): a body drifting off the person is then lost sooner, and a session
  // starts again from where it was. 0: below 0 only. Measured on the PETS woman (README):
  // 0.4 raised her frames at IoU ≥ 0.5 from a median of 88 % to 94 % over seeds 1–6. [0, 1]
  double lost_likelihood_fraction = 0.0;

  // Frames whose stamp gap is not usable (first frame, equal or backwards stamps) are
  // advanced by this interval; gaps above max_frame_gap_s reinitialise the tracker.
  double default_frame_interval_s = 0.1;  // s, (0, 1]
  double max_frame_gap_s = 1.0;           // s, > default_frame_interval_s

  // Output. Online, each frame's MAP state is final Δs frames later (the best particle's
  // ancestry through the buffer); consecutive frames may come from different particles. Offline,
  // keep_whole_path keeps every lineage back to the track's start, so that the track's whole MAP
  // state sequence (one particle's path: no foot skate) can be had at its end.
  bool keep_whole_path = false;
};

// Every problem with the options, each naming the field and the allowed range; empty when
// the options are usable.
std::vector<std::string> validate(const TrackerOptions& options);

}  // namespace kneed_walker::core::tracking
