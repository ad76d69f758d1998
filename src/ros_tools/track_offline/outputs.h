// track_offline's outputs: the joints CSV, the image boxes CSV, the overlay video and the strip
// picture. Each is written under a temporary name beside its target and
// renamed when the run succeeds (commit()): a run that fails leaves the targets as they were.
// The temporary keeps the extension: estimate.csv is written as estimate.partial.csv.
#pragma once

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include <fstream>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "command_line.h"

namespace kneed_walker::tools::track_offline {

class Outputs {
 public:
  // Opens every output; throws std::runtime_error naming the option that cannot be written.
  explicit Outputs(const OutputOptions& options);
  Outputs(const Outputs&) = delete;
  Outputs& operator=(const Outputs&) = delete;

  // Overlay pictures are drawn (for the video or the strip).
  bool drawing() const { return !options_.overlay_path.empty() || !options_.strip_path.empty(); }
  void openOverlay(cv::Size size, double fps);
  bool writesBoxes() const { return !options_.boxes_path.empty(); }
  bool writesGroundTrack() const { return !options_.ground_track_path.empty(); }

  // One body's joints at a frame (REP 155 body id), with its image box (empty: not written).
  void writePose(int frame, double stamp_s, const core::body::BodyPose& pose, int body, int track,
                 const cv::Rect2d& image_box);
  // One body's ground track at a frame.
  void writeGroundTrack(int frame, int body, const core::person::GroundTrackEstimate& estimate);
  // A frame's overlay picture: to the video, and to the strip when it is one of --strip-frames,
  // cropped around `bodies_box` (the tracked bodies' image boxes).
  void writeOverlay(const cv::Mat& picture, int frame, const std::optional<cv::Rect2d>& bodies_box);

  // Writes the strip, closes the files and renames them onto their targets.
  void commit();

 private:
  struct File {
    std::string target, temporary;
  };
  // The temporaries, removed unless renamed (also when a later output fails to open).
  struct Temporaries {
    std::vector<File> files;
    bool renamed = false;
    ~Temporaries();
  };
  const File& add(const std::string& option, const std::string& target);

  OutputOptions options_;
  Temporaries temporaries_;
  std::ofstream csv_, boxes_csv_, ground_csv_;
  std::string overlay_temporary_, strip_temporary_;
  cv::VideoWriter overlay_;
  std::map<int, cv::Mat> strip_tiles_;  // by frame
};

}  // namespace kneed_walker::tools::track_offline
