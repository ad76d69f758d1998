// video_to_bag: a video from a calibrated static camera as a rosbag, the way a camera driver
// would have recorded it, so that track.launch bag:= plays real footage (issue 12):
//   /camera/image_raw    sensor_msgs/Image (bgr8), frame_id camera_optical
//   /camera/camera_info  sensor_msgs/CameraInfo from the calibration file
//   /tf_static           world -> camera_optical (latched), from the calibration's R, t
// Frames are stamped --fps apart from --start-stamp: by default the video's own rate, which must
// be the camera's, as the walker's dynamics need the true interval (PETS 2009 was captured at
// about 7 frames per second although its AVI header says 10: the demo gives --fps 7). The bag is
// written as NAME.partial.bag and renamed when done (a failed run leaves an earlier bag as it
// was); SIGINT or SIGTERM ends it after the current frame with a whole bag of the frames done
// and exit status 128 + the signal.
//
//   rosrun kneed_walker video_to_bag --video ../shared/data/pets2009/vtest.avi
//       --camera ../shared/data/pets2009/View_001_camera.yml --out pets.bag [--fps 7]
//       [--first-frame 0] [--frames N]                                          (one line)
#include <CLI/CLI.hpp>
#include <cv_bridge/cv_bridge.h>
#include <opencv2/videoio.hpp>
#include <ros/time.h>
#include <rosbag/bag.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "options.h"
#include "kneed_walker/ros/bag_writing.h"
#include "kneed_walker/ros/conversions.h"
#include "camera_file.h"
#include "interrupt.h"

namespace kw = kneed_walker::core;

namespace {

struct Settings {
  std::string video, camera_path, out;
  double camera_unit_m = 0.001, fps = 0, start_stamp_s = 1.7e9;  // fps 0: the video's
  int first_frame = 0, frames = 0;  // 0: to the end
};

// Writes the bag to `path`; returns the frames written. `fps` becomes the rate used.
int convert(const Settings& s, const std::string& path, double& fps) {
  const kw::vision::Camera camera = kneed_walker::tools::loadCamera("video_to_bag", s.camera_path, s.camera_unit_m);
  cv::VideoCapture video(s.video);
  if (!video.isOpened()) throw std::runtime_error("--video: cannot open " + s.video);
  fps = s.fps > 0 ? s.fps : video.get(cv::CAP_PROP_FPS);
  if (!(fps > 0)) throw std::runtime_error("--video " + s.video + ": the video has no frame rate; give --fps");
  cv::Mat image;
  for (int skipped = 0; skipped < s.first_frame; ++skipped)
    if (!video.read(image)) throw std::runtime_error("--first-frame: the video has only " + std::to_string(skipped) + " frames");
  const std::string camera_frame = "camera_optical";
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  const ros::Time first_stamp(s.start_stamp_s);
  kneed_walker::ros_glue::writeStaticCameraPose(bag, camera, "world", camera_frame, first_stamp, "/video_to_bag");
  sensor_msgs::CameraInfo info = kneed_walker::ros_glue::toCameraInfo(camera, camera_frame);
  int written = 0;
  while ((s.frames == 0 || written < s.frames) && kneed_walker::tools::stopSignal() == 0 && video.read(image)) {
    if (image.cols != camera.width() || image.rows != camera.height())
      throw std::runtime_error("--video: frame " + std::to_string(s.first_frame + written) + " is " +
                               std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                               " but --camera is for " + std::to_string(camera.width()) + "x" +
                               std::to_string(camera.height()));
    std_msgs::Header header;
    header.seq = static_cast<std::uint32_t>(written);
    header.stamp = first_stamp + ros::Duration(written / fps);
    header.frame_id = camera_frame;
    info.header = header;
    bag.write("/camera/image_raw", header.stamp, *cv_bridge::CvImage(header, "bgr8", image).toImageMsg());
    bag.write("/camera/camera_info", header.stamp, info);
    ++written;
    if (written % 50 == 0) std::fprintf(stderr, "\rvideo_to_bag: %d frames", written);
  }
  bag.close();
  if (written == 0) throw std::runtime_error("--video: no frame to write from frame " + std::to_string(s.first_frame));
  return written;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Writes a video from a calibrated static camera as a rosbag (image, camera_info, /tf_static)."};
  Settings s;
  using kneed_walker::tools::FiniteRange;
  app.add_option("--video", s.video, "the video (any format OpenCV reads)")->required()->check(CLI::ExistingFile);
  app.add_option("--camera", s.camera_path, "calibration (OpenCV YAML: camera_matrix, distortion_coefficients, R, t)")
      ->required()->check(CLI::ExistingFile);
  app.add_option("--camera-unit", s.camera_unit_m, "metres per length unit of the calibration's t")->capture_default_str()
      ->check(FiniteRange(1e-6, 1e3));
  app.add_option("--out", s.out, "the bag to write")->required();
  app.add_option("--fps", s.fps, "the camera's frame rate, frames/s (default: the video's; PETS 2009: about 7, "
                                 "whatever its header says)")
      ->check(FiniteRange(0.1, 1000));
  app.add_option("--first-frame", s.first_frame, "the video's first frame to write")->capture_default_str()
      ->check(CLI::Range(0, 10000000));
  app.add_option("--frames", s.frames, "frames to write (0: to the end)")->capture_default_str()->check(CLI::Range(0, 10000000));
  app.add_option("--start-stamp", s.start_stamp_s, "stamp of the first frame, s since the epoch")->capture_default_str()
      ->check(FiniteRange(1e-3, 4e9));
  CLI11_PARSE(app, argc, argv);
  {
    const std::filesystem::path dir = std::filesystem::absolute(s.out).parent_path();
    if (!std::filesystem::is_directory(dir)) {
      std::fprintf(stderr, "video_to_bag: --out: %s is not a directory\n", dir.c_str());
      return 2;
    }
  }
  std::filesystem::path temporary = s.out;
  temporary.replace_extension(".partial" + temporary.extension().string());
  try {
    ros::Time::init();
    kneed_walker::tools::stopOnSignals();
    double fps = 0;
    const int written = convert(s, temporary.string(), fps);
    std::filesystem::rename(temporary, s.out);
    std::fprintf(stderr, "\r");
    std::printf("video_to_bag: wrote %d frames at %g fps (%.1f s) to %s\n", written, fps, written / fps, s.out.c_str());
    if (const int signal = kneed_walker::tools::stopSignal(); signal != 0) {
      std::fprintf(stderr, "video_to_bag: %s after %d frames: the bag holds them\n",
                   kneed_walker::tools::stopSignalName(signal), written);
      return 128 + signal;
    }
  } catch (const std::exception& e) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);  // an earlier bag at --out stays as it was
    std::fprintf(stderr, "video_to_bag: %s\n", e.what());
    return 1;
  }
  return 0;
}
