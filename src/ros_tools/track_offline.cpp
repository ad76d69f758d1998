// track_offline: the tracker (paper §4) on a recorded sequence, frame by frame, deterministic for
// a seed: a rosbag (image + camera_info topics; the camera's pose from /tf_static or a camera
// file) or a video with a camera file; one person, or up to --max-people at once. Writes the MAP
// joints per frame and body as CSV `frame,stamp,joint,x,y,z,body` (the synthetic ground truth's
// format, and the REP 155 body id): by default each track's
// whole MAP state sequence, one particle's path written when the track ends (--lagged: each
// frame Δs frames later, as the nodelet; --filtered: each frame's best particle at once),
// optionally an overlay video and the projected body's image box per frame (for comparing
// with a person detector's boxes: scripts/box_overlap), and prints the timing.
//
//   rosrun kneed_walker track_offline --bag seq.bag --camera seq_camera.yml --init-box 300 200 350 320
//       --out-csv estimate.csv [--overlay overlay.avi]                                 (one line)
//   rosrun kneed_walker track_offline --video vtest.avi --camera View_001_camera.yml
//       --boxes View_001_person_boxes.csv --first-frame 600 --out-csv estimate.csv    (one line)
#include <CLI/CLI.hpp>
#include <Eigen/Geometry>
#include <cv_bridge/cv_bridge.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2_msgs/TFMessage.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iomanip>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>

#include "kneed_walker/core/tracking/tracking_session.h"
#include "kneed_walker/core/vision/overlay.h"
#include "kneed_walker/ros/conversions.h"
#include "median.h"
#include "options.h"
#include "package_files.h"

namespace kw = kneed_walker::core;
using kneed_walker::tools::FiniteRange;
using kneed_walker::tools::median;

namespace {

// A sequence of frames that can be read again from its start.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual void rewind() = 0;
  // The next BGR frame and its stamp (s); false at the end.
  virtual bool next(cv::Mat& bgr, double& stamp_s) = 0;
  virtual int count() const = 0;
};

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
  bool next(cv::Mat& bgr, double& stamp_s) override {
    if (!video_.read(bgr)) return false;
    stamp_s = index_++ / fps_;
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
  bool next(cv::Mat& bgr, double& stamp_s) override {
    for (; it_ != view_->end(); ++it_) {
      const sensor_msgs::Image::ConstPtr image = it_->instantiate<sensor_msgs::Image>();
      if (!image) continue;
      bgr = cv_bridge::toCvCopy(image, "bgr8")->image;
      stamp_s = image->header.stamp.toSec();
      ++it_;
      return true;
    }
    return false;
  }
  int count() const override { return count_; }
  rosbag::Bag& bag() { return bag_; }

 private:
  std::string topic_;
  rosbag::Bag bag_;
  std::unique_ptr<rosbag::View> view_;
  rosbag::View::iterator it_;
  int count_ = 0;
};

// The camera of a bag: its first camera_info and the /tf_static transform to its frame.
kw::vision::Camera bagCamera(rosbag::Bag& bag, const std::string& info_topic, const std::string& world_frame) {
  sensor_msgs::CameraInfo::ConstPtr info;
  for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery(info_topic)))
    if ((info = m.instantiate<sensor_msgs::CameraInfo>())) break;
  if (!info) throw std::runtime_error("the bag has no camera_info on " + info_topic + "; give --camera");
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

// The boxes of a boxes CSV (frame,x1,y1,x2,y2,score,...) by frame, with their scores.
std::map<int, std::vector<std::pair<cv::Rect2d, double>>> readBoxes(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot read the boxes");
  std::string line;
  std::getline(in, line);
  std::map<int, std::vector<std::pair<cv::Rect2d, double>>> boxes;
  int number = 1;
  while (std::getline(in, line)) {
    ++number;
    std::istringstream fields(line);
    std::string cell;
    std::vector<double> v;
    while (std::getline(fields, cell, ',')) v.push_back(std::atof(cell.c_str()));
    if (v.size() < 6 || !(v[3] > v[1] && v[4] > v[2]))
      throw std::runtime_error(path + ":" + std::to_string(number) + ": expected frame,x1,y1,x2,y2,score,...");
    boxes[static_cast<int>(v[0])].push_back({cv::Rect2d(cv::Point2d(v[1], v[2]), cv::Point2d(v[3], v[4])), v[5]});
  }
  return boxes;
}

