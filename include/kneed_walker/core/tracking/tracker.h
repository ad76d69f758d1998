// The tracker (paper §4–5): frames of one calibrated static camera in, the MAP 3D pose of one
// walking person out. A particle is the whole body's state (the walker, the prior's stride
// variables, the placement DOFs) plus which optimal gait it walks around; the transition is the
// body prior (prior/body_prior.h), the weight the image likelihood (vision/likelihood.h); the
// particle filter (particle_filter.h) resamples from t − Δs. Everything the nodelet and
// track_offline do goes through this class.
//
// World frame: the camera's (metres, Z up, REP 103); the ground is the given plane.
#pragma once

#include <opencv2/core.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "kneed_walker/core/gait/gait_table.h"
#include "kneed_walker/core/person/ground_track.h"
#include "kneed_walker/core/prior/body_prior.h"
#include "kneed_walker/core/tracking/particle_filter.h"
#include "kneed_walker/core/tracking/tracker_options.h"
#include "kneed_walker/core/vision/camera.h"
#include "kneed_walker/core/vision/ground_plane.h"
#include "kneed_walker/core/vision/likelihood.h"

namespace kneed_walker::core::tracking {

// A coarse initial state, with a large spread (paper §5). Heading from +X towards +Y.
struct InitialGuess {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();  // ground XY under the body
  double position_sd_m = 0.25;
  // The position's covariance, m², when known (a ground track's: long along the line of sight);
  // it replaces position_sd_m.
  std::optional<Eigen::Matrix2d> position_covariance_m2;
  double heading_rad = 0;
  double heading_sd_rad = 0.3;  // ≥ π: any heading
  double min_speed_kmh = 3.0, max_speed_kmh = 6.0;  // the gaits the particles may start on
  // The leg on the ground in the first frame, if known. Seen from the side, a walker and its
  // mirror image (the other leg in stance) look nearly alike (the legs differ only in which one
  // is nearer the camera), and a track started on the wrong leg stays mirrored: measured on the
  // synthetic sequences, 150–250 mm mean joint error against 60–110 mm started on the right leg.
  std::optional<dynamics::Leg> stance_leg;
  // The person's standing height, m, when known (e.g. from their box on the ground): a session
  // makes the track's tracker for it (TrackingSession); unset, the tracker's person_height_m.
  std::optional<double> person_height_m;
  // The person this tracker followed before (a lost track found again): start with the colours
  // learned then instead of learning them from a body placed at the guess, which fails when the
  // guess sits beside the person (too few pixels the background explains badly).
  bool same_person = false;
  // A rough guess (a box's, a person found in the image): a session (TrackingSession) watches the
  // person's ground track for SessionOptions::start_window_s first, and starts the particles at
  // the window's first frame from what the track measured there over the window: the position
  // with its covariance, the heading and the speed. The guess gives where the ground track
  // starts, and the speeds when the track cannot tell the walking direction.
  bool from_ground_track = false;
};

// A guess from a person's box in the image: the feet at the middle of the box's bottom edge on
// the ground plane; heading unknown; started from the person's ground track (from_ground_track). Throws std::invalid_argument when the box is
// empty, lies mostly (over half its area) outside the image, or its bottom does not see the ground.
InitialGuess guessFromBox(const vision::Camera& camera, const vision::GroundPlane& ground,
                          const cv::Rect2d& box_px);

// A particle's target gait (TrackerOptions::gait_speed_sd_kmh): the person's speed, km/h, and
// step length, m, and the step each took at the particle's last heel strike.
struct TargetGait {
  double speed_kmh = 0, step_m = 0;
  double speed_change_kmh = 0, step_change_m = 0;
};

// The target's move at a heel strike, before it is checked against the gaits the particles may
// walk: each change is TrackerOptions::gait_change_persistence ρ times the last plus N(0, sd²)
// (gait_speed_sd_kmh, gait_step_sd_m), a damped second-order random walk; at ρ = 0 the random
// walk of independent steps. Draws two standard normals, the speed's first.
TargetGait movedTarget(const TargetGait& target, const TrackerOptions& options, common::Random& random);

// One particle.
struct TrackerParticle {
  prior::BodyParticle body;  // its walker walks around the gait of its target (body.walker.gait)
  TargetGait target;
  int gait_slope = 0;  // the slope its gaits walk: an index into Tracker::gaitSlopesRad()
  vision::BodyImageAxes axes;                     // its parts' image axes at the last frame (for flow)
  std::array<Eigen::Vector3f, body::kNumBodyJoints> joints;  // its joints at the last frame, world, m
  float log_likelihood = 0;                       // of the last frame
};

struct TrackEstimate {
  int frame = 0;
  double stamp_s = 0;
  body::BodyPose pose;  // of the MAP particle (the best weighted one), world, metres
  std::array<Eigen::Vector3d, body::kNumBodyJoints> joint_sd_m;  // weighted spread of each joint
  Eigen::Matrix3d waist_covariance_m2 = Eigen::Matrix3d::Zero();
  double heading_rad = 0, heading_sd_rad = 0;
  double speed_kmh = 0;            // the MAP particle's target gait's speed, the person's km/h
  // The MAP particle's planar walker (paper §3) in SI units: q rad, q̇ rad/s, time_in_stride s,
  // stance_foot_x m; and the slope of its gait, rad.
  dynamics::WalkerState walker;
  double gait_slope_rad = 0;
  // The springs in force for the MAP particle (paper eqs. 1–3: its stochastic stiffnesses, the
  // gait's dampings and rest angles) and the toe-off impulse ι of its coming heel strike, in SI
  // for the person's height and mass: N·m/rad, N·m·s/rad, rad; N·s.
  dynamics::SpringParameters springs;
  double toe_off_impulse_ns = 0;
  double effective_sample_size = 0;
  int num_particles = 0;  // the particles now (TrackerOptions::frame_budget_fraction may change it)
  bool resampled = false;
  double map_log_likelihood = 0;
  bool lost = false;               // the likelihood says the body is no longer where the particles are
};

// When a track is lost: after kLostAfterFrames frames in a row whose MAP log-likelihood ratio
// is low. Low is below 0 (the best particle explains the image worse than the background
// does), or, with TrackerOptions::lost_likelihood_fraction f > 0, below f times the ratio's
// median over the last kLostMedianFrames frames (once there are kLostMedianMinFrames): a body
// that drifts onto part of the person and part of the background keeps a positive ratio, but
// far below what it had while on them. Low frames enter the median too, so a ratio that stays
// low for half the window becomes the new level (a person who is harder to see, not a drift).
class TrackLossDetector {
 public:
  static constexpr int kLostAfterFrames = 3;
  static constexpr int kLostMedianFrames = 20;
  static constexpr int kLostMedianMinFrames = 5;  // the median needs this many frames
  explicit TrackLossDetector(double fraction = 0.0) : fraction_(fraction) {}
  // Takes a frame's MAP log-likelihood ratio (NaN or ±inf is low); returns whether the track
  // is lost as of this frame.
  bool update(double map_log_likelihood);
  bool lost() const { return low_frames_ >= kLostAfterFrames; }

