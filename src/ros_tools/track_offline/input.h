// track_offline's input: the frames of a bag or a video, the camera that saw them, and the
// background the session is given.
#pragma once

#include <opencv2/core.hpp>

#include <memory>
#include <string>

#include "command_line.h"
#include "kneed_walker/core/tracking/tracking_session.h"

namespace kneed_walker::tools::track_offline {

// A frame of the input: BGR and its stamp, or why it cannot be used (the frame is skipped and
// counted, as the nodelet skips it: ros_glue::frameProblem).
struct Frame {
  cv::Mat bgr;
  double stamp_s = 0;
  std::string problem;  // empty: usable
};

// A sequence of frames that can be read again from its start.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual void rewind() = 0;
  // The next frame; false at the end.
  virtual bool next(Frame& frame) = 0;
  virtual int count() const = 0;
};

struct Input {
  std::unique_ptr<FrameSource> frames;
  core::vision::Camera camera;
  core::vision::GroundPlane ground;  // the calibration's; level without one
};

// The bag or the video, and its camera: the calibration file's, else the bag's first camera_info
// and its /tf_static transform from the world frame. Throws std::runtime_error naming the
// option when something cannot be read.
Input openInput(const InputOptions& options);

// Gives the session its background unless it learns one itself (background_from_start): the
// image of the empty scene, else background_samples frames spread over the whole input (then
// rewound).
void giveBackground(const InputOptions& options, const core::vision::BackgroundOptions& background, FrameSource& frames,
                    core::tracking::TrackingSession& session);

}  // namespace kneed_walker::tools::track_offline