// The walking direction from the box nearest `box` `lookahead` frames later: the ground
// points under the two boxes' bottoms. Empty when the person hardly moved or no box is near.
std::optional<double> headingFromBoxes(const std::map<int, std::vector<std::pair<cv::Rect2d, double>>>& boxes,
                                       int frame, const cv::Rect2d& box, int lookahead,
                                       const kw::vision::Camera& camera, const kw::vision::GroundPlane& ground) {
  const auto later = boxes.find(frame + lookahead);
  if (later == boxes.end()) return std::nullopt;
  const cv::Point2d centre = (box.tl() + box.br()) * 0.5;
  const cv::Rect2d* nearest = nullptr;
  double best = 0.5 * box.height;  // a box further than half a body away is someone else
  for (const auto& [candidate, score] : later->second) {
    const double d = cv::norm((candidate.tl() + candidate.br()) * 0.5 - centre);
    if (d < best) best = d, nearest = &candidate;
  }
  if (!nearest) return std::nullopt;
  const Eigen::Vector2d from = kw::tracking::guessFromBox(camera, ground, box).position_m;
  const Eigen::Vector2d to = kw::tracking::guessFromBox(camera, ground, *nearest).position_m;
  if ((to - from).norm() < 0.15) return std::nullopt;
  return std::atan2(to.y() - from.y(), to.x() - from.x());
}