 private:
  double fraction_;
  int low_frames_ = 0;
  std::array<double, kLostMedianFrames> recent_{};  // ring of the last finite ratios
  int recent_count_ = 0, recent_next_ = 0;
};

// Time spent on the last frame, milliseconds.
struct TrackerTiming {
  double precompute_ms = 0;  // wall: the frame's evidence (maps, prefix sums, flow)
  double particles_ms = 0;   // wall: propagating and weighing every particle, resampling included
  double resample_ms = 0;    // wall: resampling, including the re-propagation of Δs frames
  double total_ms = 0;       // wall: the whole frame
  double dynamics_cpu_ms = 0;    // thread time in the prior's transitions (walker dynamics), all threads
  double likelihood_cpu_ms = 0;  // thread time in pose, projection and likelihood, all threads
  int particle_steps = 0;        // transitions and weighings done (more than N when resampled)
};

class Tracker {
 public:
  // `prior_table` is the prior's gait table (optimised with its fixed controls), made for
  // `body` proportions. Throws std::invalid_argument naming any bad option.
  Tracker(const vision::Camera& camera, const vision::GroundPlane& ground, const gait::GaitTable& prior_table,
          const prior::PriorOptions& prior, const TrackerOptions& options,
          const vision::LikelihoodOptions& likelihood = {});
  ~Tracker();

