// A stream of frames in, an answer per frame out: what the nodelet and track_offline share
// around the Tracker itself, so that the same frames and seed give the same poses online and
// offline. The session
//   * learns the background from the first `background_frames` frames when none is given,
//     holding them and then tracking through them (so no frame goes unanswered);
//   * tracks up to `max_people` people at once, one Tracker each, in body slots 1..max_people
//     (the REP 155 body id a slot's tracks are published under); the frame, the background
//     model and the search for people are shared, each tracker weighs its own region;
//   * starts a track from a guess or a box when given one, and otherwise finds people itself
//     (vision/person_detector.h): a blob the size of a person, away from every track, seen
//     again `heading_frames` later nearby, gives the position and the walking direction;
//   * starts a track from a rough guess (a box, a person found: InitialGuess::from_ground_track)
//     once the person's ground track has watched them for `start_window_s`: the frames are held
//     meanwhile (their answers too), and then tracked from the first, the particles starting
//     where the track says the person stood, walked and how fast;
//   * ends a track that is lost (TrackEstimate::lost: the person left, or is hidden) or that
//     has merged with an older one (their waists nearer than `merge_distance_m`); a lost
//     track starts again at the next frame from a person found near where it lost them
//     (`reacquire_distance_m`), else people are looked for again;
//   * keeps the fixed-lag MAP state sequence (paper §4: the ancestry of the best particle,
//     kept to one lineage while it weighs nearly as much; final Δs frames later) per input
//     frame and person.
// Frames must come in order of stamp; reset() starts over (a bag that loops).
#pragma once

#include <opencv2/core.hpp>

#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "kneed_walker/core/person/ground_track.h"
#include "kneed_walker/core/person/walker_finder.h"
#include "kneed_walker/core/tracking/tracker.h"
#include "kneed_walker/core/vision/person_detector.h"

