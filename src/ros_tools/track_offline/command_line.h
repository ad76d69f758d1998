// track_offline's command line: what to read, where the person starts, how to track (the core's
// option tables, common/option_table.h) and what to write.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "kneed_walker/core/tracking/tracking_session.h"

namespace kneed_walker::tools::track_offline {

struct InputOptions {
  std::string bag_path, video_path;  // exactly one
  std::string camera_path;           // calibration; empty: the bag's camera_info and /tf_static
  double camera_unit_m = 0.001;      // metres per unit of the calibration's t
  std::string image_topic = "/camera/image_raw", info_topic = "/camera/camera_info", world_frame = "world";
  double fps = 0;       // a video's frame rate; 0: the container's
  int first_frame = 0;  // frames before it are read and not tracked
  int max_frames = 0;   // frames tracked at most; 0: all
  std::string background_path;  // an image of the empty scene
  // Offline only (a stream cannot see its future): the background from this many frames spread
  // over the whole input, unless background_from_start (the session's first background_frames).
  int background_samples = 25;
  bool background_from_start = false;
};

// Where the person starts: a box, a ground position, the best box of a boxes CSV (which then
// also restarts lost tracks), or nothing (the session finds people itself).
struct StartOptions {
  std::vector<double> init_box;       // x1 y1 x2 y2, px
  std::vector<double> init_position;  // X Y, m
  std::string boxes_path;
  core::tracking::InitialGuess guess;  // spreads, speeds, stance; heading when heading_given
  bool heading_given = false;
};

// Which estimate is written per frame (see --help).
enum class WrittenEstimate { kMapSequence, kLagged, kFiltered };

struct OutputOptions {
  std::string csv_path;  // required
  std::string boxes_path, overlay_path, strip_path;
  std::string ground_track_path;  // each person's ground track (person/ground_track.h)
  std::vector<int> strip_frames;
  WrittenEstimate estimate = WrittenEstimate::kMapSequence;
};

struct Options {
  InputOptions input;
  StartOptions start;
  OutputOptions output;
  std::string gait_table_path, prior_path, walker_model_path;
  core::tracking::TrackerOptions tracker;
  core::tracking::SessionOptions session;
  core::vision::LikelihoodOptions likelihood;
};

// The command line, parsed and checked, options that relate to each other included. Empty when
// the run stops here: `exit_code` 0 for --help, else 1 with each problem printed, naming the
// option.
std::optional<Options> parseOptions(int argc, char** argv, int& exit_code);

}  // namespace kneed_walker::tools::track_offline
