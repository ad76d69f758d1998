#include "kneed_walker/core/tracking/tracker.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "kneed_walker/core/common/config_file.h"
#include "kneed_walker/core/dynamics/walker_model.h"
#include "kneed_walker/core/vision/person_detector.h"

namespace kneed_walker::core::tracking {
namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

}  // namespace

InitialGuess guessFromBox(const vision::Camera& camera, const vision::GroundPlane& ground,
                          const cv::Rect2d& box) {
  if (!(box.width > 0 && box.height > 0)) throw std::invalid_argument("the person's box is empty");
  // A box mostly off the image (a typo, or a uint32 offset wrapped around) would place the guess
  // where nobody can be seen.
  const cv::Rect2d image(0, 0, camera.width(), camera.height());
  if ((box & image).area() < 0.5 * box.area())
    throw std::invalid_argument("the person's box (" + std::to_string(box.x) + ", " + std::to_string(box.y) + ") " +
                                std::to_string(box.width) + "x" + std::to_string(box.height) +
                                " px lies mostly outside the " + std::to_string(camera.width()) + "x" +
                                std::to_string(camera.height()) + " image");
  // The ground point under the middle of the box's bottom edge.
  const std::optional<Eigen::Vector3d> point =
      vision::groundPointOnPlane(camera, ground, {box.x + 0.5 * box.width, box.y + box.height});
  if (!point) throw std::invalid_argument("the bottom of the person's box does not see the ground");
  InitialGuess guess;
  guess.position_m = point->head<2>();
  guess.heading_sd_rad = M_PI;
  guess.from_ground_track = true;
  return guess;
}

Tracker::Tracker(const vision::Camera& camera, const vision::GroundPlane& ground,
                 const gait::GaitTable& table, const prior::PriorOptions& prior_options,
                 const TrackerOptions& options, const vision::LikelihoodOptions& likelihood)
    : camera_(camera), ground_(ground), options_(options), likelihood_(likelihood) {
  common::throwIfInvalid("tracker options", validate(options));
  prior::requirePriorTable(table, prior_options);
  // The gaits the particles start on: the table's feasible gaits, as fast and long-stepped as
  // the options ask at least, scaled to the person by Froude similarity, at the slope nearest
  // the ground's that has any and at every slope between it and the level. The prior's table has no gait uphill beyond 4.3°: on a steeper climb the
  // particles walk the 4.3° gaits and those between; their bodies are turned onto the ground's
  // slope (BodyPrior).
  const gait::GaitGrid& grid = table.grid;
  auto startsOn = [&](int i) {
    const auto cell = grid.cell(i);
    return table.entries[i].feasible && grid.speeds_kmh[cell[0]] >= options.min_gait_speed_kmh &&
           grid.step_lengths_m[cell[1]] >= options.min_gait_step_m;
  };
  std::vector<int> with_gaits;  // the grid's slopes that have a gait to start on
  for (int s = 0; s < static_cast<int>(grid.slopes_rad.size()); ++s) {
    bool any = false;
    for (int i = 0; i < grid.size() && !any; ++i) any = grid.cell(i)[2] == s && startsOn(i);
    if (any) with_gaits.push_back(s);
  }
  if (with_gaits.empty())
    throw std::invalid_argument("the prior's gait table has no feasible gait at any slope from " +
                                std::to_string(options.min_gait_speed_kmh) + " km/h and " +
                                std::to_string(options.min_gait_step_m) + " m steps");
  const int nearest = *std::min_element(with_gaits.begin(), with_gaits.end(), [&](int a, int b) {
    return std::abs(grid.slopes_rad[a] - options.ground_slope_rad) < std::abs(grid.slopes_rad[b] - options.ground_slope_rad);
  });
  std::vector<int> bank_slopes;  // grid slope indices, ascending
  for (const int s : with_gaits) {
    const double slope = grid.slopes_rad[s];
    const bool between = std::min(0.0, grid.slopes_rad[nearest]) <= slope && slope <= std::max(0.0, grid.slopes_rad[nearest]);
    if (s == nearest || between) bank_slopes.push_back(s);
  }
  const dynamics::WalkerSimulator simulator(dynamics::dimensionlessWalker(table.body));
  const double leg_m = table.body.leg_length_per_height * options.person_height_m;
  const double froude_speed = std::sqrt(leg_m / grid.referenceLegLength());
  const double step_scale = leg_m / grid.referenceLegLength();
  for (size_t b = 0; b < bank_slopes.size(); ++b) {
    const int slope = bank_slopes[b];
    gait_slopes_rad_.push_back(grid.slopes_rad[slope]);
    const size_t first = bank_.size();
    for (int i = 0; i < grid.size(); ++i) {
      const auto cell = grid.cell(i);
      if (cell[2] != slope || !startsOn(i)) continue;
      BankGait gait;
      gait.prior = std::make_unique<prior::BodyPrior>(
          prior::WalkerPrior(simulator, table.entries[i].gait, prior_options), options.person_height_m,
          table.body.leg_length_per_height, grid.gravity, options.ground_slope_rad);
      gait.speed_kmh = grid.speeds_kmh[cell[0]] * froude_speed;
      gait.step_length_m = grid.step_lengths_m[cell[1]] * step_scale;
      gait.slope = static_cast<int>(b);
      bank_.push_back(std::move(gait));
    }
    lattices_.push_back(gaitLattice(table, slope, bank_.begin() + first, bank_.end(), froude_speed, step_scale));
  }
  shape_ = bank_.front().prior->shape();
  for (const body::BodyPart part : {body::kTorsoPart, body::kLeftThighPart, body::kRightThighPart}) {
    body::PartShape& p = shape_.parts[part];
    for (double* breadth : {&p.proximal_width_m, &p.proximal_depth_m, &p.distal_width_m, &p.distal_depth_m})
      *breadth *= options.person_breadth_scale;
  }
}