namespace kneed_walker::core::tracking {

struct SessionOptions {
  int background_frames = 20;  // frames held at the start to learn the background from, [1, 500]
  int heading_frames = 5;      // a found person's direction from their blob this many frames on, [1, 50]
  double min_walk_m = 0.15;    // the blob must move at least this far in heading_frames, m
  // A track started from a rough guess (a box, a person found) waits this long, its frames held,
  // while the person's ground track measures where they go; then it starts from the ground
  // track at the first of those frames and tracks through them. 0: at once, from the guess.
  // s, [0, 5].
  double start_window_s = 1.0;
  bool find_people = true;     // find the person in the image when no guess or box is given
  // The walking speeds a track started from a box or a found person starts on, km/h (the table's
  // gaits in this range; TrackerOptions::min_gait_speed_kmh says which gaits exist). 1.5–6 with
  // the slow walks, as the demo's track_offline --min-speed 1.5.
  double min_start_speed_kmh = 3.0;  // [0, 20]
  double max_start_speed_kmh = 6.0;  // [min_start_speed_kmh, 20]
  int max_people = 1;              // people tracked at once, [1, 16]; each costs a tracker's time
  // Two tracks whose waists come nearer than this on the ground follow one person: the newer
  // ends, m, [0, 5]. (People walking side by side keep about 0.6 m between their waists.)
  double merge_distance_m = 0.35;
  // A lost track starts again at the next frame from the person found nearest to where it lost
  // them, within this, m, [0, 5] (0: never; the person is looked for as anyone else,
  // heading_frames on).
  double reacquire_distance_m = 1.0;
  vision::PersonDetectorOptions detector;
  person::GroundTrackOptions ground_track;  // each track's person's ground track
  // Each track's person height from the stature their ground track measures at its first frame
  // (TrackerOptions::person_height_m when their head is not seen); false: person_height_m for
  // everyone. The tools set it false when the user gives person_height_m.
  bool estimate_person_height = true;
};

// Makes the tracker of a body slot (1..max_people). The trackers of a session differ only in
// their seed: see trackerFactory.
// `person_height_m`: the person's, when known (else the options').
using TrackerFactory = std::function<std::unique_ptr<Tracker>(int body, std::optional<double> person_height_m)>;
// Trackers with these arguments (tracker.h), body 1's seeded with options.seed (a lone person
// is tracked exactly as by one Tracker), body b's with a seed mixed from it and b.
TrackerFactory trackerFactory(const vision::Camera& camera, const vision::GroundPlane& ground,
                              const gait::GaitTable& prior_table, const prior::PriorOptions& prior,
                              const TrackerOptions& options, const vision::LikelihoodOptions& likelihood = {});

// The session's options people set: name, range, unit, help (common/option_table.h).
const common::OptionTable<SessionOptions>& sessionOptionTable();
// Every problem with the options, naming the option; empty when usable.
std::vector<std::string> validate(const SessionOptions& options);

enum class SessionState {
  kLearningBackground,  // frames are held until the background is learned
  kWaitingForPerson,    // nobody is tracked: no guess or box given and nobody found yet
  kStartingTrack,       // (state() only) a track is starting: its frames are held while its ground track watches the person
  kTracking,            // someone is tracked at this frame
  kLost,                // every track was lost at this frame; people are looked for again
};
const char* stateName(SessionState state);

// A frame of the MAP state sequence, final: its input frame, stamp and pose.
struct MapFrame {
  int input = 0;
  double stamp_s = 0;
  body::BodyPose pose;
  int track = 0;  // the body's track it belongs to (PersonAnswer::track)
};

// One body slot's part of a frame's answer: there is one for each slot whose track ran, started
// or ended at the frame.
struct PersonAnswer {
  int body = 1;          // the slot, 1..max_people: the REP 155 body id
  bool started = false;  // a track started in this slot at this frame
  // The track of `estimate`, counted from 1 in this slot since the session was made (reset() too):
  // a new number each time the slot's walkers start (a lost person started again, another
  // person): the pose jumps there, so poses of different tracks are not joined (a path, a
  // velocity, foot skate).
  int track = 0;
  // The slot's track ended at this frame (lost, merged into an older track, replaced by a given
  // guess); a track started at the same frame is a new one.
  bool ended = false;
  // This frame's filtered estimate: of the track that ran, else of the one started (none when
  // a track ended before its step, as a replaced one).
  std::optional<TrackEstimate> estimate;
  // MAP frames that became final with this frame: frame t − Δs while tracking, and the rest
  // of a track when it ends (a tracker that keeps the whole path: all of the track when it ends).
  std::vector<MapFrame> map_frames;
  // The person's ground track at this frame (person/ground_track.h), filtered: where they stand
  // and go on the floor and how tall they are, from their silhouette alone.
  std::optional<person::GroundTrackEstimate> ground_track;
  // When the track ends and its tracker keeps its whole path (offline): its ground track over
  // all its frames, smoothed, with each frame's input index.
  std::vector<std::pair<int, person::GroundTrackEstimate>> ground_track_smoothed;
  std::string message;  // what happened, for people (started where, lost, merged)
};

struct SessionAnswer {
  int input = 0;  // the frame's index among the frames fed since the last reset(), from 0
  double stamp_s = 0;
  SessionState state = SessionState::kWaitingForPerson;
  bool start_failed = false;         // a given guess or box could not start a track (message says why)
  std::vector<PersonAnswer> people;  // in order of body
  std::string message;               // why nobody is tracked, or why a given guess failed
  // The answer for a body, or nullptr.
  const PersonAnswer* person(int body) const;
  bool started() const;  // some track started at this frame
};

class TrackingSession {
 public:
  // Throws std::invalid_argument naming bad options (the session's, or the trackers' as the
  // factory's first tracker refuses them).
  TrackingSession(TrackerFactory make_tracker, const SessionOptions& options = {});

  // A background given (an image of the empty scene, or frames sampled by the caller): no
  // frames are held to learn one.
  void setBackground(vision::BackgroundModel background);
  // The next frame starts a track from this guess, in a free slot, else replacing the track
  // nearest to it (with max_people 1: replacing any track).
  void startFrom(const InitialGuess& guess);
  // The next frame starts a track from the person in this box (heading unknown), as startFrom.
  // Throws std::invalid_argument when the box's bottom does not see the ground.
  void startFromBox(const cv::Rect2d& box_px);

  // One frame (BGR 8-bit, the camera's size; else std::invalid_argument and nothing changes).
  // Returns the answers of the frames completed by it, in input order: none while frames are
  // held (for the background, or while a track starts), all of them once they are done, else
  // this frame's.
  std::vector<SessionAnswer> feed(const cv::Mat& bgr, double stamp_s);
  // At the end of the input: answers the frames still held (learning the background from them
  // when they were too few; starting the starting tracks from the frames seen).
  std::vector<SessionAnswer> flushHeld();
  // The rest of the current tracks' MAP state sequences (end of input), by body; ends them.
  std::vector<PersonAnswer> finish();
  // Forgets the track, the held frames and a background learned from them (a given one is
  // kept); frames are counted from 0 again.
  void reset();

  SessionState state() const { return state_; }
  // A slot's tracker, 1..max_people (made when the slot is first used; before, body 1's, made
  // at construction: the camera, ground, background and settings every slot's tracker shares).
  const Tracker& tracker(int body = 1) const;
  int framesFed() const { return next_input_; }
  int framesHeld() const;  // fed frames not yet answered
  int trackCount() const;  // tracks running now
  // Frames waiting behind the next one fed, for the trackers' frame budgets (Tracker::setBacklogFrames).
  void setBacklogFrames(int frames);
  // Wall time of the last fed frame's tracking, all tracks and the search for people, ms.
  double lastFrameMs() const { return last_frame_ms_; }

