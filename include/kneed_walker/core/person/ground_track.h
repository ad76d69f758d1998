// A person's ground track: where they stand on the floor, how fast they go there, and how tall
// they are, from the rows where their silhouette meets the floor and where it ends on top, each
// frame, filtered over time. It is per person, not per particle: a plain, robust estimate of
// depth and heading that the walker's particles start from and are held to.
//
// Measurement (one frame): the person's foreground region (the blob of the background model's
// foreground that the predicted image box overlaps), its column centroid, and its bottom and top
// edges at sub-pixel. An edge is found by matting, not by a threshold: along a column crossing
// the edge each pixel's share of person is α = ((I − B)·(F − B)) / |F − B|² (I the frame's
// colour, B the background model's mean, F the person's colour just inside the edge), and the
// edge lies Σα past the last row that is wholly background. Blur and the pixel grid move
// colour across the edge but keep Σα, so the 1–2 px that a threshold's silhouette bleeds past
// the body does not bias the edge.
//
// Filter: an extended Kalman filter on s = (x, y, vx, vy, stature) (world, m and m/s; the
// walk a constant velocity driven by white acceleration noise), measured in pixels by
//   u    = the column of the body's axis at half its stature,
//   foot = the row of the feet's nearest point to the camera: the lowest image row belongs to
//          the nearer foot, nearer than the waist by `near_foot_across_m` when the person walks
//          across the line of sight and `near_foot_along_m` when along it,
//   head = the row of the top of the head, `stature` above the ground,
// each with its pixel noise and the spread of its body offset carried through the projection's
// Jacobian: from a low camera one pixel of foot row is many centimetres of range, and the
// filter's covariance is long along the line of sight. A measurement further than `gate_sd`
// standard deviations from the prediction is refused (a shadow, an occluder, a second person)
// and the filter predicts through; so is an edge cut by the image border. Offline, a
// Rauch–Tung–Striebel smoother runs the track backwards.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "kneed_walker/core/common/option_table.h"
#include "kneed_walker/core/vision/background_model.h"
#include "kneed_walker/core/vision/camera.h"
#include "kneed_walker/core/vision/ground_plane.h"

namespace kneed_walker::core::person {

struct GroundTrackOptions {
  double foreground_squared_distance = 30.0;  // the foreground's threshold (vision::foregroundMask)
  int min_pixels = 30;                        // smallest region that is a person, px
  // A region wider than this many times the expected box (a person 0.6 m across) is people
  // merged (walking side by side, passing): not measured.
  double max_width_ratio = 2.0;
  double min_edge_contrast = 20.0;  // |F − B| below which an edge is the mask's edge, not matted, grey levels
  double centre_sd_m = 0.04;        // the silhouette's centroid about the body's axis (arms, legs), m
  double centre_sd_px = 1.0;
  double foot_row_sd_px = 0.7;
  double head_row_sd_px = 0.7;
  double head_sd_m = 0.02;           // the head's top about the stature (the head bobs), m
  // The silhouette's lowest row nearer the camera than the waist, walking across the line of
  // sight and along it, m. Fitted on the captured walks of scripts/evaluate_captured_walks (the
  // median range bias of each view within ±25 mm); a rounded sole's lowest image point and a
  // narrow step make them smaller than the feet's spread.
  double near_foot_across_m = 0.03;
  double near_foot_along_m = 0.10;
  double near_foot_sd_m = 0.06;      // its spread over a stride, m
  // White acceleration noise, m/s² per √Hz. On the captured walks 0.25 gave the best heading one
  // second in (0.15 and 0.5: worse from robot-eye height, where the nearer foot's row swings with
  // each step).
  double acceleration_sd = 0.25;
  double stature_drift_sd = 0.005;   // the stature's random walk, m per √s (0 when given)
  double gate_sd = 4.0;              // a measurement this many sd from the prediction is refused
  double start_position_sd_m = 1.0;  // the start's position spread before its first measurement, m
  double start_speed_sd_mps = 1.0;
  double start_stature_m = 1.70, start_stature_sd_m = 0.15;  // when the stature is not given
  double given_stature_sd_m = 0.02;  // a given stature's error (shoes, hair), m
};

// The options people set: name, range, unit, help (common/option_table.h).
const common::OptionTable<GroundTrackOptions>& groundTrackOptionTable();
// Every problem with the options, naming the option; empty when usable.
std::vector<std::string> validate(const GroundTrackOptions& options);

// What one frame shows of the person (image px: columns u right, rows v down, pixel centres
// at integers).
struct SilhouetteMeasurement {
  cv::Rect box_px;            // the region's bounding box
  int pixels = 0;             // its pixels
  double centre_u_px = 0;     // the column centroid of its pixels
  double foot_v_px = 0;       // its bottom edge, sub-pixel
  double head_v_px = 0;       // its top edge, sub-pixel
  bool centre_seen = false;   // false when the region is cut at a side (the image's or the search's)
  bool foot_seen = false;     // ... at the bottom
  bool head_seen = false;     // ... at the top
};

// The person's region in `search_px` (clipped to the frame): the foreground blobs with most of
// their pixels inside `expected_px`, else the one with most pixels there; nullopt when none has
// min_pixels, or when the region is over max_width_ratio times as wide as `expected_px`. Throws std::invalid_argument when the frame does not match the background model.
std::optional<SilhouetteMeasurement> measureSilhouette(const cv::Mat& bgr, const vision::BackgroundModel& background,
                                                       const cv::Rect& search_px, const cv::Rect2d& expected_px,
                                                       const GroundTrackOptions& options);

// The filter's state indices.
enum GroundTrackIndex { kX = 0, kY, kVx, kVy, kStature, kGroundTrackDims };
using GroundTrackVector = Eigen::Matrix<double, kGroundTrackDims, 1>;
using GroundTrackMatrix = Eigen::Matrix<double, kGroundTrackDims, kGroundTrackDims>;

// The ground track at one frame: world frame (REP 103, Z up), the position the waist's ground
// point.
struct GroundTrackEstimate {
  double stamp_s = 0;
  GroundTrackVector mean = GroundTrackVector::Zero();  // x, y m; vx, vy m/s; stature m
  GroundTrackMatrix covariance = GroundTrackMatrix::Zero();
  bool measured = false;  // a silhouette was found near the prediction
  bool centre_used = false, foot_used = false, head_used = false;  // its parts the filter took
  Eigen::Vector2d position() const { return mean.head<2>(); }
  Eigen::Vector2d velocity() const { return mean.segment<2>(kVx); }
  double stature() const { return mean(kStature); }
  double headingRad() const;  // of the velocity, from +X towards +Y
  double headingSdRad() const;  // from the velocity's covariance (π when the speed is unknown)
};

// Where a person's walkers start from their ground track at one frame (TrackingSession's start
// after SessionOptions::start_window_s): where they stood, the estimate's spread widened by the
// body's own offset from the silhouette's foot point (`offset_sd_m`), and which way and how fast
// they walked when the velocity tells it (its speed over twice its spread along it).
struct WalkStart {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  Eigen::Matrix2d position_covariance_m2 = Eigen::Matrix2d::Identity();
  std::optional<double> heading_rad;  // none when the velocity does not tell the direction
  double heading_sd_rad = M_PI;       // at least kMinWalkStartHeadingSdRad
  double speed_kmh = 0, speed_sd_kmh = 0;
};
// The walk's direction wavers with each step about the ground track's mean: a start's heading
// spread is at least this, rad.
constexpr double kMinWalkStartHeadingSdRad = 0.1;
WalkStart walkStart(const GroundTrackEstimate& at, double offset_sd_m);

class GroundTracker {
 public:
  // `keep_history`: every frame's steps are kept for filtered() and smoothed() (offline);
  // else the last only (online, bounded memory). Throws std::invalid_argument naming a bad option.
  GroundTracker(const vision::Camera& camera, const vision::GroundPlane& ground, const GroundTrackOptions& options = {},
                bool keep_history = true);