Tracker::GaitLattice Tracker::gaitLattice(const gait::GaitTable& table, int slope,
                                          std::vector<BankGait>::const_iterator begin,
                                          std::vector<BankGait>::const_iterator end, double froude_speed,
                                          double step_scale) {
  const gait::GaitGrid& grid = table.grid;
  // The targets' lattice over these bank gaits' speeds and steps, 0.1 km/h and 1 cm apart.
  const auto [slowest, fastest] =
      std::minmax_element(begin, end, [](const BankGait& a, const BankGait& b) { return a.speed_kmh < b.speed_kmh; });
  const auto [shortest, longest] = std::minmax_element(
      begin, end, [](const BankGait& a, const BankGait& b) { return a.step_length_m < b.step_length_m; });
  GaitLattice lattice;
  lattice.speed0_kmh = slowest->speed_kmh;
  lattice.step0_m = shortest->step_length_m;
  lattice.speed_step_kmh = 0.1;
  lattice.step_step_m = 0.01;
  lattice.speeds = 1 + static_cast<int>(std::round((fastest->speed_kmh - lattice.speed0_kmh) / lattice.speed_step_kmh));
  lattice.steps = 1 + static_cast<int>(std::round((longest->step_length_m - lattice.step0_m) / lattice.step_step_m));
  lattice.gaits.resize(static_cast<size_t>(lattice.speeds) * lattice.steps);
  lattice.walkable.assign(lattice.gaits.size(), 0);
  for (int v = 0; v < lattice.speeds; ++v)
    for (int l = 0; l < lattice.steps; ++l) {
      const double speed_kmh = std::min(fastest->speed_kmh, lattice.speed0_kmh + v * lattice.speed_step_kmh);
      const double step_m = std::min(longest->step_length_m, lattice.step0_m + l * lattice.step_step_m);
      gait::InterpolationNote note;
      const size_t k = static_cast<size_t>(v) * lattice.steps + l;
      // In the table's units, inside its grid (the scaling back may round past its ends).
      const double table_speed_kmh = std::clamp(speed_kmh / froude_speed, grid.speeds_kmh.front(), grid.speeds_kmh.back());
      const double table_step_m =
          std::clamp(step_m / step_scale, grid.step_lengths_m.front(), grid.step_lengths_m.back());
      lattice.gaits[k] = gait::interpolateGait(table, table_speed_kmh, table_step_m, grid.slopes_rad[slope], &note).controls;
      lattice.walkable[k] = note.nearest < 0;
    }
  return lattice;
}

int Tracker::GaitLattice::at(double speed_kmh, double step_m) const {
  const double v = std::round((speed_kmh - speed0_kmh) / speed_step_kmh);
  const double l = std::round((step_m - step0_m) / step_step_m);
  if (!(v >= 0 && v < speeds && l >= 0 && l < steps)) return -1;
  const int k = static_cast<int>(v) * steps + static_cast<int>(l);
  return walkable[k] ? k : -1;
}

