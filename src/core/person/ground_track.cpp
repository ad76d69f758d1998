#include "kneed_walker/core/person/ground_track.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "kneed_walker/core/common/config_file.h"
#include "kneed_walker/core/vision/person_detector.h"

namespace kneed_walker::core::person {

const common::OptionTable<GroundTrackOptions>& groundTrackOptionTable() {
  using common::OptionField;
  using O = GroundTrackOptions;
  static const common::OptionTable<GroundTrackOptions> table{
      {"ground_foreground_squared_distance", [](O& o) -> OptionField { return &o.foreground_squared_distance; }, 1,
       1000, "", "a pixel is the person's when its squared Mahalanobis distance from the background is above this"},
      {"ground_min_pixels", [](O& o) -> OptionField { return &o.min_pixels; }, 1, 100000, "px",
       "the smallest region the ground track takes for the person"},
      {"ground_max_width_ratio", [](O& o) -> OptionField { return &o.max_width_ratio; }, 1, 100, "",
       "a region wider than this many times one person's expected box is people merged: not measured"},
      {"ground_min_edge_contrast", [](O& o) -> OptionField { return &o.min_edge_contrast; }, 0, 442, "grey levels",
       "an edge is matted when the person's colour differs from the background's by this, else the mask's"},
      {"ground_centre_sd_m", [](O& o) -> OptionField { return &o.centre_sd_m; }, 0, 1, "m",
       "the silhouette's centroid about the body's axis"},
      {"ground_centre_sd_px", [](O& o) -> OptionField { return &o.centre_sd_px; }, 0.01, 100, "px",
       "the centroid's pixel noise"},
      {"ground_foot_row_sd_px", [](O& o) -> OptionField { return &o.foot_row_sd_px; }, 0.01, 100, "px",
       "the bottom edge's pixel noise"},
      {"ground_head_row_sd_px", [](O& o) -> OptionField { return &o.head_row_sd_px; }, 0.01, 100, "px",
       "the top edge's pixel noise"},
      {"ground_head_sd_m", [](O& o) -> OptionField { return &o.head_sd_m; }, 0, 1, "m",
       "the head's top about the stature over a stride"},
      {"ground_near_foot_across_m", [](O& o) -> OptionField { return &o.near_foot_across_m; }, 0, 1, "m",
       "how much nearer the camera than the waist the nearer foot is, walking across the line of sight"},
      {"ground_near_foot_along_m", [](O& o) -> OptionField { return &o.near_foot_along_m; }, 0, 1, "m",
       "... walking along it"},
      {"ground_near_foot_sd_m", [](O& o) -> OptionField { return &o.near_foot_sd_m; }, 0, 1, "m",
       "the nearer foot's offset's spread over a stride"},
      {"ground_acceleration_sd", [](O& o) -> OptionField { return &o.acceleration_sd; }, 0.001, 20, "m/s^2/sqrt(Hz)",
       "the ground track's white acceleration noise"},
      {"ground_stature_drift_sd", [](O& o) -> OptionField { return &o.stature_drift_sd; }, 0, 1, "m/sqrt(s)",
       "the estimated stature's random walk"},
      {"ground_gate_sd", [](O& o) -> OptionField { return &o.gate_sd; }, 1, 100, "sd",
       "a measurement this far from the ground track's prediction is refused"},
      {"ground_start_position_sd_m", [](O& o) -> OptionField { return &o.start_position_sd_m; }, 0.01, 100, "m",
       "the start's position spread before its first measurement"},
      {"ground_start_speed_sd_mps", [](O& o) -> OptionField { return &o.start_speed_sd_mps; }, 0.01, 10, "m/s",
       "the start's speed spread"},
      {"ground_start_stature_m", [](O& o) -> OptionField { return &o.start_stature_m; }, 0.5, 2.5, "m",
       "the stature a track starts from when the person's height is not given"},
      {"ground_start_stature_sd_m", [](O& o) -> OptionField { return &o.start_stature_sd_m; }, 0.001, 1, "m",
       "... and its spread"},
      {"ground_given_stature_sd_m", [](O& o) -> OptionField { return &o.given_stature_sd_m; }, 0, 0.5, "m",
       "a given person height's error (shoes, hair)"},
  };
  return table;
}

std::vector<std::string> validate(const GroundTrackOptions& options) {
  return common::rangeProblems(options, groundTrackOptionTable());
}

namespace {

// The edge between the person, whose region's last row in this column is `last_inside`, and the
// background beyond it in `direction` (+1: below, −1: above), in image rows, by matting (see the
// header): Σα over the rows from `reach` inside to `reach` + 1 outside the mask's edge. None
// when those rows leave the image or the colours do not differ enough (a column at the blob's
// side, where the mask's closing reaches past the person).
std::optional<double> mattedEdge(const cv::Mat& bgr, const cv::Mat& background_mean, int x, int last_inside,
                                 int direction, double min_contrast) {
  constexpr int kReach = 2;
  const int first = last_inside - direction * kReach, last = last_inside + direction * (kReach + 1);
  const int inside = last_inside - direction * (kReach + 1);
  const auto in_image = [&](int row) { return row >= 0 && row < bgr.rows; };
  if (!in_image(first) || !in_image(last) || !in_image(inside)) return std::nullopt;
  const auto colour = [&](int row) {
    const cv::Vec3b& p = bgr.at<cv::Vec3b>(row, x);
    return Eigen::Vector3d(p[0], p[1], p[2]);
  };
  const auto background = [&](int row) {
    const float* m = background_mean.ptr<float>(row) + x * vision::kMeasurementChannels;
    return Eigen::Vector3d(m[0], m[1], m[2]);
  };
  const Eigen::Vector3d person = colour(inside);
  double alpha_sum = 0;
  for (int row = first; row != last + direction; row += direction) {
    const Eigen::Vector3d b = background(row);
    const Eigen::Vector3d contrast = person - b;
    const double contrast2 = contrast.squaredNorm();
    if (contrast2 < min_contrast * min_contrast) return std::nullopt;
    alpha_sum += std::clamp((colour(row) - b).dot(contrast) / contrast2, 0.0, 1.0);
  }
  return first - 0.5 * direction + direction * alpha_sum;
}

// The lowest (direction +1) or highest (−1) of the matted edges, else, none being matted,
// the mask's own edge: half a pixel past the region's last row there.
double outerEdge(const std::vector<std::optional<double>>& matted, int mask_last_row, int direction) {
  std::optional<double> outer;
  for (const std::optional<double>& edge : matted)
    if (edge && (!outer || direction * (*edge - *outer) > 0)) outer = edge;
  return outer.value_or(mask_last_row + 0.5 * direction);
}

}  // namespace

std::optional<SilhouetteMeasurement> measureSilhouette(const cv::Mat& bgr, const vision::BackgroundModel& background,
                                                       const cv::Rect& search_px, const cv::Rect2d& expected_px,
                                                       const GroundTrackOptions& options) {
  const cv::Rect roi = search_px & cv::Rect(cv::Point(), bgr.size());
  if (roi.area() == 0) return std::nullopt;
  const cv::Mat mask = vision::foregroundMask(background, bgr, roi, options.foreground_squared_distance);
  cv::Mat labels, stats, centroids;
  const int count = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);
  // Each blob's pixels inside the expected box.
  const cv::Rect expected = (cv::Rect(cv::Point2d(std::floor(expected_px.x), std::floor(expected_px.y)),
                                      cv::Point2d(std::ceil(expected_px.br().x), std::ceil(expected_px.br().y))) &
                             roi) - roi.tl();
  std::vector<int> inside(count, 0);
  for (int y = expected.y; y < expected.y + expected.height; ++y) {
    const int* row = labels.ptr<int>(y);
    for (int x = expected.x; x < expected.x + expected.width; ++x) ++inside[row[x]];
  }
  std::vector<char> chosen(count, 0);
  int best = 0;  // the blob with most pixels inside (label 0 is the background: none)
  for (int label = 1; label < count; ++label) {
    if (2 * inside[label] >= stats.at<int>(label, cv::CC_STAT_AREA) && inside[label] > 0) chosen[label] = 1;
    if (inside[label] > (best > 0 ? inside[best] : 0)) best = label;
  }
  if (std::none_of(chosen.begin(), chosen.end(), [](char c) { return c; })) {
    if (best == 0) return std::nullopt;
    chosen[best] = 1;
  }
  SilhouetteMeasurement m;
  double column_sum = 0;
  cv::Rect box;
  for (int label = 1; label < count; ++label) {
    if (!chosen[label]) continue;
    const int area = stats.at<int>(label, cv::CC_STAT_AREA);
    m.pixels += area;
    column_sum += area * centroids.at<double>(label, 0);
    const cv::Rect own(stats.at<int>(label, cv::CC_STAT_LEFT), stats.at<int>(label, cv::CC_STAT_TOP),
                       stats.at<int>(label, cv::CC_STAT_WIDTH), stats.at<int>(label, cv::CC_STAT_HEIGHT));
    box = box.area() ? (box | own) : own;
  }
  if (m.pixels < options.min_pixels || box.width > options.max_width_ratio * expected_px.width) return std::nullopt;
  m.box_px = box + roi.tl();
  m.centre_u_px = roi.x + column_sum / m.pixels;
  // Each column's lowest and highest pixel of the region.
  std::vector<int> lowest(box.width, -1), highest(box.width, -1);
  for (int y = box.y; y < box.y + box.height; ++y) {
    const int* row = labels.ptr<int>(y);
    for (int x = box.x; x < box.x + box.width; ++x) {
      if (!chosen[row[x]]) continue;
      const int c = x - box.x;
      if (highest[c] < 0) highest[c] = y;
      lowest[c] = y;
    }
  }
  // The bottom (top) edge: the lowest (highest) matted edge of the columns that reach within a
  // pixel of the region's lowest (highest) row: the silhouette's extreme point (a median of
  // those columns sat up to a pixel inside it where a rounded toe or heel is lowest).
  const cv::Mat& mean = background.mean();
  std::vector<std::optional<double>> foot_edges, head_edges;
  const int bottom = box.y + box.height - 1, top = box.y;
  for (int c = 0; c < box.width; ++c) {
    const int x = roi.x + box.x + c;
    if (lowest[c] >= bottom - 1)
      foot_edges.push_back(mattedEdge(bgr, mean, x, roi.y + lowest[c], +1, options.min_edge_contrast));
    if (highest[c] >= 0 && highest[c] <= top + 1)
      head_edges.push_back(mattedEdge(bgr, mean, x, roi.y + highest[c], -1, options.min_edge_contrast));
  }
  m.foot_v_px = outerEdge(foot_edges, roi.y + bottom, +1);
  m.head_v_px = outerEdge(head_edges, roi.y + top, -1);
  // An edge on the search region's border may go on outside it: not seen.
  m.foot_seen = bottom < roi.height - 1;
  m.head_seen = top > 0;
  m.centre_seen = box.x > 0 && box.x + box.width < roi.width;
  return m;
}

