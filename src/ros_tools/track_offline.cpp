// track_offline: the tracker (paper §4) on a recorded sequence, frame by frame, deterministic for
// a seed: a rosbag (image + camera_info topics; the camera's pose from /tf_static or a camera
// file) or a video with a camera file; one person, or up to --max-people at once. Writes the MAP
// joints per frame and body as CSV `frame,stamp,joint,x,y,z,body,track` (the synthetic ground
// truth's format, the REP 155 body id, and the body's track: a new number where it started
// again, its pose jumping there): by default each track's whole MAP state sequence, one
// particle's path written when the track ends (--lagged: each frame Δs frames later, as the
// nodelet; --filtered: each frame's best particle at once), optionally an overlay video and the
// projected body's image box per frame (for comparing with a person detector's boxes:
// scripts/box_overlap), and prints the timing. SIGINT or SIGTERM ends the run after the frame being
// tracked: the outputs are written whole for the frames done, and the exit status is 128 + the
// signal (130, 143). The parts: track_offline/command_line (options),
// input (frames, camera, background), person_start, tracking_loop and outputs.
//
//   rosrun kneed_walker track_offline --bag seq.bag --camera seq_camera.yml --init-box 300 200 350 320
//       --out-csv estimate.csv [--overlay overlay.avi]                                 (one line)
//   rosrun kneed_walker track_offline --video vtest.avi --camera View_001_camera.yml
//       --boxes View_001_person_boxes.csv --first-frame 600 --out-csv estimate.csv    (one line)
#include "track_offline/command_line.h"
#include "track_offline/input.h"
#include "track_offline/outputs.h"
#include "track_offline/person_start.h"
#include "track_offline/tracking_loop.h"
#include "interrupt.h"
#include "tool_main.h"

namespace kw = kneed_walker::core;
namespace to = kneed_walker::tools::track_offline;

namespace {

int run(int argc, char** argv) {
  int exit_code = 0;
  std::optional<to::Options> options = to::parseOptions(argc, argv, exit_code);
  if (!options) return exit_code;
  to::Outputs outputs(options->output);  // first: an unwritable output fails before any work
  to::Input input = to::openInput(options->input);
  outputs.openOverlay(cv::Size(input.camera.width(), input.camera.height()),
                      options->input.fps > 0 ? options->input.fps : 10);
  if (!options->input.camera_path.empty()) options->tracker.ground_slope_rad = input.ground.slope_rad;
  const kw::gait::GaitTable table = kw::gait::loadGaitTable(
      options->gait_table_path, kw::dynamics::loadBodyProportions(options->walker_model_path));
  kw::tracking::TrackingSession session(
      kw::tracking::trackerFactory(input.camera, input.ground, table, kw::prior::loadPriorOptions(options->prior_path),
                                   options->tracker, options->likelihood),
      options->session);
  to::giveBackground(options->input, options->likelihood.background, *input.frames, session);
  const to::PersonStart start(options->start, input.camera, input.ground);
  start.startFirst(session, options->input.first_frame);
  kneed_walker::tools::stopOnSignals();
  const to::RunSummary summary = to::TrackingLoop(*options, input, session, start, outputs).run();
  outputs.commit();
  to::printSummary(summary, *options);
  return summary.interrupted_by == 0 ? 0 : 128 + summary.interrupted_by;  // as the shell reports a signal
}

}  // namespace

int main(int argc, char** argv) { return kneed_walker::tools::runTool("track_offline", run, argc, argv); }
