// A stream of frames in, an answer per frame out: what the nodelet and track_offline share
// around the Tracker itself, so that the same frames and seed give the same poses online and
// offline. The session
//   * learns the background from the first `background_frames` frames when none is given,
//     holding them and then tracking through them (so no frame goes unanswered);
//   * starts a track from a guess or a box when given one, and otherwise finds the person
//     itself (vision/person_detector.h): a blob the size of a person, seen again
//     `heading_frames` later nearby, gives the position and the walking direction;
//   * reports a lost track (TrackEstimate::lost) and looks for the person again;
//   * keeps the MAP state sequence (paper §4: the ancestry of the best particle, final Δs
//     frames later) per input frame.
// Frames must come in order of stamp; reset() starts over (a bag that loops).
#pragma once

#include <opencv2/core.hpp>

#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "kneed_walker/core/tracking/tracker.h"
#include "kneed_walker/core/vision/person_detector.h"

namespace kneed_walker::core::tracking {

struct SessionOptions {
  int background_frames = 20;  // frames held at the start to learn the background from, [1, 500]
  int heading_frames = 5;      // a found person's direction from their blob this many frames on, [1, 50]
  double min_walk_m = 0.15;    // the blob must move at least this far in heading_frames, m
  bool find_people = true;     // find the person in the image when no guess or box is given
  // The walking speeds a track started from a box or a found person starts on, km/h (the table's
  // gaits in this range; TrackerOptions::min_gait_speed_kmh says which gaits exist). 1.5–6 with
  // the slow walks, as the demo's track_offline --min-speed 1.5.
  double min_start_speed_kmh = 3.0;  // [0, 20]
  double max_start_speed_kmh = 6.0;  // [min_start_speed_kmh, 20]
  vision::PersonDetectorOptions detector;
};

// Every problem with the options, naming the field; empty when usable.
std::vector<std::string> validate(const SessionOptions& options);

enum class SessionState {
  kLearningBackground,  // frames are held until the background is learned
  kWaitingForPerson,    // no guess or box given and nobody found yet
  kTracking,            // an estimate for this frame
  kLost,                // the track was lost at this frame; the person is looked for again
};
const char* stateName(SessionState state);

// A frame of the MAP state sequence, final: its input frame, stamp and pose.
struct MapFrame {
  int input = 0;
  double stamp_s = 0;
  body::BodyPose pose;
};

struct SessionAnswer {
  int input = 0;  // the frame's index among the frames fed since the last reset(), from 0
  double stamp_s = 0;
  SessionState state = SessionState::kWaitingForPerson;
  bool started = false;                   // a track started at this frame
  bool start_failed = false;              // a given guess or box could not start a track (message says why)
  std::optional<TrackEstimate> estimate;  // this frame's filtered estimate (kTracking, kLost)
  // MAP frames that became final with this frame: frame t − Δs while tracking, and the rest
  // of a track when it ends (a tracker that keeps the whole path: all of the track when it ends).
  std::vector<MapFrame> map_frames;
  std::string message;  // what happened, for people (why waiting, lost, started)
};

class TrackingSession {
 public:
  // Throws std::invalid_argument naming bad options.
  TrackingSession(std::unique_ptr<Tracker> tracker, const SessionOptions& options = {});

  // A background given (an image of the empty scene, or frames sampled by the caller): no
  // frames are held to learn one.
  void setBackground(vision::BackgroundModel background);
  // The next frame starts a track from this guess (replacing any track).
  void startFrom(const InitialGuess& guess);
  // The next frame starts a track from the person in this box (heading unknown). Throws
  // std::invalid_argument when the box's bottom does not see the ground.
  void startFromBox(const cv::Rect2d& box_px);

  // One frame (BGR 8-bit, the camera's size; else std::invalid_argument and nothing changes).
  // Returns the answers of the frames completed by it, in input order: none while frames are
  // held for the background, all of them once it is learned, else this frame's.
  std::vector<SessionAnswer> feed(const cv::Mat& bgr, double stamp_s);
  // At the end of an input shorter than background_frames: learns from the frames held so
  // far and answers them.
  std::vector<SessionAnswer> flushHeld();
  // The rest of the current track's MAP state sequence (end of input); ends the track.
  std::vector<MapFrame> finish();
  // Forgets the track, the held frames and a background learned from them (a given one is
  // kept); frames are counted from 0 again.
  void reset();

  SessionState state() const { return state_; }
  const Tracker& tracker() const { return *tracker_; }
  int framesFed() const { return next_input_; }

 private:
  struct Sighting {
    int input = 0;
    vision::PersonCandidate person;
  };
  SessionAnswer process(const cv::Mat& bgr, double stamp_s, int input);
  // A guess from the people seen now and heading_frames ago; nullopt while nobody qualifies.
  std::optional<InitialGuess> guessFromSightings(const cv::Mat& bgr, int input);
  std::vector<MapFrame> endTrack();
  void collectMapFrames(SessionAnswer& answer);

  std::unique_ptr<Tracker> tracker_;
  SessionOptions options_;
  bool background_given_ = false;
  SessionState state_ = SessionState::kLearningBackground;
  std::vector<std::pair<cv::Mat, double>> held_;  // frames held to learn the background
  std::optional<InitialGuess> pending_guess_;
  std::deque<std::vector<Sighting>> sightings_;   // the people found in the last frames
  std::optional<Eigen::Vector2d> last_seen_m_;    // where a lost track last was
  std::vector<std::pair<int, double>> track_inputs_;  // per tracker frame: input index, stamp
  int map_written_ = -1;                          // the last tracker frame given as a MapFrame
  int next_input_ = 0;
};

}  // namespace kneed_walker::core::tracking