 private:
  // A frame held by a starting track.
  struct HeldFrame {
    cv::Mat bgr;
    double stamp_s = 0;
    int input = 0;
  };
  // A track waiting for its ground track's window.
  struct Start {
    InitialGuess guess;
    std::optional<double> height_m;  // given (the guess's, or person_height_m); else measured
    std::string why;                 // what the start's message begins with
    std::vector<HeldFrame> frames;   // from the frame it began at
  };
  struct Slot {
    std::unique_ptr<Tracker> tracker;  // made when first used
    std::optional<Start> start;        // its track is starting
    int started_input = -1;            // the input its track started at (the older track wins a merge)
    int track = 0;                     // its walkers' track number (PersonAnswer::track): the last started
    std::vector<std::pair<int, double>> track_inputs;  // per tracker frame: input index, stamp
    int map_written = -1;              // the last tracker frame given as a MapFrame
    std::optional<InitialGuess> reacquire;  // its lost person, found again: the next frame starts there
    std::unique_ptr<person::GroundTracker> ground;  // the track's person's ground track
    std::vector<int> ground_inputs;                 // the input index of each of its frames
    bool running() const { return tracker && tracker->started(); }
    bool busy() const { return running() || start.has_value(); }
  };
  // Learns the background from the frames held for it, and tracks them.
  void learnBackgroundFromHeld();
  // Tracks the frame; its answer joins held_answers_.
  void process(const cv::Mat& bgr, double stamp_s, int input);
  // The held answers, when no track is starting.
  std::vector<SessionAnswer> releaseAnswers();
  // The answer's state and message from its people.
  void describe(SessionAnswer& answer) const;
  // A guess for a person found in the image (the options' start speeds).
  InitialGuess foundPersonGuess(const Eigen::Vector2d& position_m, double heading_rad, double heading_sd_rad) const;
  // The people found in the frame away from the running tracks.
  std::vector<vision::PersonCandidate> untrackedPeople(const cv::Mat& bgr) const;
  // Begins the slot's track at this frame: its ground track starts at the guess. The particles
  // start when the window is full (finishStart), or at this frame's end for a guess that does
  // not wait.
  void beginStart(int slot, const cv::Mat& bgr, double stamp_s, int input, const InitialGuess& guess,
                  PersonAnswer& person, const std::string& why = "");
  bool startDue(const Slot& slot) const;
  // Starts the slot's particles at its start's first frame and tracks its held frames, filling in
  // their held answers (a track lost among them starts again at the next from the ground track).
  // A guess that cannot start a track: the last held answer says why.
  void finishStart(int slot);
  // The slot's person in the held answer of an input.
  PersonAnswer& heldPerson(int input, int body);
  // Ends the slot's track: the rest of its MAP frames; its smoothed ground track into `person`.
  std::vector<MapFrame> endTrack(Slot& slot, PersonAnswer* person = nullptr);
  // Ends the slot's walkers (its tracker's track), keeping its ground track: the rest of their MAP frames.
  std::vector<MapFrame> endWalker(Slot& slot);
  // `guess` moved to a ground track's estimate (person::walkStart): its position and spread, its
  // walking direction and speed when its velocity tells them.
  InitialGuess guessFromGroundTrack(InitialGuess guess, const person::GroundTrackEstimate& at) const;
  // The slot's ground track's step at this frame, into `person`.
  void trackGround(Slot& slot, const cv::Mat& bgr, double stamp_s, int input, PersonAnswer& person);
  void collectMapFrames(Slot& slot, PersonAnswer& person);
  // The slot's tracker, made again when the person's height differs from its own.
  Tracker& slotTracker(int slot, std::optional<double> person_height_m = std::nullopt);

  TrackerFactory make_tracker_;
  double default_height_m_ = 0;  // the factory's trackers' person height when none is given
  SessionOptions options_;
  std::vector<Slot> slots_;  // max_people; slot s is body s + 1
  vision::BackgroundModel background_;
  bool background_given_ = false;
  SessionState state_ = SessionState::kLearningBackground;
  std::vector<std::pair<cv::Mat, double>> held_;  // frames held to learn the background
  std::deque<SessionAnswer> held_answers_;         // answers held while a track starts
  std::optional<InitialGuess> pending_guess_;
  person::WalkerFinder walker_finder_;             // people seen walking, away from the tracks
  std::optional<Eigen::Vector2d> last_seen_m_;    // where the last lost track last was
  int next_input_ = 0;
  int backlog_frames_ = 0;
  double last_frame_ms_ = 0;
};

}  // namespace kneed_walker::core::tracking