TargetGait movedTarget(const TargetGait& target, const TrackerOptions& options, common::Random& random) {
  const double persistence = options.gait_change_persistence;
  std::normal_distribution<double> normal(0.0, 1.0);
  TargetGait moved;
  moved.speed_change_kmh = persistence * target.speed_change_kmh + options.gait_speed_sd_kmh * normal(random);
  moved.step_change_m = persistence * target.step_change_m + options.gait_step_sd_m * normal(random);
  moved.speed_kmh = target.speed_kmh + moved.speed_change_kmh;
  moved.step_m = target.step_m + moved.step_change_m;
  return moved;
}

void Tracker::changeGait(TrackerParticle& p, common::Random& random) const {
  const bool slopes_change = gait_slopes_rad_.size() > 1 && options_.gait_slope_change_probability > 0;
  if (options_.gait_speed_sd_kmh == 0 && options_.gait_step_sd_m == 0 && !slopes_change) return;
  const TargetGait moved = movedTarget(p.target, options_, random);
  // On a hill the target may also step to a neighbouring slope's gaits (a slope past the bank's
  // ends: it stays). Drawn only then, so that level tracks draw the same numbers as before.
  int slope = p.gait_slope;
  if (slopes_change && std::bernoulli_distribution(options_.gait_slope_change_probability)(random)) {
    const int to = slope + (std::bernoulli_distribution(0.5)(random) ? 1 : -1);
    if (to >= 0 && to < static_cast<int>(gait_slopes_rad_.size())) slope = to;
  }
  const GaitLattice& lattice = lattices_[slope];
  const int k = lattice.at(moved.speed_kmh, moved.step_m);
  if (k < 0) {  // outside the gaits the particles may walk: the target stays, and stops moving
    p.target.speed_change_kmh = p.target.step_change_m = 0;
    return;
  }
  p.gait_slope = slope;
  p.target = moved;
  prior::walkGait(p.body.walker, lattice.gaits[k]);
}

Tracker::~Tracker() = default;

void Tracker::setBackground(vision::BackgroundModel background) {
  if (background.size() != cv::Size(camera_.width(), camera_.height()))
    throw std::invalid_argument("the background model's size differs from the camera's");
  background_ = std::move(background);
}

body::BodyPose Tracker::onGround(body::BodyPose pose, const TrackerParticle& particle) const {
  // The body prior places the walker's slope frame at height 0 under its origin; the ground
  // there is the plane's.
  const double lift = ground_.height(particle.body.placement.value.ground_origin_m);
  for (auto& joint : pose.joints) joint.z() += lift;
  for (auto& foot : pose.foot_centres) foot.z() += lift;
  pose.ground_point_m.z() += lift;
  return pose;
}

body::BodyPose Tracker::pose(const TrackerParticle& particle) const {
  return onGround(bodyPrior().pose(particle.body), particle);
}

const body::BodyShape& Tracker::shape() const { return shape_; }

void Tracker::project(const body::BodyPose& pose, vision::BodyOutlines& outlines) const {
  vision::projectBodyParts(camera_, pose, shape(), outlines);
}

cv::Rect2d Tracker::imageBox(const body::BodyPose& pose) const {
  vision::BodyOutlines outlines;
  project(pose, outlines);
  double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
  for (const vision::PartOutline& part : outlines)
    if (part.visible)
      for (int i = 0; i < part.size; ++i) {
        x0 = std::min(x0, part.hull[i].x()), x1 = std::max(x1, part.hull[i].x());
        y0 = std::min(y0, part.hull[i].y()), y1 = std::max(y1, part.hull[i].y());
      }
  return x0 <= x1 ? cv::Rect2d(cv::Point2d(x0, y0), cv::Point2d(x1, y1)) : cv::Rect2d();
}

double Tracker::weigh(TrackerParticle& particle, int frame, const body::BodyPose& prior_pose) const {
  const body::BodyPose pose = onGround(prior_pose, particle);
  thread_local vision::BodyOutlines outlines;
  project(pose, outlines);
  const vision::FrameEvidence* evidence = nullptr;
  const GroundHold* hold = nullptr;
  for (size_t i = 0; i < evidence_frames_.size(); ++i)
    if (evidence_frames_[i] == frame) evidence = evidence_[i].get(), hold = &evidence_ground_[i];
  if (!evidence) throw std::logic_error("the tracker has no evidence for a frame it weighs");
  const bool has_previous = frame > 0 && particle.axes[body::kTorsoPart].visible;
  const double log_likelihood = vision::evaluateLikelihood(*evidence, outlines, has_previous ? &particle.axes : nullptr,
                                                           likelihood_);
  particle.axes = vision::imageAxes(outlines);
  for (int j = 0; j < body::kNumBodyJoints; ++j) particle.joints[j] = pose.joints[j].cast<float>();
  particle.log_likelihood = static_cast<float>(log_likelihood);
  const double heading = particle.body.placement.value.heading_rad;
  return log_likelihood + hold->position.logDensity(pose.joints[body::kWaist].head<2>()) +
         hold->velocity.logDensity(particle.target.speed_kmh / 3.6 * Eigen::Vector2d(std::cos(heading), std::sin(heading)));
}