  // Starts a track of a person standing at `position_m` (roughly: start_position_sd_m) at
  // `stamp_s`, `stature_m` tall when known (within given_stature_sd_m; it does not drift).
  // Forgets the last track.
  void start(const Eigen::Vector2d& position_m, std::optional<double> stature_m, double stamp_s);
  bool started() const { return started_; }
  // Whether every frame's steps are kept from now on; false forgets all but the last.
  void keepHistory(bool keep);

  // One frame: predicts to its stamp (after the last), measures the person near the prediction
  // and corrects. Returns the frame's estimate.
  const GroundTrackEstimate& update(const cv::Mat& bgr, const vision::BackgroundModel& background, double stamp_s);
  // The same in its two halves: the prediction to a stamp, then a frame's measurement (or none).
  void predict(double stamp_s);
  void correct(const std::optional<SilhouetteMeasurement>& measurement);

  // The last frame's estimate (before the first frame: the start).
  const GroundTrackEstimate& current() const { return state_; }
  // The person's box in the image at the current estimate (their body as a cylinder 0.6 m wide),
  // and the region to look for them in (the box over the estimate's 2-sd spread, and a margin).
  cv::Rect2d expectedBox() const;
  cv::Rect searchRegion() const;
  // The filtered estimates of the track (with keep_history; else the last), oldest first, and the same smoothed (Rauch–Tung–Striebel).
  std::vector<GroundTrackEstimate> filtered() const;
  std::vector<GroundTrackEstimate> smoothed() const;

  // The measurement model: (u, foot v, head v), px, at a state; nullopt when a point is behind
  // the camera.
  std::optional<Eigen::Vector3d> expectedPixels(const GroundTrackVector& state) const;


 private:
  struct Step {
    GroundTrackVector predicted_mean;
    GroundTrackMatrix predicted_covariance;
    GroundTrackMatrix transition;  // from the previous step's filtered state
    GroundTrackEstimate filtered;
  };
  Eigen::Vector3d groundPoint(const Eigen::Vector2d& xy_m) const;
  // The same with the nearer foot's offset given, m.
  std::optional<Eigen::Vector3d> expectedPixels(const GroundTrackVector& state, double near_foot_m) const;
  // The nearer foot's offset towards the camera, m, for a state's walking direction.
  double nearFootM(const GroundTrackVector& state) const;
  cv::Rect2d boxAt(const GroundTrackVector& state) const;

  vision::Camera camera_;
  vision::GroundPlane ground_;
  GroundTrackOptions options_;
  bool keep_history_;
  bool started_ = false;
  bool stature_given_ = false;
  bool measured_once_ = false;  // the state has been placed at a measurement's pixels
  GroundTrackEstimate state_;
  std::vector<Step> history_;
};

}  // namespace kneed_walker::core::person
