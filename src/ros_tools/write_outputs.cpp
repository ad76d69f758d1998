// write_outputs: a node that writes what the tracker nodelet publishes into files, for a run
// through track.launch (its out_dir argument; scripts/demo): every tracked person's joints
// from ~body_poses as CSV `frame,stamp,joint,x,y,z,body,track` (track_offline's format), the smoothed
// ones from ~body_poses_smoothed as joints_smoothed.csv (as track_offline --lagged writes them),
// their image boxes as `frame,x1,y1,x2,y2,body` (for scripts/box_overlap), and ~overlay as an
// MJPG video;
// at the end it prints the tracker's last ~status counts (frames received, processed, skipped,
// dropped, answered).
// `frame` is the index of the input image, by stamp, among the images seen on the input topic
// (a bag's frame number when the bag starts at its video's first frame); poses whose image was
// not seen are numbered from the images around them by the input's frame interval. The files
// are written as the messages come (the overlay) or when the node stops (the CSVs, in order of
// frame and body) when the node stops: at Ctrl-C, or --idle-timeout seconds (wall time) after the
// last message once messages came (a bag has played; track.launch then ends). The input's frame
// rate (the overlay video's) is --fps if given, else the median interval of the input images'
// stamps: the overlay waits for the first kRateImages images to know it.
//
//   rosrun kneed_walker write_outputs --out-dir DIR [--fps 0] [--tracker /kneed_walker]
//       [--image /camera/image_raw] [--idle-timeout 0]
#include <CLI/CLI.hpp>
#include <cv_bridge/cv_bridge.h>
#include <opencv2/videoio.hpp>
#include <ros/ros.h>
#include <sensor_msgs/Image.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <fstream>
#include <iomanip>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "kneed_walker/BodyPoseArray.h"
#include "kneed_walker/TrackingStatus.h"
#include "median.h"
#include "options.h"

namespace {

// Images whose stamps give the frame rate when --fps is not given.
constexpr size_t kRateImages = 5;
// The overlay's rate when the input ended before two images were seen, or when this many
// overlays came before kRateImages images (the input topic is not the tracker's).
constexpr double kFallbackFps = 10.0;
constexpr size_t kMaxWaitingOverlays = 100;

class OutputWriter {
 public:
  OutputWriter(const std::string& out_dir, double fps, const std::string& image_topic)
      : out_dir_(out_dir), image_topic_(image_topic), fps_(fps) {}

  void onImage(const sensor_msgs::ImageConstPtr& image) {
    last_message_ = ros::WallTime::now();
    image_stamps_.insert(image->header.stamp);
  }
  void onPoses(const kneed_walker::BodyPoseArrayConstPtr& poses) {
    last_message_ = ros::WallTime::now();
    poses_[poses->header.stamp] = *poses;
  }
  void onStatus(const kneed_walker::TrackingStatusConstPtr& status) { status_ = status; }
  // Wall seconds since the last message; negative before the first.
  double idleS() const { return last_message_.isZero() ? -1 : (ros::WallTime::now() - last_message_).toSec(); }
  void onOverlay(const sensor_msgs::ImageConstPtr& image) {
    last_message_ = ros::WallTime::now();
    cv_bridge::CvImageConstPtr bgr;
    try {
      bgr = cv_bridge::toCvShare(image, "bgr8");
    } catch (const cv_bridge::Exception& e) {
      ROS_WARN_THROTTLE(5.0, "write_outputs: an overlay image cannot be converted (%s); skipped", e.what());
      return;
    }
    waiting_overlays_.push_back(bgr->image.clone());
    if (overlay_.isOpened()) {
      writeOverlays(overlay_fps_);
    } else if (fps_ > 0 || image_stamps_.size() >= kRateImages) {
      writeOverlays(rate());
    } else if (waiting_overlays_.size() > kMaxWaitingOverlays) {
      ROS_WARN("write_outputs: %zu overlays and %zu images on %s: the frame rate is not known, overlay.avi at %g fps "
               "(give --fps, or --image the tracker's input)", waiting_overlays_.size(), image_stamps_.size(),
               image_topic_.c_str(), kFallbackFps);
      writeOverlays(kFallbackFps);
    }
  }

  // The input's frame rate: --fps, else from the median interval of the images' stamps (0: not
  // known, fewer than two images).
  double rate() const {
    if (fps_ > 0) return fps_;
    if (image_stamps_.size() < 2) return 0;
    std::vector<double> intervals;
    for (auto it = image_stamps_.begin(), next = std::next(it); next != image_stamps_.end(); it = next++)
      intervals.push_back((*next - *it).toSec());
    const double interval_s = kneed_walker::tools::median(std::move(intervals));
    return interval_s > 0 ? 1.0 / interval_s : 0;
  }