double Tracker::HeldVector::logDensity(const Eigen::Vector2d& value) const {
  if (!active) return 0;
  // log Student-t (ν = 4, 2D), 0 at the mean: −(ν + 2)/2 log(1 + m²/ν).
  const Eigen::Vector2d offset = value - mean;
  return -3.0 * std::log1p(offset.dot(information * offset) / 4.0);
}

Tracker::GroundHold Tracker::groundHold(const person::GroundTrackEstimate* ground_track) const {
  // The track's mean and covariance of (x, y) or (vx, vy) from `first`, the covariance widened by sd².
  const auto held = [&](int first, double sd) {
    HeldVector v;
    if (!ground_track || sd <= 0) return v;
    v.mean = ground_track->mean.segment<2>(first);
    v.information = (ground_track->covariance.block<2, 2>(first, first) + sd * sd * Eigen::Matrix2d::Identity()).inverse();
    v.active = v.information.allFinite() && v.mean.allFinite();
    return v;
  };
  return {held(person::kX, options_.ground_track_sd_m), held(person::kVx, options_.ground_track_velocity_sd_mps)};
}

void Tracker::projectGuessBody(const InitialGuess& guess, vision::BodyOutlines& outlines) const {
  // The guess's body in mid-stance (legs together), on a mid-range gait.
  int middle = 0;
  const double mid_speed = 0.5 * (guess.min_speed_kmh + guess.max_speed_kmh);
  for (int g = 1; g < gaitCount(); ++g)
    if (std::abs(bank_[g].speed_kmh - mid_speed) < std::abs(bank_[middle].speed_kmh - mid_speed)) middle = g;
  common::Random random(mixSeed(options_.filter.seed, 0, 7, 0));
  body::BodyPose pose;
  TrackerParticle particle;
  particle.body = bank_[middle].prior->sample(0.25, guess.position_m, guess.heading_rad, random, pose);
  project(this->pose(particle), outlines);
}

void Tracker::learnAppearance(const cv::Mat& bgr, const InitialGuess& guess) {
  vision::BodyOutlines outlines;
  projectGuessBody(guess, outlines);
  // Pixels inside each part that the background explains worse than a flat foreground density
  // (colour uniform over 256³, gradient zero-mean with the appearance model's spread) would.
  const double gradient_sd = likelihood_.appearance.gradient_sd;
  const float foreground_floor =
      static_cast<float>(-3 * std::log(256.0) - std::log(2 * M_PI * gradient_sd * gradient_sd));
  const cv::Mat z = vision::measurements(bgr);
  cv::Mat density;
  const cv::Rect image(0, 0, bgr.cols, bgr.rows);
  background_.logDensity(z, image, density);
  std::array<std::vector<cv::Vec3b>, vision::kNumPartKinds> samples;
  vision::RowSpans spans;
  for (int p = 0; p < body::kNumBodyParts; ++p) {
    vision::rasterize(outlines[p], spans);
    const vision::PartKind kind = vision::partKind(static_cast<body::BodyPart>(p));
    for (int k = 0; k < spans.rows; ++k) {
      const int y = spans.first_row + k;
      if (y < 0 || y >= bgr.rows) continue;
      for (int x = std::max(0, spans.left[k]); x < std::min(bgr.cols, spans.right[k]); ++x)
        if (density.at<float>(y, x) < foreground_floor) samples[kind].push_back(bgr.at<cv::Vec3b>(y, x));
    }
  }
  appearance_ = vision::AppearanceModel::learn(samples, likelihood_.appearance);
}

