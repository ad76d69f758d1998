#include "kneed_walker/core/tracking/tracking_session.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "kneed_walker/core/common/config_file.h"

namespace kneed_walker::core::tracking {

namespace {

// A track started from its ground track walks the gaits within the measured speed's 2-sd range
// widened by the gait table's speed spacing, km/h.
constexpr double kStartSpeedMarginKmh = 0.5;

}  // namespace

const common::OptionTable<SessionOptions>& sessionOptionTable() {
  using common::OptionField;
  using O = SessionOptions;
  static const common::OptionTable<SessionOptions> table{
      {"background_frames", [](O& o) -> OptionField { return &o.background_frames; }, 1, 500, "frames",
       "frames held at the start to learn the background from (then tracked)"},
      {"find_people", [](O& o) -> OptionField { return &o.find_people; }, 0, 0, "",
       "find walking people in the image when no box or guess is given"},
      {"heading_frames", [](O& o) -> OptionField { return &o.heading_frames; }, 1, 50, "frames",
       "a found person's walking direction from their blob this many frames on"},
      {"start_window_s", [](O& o) -> OptionField { return &o.start_window_s; }, 0, 5, "s",
       "a track from a box or a found person starts after its ground track watched them this long, "
       "from where it says they stood and walked (the frames are held, then tracked; 0: at once)"},
      {"min_start_speed_kmh", [](O& o) -> OptionField { return &o.min_start_speed_kmh; }, 0, 20, "km/h",
       "a new track starts on the gaits from this speed"},
      {"max_start_speed_kmh", [](O& o) -> OptionField { return &o.max_start_speed_kmh; }, 0, 20, "km/h",
       "... to this speed"},
      {"max_people", [](O& o) -> OptionField { return &o.max_people; }, 1, 16, "",
       "people tracked at once, each with its own particles (body ids 1..max_people)"},
      {"merge_distance_m", [](O& o) -> OptionField { return &o.merge_distance_m; }, 0, 5, "m",
       "two tracks whose waists come this near follow one person: the newer ends"},
      {"reacquire_distance_m", [](O& o) -> OptionField { return &o.reacquire_distance_m; }, 0, 5, "m",
       "a lost track starts again at the next frame from a person found this near (0: never)"},
  };
  return table;
}

std::vector<std::string> validate(const SessionOptions& o) {
  std::vector<std::string> problems = common::rangeProblems(o, sessionOptionTable());
  if (o.min_start_speed_kmh > o.max_start_speed_kmh)
    problems.push_back("min_start_speed_kmh = " + std::to_string(o.min_start_speed_kmh) +
                       " is above max_start_speed_kmh = " + std::to_string(o.max_start_speed_kmh));
  if (!(std::isfinite(o.min_walk_m) && o.min_walk_m >= 0 && o.min_walk_m <= 5))
    problems.push_back("min_walk_m = " + std::to_string(o.min_walk_m) + " is outside [0, 5]");
  const vision::PersonDetectorOptions& d = o.detector;
  if (!(std::isfinite(d.foreground_squared_distance) && d.foreground_squared_distance > 0))
    problems.push_back("detector.foreground_squared_distance must be a positive number");
  if (d.min_pixels < 1) problems.push_back("detector.min_pixels must be at least 1");
  if (!(std::isfinite(d.min_height_m) && std::isfinite(d.max_height_m) && 0 < d.min_height_m &&
        d.min_height_m < d.max_height_m))
    problems.push_back("detector.min_height_m and max_height_m must be finite with 0 < min < max");
  if (!(std::isfinite(d.min_fill) && d.min_fill >= 0 && d.min_fill <= 1))
    problems.push_back("detector.min_fill must be in [0, 1]");
  for (std::string& problem : person::validate(o.ground_track)) problems.push_back(std::move(problem));
  return problems;
}

TrackerFactory trackerFactory(const vision::Camera& camera, const vision::GroundPlane& ground,
                              const gait::GaitTable& prior_table, const prior::PriorOptions& prior,
                              const TrackerOptions& options, const vision::LikelihoodOptions& likelihood) {
  return [=](int body, std::optional<double> person_height_m) {
    TrackerOptions own = options;
    if (person_height_m) own.person_height_m = *person_height_m;
    if (body > 1) own.filter.seed = mixSeed(options.filter.seed, 0, 1000 + static_cast<std::uint64_t>(body), 0);
    return std::make_unique<Tracker>(camera, ground, prior_table, prior, own, likelihood);
  };
}

const char* stateName(SessionState state) {
  switch (state) {
    case SessionState::kLearningBackground: return "learning the background";
    case SessionState::kWaitingForPerson: return "waiting for a person";
    case SessionState::kStartingTrack: return "starting a track";
    case SessionState::kTracking: return "tracking";
    case SessionState::kLost: return "lost";
  }
  return "?";
}

const PersonAnswer* SessionAnswer::person(int body) const {
  for (const PersonAnswer& p : people)
    if (p.body == body) return &p;
  return nullptr;
}

bool SessionAnswer::started() const {
  return std::any_of(people.begin(), people.end(), [](const PersonAnswer& p) { return p.started; });
}

TrackingSession::TrackingSession(TrackerFactory make_tracker, const SessionOptions& options)
    : make_tracker_(std::move(make_tracker)), options_(options), walker_finder_(options.heading_frames, options.min_walk_m) {
  if (!make_tracker_) throw std::invalid_argument("TrackingSession needs a tracker factory");
  common::throwIfInvalid("session options", validate(options));
  slots_.resize(options.max_people);
  slots_[0].tracker = make_tracker_(1, std::nullopt);
  if (!slots_[0].tracker) throw std::invalid_argument("the tracker factory made no tracker");
  default_height_m_ = slots_[0].tracker->personHeightM();
}

const Tracker& TrackingSession::tracker(int body) const {
  if (body < 1 || body > static_cast<int>(slots_.size()))
    throw std::out_of_range("body " + std::to_string(body) + " is not a slot of this session (1.." +
                            std::to_string(slots_.size()) + ")");
  const Slot& slot = slots_[body - 1];
  return slot.tracker ? *slot.tracker : *slots_[0].tracker;
}

Tracker& TrackingSession::slotTracker(int slot, std::optional<double> person_height_m) {
  const double wanted = person_height_m.value_or(default_height_m_);
  if (!slots_[slot].tracker || std::abs(slots_[slot].tracker->personHeightM() - wanted) > 1e-9) {
    slots_[slot].tracker = make_tracker_(slot + 1, person_height_m);
    slots_[slot].tracker->setBacklogFrames(backlog_frames_);
    if (!background_.empty()) slots_[slot].tracker->setBackground(background_);
  }
  return *slots_[slot].tracker;
}

int TrackingSession::trackCount() const {
  return static_cast<int>(std::count_if(slots_.begin(), slots_.end(), [](const Slot& s) { return s.running(); }));
}

void TrackingSession::setBackground(vision::BackgroundModel background) {
  for (Slot& slot : slots_)
    if (slot.tracker) slot.tracker->setBackground(background);  // shares the model's pixels
  background_ = std::move(background);
  background_given_ = true;
  if (state_ == SessionState::kLearningBackground) state_ = SessionState::kWaitingForPerson;
  held_.clear();
}

void TrackingSession::startFrom(const InitialGuess& guess) { pending_guess_ = guess; }

void TrackingSession::setBacklogFrames(int frames) {
  backlog_frames_ = frames;
  for (Slot& slot : slots_)
    if (slot.tracker) slot.tracker->setBacklogFrames(frames);
}

void TrackingSession::startFromBox(const cv::Rect2d& box_px) {
  pending_guess_ = guessFromBox(tracker().camera(), tracker().ground(), box_px);
  pending_guess_->min_speed_kmh = options_.min_start_speed_kmh;
  pending_guess_->max_speed_kmh = options_.max_start_speed_kmh;
}

std::vector<SessionAnswer> TrackingSession::feed(const cv::Mat& bgr, double stamp_s) {
  const vision::Camera& camera = tracker().camera();
  if (bgr.type() != CV_8UC3 || bgr.cols != camera.width() || bgr.rows != camera.height())
    throw std::invalid_argument("the frame is " + std::to_string(bgr.cols) + "x" + std::to_string(bgr.rows) +
                                " with " + std::to_string(bgr.channels()) + " channels; the camera's is " +
                                std::to_string(camera.width()) + "x" + std::to_string(camera.height()) + " BGR");
  if (!std::isfinite(stamp_s)) throw std::invalid_argument("the frame's stamp is not finite");
  const int input = next_input_++;
  if (state_ != SessionState::kLearningBackground) {
    process(bgr, stamp_s, input);
    return releaseAnswers();
  }
  held_.emplace_back(bgr.clone(), stamp_s);
  if (static_cast<int>(held_.size()) < options_.background_frames) return {};
  learnBackgroundFromHeld();
  return releaseAnswers();
}

void TrackingSession::learnBackgroundFromHeld() {
  if (held_.empty()) return;
  std::vector<cv::Mat> frames;
  for (const auto& [frame, stamp] : held_) frames.push_back(frame);
  std::vector<std::pair<cv::Mat, double>> held = std::move(held_);
  setBackground(vision::BackgroundModel::learn(frames));
  background_given_ = false;  // learned from the input: reset() learns again
  const int first = next_input_ - static_cast<int>(held.size());
  for (size_t i = 0; i < held.size(); ++i) process(held[i].first, held[i].second, first + static_cast<int>(i));
}

std::vector<SessionAnswer> TrackingSession::flushHeld() {
  learnBackgroundFromHeld();
  // The input ended: a starting track starts from the frames it has.
  for (int s = 0; s < static_cast<int>(slots_.size()); ++s)
    if (slots_[s].start) finishStart(s);
  return releaseAnswers();
}

std::vector<SessionAnswer> TrackingSession::releaseAnswers() {
  if (std::any_of(slots_.begin(), slots_.end(), [](const Slot& slot) { return slot.start.has_value(); })) return {};
  std::vector<SessionAnswer> answers(std::make_move_iterator(held_answers_.begin()),
                                     std::make_move_iterator(held_answers_.end()));
  held_answers_.clear();
  return answers;
}

int TrackingSession::framesHeld() const { return static_cast<int>(held_.size() + held_answers_.size()); }

void TrackingSession::beginStart(int s, const cv::Mat& bgr, double stamp_s, int input, const InitialGuess& guess,
                                  PersonAnswer& person, const std::string& why) {
  Slot& slot = slots_[s];
  // The person's height: the guess's, else person_height_m when the user gave it, else the
  // stature their ground track measures (finishStart). The ground track keeps every frame until
  // the track starts, for its smoothed estimate at the first.
  Start start{guess, guess.person_height_m, why, {}};
  if (!start.height_m && !options_.estimate_person_height) start.height_m = default_height_m_;
  slot.ground = std::make_unique<person::GroundTracker>(tracker().camera(), tracker().ground(), options_.ground_track,
                                                        /*keep_history=*/true);
  slot.ground->start(guess.position_m, start.height_m, stamp_s);
  slot.ground_inputs.clear();
  slot.start = std::move(start);
  trackGround(slot, bgr, stamp_s, input, person);
  if (startDue(slot)) return;  // at this frame's end
  char text[160];
  std::snprintf(text, sizeof text, "starting at (%.2f, %.2f) m: watching the person's ground track for %.1f s",
                guess.position_m.x(), guess.position_m.y(), options_.start_window_s);
  person.message = text;
}

bool TrackingSession::startDue(const Slot& slot) const {
  if (!slot.start) return false;
  const Start& start = *slot.start;
  if (!start.guess.from_ground_track || options_.start_window_s <= 0) return true;
  return start.frames.back().stamp_s - start.frames.front().stamp_s >= options_.start_window_s - 1e-9;
}

PersonAnswer& TrackingSession::heldPerson(int input, int body) {
  const auto answer = std::find_if(held_answers_.begin(), held_answers_.end(),
                                   [&](const SessionAnswer& a) { return a.input == input; });
  if (answer == held_answers_.end()) throw std::logic_error("no held answer for input " + std::to_string(input));
  const auto person = std::find_if(answer->people.begin(), answer->people.end(),
                                   [&](const PersonAnswer& p) { return p.body == body; });
  if (person == answer->people.end()) throw std::logic_error("no held answer for body " + std::to_string(body));
  return *person;
}

InitialGuess TrackingSession::guessFromGroundTrack(InitialGuess guess, const person::GroundTrackEstimate& at) const {
  const person::WalkStart walk = person::walkStart(at, options_.ground_track.near_foot_sd_m);
  guess.position_m = walk.position_m;
  guess.position_covariance_m2 = walk.position_covariance_m2;
  if (!walk.heading_rad) {  // any heading, at the guess's speeds
    guess.heading_sd_rad = M_PI;
    return guess;
  }
  guess.heading_rad = *walk.heading_rad;
  guess.heading_sd_rad = walk.heading_sd_rad;
  // The gaits within the speed's 2-sd range and a gait spacing on either side, among the
  // guess's; a speed outside the guess's takes its nearest.
  const double reach_kmh = 2 * walk.speed_sd_kmh + kStartSpeedMarginKmh;
  const double low = std::max(guess.min_speed_kmh, walk.speed_kmh - reach_kmh);
  const double high = std::min(guess.max_speed_kmh, walk.speed_kmh + reach_kmh);
  if (low <= high) {
    guess.min_speed_kmh = low, guess.max_speed_kmh = high;
  } else {
    guess.min_speed_kmh = guess.max_speed_kmh = std::clamp(walk.speed_kmh, guess.min_speed_kmh, guess.max_speed_kmh);
  }
  return guess;
}

void TrackingSession::finishStart(int s) {
  Slot& slot = slots_[s];
  Start start = std::move(*slot.start);
  slot.start.reset();
  const std::vector<HeldFrame>& frames = start.frames;
  const int n = static_cast<int>(frames.size()), body = s + 1;
  // The ground track over the held frames, smoothed: at each, what the whole window saw.
  const std::vector<person::GroundTrackEstimate> ground = slot.ground->smoothed();
  if (static_cast<int>(ground.size()) != n) throw std::logic_error("a starting track's ground track lost frames");
  const bool head_seen = std::any_of(ground.begin(), ground.end(), [](const auto& g) { return g.head_used; });
  std::optional<double> height_m = start.height_m;
  const bool estimated = !height_m && head_seen;
  if (estimated)
    height_m = std::clamp(std::round(100 * ground.front().stature()) / 100, kMinPersonHeightM, kMaxPersonHeightM);
  // (A ground track that never saw the person, e.g. merged with another in one silhouette,
  // leaves the guess as it was.)
  const bool from_ground_track = start.guess.from_ground_track && options_.start_window_s > 0 &&
                                 std::any_of(ground.begin(), ground.end(), [](const auto& g) { return g.measured; });
  Tracker& tracker = slotTracker(s, height_m);
  // The held frames tracked from the first; a track lost among them starts again at the next
  // from the ground track there, with the colours it learned.
  for (int k = 0; k < n; ++k) {
    PersonAnswer& person = heldPerson(frames[k].input, body);
    tracker.setBacklogFrames(backlog_frames_ + n - 1 - k);  // online, they are a backlog of the frame budget
    TrackEstimate estimate;
    if (!tracker.started()) {
      InitialGuess guess = start.guess;
      if (k > 0) {
        guess = guessFromGroundTrack(start.guess, ground[k]);
        guess.same_person = true;
      } else if (from_ground_track) {
        guess = guessFromGroundTrack(start.guess, ground[0]);
      }
      try {
        estimate = tracker.start(frames[k].bgr, frames[k].stamp_s, guess, &ground[k]);
      } catch (const std::invalid_argument& e) {
        // The guess does not fit the image (e.g. a box around no person): the person is looked
        // for in the image instead.
        if (k == 0) {
          SessionAnswer& last = held_answers_.back();
          last.start_failed = true;
          last.message = std::string("could not start from the guess: ") + e.what();
        }
        endTrack(slot);
        break;
      }
      slot.started_input = frames[k].input;
      ++slot.track;
      person.started = true;
      char text[260];
      std::snprintf(text, sizeof text, "%sstarted at (%.2f, %.2f) m, heading %s, %.2f m tall%s%s",
                    k == 0 ? start.why.c_str() : "again: ", guess.position_m.x(), guess.position_m.y(),
                    guess.heading_sd_rad >= M_PI ? "unknown" : (std::to_string(guess.heading_rad) + " rad").c_str(),
                    tracker.personHeightM(), estimated ? " (measured)" : "",
                    k > 0 || from_ground_track ? " (from its ground track)" : "");
      person.message = text;
    } else {
      estimate = tracker.track(frames[k].bgr, frames[k].stamp_s, &ground[k]);
    }
    slot.track_inputs.emplace_back(frames[k].input, frames[k].stamp_s);
    collectMapFrames(slot, person);
    person.estimate = estimate;
    person.track = slot.track;
    if (estimate.lost) {
      last_seen_m_ = estimate.pose.joints[body::kWaist].head<2>();
      const bool last = k + 1 == n;
      for (MapFrame& frame : last ? endTrack(slot, &person) : endWalker(slot)) person.map_frames.push_back(std::move(frame));
      person.ended = true;
      person.message = last ? "lost: the best particle explains the image worse than the background; looking again"
                            : "lost: the best particle explains the image worse than the background; starting "
                              "again from the ground track";
    }
  }
  tracker.setBacklogFrames(backlog_frames_);
  if (slot.ground) {
    slot.ground->keepHistory(tracker.keepsWholePath());
    if (!tracker.keepsWholePath()) slot.ground_inputs.clear();
  }
  for (SessionAnswer& answer : held_answers_) describe(answer);
}

void TrackingSession::process(const cv::Mat& bgr, double stamp_s, int input) {
  const auto began = std::chrono::steady_clock::now();
  SessionAnswer answer;
  answer.input = input;
  answer.stamp_s = stamp_s;
  const int slots = static_cast<int>(slots_.size());
  std::vector<PersonAnswer> people(slots);
  for (int s = 0; s < slots; ++s) people[s].body = s + 1;
  auto waist = [&](int s) { return people[s].estimate->pose.joints[body::kWaist].head<2>().eval(); };
  // Where a busy slot's person is: its track's last waist, else its starting ground track's.
  auto position = [&](int s) {
    return slots_[s].running() ? slots_[s].tracker->lastPose().joints[body::kWaist].head<2>().eval()
                               : slots_[s].ground->current().position();
  };

  // A given guess goes to a free slot (one not about to start again where its person was lost,
  // if there is such), else replaces the busy track nearest to it.
  int given = -1;
  if (pending_guess_) {
    for (int s = 0; s < slots && given < 0; ++s)
      if (!slots_[s].busy() && !slots_[s].reacquire) given = s;
    for (int s = 0; s < slots && given < 0; ++s)
      if (!slots_[s].busy()) given = s;
    if (given < 0) {
      double nearest = std::numeric_limits<double>::infinity();
      for (int s = 0; s < slots; ++s) {
        const double d = (position(s) - pending_guess_->position_m).norm();
        if (d < nearest) nearest = d, given = s;
      }
    }
  }
  // The running tracks: this frame's step, each in its share of the frame's budget; a lost
  // track ends. The starting ones: their ground track's step, the frame held.
  const int running = trackCount();
  for (Slot& slot : slots_)
    if (slot.tracker) slot.tracker->setBudgetShare(1.0 / std::max(1, running));
  for (int s = 0; s < slots; ++s) {
    Slot& slot = slots_[s];
    if (s == given) continue;
    PersonAnswer& person = people[s];
    if (slot.start) {
      trackGround(slot, bgr, stamp_s, input, person);
      continue;
    }
    if (!slot.running()) continue;
    trackGround(slot, bgr, stamp_s, input, person);
    const TrackEstimate estimate =
        slot.tracker->track(bgr, stamp_s, person.ground_track ? &*person.ground_track : nullptr);
    slot.track_inputs.emplace_back(input, stamp_s);
    collectMapFrames(slot, person);
    person.estimate = estimate;
    person.track = slot.track;
    if (estimate.lost) {
      last_seen_m_ = waist(s);
      for (MapFrame& frame : endTrack(slot, &person)) person.map_frames.push_back(std::move(frame));
      person.ended = true;
      person.message = "lost: the best particle explains the image worse than the background; looking again";
    }
  }
  // Two tracks on one person: the newer ends.
  for (int a = 0; a < slots; ++a)
    for (int b = 0; b < slots; ++b) {
      if (a == b || !slots_[a].running() || !slots_[b].running() || !people[a].estimate || !people[b].estimate) continue;
      const bool b_newer = slots_[b].started_input > slots_[a].started_input ||
                           (slots_[b].started_input == slots_[a].started_input && b > a);
      if (!b_newer || (waist(a) - waist(b)).norm() >= options_.merge_distance_m) continue;
      for (MapFrame& frame : endTrack(slots_[b], &people[b])) people[b].map_frames.push_back(std::move(frame));
      people[b].ended = true;
      people[b].message = "merged with body " + std::to_string(a + 1) + ": both followed one person; ended";
    }
  // New tracks: the people lost at the last frame and found again there (but in the slot a given
  // guess takes); the given guess; else the people found walking (in the slots free since
  // before this frame).
  for (int s = 0; s < slots; ++s) {
    if (!slots_[s].reacquire || s == given) continue;
    const InitialGuess guess = *slots_[s].reacquire;
    slots_[s].reacquire.reset();
    beginStart(s, bgr, stamp_s, input, guess, people[s], "found again where lost: ");
  }
  if (pending_guess_) {
    const InitialGuess guess = *pending_guess_;
    pending_guess_.reset();
    walker_finder_.clear();
    if (slots_[given].busy()) {
      const bool was_running = slots_[given].running();
      for (MapFrame& frame : endTrack(slots_[given], &people[given]))
        people[given].map_frames.push_back(std::move(frame));
      people[given].ended = was_running;
      people[given].message = "replaced by the track of a given guess";
    }
    slots_[given].reacquire.reset();
    beginStart(given, bgr, stamp_s, input, guess, people[given]);
  } else if (options_.find_people) {
    std::vector<int> free, lost_now;
    for (int s = 0; s < slots; ++s) {
      if (!slots_[s].busy() && !people[s].ended) free.push_back(s);
      if (people[s].ended && people[s].estimate && people[s].estimate->lost) lost_now.push_back(s);
    }
    if (!free.empty() || !lost_now.empty()) {
      std::vector<vision::PersonCandidate> found = untrackedPeople(bgr);
      // A lost person is looked for where the track lost them: the nearest person found within
      // reacquire_distance_m starts the slot's track again at the next frame, walking the lost
      // heading (at the next frame: a track's frames are its own, and a given guess may come).
      for (const int s : lost_now) {
        const TrackEstimate& lost = *people[s].estimate;
        auto nearest = found.end();
        double best = options_.reacquire_distance_m;
        for (auto it = found.begin(); it != found.end(); ++it) {
          const double d = (it->ground_xy_m - lost.pose.joints[body::kWaist].head<2>()).norm();
          if (d < best) best = d, nearest = it;
        }
        if (nearest == found.end()) continue;
        slots_[s].reacquire = foundPersonGuess(nearest->ground_xy_m, lost.heading_rad, 0.6);
        slots_[s].reacquire->same_person = true;
        slots_[s].reacquire->person_height_m = slots_[s].tracker->personHeightM();
        found.erase(nearest);
        char text[96];
        std::snprintf(text, sizeof text, "; someone is %.2f m away: starting again there at the next frame", best);
        people[s].message += text;
      }
      if (!free.empty()) {
        size_t next = 0;
        for (const person::FoundWalker& walker : walker_finder_.update(std::move(found), input, last_seen_m_)) {
          if (next == free.size()) break;
          InitialGuess guess = foundPersonGuess(walker.person.ground_xy_m, walker.heading_rad, 0.5);
          guess.from_ground_track = true;
          beginStart(free[next], bgr, stamp_s, input, guess, people[free[next]]);
          ++next;
        }
        if (next == free.size()) walker_finder_.clear();
      }
    }
  }

  // A starting track's person has their ground track and no estimate yet.
  for (PersonAnswer& person : people)
    if (person.estimate || person.ended || person.ground_track) answer.people.push_back(std::move(person));
  describe(answer);
  held_answers_.push_back(std::move(answer));
  // The starts due: a guess that does not wait, a full window.
  for (int s = 0; s < slots; ++s)
    if (startDue(slots_[s])) finishStart(s);
  state_ = held_answers_.back().state;
  if (state_ != SessionState::kTracking &&
      std::any_of(slots_.begin(), slots_.end(), [](const Slot& slot) { return slot.start.has_value(); }))
    state_ = SessionState::kStartingTrack;
  last_frame_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - began).count();
}