double GroundTrackEstimate::headingRad() const { return std::atan2(mean(kVy), mean(kVx)); }

double GroundTrackEstimate::headingSdRad() const {
  const Eigen::Vector2d v = velocity();
  const double speed2 = v.squaredNorm();
  if (speed2 < 1e-12) return M_PI;
  const Eigen::Vector2d gradient = Eigen::Vector2d(-v.y(), v.x()) / speed2;  // dθ/dv
  const double variance = gradient.dot(covariance.block<2, 2>(kVx, kVx) * gradient);
  return std::min(M_PI, std::sqrt(std::max(0.0, variance)));
}

WalkStart walkStart(const GroundTrackEstimate& at, double offset_sd_m) {
  WalkStart start;
  start.position_m = at.position();
  start.position_covariance_m2 =
      at.covariance.block<2, 2>(kX, kX) + offset_sd_m * offset_sd_m * Eigen::Matrix2d::Identity();
  const Eigen::Vector2d velocity = at.velocity();
  const double speed_mps = velocity.norm();
  const Eigen::Vector2d along = speed_mps > 0 ? Eigen::Vector2d(velocity / speed_mps) : Eigen::Vector2d::UnitX();
  const double speed_sd_mps = std::sqrt(std::max(0.0, along.dot(at.covariance.block<2, 2>(kVx, kVx) * along)));
  start.speed_kmh = 3.6 * speed_mps;
  start.speed_sd_kmh = 3.6 * speed_sd_mps;
  if (speed_mps > 2 * speed_sd_mps) {
    start.heading_rad = at.headingRad();
    start.heading_sd_rad = std::max(at.headingSdRad(), kMinWalkStartHeadingSdRad);
  }
  return start;
}