cv::Rect Tracker::regionOfInterest() const {
  float x0 = 1e9f, y0 = 1e9f, x1 = -1e9f, y1 = -1e9f;
  for (const TrackerParticle& p : filter_->states())
    for (const auto& axis : p.axes)
      if (axis.visible)
        for (const auto& end : axis.ends_px) {
          x0 = std::min(x0, end.x()), x1 = std::max(x1, end.x());
          y0 = std::min(y0, end.y()), y1 = std::max(y1, end.y());
        }
  if (x0 > x1) return cv::Rect(0, 0, camera_.width(), camera_.height());
  // Part outlines reach beyond their axes by their widths, and the body moves between frames.
  const float margin = 16.0f + 0.3f * (y1 - y0);
  const cv::Rect box(cv::Point(static_cast<int>(std::floor(x0 - margin)), static_cast<int>(std::floor(y0 - margin))),
                     cv::Point(static_cast<int>(std::ceil(x1 + margin)), static_cast<int>(std::ceil(y1 + margin))));
  return box & cv::Rect(0, 0, camera_.width(), camera_.height());
}

TrackEstimate Tracker::start(const cv::Mat& bgr, double stamp_s, const InitialGuess& guess,
                             const person::GroundTrackEstimate* ground_track) {
  if (background_.empty()) throw std::logic_error("Tracker::start needs a background model (setBackground)");
  if (bgr.type() != CV_8UC3 || bgr.cols != camera_.width() || bgr.rows != camera_.height())
    throw std::invalid_argument("the frame is not a BGR 8-bit image of the camera's size");
  if (guess.position_covariance_m2 && !(guess.position_covariance_m2->allFinite() &&
                                         guess.position_covariance_m2->llt().info() == Eigen::Success))
    throw std::invalid_argument("the guess's position covariance is not positive definite");
  const auto started_at = Clock::now();
  if (!guess.same_person || appearance_.empty()) learnAppearance(bgr, guess);
  filter_ = std::make_unique<ParticleFilter<TrackerParticle>>(options_.filter);
  // A track started again within a frame budget searches with the count it allows.
  if (options_.frame_budget_fraction > 0 && cost_.measured) filter_->setParticleCount(cost_.count);
  frame_ = 0;
  stamp_s_ = stamp_s;
  loss_ = TrackLossDetector(options_.lost_likelihood_fraction);
  evidence_.clear();
  evidence_frames_.clear();
  evidence_dt_s_.clear();
  evidence_ground_.clear();
  cv::cvtColor(bgr, previous_grey_, cv::COLOR_BGR2GRAY);

  // The region the guess can reach: its spread around the position, the person's height up.
  const Eigen::Matrix2d position_factor =
      guess.position_covariance_m2 ? Eigen::Matrix2d(guess.position_covariance_m2->llt().matrixL())
                                   : Eigen::Matrix2d(guess.position_sd_m * Eigen::Matrix2d::Identity());
  const double position_sd_m =
      guess.position_covariance_m2
          ? std::sqrt(Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(*guess.position_covariance_m2).eigenvalues().maxCoeff())
          : guess.position_sd_m;
  const double reach = 2.5 * position_sd_m + 1.0;
  float x0 = 1e9f, y0 = 1e9f, x1 = -1e9f, y1 = -1e9f;
  for (int k = 0; k < 16; ++k)
    for (double up : {0.0, 1.15 * options_.person_height_m}) {
      const Eigen::Vector2d xy = guess.position_m + reach * Eigen::Vector2d(std::cos(k * M_PI / 8), std::sin(k * M_PI / 8));
      if (const auto px = camera_.project(Eigen::Vector3d(xy.x(), xy.y(), ground_.height(xy) + up))) {
        x0 = std::min<float>(x0, px->x()), x1 = std::max<float>(x1, px->x());
        y0 = std::min<float>(y0, px->y()), y1 = std::max<float>(y1, px->y());
      }
    }
  const cv::Rect roi = x0 > x1 ? cv::Rect(0, 0, bgr.cols, bgr.rows)
                               : cv::Rect(cv::Point(int(x0), int(y0)), cv::Point(int(x1) + 1, int(y1) + 1));
  const auto precompute_at = Clock::now();
  evidence_.push_back(std::make_unique<vision::FrameEvidence>());
  evidence_.back()->compute(bgr, cv::Mat(), roi, background_, appearance_, likelihood_);
  {
    vision::BodyOutlines outlines;
    projectGuessBody(guess, outlines);
    evidence_.back()->setReferenceAreas(vision::partAreas(outlines));
  }
  evidence_frames_.push_back(0);
  evidence_dt_s_.push_back(0.0);
  evidence_ground_.push_back(groundHold(ground_track));
  timing_ = TrackerTiming{};
  timing_.precompute_ms = msSince(precompute_at);

  // The gaits in the guess's speed range; when it falls between the bank's speeds (which scale
  // with the person's leg), those nearest it.
  std::vector<int> gaits;
  auto outside_kmh = [&](int g) {
    return std::max({0.0, guess.min_speed_kmh - bank_[g].speed_kmh, bank_[g].speed_kmh - guess.max_speed_kmh});
  };
  double nearest_kmh = std::numeric_limits<double>::infinity();
  for (int g = 0; g < gaitCount(); ++g) nearest_kmh = std::min(nearest_kmh, outside_kmh(g));
  for (int g = 0; g < gaitCount(); ++g)
    if (outside_kmh(g) <= nearest_kmh + 1e-9) gaits.push_back(g);
  const auto particles_at = Clock::now();
  const FilterStepReport report = filter_->initialize(
      [&](common::Random& random) {
        TrackerParticle p;
        const BankGait& gait = bank_[gaits[std::uniform_int_distribution<int>(0, static_cast<int>(gaits.size()) - 1)(random)]];
        p.target.speed_kmh = gait.speed_kmh;
        p.target.step_m = gait.step_length_m;
        p.gait_slope = gait.slope;
        std::normal_distribution<double> normal(0.0, 1.0);
        const double phase = std::uniform_real_distribution<double>(0.0, 1.0)(random);
        const Eigen::Vector2d at = guess.position_m + position_factor * Eigen::Vector2d(normal(random), normal(random));
        const double heading = guess.heading_sd_rad >= M_PI
                                   ? std::uniform_real_distribution<double>(-M_PI, M_PI)(random)
                                   : guess.heading_rad + guess.heading_sd_rad * normal(random);
        const dynamics::Leg stance =
            guess.stance_leg ? *guess.stance_leg
                             : std::bernoulli_distribution(0.5)(random) ? dynamics::Leg::kLeft : dynamics::Leg::kRight;
        body::BodyPose unused;
        // From the gait's tabulated cycle: the initial search draws initial_oversampling × N.
        p.body = gait.prior->sample(phase, at, heading, random, unused, stance, prior::WalkerPrior::Start::kFromCycle);
        return p;
      },
      [&](TrackerParticle& p, int frame) { return weigh(p, frame, bodyPrior().pose(p.body)); }, 0);
  timing_.particles_ms = msSince(particles_at);
  timing_.total_ms = msSince(started_at);
  TrackEstimate e = estimate(report);
  last_pose_ = e.pose;
  return e;
}