  void onSmoothedPoses(const kneed_walker::BodyPoseArrayConstPtr& poses) {
    last_message_ = ros::WallTime::now();
    smoothed_[poses->header.stamp] = *poses;
  }

  // The CSVs; returns false when one cannot be written.
  bool finish() {
    double fps = rate();
    if (!waiting_overlays_.empty() && fps <= 0) {
      std::printf("write_outputs: the input's frame rate is not known (fewer than two images seen): overlay.avi at %g fps\n",
                  kFallbackFps);
      fps = kFallbackFps;
    }
    writeOverlays(fps);
    overlay_.release();
    const double frame_fps = fps > 0 ? fps : kFallbackFps;
    std::ofstream joints(out_dir_ + "/joints.csv"), boxes(out_dir_ + "/boxes.csv"),
        smoothed(out_dir_ + "/joints_smoothed.csv");
    if (!joints || !boxes || !smoothed) return false;
    boxes << "frame,x1,y1,x2,y2,body\n";
    const int bodies = writeJoints(joints, poses_, frame_fps);
    writeJoints(smoothed, smoothed_, frame_fps);
    for (const auto& [stamp, array] : poses_) {
      const long frame = frameOf(stamp, frame_fps);
      for (const kneed_walker::BodyPose& body : array.bodies) {
        const sensor_msgs::RegionOfInterest& b = body.image_box;
        if (b.width > 0 && b.height > 0)
          boxes << frame << ',' << b.x_offset << ',' << b.y_offset << ',' << b.x_offset + b.width << ','
                << b.y_offset + b.height << ',' << body.body_id << '\n';
      }
    }
    // Printed, not logged: rosout is gone once the node has shut down.
    std::printf("write_outputs: %zu frames with %d poses in %s/joints.csv and boxes.csv, %zu smoothed frames in "
                "joints_smoothed.csv, %d overlay frames in overlay.avi at %.3g fps (%s)\n",
                poses_.size(), bodies, out_dir_.c_str(), smoothed_.size(), overlay_frames_, overlay_fps_,
                fps_ > 0 ? "--fps" : "from the input's stamps");
    if (status_)
      std::printf("write_outputs: the tracker's counts: %lu frames received, %lu processed, %lu skipped (unusable), "
                  "%lu dropped (arrived while busy), %lu answered\n",
                  static_cast<unsigned long>(status_->frames_received), static_cast<unsigned long>(status_->frames_processed),
                  static_cast<unsigned long>(status_->frames_skipped), static_cast<unsigned long>(status_->frames_dropped),
                  static_cast<unsigned long>(status_->frames_answered));
    return static_cast<bool>(joints) && static_cast<bool>(boxes) && static_cast<bool>(smoothed);
  }

 private:
  using PosesByStamp = std::map<ros::Time, kneed_walker::BodyPoseArray>;
  // Joints as `frame,stamp,joint,x,y,z,body,track`, in order of frame and body; returns the poses written.
  int writeJoints(std::ofstream& csv, const PosesByStamp& poses, double fps) const {
    csv << "frame,stamp,joint,x,y,z,body,track\n" << std::fixed << std::setprecision(9);
    int bodies = 0;
    for (const auto& [stamp, array] : poses) {
      const long frame = frameOf(stamp, fps);
      for (const kneed_walker::BodyPose& body : array.bodies) {
        ++bodies;
        for (size_t j = 0; j < body.joint_names.size() && j < body.joint_positions.size(); ++j) {
          const geometry_msgs::Point& p = body.joint_positions[j];
          csv << frame << ',' << stamp.toSec() << ',' << body.joint_names[j] << ',' << p.x << ',' << p.y << ','
              << p.z << ',' << body.body_id << ',' << body.track << '\n';
        }
      }
    }
    return bodies;
  }

  // The overlay frames waiting for the video: written once the rate is known.
  void writeOverlays(double fps) {
    if (fps <= 0) return;
    for (; !waiting_overlays_.empty(); waiting_overlays_.pop_front()) {
      const cv::Mat& image = waiting_overlays_.front();
      if (!overlay_.isOpened()) {
        overlay_fps_ = fps;
        overlay_.open(out_dir_ + "/overlay.avi", cv::CAP_OPENCV_MJPEG, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), fps,
                      image.size());
        if (!overlay_.isOpened()) ROS_ERROR("write_outputs: cannot write %s/overlay.avi", out_dir_.c_str());
      }
      if (overlay_.isOpened() && image.size() == overlay_size_.value_or(image.size())) {
        overlay_size_ = image.size();
        overlay_.write(image);
        ++overlay_frames_;
      }
    }
  }