GroundTracker::GroundTracker(const vision::Camera& camera, const vision::GroundPlane& ground,
                             const GroundTrackOptions& options, bool keep_history)
    : camera_(camera), ground_(ground), options_(options), keep_history_(keep_history) {
  common::throwIfInvalid("ground track options", validate(options));
}

Eigen::Vector3d GroundTracker::groundPoint(const Eigen::Vector2d& xy_m) const {
  return {xy_m.x(), xy_m.y(), ground_.height(xy_m)};
}

double GroundTracker::nearFootM(const GroundTrackVector& state) const {
  const Eigen::Vector2d sight = (state.head<2>() - camera_.centre().head<2>()).normalized();
  const Eigen::Vector2d velocity = state.segment<2>(kVx);
  const double speed2 = velocity.squaredNorm();
  // Averaged over all walking directions: E|sin φ| = E|cos φ| = 2/π.
  const double average = 2 / M_PI * (options_.near_foot_across_m + options_.near_foot_along_m);
  if (speed2 < 1e-12) return average;
  const double along = std::abs(sight.dot(velocity)) / std::sqrt(speed2);
  const double directional =
      options_.near_foot_along_m * along + options_.near_foot_across_m * std::sqrt(std::max(0.0, 1 - along * along));
  // A walking direction is known once the speed is well above a slow stroll's 0.3 m/s.
  const double known = speed2 / (speed2 + 0.09);
  return known * directional + (1 - known) * average;
}