void Tracker::stop() {
  filter_.reset();
  evidence_.clear();
  evidence_frames_.clear();
  evidence_dt_s_.clear();
  evidence_ground_.clear();
}

TrackEstimate Tracker::track(const cv::Mat& bgr, double stamp_s, const person::GroundTrackEstimate* ground_track) {
  if (!filter_) throw std::logic_error("Tracker::track before start");
  if (bgr.type() != CV_8UC3 || bgr.cols != camera_.width() || bgr.rows != camera_.height())
    throw std::invalid_argument("the frame is not a BGR 8-bit image of the camera's size");
  const auto started_at = Clock::now();
  const double gap = stamp_s - stamp_s_;
  dt_s_ = gap > 0 && gap <= options_.max_frame_gap_s ? gap : options_.default_frame_interval_s;
  stamp_s_ = stamp_s;
  ++frame_;
  const auto precompute_at = Clock::now();
  auto evidence = std::make_unique<vision::FrameEvidence>();
  evidence->compute(bgr, previous_grey_, regionOfInterest(), background_, appearance_, likelihood_);
  {
    vision::BodyOutlines outlines;
    project(last_pose_, outlines);
    evidence->setReferenceAreas(vision::partAreas(outlines));
  }
  evidence_.push_back(std::move(evidence));
  evidence_frames_.push_back(frame_);
  evidence_dt_s_.push_back(dt_s_);
  evidence_ground_.push_back(groundHold(ground_track));
  while (static_cast<int>(evidence_.size()) > options_.filter.resample_lag_frames + 1) {
    evidence_.erase(evidence_.begin());
    evidence_frames_.erase(evidence_frames_.begin());
    evidence_dt_s_.erase(evidence_dt_s_.begin());
    evidence_ground_.erase(evidence_ground_.begin());
  }
  cv::cvtColor(bgr, previous_grey_, cv::COLOR_BGR2GRAY);
  timing_ = TrackerTiming{};
  timing_.precompute_ms = msSince(precompute_at);

  // Frames buffered for resampling may have other intervals; each particle step uses the
  // interval into its frame.
  const auto particles_at = Clock::now();
  dynamics_ns_ = likelihood_ns_ = steps_ = 0;
  const FilterStepReport report = filter_->step(
      [&](TrackerParticle& p, int frame, common::Random& random) { return propagate(p, frame, random); }, frame_);
  timing_.particles_ms = msSince(particles_at);
  timing_.resample_ms = report.resample_ms;
  timing_.dynamics_cpu_ms = 1e-6 * dynamics_ns_;
  timing_.likelihood_cpu_ms = 1e-6 * likelihood_ns_;
  timing_.particle_steps = steps_;
  loss_.update(report.max_log_likelihood);
  timing_.total_ms = msSince(started_at);
  if (options_.frame_budget_fraction > 0) fitParticleCount(report.resampled);
  TrackEstimate e = estimate(report);
  last_pose_ = e.pose;
  return e;
}