  // The background model (learned from frames of this camera); needed before start().
  void setBackground(vision::BackgroundModel background);
  const vision::BackgroundModel& background() const { return background_; }

  // Learns the parts' appearance from `bgr` at the guess and draws the particles there.
  // `ground_track`: the person's ground track at this frame, if known; the particles are held to
  // it (TrackerOptions::ground_track_sd_m).
  TrackEstimate start(const cv::Mat& bgr, double stamp_s, const InitialGuess& guess,
                      const person::GroundTrackEstimate* ground_track = nullptr);
  // The next frame: propagates, weighs, resamples if needed. Frames must come in order of stamp.
  TrackEstimate track(const cv::Mat& bgr, double stamp_s, const person::GroundTrackEstimate* ground_track = nullptr);

  bool started() const { return filter_ != nullptr; }
  // Ends the track (started() is false until the next start()).
  void stop();
  const vision::Camera& camera() const { return camera_; }
  const vision::GroundPlane& ground() const { return ground_; }
  int lagFrames() const { return options_.filter.resample_lag_frames; }  // Δs
  const std::vector<TrackerParticle>& particles() const { return filter_->states(); }
  const std::vector<double>& logWeights() const { return filter_->logWeights(); }
  // The MAP state sequence over the buffered frames (oldest first) as body poses, and their frames.
  std::vector<body::BodyPose> mapPoses(std::vector<int>* frames) const;
  // With FilterOptions::keep_paths: the MAP state sequence from the track's first frame.
  std::vector<body::BodyPose> wholeMapPoses(std::vector<int>* frames) const;
  bool keepsWholePath() const { return options_.filter.keep_paths; }
  double personHeightM() const { return options_.person_height_m; }
  const TrackerTiming& timing() const { return timing_; }
  // The table's gaits a track's particles start on (its grid points the options allow).
  int gaitCount() const { return static_cast<int>(bank_.size()); }
  // The slopes of those gaits, rad, ascending: the table's nearest the ground's that has any,
  // and every slope between it and the level that has any.
  const std::vector<double>& gaitSlopesRad() const { return gait_slopes_rad_; }
  // The pose of a particle (world, metres).
  body::BodyPose pose(const TrackerParticle& particle) const;
  // Its parts' image outlines.
  void project(const body::BodyPose& pose, vision::BodyOutlines& outlines) const;
  // The bounding box of a pose's visible projected parts, px (empty when none is in view).
  cv::Rect2d imageBox(const body::BodyPose& pose) const;
  // Frames waiting behind the next one (online: the nodelet's queue). With a frame budget
  // (TrackerOptions::frame_budget_fraction) the count is fitted so that they are caught up
  // within about kCatchUpS of input: each frame's budget is the interval times n / (n + backlog),
  // n the frames of kCatchUpS.
  static constexpr double kCatchUpS = 1.0;
  void setBacklogFrames(int frames) { backlog_frames_ = std::max(0, frames); }
  // The share of each frame's budget this tracker has, (0, 1]: a session tracking n people
  // gives each 1/n.
  void setBudgetShare(double share) { budget_share_ = std::clamp(share, 1e-6, 1.0); }
  // The MAP pose of the last frame started or tracked.
  const body::BodyPose& lastPose() const { return last_pose_; }
  // The person's body parts (for the person's height).
  const body::BodyShape& shape() const;