std::optional<Eigen::Vector3d> GroundTracker::expectedPixels(const GroundTrackVector& state) const {
  return expectedPixels(state, nearFootM(state));
}

std::optional<Eigen::Vector3d> GroundTracker::expectedPixels(const GroundTrackVector& state, double near_foot_m) const {
  const Eigen::Vector2d position = state.head<2>();
  const Eigen::Vector2d sight = (position - camera_.centre().head<2>()).normalized();
  const Eigen::Vector3d base = groundPoint(position);
  const auto axis = camera_.project(base + Eigen::Vector3d(0, 0, 0.5 * state(kStature)));
  const auto foot = camera_.project(groundPoint(position - near_foot_m * sight));
  const auto head = camera_.project(base + Eigen::Vector3d(0, 0, state(kStature)));
  if (!axis || !foot || !head) return std::nullopt;
  return Eigen::Vector3d(axis->x(), foot->y(), head->y());
}

void GroundTracker::start(const Eigen::Vector2d& position_m, std::optional<double> stature_m, double stamp_s) {
  if (!position_m.allFinite() || !std::isfinite(stamp_s) || (stature_m && !(*stature_m > 0)))
    throw std::invalid_argument("GroundTracker::start: the position, stature and stamp must be finite");
  history_.clear();
  stature_given_ = stature_m.has_value();
  state_ = GroundTrackEstimate{};
  state_.stamp_s = stamp_s;
  state_.mean << position_m, 0, 0, stature_m.value_or(options_.start_stature_m);
  const double p = options_.start_position_sd_m * options_.start_position_sd_m;
  const double v = options_.start_speed_sd_mps * options_.start_speed_sd_mps;
  const double stature_sd = stature_given_ ? options_.given_stature_sd_m : options_.start_stature_sd_m;
  // A variance above zero keeps the smoother's matrices invertible.
  const double s = std::max(1e-10, stature_sd * stature_sd);
  state_.covariance = GroundTrackVector(p, p, v, v, s).asDiagonal();
  started_ = true;
  measured_once_ = false;
}

void GroundTracker::predict(double stamp_s) {
  if (!started_) throw std::logic_error("GroundTracker::predict before start");
  const double dt = stamp_s - state_.stamp_s;
  if (!(dt >= 0)) throw std::invalid_argument("GroundTracker::predict: the stamp is before the last");
  GroundTrackMatrix transition = GroundTrackMatrix::Identity();
  transition(kX, kVx) = transition(kY, kVy) = dt;
  // White acceleration noise of spectral density q on each axis: its integral over dt.
  const double q = options_.acceleration_sd * options_.acceleration_sd;
  GroundTrackMatrix noise = GroundTrackMatrix::Zero();
  for (const auto& [position, velocity] : {std::pair{kX, kVx}, std::pair{kY, kVy}}) {
    noise(position, position) = q * dt * dt * dt / 3;
    noise(position, velocity) = noise(velocity, position) = q * dt * dt / 2;
    noise(velocity, velocity) = q * dt;
  }
  if (!stature_given_) noise(kStature, kStature) = options_.stature_drift_sd * options_.stature_drift_sd * dt;
  Step step;
  step.transition = transition;
  step.predicted_mean = transition * state_.mean;
  step.predicted_covariance = transition * state_.covariance * transition.transpose() + noise;
  state_ = GroundTrackEstimate{};
  state_.stamp_s = stamp_s;
  state_.mean = step.predicted_mean;
  state_.covariance = step.predicted_covariance;
  step.filtered = state_;
  if (!keep_history_) history_.clear();
  history_.push_back(step);
}