double Tracker::propagate(TrackerParticle& p, int frame, common::Random& random) {
  // Frames buffered for resampling may have other intervals: each step uses its own frame's.
  double dt = dt_s_;
  for (size_t i = 0; i < evidence_frames_.size(); ++i)
    if (evidence_frames_[i] == frame) dt = evidence_dt_s_[i];
  const auto t0 = Clock::now();
  // Speed changes inside a track: after a heel strike the new stride walks around the
  // particle's moved target (its stride samples are drawn about that gait).
  if (p.body.walker.walker.heel_strikes != p.body.walker.stride_of_means) changeGait(p, random);
  body::BodyPose pose;
  const bool fell = bodyPrior().transition(p.body, dt, random, pose).fell;
  const auto t1 = Clock::now();
  // A walker that fell is no walking person: it gets no weight (it is resampled away).
  const double log_likelihood = fell ? -std::numeric_limits<double>::infinity() : weigh(p, frame, pose);
  const auto t2 = Clock::now();
  dynamics_ns_ += std::chrono::duration_cast<std::chrono::nanoseconds>(t1 - t0).count();
  likelihood_ns_ += std::chrono::duration_cast<std::chrono::nanoseconds>(t2 - t1).count();
  ++steps_;
  return log_likelihood;
}

std::vector<body::BodyPose> Tracker::mapPoses(std::vector<int>* frames) const {
  std::vector<body::BodyPose> poses;
  for (const TrackerParticle& p : filter_->mapSequence(frames)) poses.push_back(pose(p));
  return poses;
}

std::vector<body::BodyPose> Tracker::wholeMapPoses(std::vector<int>* frames) const {
  std::vector<body::BodyPose> poses;
  for (const TrackerParticle& p : filter_->wholeMapSequence(frames)) poses.push_back(pose(p));
  return poses;
}

void Tracker::fitParticleCount(bool resampled) {
  // A frame costs its evidence and bookkeeping, plus N particle steps, plus Δs·N more on the
  // frames that resample (the re-propagation): N = (budget − other) / (step · (1 + Δs · rate)).
  if (timing_.particle_steps <= 0 || !(dt_s_ > 0)) return;
  const double step_ms = timing_.particles_ms / timing_.particle_steps;
  const double other_ms = std::max(0.0, timing_.total_ms - timing_.particles_ms);
  constexpr double kMix = 0.1;
  if (!cost_.measured) {
    cost_ = {step_ms, other_ms, resampled ? 1.0 : 0.0, true, 0};
  } else {
    cost_.step_ms += kMix * (step_ms - cost_.step_ms);
    cost_.other_ms += kMix * (other_ms - cost_.other_ms);
    cost_.resample_rate += kMix * ((resampled ? 1.0 : 0.0) - cost_.resample_rate);
  }
  const double catch_up_frames = std::max(1.0, kCatchUpS / dt_s_);
  const double budget_ms = budget_share_ * options_.frame_budget_fraction * 1000.0 * dt_s_ * catch_up_frames /
                           (catch_up_frames + backlog_frames_);
  const double per_particle_ms = cost_.step_ms * (1.0 + lagFrames() * cost_.resample_rate);
  if (!(per_particle_ms > 0)) return;  // too quick to time: keep the count
  const double affordable = (budget_ms - cost_.other_ms) / per_particle_ms;
  const double count = std::clamp(affordable, static_cast<double>(options_.min_particles),
                                  static_cast<double>(options_.filter.num_particles));
  cost_.count = static_cast<int>(count);
  filter_->setParticleCount(cost_.count);
}

