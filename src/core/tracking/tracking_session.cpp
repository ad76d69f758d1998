#include "kneed_walker/core/tracking/tracking_session.h"

#include <cmath>
#include <stdexcept>

#include "kneed_walker/core/common/config_file.h"

namespace kneed_walker::core::tracking {

std::vector<std::string> validate(const SessionOptions& o) {
  std::vector<std::string> problems;
  if (!(o.background_frames >= 1 && o.background_frames <= 500))
    problems.push_back("background_frames = " + std::to_string(o.background_frames) + " is outside [1, 500]");
  if (!(o.heading_frames >= 1 && o.heading_frames <= 50))
    problems.push_back("heading_frames = " + std::to_string(o.heading_frames) + " is outside [1, 50]");
  if (!(std::isfinite(o.min_walk_m) && o.min_walk_m >= 0 && o.min_walk_m <= 5))
    problems.push_back("min_walk_m = " + std::to_string(o.min_walk_m) + " is outside [0, 5]");
  const vision::PersonDetectorOptions& d = o.detector;
  if (!(std::isfinite(d.foreground_squared_distance) && d.foreground_squared_distance > 0))
    problems.push_back("detector.foreground_squared_distance must be a positive number");
  if (d.min_pixels < 1) problems.push_back("detector.min_pixels must be at least 1");
  if (!(std::isfinite(d.min_height_m) && std::isfinite(d.max_height_m) && 0 < d.min_height_m &&
        d.min_height_m < d.max_height_m))
    problems.push_back("detector.min_height_m and max_height_m must be finite with 0 < min < max");
  if (!(std::isfinite(o.min_start_speed_kmh) && std::isfinite(o.max_start_speed_kmh) && 0 <= o.min_start_speed_kmh &&
        o.min_start_speed_kmh <= o.max_start_speed_kmh && o.max_start_speed_kmh <= 20))
    problems.push_back("min_start_speed_kmh and max_start_speed_kmh must be finite with 0 <= min <= max <= 20 (are " +
                       std::to_string(o.min_start_speed_kmh) + " and " + std::to_string(o.max_start_speed_kmh) + ")");
  if (!(std::isfinite(d.min_fill) && d.min_fill >= 0 && d.min_fill <= 1))
    problems.push_back("detector.min_fill must be in [0, 1]");
  return problems;
}

const char* stateName(SessionState state) {
  switch (state) {
    case SessionState::kLearningBackground: return "learning the background";
    case SessionState::kWaitingForPerson: return "waiting for a person";
    case SessionState::kTracking: return "tracking";
    case SessionState::kLost: return "lost";
  }
  return "?";
}

TrackingSession::TrackingSession(std::unique_ptr<Tracker> tracker, const SessionOptions& options)
    : tracker_(std::move(tracker)), options_(options) {
  if (!tracker_) throw std::invalid_argument("TrackingSession needs a tracker");
  common::throwIfInvalid("session options", validate(options));
}

void TrackingSession::setBackground(vision::BackgroundModel background) {
  tracker_->setBackground(std::move(background));
  background_given_ = true;
  if (state_ == SessionState::kLearningBackground) state_ = SessionState::kWaitingForPerson;
  held_.clear();
}

void TrackingSession::startFrom(const InitialGuess& guess) { pending_guess_ = guess; }

void TrackingSession::startFromBox(const cv::Rect2d& box_px) {
  pending_guess_ = guessFromBox(tracker_->camera(), tracker_->ground(), box_px);
  pending_guess_->min_speed_kmh = options_.min_start_speed_kmh;
  pending_guess_->max_speed_kmh = options_.max_start_speed_kmh;
}

std::vector<SessionAnswer> TrackingSession::feed(const cv::Mat& bgr, double stamp_s) {
  const vision::Camera& camera = tracker_->camera();
  if (bgr.type() != CV_8UC3 || bgr.cols != camera.width() || bgr.rows != camera.height())
    throw std::invalid_argument("the frame is " + std::to_string(bgr.cols) + "x" + std::to_string(bgr.rows) +
                                " with " + std::to_string(bgr.channels()) + " channels; the camera's is " +
                                std::to_string(camera.width()) + "x" + std::to_string(camera.height()) + " BGR");
  if (!std::isfinite(stamp_s)) throw std::invalid_argument("the frame's stamp is not finite");
  const int input = next_input_++;
  if (state_ != SessionState::kLearningBackground) return {process(bgr, stamp_s, input)};
  held_.emplace_back(bgr.clone(), stamp_s);
  if (static_cast<int>(held_.size()) < options_.background_frames) return {};
  return flushHeld();
}

std::vector<SessionAnswer> TrackingSession::flushHeld() {
  if (held_.empty()) return {};
  std::vector<cv::Mat> frames;
  for (const auto& [frame, stamp] : held_) frames.push_back(frame);
  tracker_->setBackground(vision::BackgroundModel::learn(frames));
  state_ = SessionState::kWaitingForPerson;
  std::vector<SessionAnswer> answers;
  const int first = next_input_ - static_cast<int>(held_.size());
  for (size_t i = 0; i < held_.size(); ++i)
    answers.push_back(process(held_[i].first, held_[i].second, first + static_cast<int>(i)));
  held_.clear();
  return answers;
}

SessionAnswer TrackingSession::process(const cv::Mat& bgr, double stamp_s, int input) {
  SessionAnswer answer;
  answer.input = input;
  answer.stamp_s = stamp_s;
  TrackEstimate estimate;
  if (pending_guess_ || !tracker_->started()) {
    std::optional<InitialGuess> guess = pending_guess_;
    if (!guess && options_.find_people) guess = guessFromSightings(bgr, input);
    if (!guess) {
      state_ = answer.state = SessionState::kWaitingForPerson;
      answer.message = options_.find_people ? "looking for a walking person" : "waiting for the person's box";
      return answer;
    }
    if (tracker_->started()) answer.map_frames = endTrack();
    pending_guess_.reset();
    sightings_.clear();
    try {
      estimate = tracker_->start(bgr, stamp_s, *guess);
    } catch (const std::invalid_argument& e) {
      // The guess does not fit the image (e.g. a box around no person): the frame is
      // answered as waiting and the person is looked for in the image instead.
      state_ = answer.state = SessionState::kWaitingForPerson;
      answer.start_failed = true;
      answer.message = std::string("could not start from the guess: ") + e.what();
      return answer;
    }
    answer.started = true;
    char text[160];
    std::snprintf(text, sizeof text, "started at (%.2f, %.2f) m, heading %s", guess->position_m.x(),
                  guess->position_m.y(),
                  guess->heading_sd_rad >= M_PI ? "unknown" : (std::to_string(guess->heading_rad) + " rad").c_str());
    answer.message = text;
  } else {
    estimate = tracker_->track(bgr, stamp_s);
  }
  track_inputs_.emplace_back(input, stamp_s);
  collectMapFrames(answer);
  answer.estimate = estimate;
  if (estimate.lost) {
    state_ = answer.state = SessionState::kLost;
    last_seen_m_ = estimate.pose.joints[body::kWaist].head<2>();
    for (MapFrame& frame : endTrack()) answer.map_frames.push_back(std::move(frame));
    answer.message = "lost: the best particle explains the image worse than the background; looking again";
  } else {
    state_ = answer.state = SessionState::kTracking;
  }
  return answer;
}

void TrackingSession::collectMapFrames(SessionAnswer& answer) {
  // The MAP state sequence's oldest buffered frame is final once Δs later frames weighed it.
  // A tracker that keeps the whole path gives it all when the track ends instead.
  if (tracker_->keepsWholePath()) return;
  std::vector<int> frames;
  const std::vector<body::BodyPose> poses = tracker_->mapPoses(&frames);
  if (frames.empty() || static_cast<int>(frames.size()) < tracker_->lagFrames() + 1) return;
  if (frames.front() <= map_written_) return;
  map_written_ = frames.front();
  const auto& [input, stamp] = track_inputs_.at(frames.front());
  answer.map_frames.push_back({input, stamp, poses.front()});
}

std::vector<MapFrame> TrackingSession::endTrack() {
  std::vector<MapFrame> rest;
  if (tracker_->started()) {
    std::vector<int> frames;
    const std::vector<body::BodyPose> poses =
        tracker_->keepsWholePath() ? tracker_->wholeMapPoses(&frames) : tracker_->mapPoses(&frames);
    for (size_t i = 0; i < frames.size(); ++i) {
      if (frames[i] <= map_written_) continue;
      const auto& [input, stamp] = track_inputs_.at(frames[i]);
      rest.push_back({input, stamp, poses[i]});
    }
    tracker_->stop();
  }
  track_inputs_.clear();
  map_written_ = -1;
  return rest;
}

std::optional<InitialGuess> TrackingSession::guessFromSightings(const cv::Mat& bgr, int input) {
  std::vector<Sighting> now;
  for (const vision::PersonCandidate& person :
       vision::findPeople(tracker_->background(), bgr, tracker_->camera(), tracker_->ground(), options_.detector))
    now.push_back({input, person});
  while (!sightings_.empty() && (sightings_.front().empty() || sightings_.front().front().input < input - options_.heading_frames))
    sightings_.pop_front();
  sightings_.push_back(now);
  if (sightings_.front().empty() || sightings_.front().front().input != input - options_.heading_frames) return std::nullopt;
  // Nearest first to where a lost track was last seen, else the largest first.
  std::vector<const Sighting*> order;
  for (const Sighting& s : now) order.push_back(&s);
  if (last_seen_m_)
    std::stable_sort(order.begin(), order.end(), [&](const Sighting* a, const Sighting* b) {
      return (a->person.ground_xy_m - *last_seen_m_).norm() < (b->person.ground_xy_m - *last_seen_m_).norm();
    });
  for (const Sighting* current : order) {
    const cv::Point2d centre = (current->person.box_px.tl() + current->person.box_px.br()) * 0.5;
    const Sighting* before = nullptr;
    double nearest = 0.5 * current->person.box_px.height;  // further than half a body is someone else
    for (const Sighting& old : sightings_.front()) {
      const double d = cv::norm((old.person.box_px.tl() + old.person.box_px.br()) * 0.5 - centre);
      if (d < nearest) nearest = d, before = &old;
    }
    if (!before) continue;
    const Eigen::Vector2d walked = current->person.ground_xy_m - before->person.ground_xy_m;
    if (walked.norm() < options_.min_walk_m) continue;
    InitialGuess guess;
    guess.position_m = current->person.ground_xy_m;
    guess.heading_rad = std::atan2(walked.y(), walked.x());
    guess.heading_sd_rad = 0.5;
    guess.min_speed_kmh = options_.min_start_speed_kmh;
    guess.max_speed_kmh = options_.max_start_speed_kmh;
    return guess;
  }
  return std::nullopt;
}

std::vector<MapFrame> TrackingSession::finish() { return endTrack(); }

void TrackingSession::reset() {
  endTrack();
  held_.clear();
  pending_guess_.reset();
  sightings_.clear();
  last_seen_m_.reset();
  next_input_ = 0;
  state_ = background_given_ ? SessionState::kWaitingForPerson : SessionState::kLearningBackground;
}

}  // namespace kneed_walker::core::tracking