  // The input frame index of a stamp; `fps` numbers the stamps between the images seen.
  long frameOf(const ros::Time& stamp, double fps) const {
    if (image_stamps_.empty()) return std::lround(stamp.toSec() * fps);
    const auto at = image_stamps_.lower_bound(stamp);
    if (at != image_stamps_.end() && *at == stamp) return std::distance(image_stamps_.begin(), at);
    // Not seen: from the nearest image seen before it (or the first), by the frame interval.
    const auto before = at == image_stamps_.begin() ? at : std::prev(at);
    return std::distance(image_stamps_.begin(), before) + std::lround((stamp - *before).toSec() * fps);
  }

  std::string out_dir_, image_topic_;
  double fps_;
  std::set<ros::Time> image_stamps_;
  PosesByStamp poses_, smoothed_;
  cv::VideoWriter overlay_;
  std::optional<cv::Size> overlay_size_;
  std::deque<cv::Mat> waiting_overlays_;
  double overlay_fps_ = 0;
  int overlay_frames_ = 0;
  ros::WallTime last_message_;
  kneed_walker::TrackingStatusConstPtr status_;  // the tracker's last ~status
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "write_outputs");
  const std::vector<std::string> args = [&] {
    std::vector<std::string> kept;
    ros::removeROSArgs(argc, argv, kept);
    return kept;
  }();
  CLI::App app{"Writes the tracker nodelet's poses, image boxes and overlay into files as they are published."};
  std::string out_dir, tracker = "/kneed_walker", image_topic = "/camera/image_raw";
  double fps = 0, idle_timeout_s = 0;
  app.add_option("--out-dir", out_dir, "directory for joints.csv, boxes.csv and overlay.avi (made if missing)")->required();
  app.add_option("--fps", fps,
                 "the input's frame rate (the overlay video's; numbers frames whose image was not seen); 0: from the "
                 "input images' stamps")
      ->capture_default_str()->check(kneed_walker::tools::FiniteRange(0, 1000));
  app.add_option("--tracker", tracker, "the tracker nodelet's name")->capture_default_str();
  app.add_option("--idle-timeout", idle_timeout_s,
                 "stop this many wall seconds after the last message, once messages came (0: at Ctrl-C only)")
      ->capture_default_str()->check(kneed_walker::tools::FiniteRange(0, 1e6));
  app.add_option("--image", image_topic, "the tracker's input image topic")->capture_default_str();
  std::vector<const char*> plain;
  for (const std::string& a : args) plain.push_back(a.c_str());
  try {
    app.parse(static_cast<int>(plain.size()), plain.data());
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  mkdir(out_dir.c_str(), 0755);
  struct stat info;
  if (stat(out_dir.c_str(), &info) != 0 || !S_ISDIR(info.st_mode) || !std::ofstream(out_dir + "/joints.csv")) {
    std::fprintf(stderr, "write_outputs: --out-dir %s: cannot write there\n", out_dir.c_str());
    return 1;
  }
  ros::NodeHandle nh;
  OutputWriter writer(out_dir, fps, image_topic);
  ros::Subscriber images = nh.subscribe(image_topic, 100, &OutputWriter::onImage, &writer);
  ros::Subscriber poses = nh.subscribe(tracker + "/body_poses", 100, &OutputWriter::onPoses, &writer);
  ros::Subscriber overlay = nh.subscribe(tracker + "/overlay", 100, &OutputWriter::onOverlay, &writer);
  ros::Subscriber status = nh.subscribe(tracker + "/status", 10, &OutputWriter::onStatus, &writer);
  ros::Subscriber smoothed = nh.subscribe(tracker + "/body_poses_smoothed", 100, &OutputWriter::onSmoothedPoses, &writer);
  const ros::WallTimer idle = nh.createWallTimer(ros::WallDuration(0.5), [&](const ros::WallTimerEvent&) {
    if (idle_timeout_s > 0 && writer.idleS() > idle_timeout_s) ros::shutdown();
  });
  ros::spin();  // until Ctrl-C, roslaunch stops it, or the input has ended
  if (!writer.finish()) {
    std::fprintf(stderr, "write_outputs: --out-dir %s: cannot write the CSVs\n", out_dir.c_str());
    return 1;
  }
  return 0;
}
