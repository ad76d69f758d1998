// Where track_offline's person starts, and starts again: from --init-box, --init-position or
// the best box of a --boxes CSV at the first frame; a lost track starts again from the CSV's
// box nearest to where the person was last seen.
#pragma once

#include <opencv2/core.hpp>

#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "command_line.h"

namespace kneed_walker::tools::track_offline {

class PersonStart {
 public:
  // Reads the boxes CSV (frame,x1,y1,x2,y2,score,...); throws naming the line that is wrong.
  PersonStart(const StartOptions& options, const core::vision::Camera& camera, const core::vision::GroundPlane& ground);

  // Starts the session's first track at `frame` as the options say (nothing given: the session
  // finds people itself). Throws std::runtime_error naming the option when it cannot.
  void startFirst(core::tracking::TrackingSession& session, int frame) const;
  // A lost track's restart at `frame`: the guess from the CSV's box there nearest to `lost_at_px`.
  std::optional<core::tracking::InitialGuess> restartNear(int frame, const cv::Point2d& lost_at_px) const;
  bool restarts() const { return !boxes_.empty(); }

 private:
  using ScoredBoxes = std::vector<std::pair<cv::Rect2d, double>>;
  // The guess from a box: the feet under its bottom; with the heading given, started at once,
  // else from the person's ground track (InitialGuess::from_ground_track).
  core::tracking::InitialGuess guessAt(const cv::Rect2d& box) const;

  const StartOptions& options_;
  const core::vision::Camera& camera_;
  const core::vision::GroundPlane& ground_;
  std::map<int, ScoredBoxes> boxes_;  // by frame
};

}  // namespace kneed_walker::tools::track_offline