 private:
  // A grid point's gait: a track's particles start on its stride's tabulated cycle.
  struct BankGait {
    std::unique_ptr<prior::BodyPrior> prior;
    double speed_kmh = 0, step_length_m = 0;  // the person's, by Froude scaling
    int slope = 0;                            // index into gait_slopes_rad_
  };
  // The gaits the particles' targets may move through: the table interpolated at the bank's
  // slope on a fine lattice of the person's speeds and step lengths over the bank's range, so
  // that a target's step at a heel strike is a lookup (no allocation on the particles' path).
  struct GaitLattice {
    double speed0_kmh = 0, speed_step_kmh = 0, step0_m = 0, step_step_m = 0;
    int speeds = 0, steps = 0;
    std::vector<dynamics::WalkerControls> gaits;  // each point's gait's controls; speeds × steps, speed-major
    std::vector<char> walkable;     // the point's cell has a feasible gait that weighs
    // The lattice point nearest (speed, step), or −1 outside the lattice or where not walkable.
    int at(double speed_kmh, double step_m) const;
  };
  // The lattice of the grid's slope `slope` over the speeds and steps of the bank gaits
  // [begin, end), which walk it; the factors scale the table's axes to the person's.
  static GaitLattice gaitLattice(const gait::GaitTable& table, int slope, std::vector<BankGait>::const_iterator begin,
                                 std::vector<BankGait>::const_iterator end, double froude_speed, double step_scale);
  // Every particle's transition and pose (a bank gait's prior: they differ only in the gait
  // their particles start on, and a particle carries the gait it walks).
  const prior::BodyPrior& bodyPrior() const { return *bank_.front().prior; }
  // At a heel strike: the particle's target takes its random step and its new stride walks it.
  void changeGait(TrackerParticle& particle, common::Random& random) const;
  // The ground track's hold on a frame's particles: their waist against its position (m), with
  // `information` the inverse of its covariance plus ground_track_sd_m², and their walk's velocity
  // against its velocity (m/s), likewise (inactive: no ground track, or not held).
  struct HeldVector {
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    Eigen::Matrix2d information = Eigen::Matrix2d::Zero();
    bool active = false;
    double logDensity(const Eigen::Vector2d& value) const;  // a Student-t's, 0 at the mean; 0 inactive
  };
  struct GroundHold {
    HeldVector position, velocity;
  };
  GroundHold groundHold(const person::GroundTrackEstimate* ground_track) const;
  // Weighs a particle by `frame`, its pose as the body prior gave it (before onGround): the
  // image likelihood, and the ground track's hold.
  double weigh(TrackerParticle& particle, int frame, const body::BodyPose& prior_pose) const;
  // A body prior's pose raised onto the ground plane.
  body::BodyPose onGround(body::BodyPose pose, const TrackerParticle& particle) const;
  // Propagates one particle into `frame` and weighs it, adding the times to the counters.
  double propagate(TrackerParticle& particle, int frame, common::Random& random);
  TrackEstimate estimate(const FilterStepReport& report) const;
  // With a frame budget: the count the next resampling draws, from this frame's measured costs.
  void fitParticleCount(bool resampled);
  cv::Rect regionOfInterest() const;
  void learnAppearance(const cv::Mat& bgr, const InitialGuess& guess);
  // The body standing in mid-stance at the guess, projected.
  void projectGuessBody(const InitialGuess& guess, vision::BodyOutlines& outlines) const;

  vision::Camera camera_;
  vision::GroundPlane ground_;
  TrackerOptions options_;
  vision::LikelihoodOptions likelihood_;
  std::vector<BankGait> bank_;
  std::vector<double> gait_slopes_rad_;  // the bank's slopes, ascending
  std::vector<GaitLattice> lattices_;    // one per slope of gait_slopes_rad_
  body::BodyShape shape_;  // the gaits' body shape, with the options' breadth
  vision::BackgroundModel background_;
  vision::AppearanceModel appearance_;
  std::unique_ptr<ParticleFilter<TrackerParticle>> filter_;
  // The evidence of the buffered frames, newest last (resampling weighs the last Δs again).
  std::vector<std::unique_ptr<vision::FrameEvidence>> evidence_;
  std::vector<int> evidence_frames_;
  std::vector<double> evidence_dt_s_;  // the interval into each buffered frame, s
  std::vector<GroundHold> evidence_ground_;  // the ground track's hold on each buffered frame
  std::atomic<std::int64_t> dynamics_ns_{0}, likelihood_ns_{0};
  std::atomic<int> steps_{0};
  cv::Mat previous_grey_;
  int frame_ = 0;
  double stamp_s_ = 0, dt_s_ = 0;
  TrackLossDetector loss_;
  int backlog_frames_ = 0;
  double budget_share_ = 1.0;
  // Running means (exponential, over about 10 frames) of a particle step's wall time, the
  // frame's other work, and how often frames resample: what fitParticleCount plans with.
  struct FrameCost {
    double step_ms = 0, other_ms = 0, resample_rate = 0;
    bool measured = false;
    int count = 0;  // the count they allow: the next resampling's, and a restarted track's
  } cost_;
  body::BodyPose last_pose_;
  TrackerTiming timing_;
};

}  // namespace kneed_walker::core::tracking