void TrackingSession::describe(SessionAnswer& answer) const {
  bool tracking = false, lost = false;
  for (const PersonAnswer& person : answer.people)
    if (person.estimate) (person.estimate->lost ? lost : tracking) = true;
  answer.state = tracking ? SessionState::kTracking : lost ? SessionState::kLost : SessionState::kWaitingForPerson;
  if (answer.start_failed) return;
  switch (answer.state) {
    case SessionState::kTracking: answer.message.clear(); break;
    case SessionState::kLost: answer.message = "lost: looking for people again"; break;
    default: answer.message = options_.find_people ? "looking for a walking person" : "waiting for the person's box";
  }
}

void TrackingSession::collectMapFrames(Slot& slot, PersonAnswer& person) {
  // The MAP state sequence's oldest buffered frame is final once Δs later frames weighed it.
  // A tracker that keeps the whole path gives it all when the track ends instead.
  const Tracker& tracker = *slot.tracker;
  if (tracker.keepsWholePath()) return;
  std::vector<int> frames;
  const std::vector<body::BodyPose> poses = tracker.mapPoses(&frames);
  if (frames.empty() || static_cast<int>(frames.size()) < tracker.lagFrames() + 1) return;
  if (frames.front() <= slot.map_written) return;
  slot.map_written = frames.front();
  const auto& [input, stamp] = slot.track_inputs.at(frames.front());
  person.map_frames.push_back({input, stamp, poses.front(), slot.track});
}