TrackEstimate Tracker::estimate(const FilterStepReport& report) const {
  TrackEstimate e;
  e.frame = frame_;
  e.stamp_s = stamp_s_;
  e.effective_sample_size = report.effective_sample_size;
  e.num_particles = filter_->particleCount();
  e.resampled = report.resampled;
  const auto& particles = filter_->states();
  const auto& log_weights = filter_->logWeights();
  const int best = filter_->best();
  e.pose = pose(particles[best]);
  e.map_log_likelihood = particles[best].log_likelihood;
  e.lost = loss_.lost();
  e.speed_kmh = particles[best].target.speed_kmh;
  e.heading_rad = particles[best].body.placement.value.heading_rad;
  const prior::BodyPrior& prior = bodyPrior();
  e.walker = particles[best].body.walker.walker;
  e.walker.qdot /= prior.naturalTimeS();
  e.walker.time_in_stride *= prior.naturalTimeS();
  e.walker.stance_foot_x *= prior.legLengthM();
  e.gait_slope_rad = gait_slopes_rad_[particles[best].gait_slope];
  {
    // The walker's units are the body mass M, the leg length L and the natural time T = √(L/g):
    // a torque is M g L, a damping M g L T, an impulse M L / T.
    const double mass_kg = options_.person_mass_kg, leg_m = prior.legLengthM(), time_s = prior.naturalTimeS();
    const double torque_nm = mass_kg * leg_m * leg_m / (time_s * time_s);
    const dynamics::WalkerControls c = prior.walkerPrior().controls(particles[best].body.walker);
    e.springs = c.springs;
    e.springs.stance_knee_stiffness *= torque_nm;
    e.springs.swing_knee_stiffness *= torque_nm;
    e.springs.hip_stiffness *= torque_nm;
    e.springs.torso_stiffness *= torque_nm;
    e.springs.stance_knee_damping *= torque_nm * time_s;
    e.springs.swing_knee_damping *= torque_nm * time_s;
    e.springs.torso_damping *= torque_nm * time_s;
    e.toe_off_impulse_ns = c.toe_off_impulse * mass_kg * leg_m / time_s;
  }
  // Weighted spreads.
  std::array<Eigen::Vector3d, body::kNumBodyJoints> mean, second;
  mean.fill(Eigen::Vector3d::Zero());
  second.fill(Eigen::Vector3d::Zero());
  Eigen::Matrix3d waist_outer = Eigen::Matrix3d::Zero();
  double heading_sin = 0, heading_cos = 0;
  for (size_t i = 0; i < particles.size(); ++i) {
    const double w = std::exp(log_weights[i]);
    for (int j = 0; j < body::kNumBodyJoints; ++j) {
      const Eigen::Vector3d x = particles[i].joints[j].cast<double>();
      mean[j] += w * x;
      second[j] += w * x.cwiseProduct(x);
    }
    const Eigen::Vector3d waist = particles[i].joints[body::kWaist].cast<double>();
    waist_outer += w * waist * waist.transpose();
    heading_sin += w * std::sin(particles[i].body.placement.value.heading_rad);
    heading_cos += w * std::cos(particles[i].body.placement.value.heading_rad);
  }
  for (int j = 0; j < body::kNumBodyJoints; ++j)
    e.joint_sd_m[j] = (second[j] - mean[j].cwiseProduct(mean[j])).cwiseMax(0.0).cwiseSqrt();
  e.waist_covariance_m2 = waist_outer - mean[body::kWaist] * mean[body::kWaist].transpose();
  const double resultant = std::hypot(heading_sin, heading_cos);
  e.heading_sd_rad = std::sqrt(std::max(0.0, -2 * std::log(std::max(resultant, 1e-12))));
  return e;
}

bool TrackLossDetector::update(double map_log_likelihood) {
  double floor = 0;
  if (fraction_ > 0 && recent_count_ >= kLostMedianMinFrames) {
    std::array<double, kLostMedianFrames> sorted = recent_;
    const auto end = sorted.begin() + recent_count_;
    const auto middle = sorted.begin() + recent_count_ / 2;
    std::nth_element(sorted.begin(), middle, end);
    floor = std::max(0.0, fraction_ * *middle);
  }
  const bool finite = std::isfinite(map_log_likelihood);
  low_frames_ = !finite || map_log_likelihood < floor ? low_frames_ + 1 : 0;
  if (finite) {
    recent_[recent_next_] = map_log_likelihood;
    recent_next_ = (recent_next_ + 1) % kLostMedianFrames;
    recent_count_ = std::min(recent_count_ + 1, kLostMedianFrames);
  }
  return lost();
}

}  // namespace kneed_walker::core::tracking