// The best-scoring box of `frame` in a boxes CSV (frame,x1,y1,x2,y2,score,...).
std::optional<cv::Rect2d> bestBox(const std::map<int, std::vector<std::pair<cv::Rect2d, double>>>& boxes, int frame) {
  const auto it = boxes.find(frame);
  if (it == boxes.end() || it->second.empty()) return std::nullopt;
  return std::max_element(it->second.begin(), it->second.end(),
                          [](const auto& a, const auto& b) { return a.second < b.second; })->first;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Tracks a walking person in a bag or video with the Kneed Walker; writes the MAP joints as CSV."};
  std::string bag_path, video_path, camera_path, image_topic = "/camera/image_raw",
              info_topic = "/camera/camera_info", world_frame = "world", out_csv, overlay_path, boxes_path,
              background_path, out_boxes;
  std::string table_path = kneed_walker::tools::packageFile("config/prior_gait_table.yaml");
  std::string prior_path = kneed_walker::tools::packageFile("config/prior.yaml");
  std::string walker_model = kneed_walker::tools::packageFile("config/walker_model.yaml");
  double camera_unit_m = 0.001, fps = 0;
  std::vector<double> init_box, init_position;
  kw::tracking::InitialGuess guess;
  bool heading_given = false;
  int first_frame = 0, max_frames = 0;
  // Offline only (a stream cannot see its future): the background from frames spread over the
  // whole input.
  int background_samples = 25;
  bool filtered = false, lagged = false, background_from_start = false;
  kw::tracking::TrackerOptions options;
  kw::vision::LikelihoodOptions likelihood;
  auto* input = app.add_option_group("input", "one of --bag, --video");
  input->add_option("--bag", bag_path, "rosbag with image and camera_info topics")->check(CLI::ExistingFile);
  input->add_option("--video", video_path, "video file (with --camera)")->check(CLI::ExistingFile);
  input->require_option(1);
  app.add_option("--camera", camera_path, "calibration (OpenCV YAML; may hold the ground plane); a bag's camera_info + /tf_static otherwise")
      ->check(CLI::ExistingFile);
  app.add_option("--camera-unit", camera_unit_m, "metres per unit of the calibration's t")->capture_default_str()
      ->check(FiniteRange(1e-6, 1e3));
  app.add_option("--image-topic", image_topic, "the bag's image topic")->capture_default_str();
  app.add_option("--info-topic", info_topic, "the bag's camera_info topic")->capture_default_str();
  app.add_option("--fps", fps, "video frame rate (default: the container's)")->check(FiniteRange(0.1, 1000));
  app.add_option("--init-box", init_box, "the person's box in the first frame: x1 y1 x2 y2 (px)")->expected(4)
      ->check(FiniteRange(-1e5, 1e5));
  app.add_option("--boxes", boxes_path,
                 "boxes CSV (frame,x1,y1,x2,y2,score,...): the first frame's best box; the walking direction "
                 "from the nearest box 5 frames on")
      ->check(CLI::ExistingFile);
  app.add_option("--init-position", init_position, "ground position X Y (m) instead of a box")->expected(2)
      ->check(FiniteRange(-1e5, 1e5));
  app.add_option("--init-position-sd", guess.position_sd_m, "spread of the initial position, m")->capture_default_str()
      ->check(FiniteRange(0.0, 10.0));
  app.add_option("--init-heading", guess.heading_rad, "walking direction, rad from +X towards +Y (default: unknown)")
      ->check(FiniteRange(-100, 100))->each([&](const std::string&) { heading_given = true; });
  app.add_option("--init-heading-sd", guess.heading_sd_rad, "spread of the heading, rad (≥ π: any direction)")->capture_default_str()
      ->check(FiniteRange(0.0, 10.0));
  std::string init_stance;
  app.add_option("--init-stance", init_stance, "the leg on the ground in the first frame: left or right (default: unknown)")
      ->check(CLI::IsMember({"left", "right"}));
  kw::tracking::SessionOptions session_options;
  kneed_walker::tools::addTableOptions(app, kw::tracking::trackerOptionTable(), options);
  kneed_walker::tools::addTableOptions(app, kw::tracking::sessionOptionTable(), session_options);
  kneed_walker::tools::addTableOptions(app, kw::vision::likelihoodOptionTable(), likelihood);
  app.add_option("--first-frame", first_frame, "start tracking at this frame")->capture_default_str()->check(CLI::NonNegativeNumber);
  app.add_option("--frames", max_frames, "track at most this many frames (0: all)")->check(CLI::NonNegativeNumber);
  app.add_option("--background", background_path, "an image of the empty scene instead")->check(CLI::ExistingFile);
  app.add_option("--background-samples", background_samples,
                 "frames spread over the whole input that the background is learned from")
      ->capture_default_str()->check(CLI::Range(1, 500));
  app.add_flag("--background-from-start", background_from_start,
               "learn the background from the first --background-frames frames, as the nodelet does, "
               "instead of frames spread over the whole input");
  auto* filtered_flag = app.add_flag("--filtered", filtered,
                                     "write each frame's best particle as it comes, instead of each track's whole MAP "
                                     "state sequence (one particle's path, written when the track ends)");
  app.add_flag("--lagged", lagged,
               "write each frame's MAP state Δs frames later, as the nodelet publishes it (the best particle's "
               "ancestry through the buffer; consecutive frames may come from different particles), instead "
               "of each track's whole MAP state sequence")
      ->excludes(filtered_flag);
  app.add_option("--table", table_path, "the prior's gait table")->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--prior", prior_path, "prior parameters")->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--walker-model", walker_model, "body proportions")->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--out-csv", out_csv, "MAP joints per frame and body (frame,stamp,joint,x,y,z,body)")->required();
  app.add_option("--overlay", overlay_path, "overlay video (MJPG .avi)");
  std::string strip_path;
  std::vector<int> strip_frames;
  app.add_option("--strip", strip_path,
                 "a picture of the overlay at --strip-frames, each cropped around the tracked body, side by side (PNG)");
  app.add_option("--strip-frames", strip_frames, "frames for --strip, comma-separated")
      ->delimiter(',')->check(CLI::NonNegativeNumber);
  app.add_option("--out-boxes", out_boxes,
                 "the MAP body's image box per frame and body, as written to --out-csv (frame,x1,y1,x2,y2,body; px): "
                 "the bounding box of the projected parts' outlines");
  CLI11_PARSE(app, argc, argv);
  options.filter.keep_paths = !filtered && !lagged;
  // The tables' ranges were checked as the options were parsed; what is left relates options.
  bool refused = false;
  for (const std::vector<std::string>& problems : {validate(options), validate(session_options), validate(likelihood)})
    for (const std::string& problem : problems) {
      const std::size_t name_end = problem.find(' ');  // each problem starts with the option's name
      std::fprintf(stderr, "track_offline: --%s%s\n", kw::common::kebabCase(problem.substr(0, name_end)).c_str(),
                   problem.substr(name_end).c_str());
      refused = true;
    }
  if (!camera_path.empty() && options.ground_slope_rad != 0) {
    std::fprintf(stderr,
                 "track_offline: --ground-slope-rad %g: the calibration --camera %s gives the ground (its "
                 "ground_slope_rad, level when it has none); leave --ground-slope-rad out\n",
                 options.ground_slope_rad, camera_path.c_str());
    refused = true;
  }
  if (refused) return 1;
  // A track started from a box or a position starts on the same speeds as a person found.
  guess.min_speed_kmh = session_options.min_start_speed_kmh;
  guess.max_speed_kmh = session_options.max_start_speed_kmh;
  if (!strip_path.empty() && strip_frames.empty()) {
    std::fprintf(stderr, "track_offline: --strip needs --strip-frames\n");
    return 1;
  }
  if (!strip_path.empty() && !cv::haveImageWriter(strip_path)) {
    std::fprintf(stderr, "track_offline: --strip %s: not a picture file OpenCV can write (.png, .jpg)\n", strip_path.c_str());
    return 1;
  }
  if (!init_stance.empty()) guess.stance_leg = init_stance == "left" ? kw::dynamics::Leg::kLeft : kw::dynamics::Leg::kRight;

  // The outputs are opened first (an unwritable one fails at once) and removed when the run
  // fails (no partial output is left behind).
  std::ofstream csv(out_csv);
  if (!csv) {
    std::fprintf(stderr, "track_offline: --out-csv %s: cannot write\n", out_csv.c_str());
    return 1;
  }
  std::ofstream boxes_csv;
  if (!out_boxes.empty()) {
    boxes_csv.open(out_boxes);
    if (!boxes_csv) {
      std::fprintf(stderr, "track_offline: --out-boxes %s: cannot write\n", out_boxes.c_str());
      std::remove(out_csv.c_str());
      return 1;
    }
  }
  if (!strip_path.empty()) {
    if (!std::ofstream(strip_path)) {
      std::fprintf(stderr, "track_offline: --strip %s: cannot write\n", strip_path.c_str());
      std::remove(out_csv.c_str());
      if (!out_boxes.empty()) std::remove(out_boxes.c_str());
      return 1;
    }
    std::remove(strip_path.c_str());
  }
  const bool draw = !overlay_path.empty() || !strip_path.empty();  // overlay pictures are drawn
  cv::VideoWriter overlay;
  auto removeOutputs = [&] {
    csv.close();
    boxes_csv.close();
    overlay.release();
    std::remove(out_csv.c_str());
    if (!out_boxes.empty()) std::remove(out_boxes.c_str());
    if (!overlay_path.empty()) std::remove(overlay_path.c_str());
    if (!strip_path.empty()) std::remove(strip_path.c_str());
  };
  try {
    std::unique_ptr<FrameSource> source;
    std::optional<kw::vision::Camera> camera;
    if (!bag_path.empty()) {
      auto bag = std::make_unique<BagSource>(bag_path, image_topic);
      if (camera_path.empty()) camera = bagCamera(bag->bag(), info_topic, world_frame);
      source = std::move(bag);
    } else {
      if (camera_path.empty()) throw std::runtime_error("--video needs --camera");
      source = std::make_unique<VideoSource>(video_path, fps);
    }
    if (!camera_path.empty()) camera = kw::vision::Camera::load(camera_path, camera_unit_m);
    if (!overlay_path.empty()) {
      overlay.open(overlay_path, cv::CAP_OPENCV_MJPEG, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), fps > 0 ? fps : 10,
                   cv::Size(camera->width(), camera->height()));
      if (!overlay.isOpened()) throw std::runtime_error("--overlay " + overlay_path + ": cannot write the video");
    }
    const kw::vision::GroundPlane ground =
        camera_path.empty() ? kw::vision::GroundPlane{} : kw::vision::loadGroundPlane(camera_path);
    if (!camera_path.empty()) options.ground_slope_rad = ground.slope_rad;
    const kw::gait::GaitTable table =
        kw::gait::loadGaitTable(table_path, kw::dynamics::loadBodyProportions(walker_model));
    kw::tracking::TrackingSession session(
        kw::tracking::trackerFactory(*camera, ground, table, kw::prior::loadPriorOptions(prior_path), options, likelihood),
        session_options);

    // The background: an image, frames spread over the input, or (--background-from-start) the
    // session's own from the first frames.
    const int total = source->count();
    if (!background_path.empty()) {
      cv::Mat image = cv::imread(background_path);
      if (image.empty()) throw std::runtime_error("--background " + background_path + ": not a readable image");
      session.setBackground(kw::vision::BackgroundModel::learn({image}, likelihood.background));
    } else if (!background_from_start) {
      std::vector<cv::Mat> samples;
      const int n = std::max(1, std::min(background_samples, total));
      cv::Mat frame;
      double stamp;
      for (int index = 0, next = 0; static_cast<int>(samples.size()) < n && source->next(frame, stamp); ++index) {
        if (index == next) {
          samples.push_back(frame.clone());
          next = n == 1 ? total : static_cast<int>(static_cast<long>(samples.size()) * (total - 1) / (n - 1));
        }
      }
      session.setBackground(kw::vision::BackgroundModel::learn(samples, likelihood.background));
      source->rewind();
    }

    // Where the person starts: a box, a position, the boxes CSV, or (none given) the session
    // finds the walking person itself.
    const std::map<int, std::vector<std::pair<cv::Rect2d, double>>> boxes =
        boxes_path.empty() ? std::map<int, std::vector<std::pair<cv::Rect2d, double>>>{} : readBoxes(boxes_path);
    auto guessAt = [&](const cv::Rect2d& box, int index) {
      kw::tracking::InitialGuess from_box = kw::tracking::guessFromBox(*camera, ground, box);
      from_box.min_speed_kmh = guess.min_speed_kmh;
      from_box.max_speed_kmh = guess.max_speed_kmh;
      from_box.position_sd_m = guess.position_sd_m;
      if (heading_given) {
        from_box.heading_rad = guess.heading_rad;
        from_box.heading_sd_rad = guess.heading_sd_rad;
      } else {
        // From the boxes a few frames on, if there are any; else any direction.
        const std::optional<double> heading = headingFromBoxes(boxes, index, box, 5, *camera, ground);
        from_box.heading_rad = heading.value_or(0.0);
        from_box.heading_sd_rad = heading ? 0.5 : M_PI;
      }
      from_box.stance_leg = guess.stance_leg;
      return from_box;
    };
    if (!init_position.empty()) {
      guess.position_m = Eigen::Vector2d(init_position[0], init_position[1]);
      if (!heading_given) guess.heading_sd_rad = M_PI;
      session.startFrom(guess);
    } else if (!init_box.empty()) {
      try {
        session.startFrom(guessAt(cv::Rect2d(cv::Point2d(init_box[0], init_box[1]), cv::Point2d(init_box[2], init_box[3])),
                                  first_frame));
      } catch (const std::invalid_argument& e) {
        throw std::runtime_error(std::string("--init-box: ") + e.what());
      }
    } else if (!boxes_path.empty()) {
      const std::optional<cv::Rect2d> box = bestBox(boxes, first_frame);
      if (!box) throw std::runtime_error("no box for frame " + std::to_string(first_frame) + " in " + boxes_path);
      session.startFrom(guessAt(*box, first_frame));
    }

    csv << "frame,stamp,joint,x,y,z,body\n" << std::fixed << std::setprecision(9);
    if (boxes_csv.is_open()) boxes_csv << "frame,x1,y1,x2,y2,body\n" << std::fixed << std::setprecision(2);
    std::vector<int> source_index;  // per session input: the input's frame index
    std::map<int, cv::Mat> strip_pictures;  // by frame: the overlay cropped around the bodies
    auto writePose = [&](int input, double input_stamp, const kw::body::BodyPose& pose, int body) {
      for (int j = 0; j < kw::body::kNumBodyJoints; ++j) {
        const Eigen::Vector3d& p = pose.joints[j];
        csv << source_index.at(input) << ',' << input_stamp << ',' << kw::body::jointName(kw::body::BodyJoint(j))
            << ',' << p.x() << ',' << p.y() << ',' << p.z() << ',' << body << '\n';
      }
      if (!boxes_csv.is_open()) return;
      const cv::Rect2d box = session.tracker(body).imageBox(pose);
      if (!box.empty())
        boxes_csv << source_index.at(input) << ',' << box.x << ',' << box.y << ',' << box.br().x << ',' << box.br().y
                  << ',' << body << '\n';
    };
    std::vector<double> total_ms, precompute_ms, particles_ms;
    const bool tty = isatty(STDERR_FILENO);
    std::map<int, cv::Mat> unanswered;  // frames held by the session, for the overlay
    int index = -1, tracked = 0, answered = 0, lost = 0, resampled = 0, starts = 0, skipped = 0, most_people = 0;
    std::set<int> bodies_used;
    std::optional<cv::Point2d> lost_at_px;  // where a lost track was last seen, to start again from a box there
    auto answer = [&](const kw::tracking::SessionAnswer& a, bool latest) {
      ++answered;
      if (a.start_failed) std::fprintf(stderr, "\ntrack_offline: frame %d: %s\n", source_index.at(a.input), a.message.c_str());
      cv::Mat picture;
      if (draw) {
        picture = unanswered.at(a.input);
        unanswered.erase(a.input);
      }
      int people_now = 0;
      std::optional<cv::Rect2d> strip_box;  // the tracked bodies' image boxes, for the strip
      for (const kw::tracking::PersonAnswer& person : a.people) {
        for (const kw::tracking::MapFrame& m : person.map_frames)
          if (!filtered) writePose(m.input, m.stamp_s, m.pose, person.body);
        if (!person.estimate) continue;
        const kw::tracking::TrackEstimate& estimate = *person.estimate;
        const kw::tracking::Tracker& tracker = session.tracker(person.body);
        ++people_now;
        bodies_used.insert(person.body);
        starts += person.started;
        lost += estimate.lost;
        resampled += estimate.resampled;
        if (filtered) writePose(a.input, a.stamp_s, estimate.pose, person.body);
        if (estimate.lost)
          if (const auto px = camera->project(estimate.pose.joints[kw::body::kWaist])) lost_at_px = cv::Point2d(px->x(), px->y());
        if (draw) {
          std::vector<Eigen::Vector2f> cloud;
          if (latest && tracker.started())
            for (const auto& p : tracker.particles())
              if (const auto px = camera->project(p.joints[kw::body::kWaist].cast<double>()))
                cloud.push_back(px->cast<float>());
          kw::vision::BodyOutlines outlines;
          tracker.project(estimate.pose, outlines);
          kw::vision::drawOverlay(picture, *camera, estimate.pose, outlines, cloud);
          const cv::Rect2d box = tracker.imageBox(estimate.pose);
          if (!box.empty()) {
            if (session_options.max_people > 1)
              cv::putText(picture, std::to_string(person.body), cv::Point(cvRound(box.x), cvRound(box.y) - 3),
                          cv::FONT_HERSHEY_SIMPLEX, 0.5, {255, 255, 255}, 1, cv::LINE_AA);
            strip_box = strip_box ? (*strip_box | box) : box;
          }
        }
      }
      tracked += people_now > 0;
      most_people = std::max(most_people, people_now);
      if (draw) {
        const kw::tracking::PersonAnswer* first = a.people.empty() ? nullptr : &a.people.front();
        cv::putText(picture,
                    cv::format("frame %d  %s", source_index.at(a.input), kw::tracking::stateName(a.state)) +
                        (session_options.max_people > 1 ? cv::format("  %d people", people_now)
                         : first && first->estimate ? cv::format("  N_eff %.0f  %.1f km/h", first->estimate->effective_sample_size,
                                                                 first->estimate->speed_kmh)
                                                    : std::string()),
                    {10, 20}, cv::FONT_HERSHEY_SIMPLEX, 0.5, {255, 255, 255}, 1, cv::LINE_AA);
        if (!overlay_path.empty()) overlay.write(picture);
        const int frame_number = source_index.at(a.input);
        if (strip_box && std::find(strip_frames.begin(), strip_frames.end(), frame_number) != strip_frames.end()) {
          // A portrait crop 1.4 body heights tall around the bodies, 240 px tall in the strip.
          const cv::Rect2d& box = *strip_box;
          const Eigen::Vector2d centre(box.x + box.width / 2, box.y + box.height / 2);
          {
            const double height = 1.4 * box.height, width = std::max(0.75 * height, box.width + 0.2 * height);
            const cv::Rect crop = cv::Rect(cv::Point(cvRound(centre.x() - width / 2), cvRound(centre.y() - height / 2)),
                                           cv::Size(cvRound(width), cvRound(height))) &
                                  cv::Rect(0, 0, picture.cols, picture.rows);
            if (crop.area() > 0) {
              cv::Mat tile;
              cv::resize(picture(crop), tile, cv::Size(cvRound(240.0 * crop.width / crop.height), 240), 0, 0, cv::INTER_CUBIC);
              cv::putText(tile, std::to_string(frame_number), {4, 16}, cv::FONT_HERSHEY_SIMPLEX, 0.5, {255, 255, 255}, 1,
                          cv::LINE_AA);
              strip_pictures[frame_number] = tile;
            }
          }
        }
      }
    };
    cv::Mat frame;
    double stamp = 0;
    while (source->next(frame, stamp)) {
      ++index;
      if (index < first_frame) continue;
      if (max_frames > 0 && session.framesFed() >= max_frames) break;
      // A lost track starts again from the box nearest to where the person was last seen.
      if (lost_at_px && !boxes_path.empty()) {
        std::optional<cv::Rect2d> nearest;
        double best = 1e300;
        for (const auto& [box, score] : boxes.count(index) ? boxes.at(index) : std::vector<std::pair<cv::Rect2d, double>>{}) {
          const double d = cv::norm((box.tl() + box.br()) * 0.5 - *lost_at_px);
          if (d < best) best = d, nearest = box;
        }
        if (nearest) {
          kw::tracking::InitialGuess again = guessAt(*nearest, index);
          again.stance_leg.reset();
          session.startFrom(again);
          lost_at_px.reset();
        }
      }
      std::vector<kw::tracking::SessionAnswer> answers;
      try {
        answers = session.feed(frame, stamp);
      } catch (const std::invalid_argument& e) {
        // A frame the tracker cannot use (another size, no ground under the box): skipped and counted.
        if (skipped++ == 0) std::fprintf(stderr, "\ntrack_offline: frame %d skipped: %s\n", index, e.what());
        continue;
      }
      source_index.push_back(index);
      if (draw) unanswered[session.framesFed() - 1] = frame.clone();
      for (size_t i = 0; i < answers.size(); ++i) answer(answers[i], i + 1 == answers.size());
      if (!answers.empty() && !answers.back().people.empty() && answered > 1) {
        // The frame's whole tracking (all people, the search for new ones) and the trackers' parts.
        double precompute = 0, particles = 0;
        for (const kw::tracking::PersonAnswer& person : answers.back().people) {
          const kw::tracking::TrackerTiming& timing = session.tracker(person.body).timing();
          precompute += timing.precompute_ms;
          particles += timing.particles_ms;
        }
        total_ms.push_back(session.lastFrameMs());
        precompute_ms.push_back(precompute);
        particles_ms.push_back(particles);
      }
      const int todo = max_frames > 0 ? std::min(max_frames, total - first_frame) : total - first_frame;
      const int fed = session.framesFed();
      const int width = 30, filled = todo > 0 ? std::min(width, width * fed / todo) : width;
      std::fprintf(stderr, "%s[%s%s] %d/%d frames, %s%s", tty ? "\r" : "", std::string(filled, '#').c_str(),
                   std::string(width - filled, '-').c_str(), fed, todo, kw::tracking::stateName(session.state()),
                   tty ? "        " : "\n");
    }
    if (tty) std::fprintf(stderr, "\n");
    {
      const std::vector<kw::tracking::SessionAnswer> rest = session.flushHeld();  // an input shorter than the samples
      for (size_t i = 0; i < rest.size(); ++i) answer(rest[i], i + 1 == rest.size());
    }
    for (const kw::tracking::PersonAnswer& person : session.finish())
      for (const kw::tracking::MapFrame& m : person.map_frames)
        if (!filtered) writePose(m.input, m.stamp_s, m.pose, person.body);
    if (tracked == 0) throw std::runtime_error("no frame was tracked (nobody was found walking; give --init-box)");
    if (!strip_path.empty()) {
      if (strip_pictures.empty()) throw std::runtime_error("--strip-frames: none of them was tracked");
      std::vector<cv::Mat> tiles;
      for (const auto& [frame_number, tile] : strip_pictures) {
        if (!tiles.empty()) tiles.push_back(cv::Mat(240, 4, CV_8UC3, cv::Scalar(255, 255, 255)));
        tiles.push_back(tile);
      }
      cv::Mat strip;
      cv::hconcat(tiles, strip);
      if (!cv::imwrite(strip_path, strip)) throw std::runtime_error("--strip " + strip_path + ": cannot write the picture");
    }
    std::printf("frames=%d tracked_frames=%d skipped_frames=%d lost_frames_reported=%d restarts=%d resampled_frames=%d "
                "particles=%d\n",
                answered, tracked, skipped, lost, std::max(0, starts - static_cast<int>(bodies_used.size())), resampled,
                options.filter.num_particles);
    if (session_options.max_people > 1)
      std::printf("tracks_started=%d bodies_used=%zu most_people_at_once=%d\n", starts, bodies_used.size(), most_people);
    std::printf("tracker_ms_per_frame=%.1f precompute_ms=%.1f particles_ms=%.1f (medians)\n", median(total_ms),
                median(precompute_ms), median(particles_ms));
  } catch (const std::exception& e) {
    removeOutputs();
    std::fprintf(stderr, "track_offline: %s\n", e.what());
    return 1;
  }
  return 0;
}