void TrackingSession::trackGround(Slot& slot, const cv::Mat& bgr, double stamp_s, int input, PersonAnswer& person) {
  if (!slot.ground) return;
  person.ground_track = slot.ground->update(bgr, background_, stamp_s);
  if (slot.start) {
    slot.start->frames.push_back({slot.start->guess.from_ground_track ? bgr.clone() : bgr, stamp_s, input});
    slot.ground_inputs.push_back(input);
  } else if (slot.tracker->keepsWholePath()) {
    slot.ground_inputs.push_back(input);
  }
}

std::vector<MapFrame> TrackingSession::endTrack(Slot& slot, PersonAnswer* person) {
  if (person && slot.ground && !slot.start && slot.tracker->keepsWholePath()) {
    const std::vector<person::GroundTrackEstimate> smoothed = slot.ground->smoothed();
    for (size_t i = 0; i < smoothed.size() && i < slot.ground_inputs.size(); ++i)
      person->ground_track_smoothed.emplace_back(slot.ground_inputs[i], smoothed[i]);
  }
  slot.ground.reset();
  slot.ground_inputs.clear();
  slot.start.reset();
  return endWalker(slot);
}

std::vector<MapFrame> TrackingSession::endWalker(Slot& slot) {
  std::vector<MapFrame> rest;
  if (slot.running()) {
    std::vector<int> frames;
    const std::vector<body::BodyPose> poses =
        slot.tracker->keepsWholePath() ? slot.tracker->wholeMapPoses(&frames) : slot.tracker->mapPoses(&frames);
    for (size_t i = 0; i < frames.size(); ++i) {
      if (frames[i] <= slot.map_written) continue;
      const auto& [input, stamp] = slot.track_inputs.at(frames[i]);
      rest.push_back({input, stamp, poses[i], slot.track});
    }
    slot.tracker->stop();
  }
  slot.track_inputs.clear();
  slot.map_written = -1;
  slot.started_input = -1;
  return rest;
}