void GroundTracker::correct(const std::optional<SilhouetteMeasurement>& measurement) {
  if (history_.empty()) throw std::logic_error("GroundTracker::correct before predict");
  state_.measured = measurement.has_value();
  if (measurement) {
    // The first measurement places the state where its pixels say (the foot row's ground point,
    // moved away by the nearer foot's offset; the stature from the top row there), so that the
    // filter linearises there; its covariance is still the start's, for the update to shrink.
    if (!measured_once_ && measurement->foot_seen) {
      const auto foot = vision::groundPointOnPlane(camera_, ground_, {measurement->centre_u_px, measurement->foot_v_px});
      if (foot) {
        const Eigen::Vector2d sight = (foot->head<2>() - camera_.centre().head<2>()).normalized();
        state_.mean.head<2>() = foot->head<2>() + nearFootM(state_.mean) * sight;
        if (!stature_given_ && measurement->head_seen) {
          const double stature = vision::heightAbove(camera_, groundPoint(state_.mean.head<2>()),
                                                     {measurement->centre_u_px, measurement->head_v_px});
          if (stature > 0.5 && stature < 2.5) state_.mean(kStature) = stature;
        }
        measured_once_ = true;
      }
    }
    // Sequential scalar updates, each linearised at the state the last left (foot, head, centre).
    // The nearer foot's offset is the prediction's: the walking direction it takes is not
    // measured by the foot row (its |cos| has a kink across the line of sight).
    const double near_foot_m = nearFootM(state_.mean);
    const std::array<bool, 3> seen{measurement->centre_seen, measurement->foot_seen, measurement->head_seen};
    const Eigen::Vector3d observed(measurement->centre_u_px, measurement->foot_v_px, measurement->head_v_px);
    std::array<bool*, 3> used{&state_.centre_used, &state_.foot_used, &state_.head_used};
    for (const int i : {1, 2, 0}) {
      if (!seen[i]) continue;
      const auto expected = expectedPixels(state_.mean, near_foot_m);
      if (!expected) break;
      // The row of the Jacobian, by central differences.
      Eigen::Matrix<double, 1, kGroundTrackDims> h;
      for (int k = 0; k < kGroundTrackDims; ++k) {
        constexpr double kStep = 1e-4;
        GroundTrackVector plus = state_.mean, minus = state_.mean;
        plus(k) += kStep;
        minus(k) -= kStep;
        const auto a = expectedPixels(plus, near_foot_m), b = expectedPixels(minus, near_foot_m);
        h(k) = (a && b) ? ((*a)(i) - (*b)(i)) / (2 * kStep) : 0;
      }
      // The body offset's spread in pixels, through the same derivatives.
      const Eigen::Vector2d sight = (state_.mean.head<2>() - camera_.centre().head<2>()).normalized();
      double variance = 0;
      if (i == 0) {
        const double per_m = h.head<2>().dot(Eigen::Vector2d(-sight.y(), sight.x()));
        variance = std::pow(options_.centre_sd_px, 2) + std::pow(per_m * options_.centre_sd_m, 2);
      } else if (i == 1) {
        const double per_m = h.head<2>().dot(sight);
        variance = std::pow(options_.foot_row_sd_px, 2) + std::pow(per_m * options_.near_foot_sd_m, 2);
      } else {
        variance = std::pow(options_.head_row_sd_px, 2) + std::pow(h(kStature) * options_.head_sd_m, 2);
      }
      const Eigen::Matrix<double, kGroundTrackDims, 1> ph = state_.covariance * h.transpose();
      const double innovation_variance = h.dot(ph) + variance;
      const double innovation = observed(i) - (*expected)(i);
      if (innovation * innovation > options_.gate_sd * options_.gate_sd * innovation_variance) continue;
      const GroundTrackVector gain = ph / innovation_variance;
      state_.mean += gain * innovation;
      // Joseph's form: symmetric and positive however the gain rounds.
      const GroundTrackMatrix keep = GroundTrackMatrix::Identity() - gain * h;
      state_.covariance = keep * state_.covariance * keep.transpose() + gain * variance * gain.transpose();
      *used[i] = true;
    }
  }
  history_.back().filtered = state_;
}

