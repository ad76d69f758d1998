#include "input.h"

#include <cv_bridge/cv_bridge.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <stdexcept>

#include "kneed_walker/ros/conversions.h"
#include "camera_file.h"

namespace kneed_walker::tools::track_offline {

namespace kw = kneed_walker::core;

namespace {

class VideoSource : public FrameSource {
 public:
  VideoSource(const std::string& path, double fps) : path_(path), fps_(fps) { rewind(); }
  void rewind() override {
    video_.open(path_);
    if (!video_.isOpened()) throw std::runtime_error(path_ + ": cannot open the video");
    if (!(fps_ > 0)) fps_ = video_.get(cv::CAP_PROP_FPS);
    if (!(fps_ > 0)) throw std::runtime_error(path_ + ": the video has no frame rate; give --fps");
    index_ = 0;
  }
  bool next(Frame& frame) override {
    if (!video_.read(frame.bgr)) return false;
    frame.stamp_s = index_++ / fps_;
    frame.problem = frame.bgr.empty() || frame.bgr.type() != CV_8UC3 ? "the video's frame is empty or not 8-bit colour" : "";
    return true;
  }
  int count() const override { return static_cast<int>(video_.get(cv::CAP_PROP_FRAME_COUNT)); }

 private:
  std::string path_;
  double fps_;
  cv::VideoCapture video_;
  int index_ = 0;
};

class BagSource : public FrameSource {
 public:
  BagSource(const std::string& path, const std::string& topic) : topic_(topic) {
    try {
      bag_.open(path, rosbag::bagmode::Read);
    } catch (const rosbag::BagException& e) {
      throw std::runtime_error("--bag " + path + ": not a readable bag: " + e.what());
    }
    rewind();
    count_ = static_cast<int>(view_->size());
    if (count_ == 0) throw std::runtime_error(path + ": no messages on " + topic);
  }
  void rewind() override {
    view_ = std::make_unique<rosbag::View>(bag_, rosbag::TopicQuery(topic_));
    it_ = view_->begin();
  }
  bool next(Frame& frame) override {
    for (; it_ != view_->end(); ++it_) {
      const sensor_msgs::Image::ConstPtr image = it_->instantiate<sensor_msgs::Image>();
      if (!image) continue;
      ++it_;
      frame.stamp_s = image->header.stamp.toSec();
      frame.problem = kneed_walker::ros_glue::frameProblem(*image, info_, false);
      frame.bgr = frame.problem.empty() ? cv_bridge::toCvCopy(image, "bgr8")->image : cv::Mat();
      return true;
    }
    return false;
  }
  int count() const override { return count_; }
  rosbag::Bag& bag() { return bag_; }
  // The intrinsics each frame is checked against (their size, the camera's model).
  void checkAgainst(const sensor_msgs::CameraInfo& info) { info_ = info; }

 private:
  std::string topic_;
  rosbag::Bag bag_;
  std::unique_ptr<rosbag::View> view_;
  rosbag::View::iterator it_;
  int count_ = 0;
  sensor_msgs::CameraInfo info_;
};

// The camera of a bag: its first camera_info and the /tf_static transform to its frame.
kw::vision::Camera bagCamera(rosbag::Bag& bag, const std::string& info_topic, const std::string& world_frame) {
  sensor_msgs::CameraInfo::ConstPtr info;
  for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery(info_topic)))
    if ((info = m.instantiate<sensor_msgs::CameraInfo>())) break;
  if (!info) throw std::runtime_error("the bag has no camera_info on " + info_topic + "; give --camera");
  if (const std::string problem = kneed_walker::ros_glue::cameraInfoProblem(*info); !problem.empty())
    throw std::runtime_error("the bag's first " + info_topic + ": " + problem + "; give --camera");
  for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery("/tf_static"))) {
    const tf2_msgs::TFMessage::ConstPtr tf = m.instantiate<tf2_msgs::TFMessage>();
    if (!tf) continue;
    for (const auto& t : tf->transforms)
      if (t.header.frame_id == world_frame && t.child_frame_id == info->header.frame_id)
        return kneed_walker::ros_glue::toCamera(*info, t);
  }
  throw std::runtime_error("the bag has no /tf_static from " + world_frame + " to " + info->header.frame_id +
                           "; give --camera");
}

}  // namespace

Input openInput(const InputOptions& options) {
  if (!options.bag_path.empty()) {
    auto bag = std::make_unique<BagSource>(options.bag_path, options.image_topic);
    kw::vision::Camera camera = options.camera_path.empty()
                                    ? bagCamera(bag->bag(), options.info_topic, options.world_frame)
                                    : kneed_walker::tools::loadCamera("track_offline", options.camera_path, options.camera_unit_m);
    const kw::vision::GroundPlane ground =
        options.camera_path.empty() ? kw::vision::GroundPlane{} : kw::vision::loadGroundPlane(options.camera_path);
    bag->checkAgainst(kneed_walker::ros_glue::toCameraInfo(camera, "camera"));
    return Input{std::move(bag), std::move(camera), ground};
  }
  if (options.camera_path.empty()) throw std::runtime_error("--video needs --camera");
  auto video = std::make_unique<VideoSource>(options.video_path, options.fps);
  return Input{std::move(video), kneed_walker::tools::loadCamera("track_offline", options.camera_path, options.camera_unit_m),
               kw::vision::loadGroundPlane(options.camera_path)};
}

void giveBackground(const InputOptions& options, const kw::vision::BackgroundOptions& background, FrameSource& frames,
                    kw::tracking::TrackingSession& session) {
  if (!options.background_path.empty()) {
    cv::Mat image = cv::imread(options.background_path);
    if (image.empty()) throw std::runtime_error("--background " + options.background_path + ": not a readable image");
    session.setBackground(kw::vision::BackgroundModel::learn({image}, background));
    return;
  }
  if (options.background_from_start) return;
  const int total = frames.count();
  const int n = std::max(1, std::min(options.background_samples, total));
  std::vector<cv::Mat> samples;
  Frame frame;
  // The frames at evenly spread indices; a frame that cannot be used gives its place to the next.
  for (int index = 0, next = 0; static_cast<int>(samples.size()) < n && frames.next(frame); ++index) {
    if (index >= next && frame.problem.empty()) {
      samples.push_back(frame.bgr.clone());
      next = n == 1 ? total : static_cast<int>(static_cast<long>(samples.size()) * (total - 1) / (n - 1));
    }
  }
  if (samples.empty()) throw std::runtime_error("no frame of the input can be used (each is skipped: " + frame.problem + ")");
  session.setBackground(kw::vision::BackgroundModel::learn(samples, background));
  frames.rewind();
}

}  // namespace kneed_walker::tools::track_offline