InitialGuess TrackingSession::foundPersonGuess(const Eigen::Vector2d& position_m, double heading_rad,
                                              double heading_sd_rad) const {
  InitialGuess guess;
  guess.position_m = position_m;
  guess.heading_rad = heading_rad;
  guess.heading_sd_rad = heading_sd_rad;
  guess.min_speed_kmh = options_.min_start_speed_kmh;
  guess.max_speed_kmh = options_.max_start_speed_kmh;
  return guess;
}

std::vector<vision::PersonCandidate> TrackingSession::untrackedPeople(const cv::Mat& bgr) const {
  const Tracker& any = tracker();
  std::vector<vision::PersonCandidate> untracked;
  for (const vision::PersonCandidate& person :
       vision::findPeople(background_, bgr, any.camera(), any.ground(), options_.detector)) {
    // Someone already tracked: their blob's centre is inside the tracked body's image box, or
    // they stand within a stride of its waist.
    const cv::Point2d centre = (person.box_px.tl() + person.box_px.br()) * 0.5;
    const bool tracked = std::any_of(slots_.begin(), slots_.end(), [&](const Slot& slot) {
      if (slot.start)
        return slot.ground->expectedBox().contains(centre) ||
               (slot.ground->current().position() - person.ground_xy_m).norm() < 0.8;
      if (!slot.running()) return false;
      const body::BodyPose& pose = slot.tracker->lastPose();
      return slot.tracker->imageBox(pose).contains(centre) ||
             (pose.joints[body::kWaist].head<2>() - person.ground_xy_m).norm() < 0.8;
    });
    if (!tracked) untracked.push_back(person);
  }
  return untracked;
}

std::vector<PersonAnswer> TrackingSession::finish() {
  std::vector<PersonAnswer> ended;
  for (int s = 0; s < static_cast<int>(slots_.size()); ++s) {
    if (!slots_[s].running()) continue;
    PersonAnswer person;
    person.body = s + 1;
    person.ended = true;
    person.map_frames = endTrack(slots_[s], &person);
    person.message = "the input ended";
    ended.push_back(std::move(person));
  }
  return ended;
}

void TrackingSession::reset() {
  for (Slot& slot : slots_) {
    endTrack(slot);
    slot.reacquire.reset();
  }
  held_.clear();
  held_answers_.clear();
  pending_guess_.reset();
  walker_finder_.clear();
  last_seen_m_.reset();
  next_input_ = 0;
  if (!background_given_) background_ = vision::BackgroundModel{};
  state_ = background_given_ ? SessionState::kWaitingForPerson : SessionState::kLearningBackground;
}

}  // namespace kneed_walker::core::tracking