void GroundTracker::keepHistory(bool keep) {
  keep_history_ = keep;
  if (!keep && history_.size() > 1) history_.erase(history_.begin(), history_.end() - 1);
}

const GroundTrackEstimate& GroundTracker::update(const cv::Mat& bgr, const vision::BackgroundModel& background,
                                                 double stamp_s) {
  predict(stamp_s);
  correct(measureSilhouette(bgr, background, searchRegion(), expectedBox(), options_));
  return state_;
}

cv::Rect2d GroundTracker::boxAt(const GroundTrackVector& state) const {
  constexpr double kRadiusM = 0.3;
  const Eigen::Vector2d position = state.head<2>();
  const Eigen::Vector2d sight = (position - camera_.centre().head<2>()).normalized();
  const Eigen::Vector2d across(-sight.y(), sight.x());
  double left = INFINITY, right = -INFINITY, top = INFINITY, bottom = -INFINITY;
  for (const Eigen::Vector2d& offset : {sight, Eigen::Vector2d(-sight), across, Eigen::Vector2d(-across)})
    for (const double height : {0.0, state(kStature)}) {
      const Eigen::Vector2d xy = position + kRadiusM * offset;
      const auto pixel = camera_.project(groundPoint(xy) + Eigen::Vector3d(0, 0, height));
      if (!pixel) continue;
      left = std::min(left, pixel->x()), right = std::max(right, pixel->x());
      top = std::min(top, pixel->y()), bottom = std::max(bottom, pixel->y());
    }
  if (!(left < right && top < bottom)) return {};
  return {left, top, right - left, bottom - top};
}

cv::Rect2d GroundTracker::expectedBox() const { return boxAt(state_.mean); }

cv::Rect GroundTracker::searchRegion() const {
  // The box at the mean and at 2 sd along the position's principal axes, the stature 2 sd taller.
  GroundTrackVector tallest = state_.mean;
  tallest(kStature) += 2 * std::sqrt(state_.covariance(kStature, kStature));
  cv::Rect2d region = boxAt(tallest);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> axes(state_.covariance.block<2, 2>(kX, kX));
  for (int a = 0; a < 2; ++a)
    for (const double sign : {-2.0, 2.0}) {
      GroundTrackVector moved = tallest;
      moved.head<2>() += sign * std::sqrt(std::max(0.0, axes.eigenvalues()(a))) * axes.eigenvectors().col(a);
      const cv::Rect2d box = boxAt(moved);
      if (box.area() > 0) region = region.area() > 0 ? (region | box) : box;
    }
  constexpr double kMarginPx = 8;
  const cv::Rect frame(0, 0, camera_.width(), camera_.height());
  const cv::Rect whole(cv::Point(static_cast<int>(std::floor(region.x - kMarginPx)),
                                 static_cast<int>(std::floor(region.y - kMarginPx))),
                       cv::Point(static_cast<int>(std::ceil(region.br().x + kMarginPx)),
                                 static_cast<int>(std::ceil(region.br().y + kMarginPx))));
  return whole & frame;
}

std::vector<GroundTrackEstimate> GroundTracker::filtered() const {
  std::vector<GroundTrackEstimate> out;
  for (const Step& step : history_) out.push_back(step.filtered);
  return out;
}

std::vector<GroundTrackEstimate> GroundTracker::smoothed() const {
  std::vector<GroundTrackEstimate> out = filtered();
  // Rauch–Tung–Striebel: x̂ₖ = xₖ + Cₖ (x̂ₖ₊₁ − x⁻ₖ₊₁), Cₖ = Pₖ Fₖ₊₁ᵀ (P⁻ₖ₊₁)⁻¹.
  for (int k = static_cast<int>(out.size()) - 2; k >= 0; --k) {
    const Step& next = history_[k + 1];
    const GroundTrackMatrix gain_t =
        next.predicted_covariance.ldlt().solve(next.transition * history_[k].filtered.covariance);
    const GroundTrackMatrix gain = gain_t.transpose();
    out[k].mean += gain * (out[k + 1].mean - next.predicted_mean);
    out[k].covariance += gain * (out[k + 1].covariance - next.predicted_covariance) * gain_t;
  }
  return out;
}

}  // namespace kneed_walker::core::person
