// track_offline's loop: each frame of the input through the tracking session, each answer to
// the outputs, a lost track started again from the boxes, a progress line, and the run's counts
// and timings.
#pragma once

#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "command_line.h"
#include "input.h"
#include "outputs.h"
#include "person_start.h"
#include "progress.h"  // src/tools

namespace kneed_walker::tools::track_offline {

struct RunSummary {
  int answered = 0;       // frames the session answered
  int tracked = 0;        // of them, frames with someone tracked
  int skipped = 0;        // frames the tracker could not use
  std::map<std::string, int> skipped_by_reason;
  int lost = 0;           // estimates that reported their track lost
  int resampled = 0;      // estimates whose step resampled
  int tracks_started = 0;
  int most_people = 0;    // tracked at once
  int interrupted_by = 0;  // the signal (SIGINT, SIGTERM) that ended the run early, or 0 (interrupt.h)
  std::set<int> bodies_used;
  // Per frame with someone tracked (the first excepted): the session's whole time, and the
  // trackers' precomputation and particles summed, ms.
  std::vector<double> total_ms, precompute_ms, particles_ms;
};

class TrackingLoop {
 public:
  TrackingLoop(const Options& options, Input& input, core::tracking::TrackingSession& session,
               const PersonStart& start, Outputs& outputs);
  // Tracks from the first frame to the end (or max_frames); throws when nobody was tracked.
  RunSummary run();

 private:
  void answer(const core::tracking::SessionAnswer& answer, bool latest);
  // The frame's overlay: each person's body, the particle cloud of the latest frame, the state.
  void drawAnswer(const core::tracking::SessionAnswer& answer, bool latest, int people_now);
  void writePose(int input, double stamp_s, const core::body::BodyPose& pose, int body, int track);
  // The person's ground track as --out-ground-track wants it: this frame's (input), filtered, or
  // the track's smoothed when it ends.
  void writeGroundTrack(const core::tracking::PersonAnswer& person, int input);
  void skip(int frame, const std::string& problem);  // counted by reason, the first of each said
  void restartLostTrack(int frame);
  void recordTiming(const std::vector<core::tracking::SessionAnswer>& answers);
  void printProgress();

  const Options& options_;
  Input& input_;
  core::tracking::TrackingSession& session_;
  const PersonStart& start_;
  Outputs& outputs_;
  RunSummary summary_;
  std::vector<int> source_index_;          // per session input: the input's frame index
  std::map<int, cv::Mat> unanswered_;      // frames held by the session, for the overlay
  std::optional<cv::Point2d> lost_at_px_;  // where a lost track was last seen
  ProgressReport progress_;
};

// The run's figures on stdout (frames, restarts, timing medians).
void printSummary(const RunSummary& summary, const Options& options);

}  // namespace kneed_walker::tools::track_offline
